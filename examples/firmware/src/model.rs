//! A tiny flight model behind the MCP state machine: the landing state machine, the
//! active controller, the MAV clock, the trajectory and a point-mass position.
//!
//! Axis 0 is elevator (forward), axis 1 is aileron (sideways); altitude is up. The
//! model advances one step of `1 / TICK_HZ` seconds per SysTick tick.
//!
//! Landing states:
//!
//! - `Flight` --landing on--> `Landing`: descends at [`CLIMB_RATE`] down to the
//!   ground, then `OnGround`.
//! - `Landing` or `OnGround` --landing off--> `TakeOff`: climbs at [`CLIMB_RATE`] to
//!   the altitude setpoint, then `Stabilization` for [`STABILIZATION_TICKS`], then
//!   `Flight`.
//! - `TakeOff` or `Stabilization` --landing on--> `Landing`.
//!
//! Controllers: manual holds altitude and position as they are; the altitude
//! controller steers the altitude to its setpoint; MPC also steers the position to
//! its setpoint. Controller ids outside table 28 are refused (the active one stays).
//!
//! Trajectory: up to [`TRAJECTORY_CAPACITY`] waypoints (as many as one unfragmented
//! XBee payload carries). Once the MAV time reaches a waypoint's time, its elevator,
//! aileron and altitude become the setpoints.

use mcp_core::mav::Vehicle;
use mcp_core::{Controller, LandingState, TelemetryId, Waypoint, Waypoints};

use crate::clock::TICK_HZ;

/// Waypoints kept: 5 fill an 84-byte trajectory report (3 + 5 * 16 = 83 bytes).
pub const TRAJECTORY_CAPACITY: usize = 5;
/// Climb and descent rate while taking off and landing, m/s.
pub const CLIMB_RATE: f32 = 0.5;
/// Altitude of the first flight, m.
pub const CRUISE_ALTITUDE: f32 = 1.0;
/// Ticks spent in `Stabilization` after a take-off.
pub const STABILIZATION_TICKS: u32 = TICK_HZ;
/// Largest horizontal speed, m/s.
pub const MAX_SPEED: f32 = 0.5;
/// Proportional gain of the controllers, 1/s.
pub const GAIN: f32 = 1.0;
/// Throttle that holds a hover.
pub const HOVER_THROTTLE: f32 = 0.5;
/// Standard gravity, m/s².
const G: f32 = 9.81;
/// The model step, s.
const DT: f32 = 1.0 / TICK_HZ as f32;

/// The aircraft state. Implements [`Vehicle`] for [`mcp_core::mav::Mav`].
#[derive(Debug, Clone)]
pub struct FlightModel {
    landing: LandingState,
    controller: Controller,
    /// Steps since start-up.
    ticks: u32,
    /// MAV time (POSIX seconds) at step `time_tick`.
    time_base: u32,
    time_tick: u32,
    altitude: f32,
    climb: f32,
    altitude_setpoint: f32,
    position: [f32; 2],
    speed: [f32; 2],
    acceleration: [f32; 2],
    setpoint: [f32; 2],
    /// Sum of the jumps made by position set commands.
    shift: [f32; 2],
    stabilizing: u32,
    trajectory: [Waypoint; TRAJECTORY_CAPACITY],
    trajectory_len: usize,
}

impl Default for FlightModel {
    fn default() -> Self {
        Self::new()
    }
}

impl FlightModel {
    /// Hovering at [`CRUISE_ALTITUDE`] over the origin, altitude controller on, MAV
    /// time 0, no trajectory.
    pub const fn new() -> Self {
        FlightModel {
            landing: LandingState::Flight,
            controller: Controller::Altitude,
            ticks: 0,
            time_base: 0,
            time_tick: 0,
            altitude: CRUISE_ALTITUDE,
            climb: 0.0,
            altitude_setpoint: CRUISE_ALTITUDE,
            position: [0.0; 2],
            speed: [0.0; 2],
            acceleration: [0.0; 2],
            setpoint: [0.0; 2],
            shift: [0.0; 2],
            stabilizing: 0,
            trajectory: [Waypoint {
                time: 0,
                elevator: 0.0,
                aileron: 0.0,
                altitude: 0.0,
            }; TRAJECTORY_CAPACITY],
            trajectory_len: 0,
        }
    }

    /// Advances the model by one tick.
    pub fn step(&mut self) {
        self.ticks = self.ticks.wrapping_add(1);
        if let Some(w) = self.active_waypoint() {
            self.setpoint = [w.elevator, w.aileron];
            self.altitude_setpoint = w.altitude;
        }
        self.step_altitude();
        self.step_position();
    }

    fn step_altitude(&mut self) {
        self.climb = 0.0;
        match self.landing {
            LandingState::OnGround => self.altitude = 0.0,
            LandingState::Landing => {
                self.climb = -CLIMB_RATE;
                self.altitude += self.climb * DT;
                if self.altitude <= 0.0 {
                    self.altitude = 0.0;
                    self.climb = 0.0;
                    self.landing = LandingState::OnGround;
                }
            }
            LandingState::TakeOff => {
                let target = self.take_off_altitude();
                self.climb = CLIMB_RATE;
                self.altitude += self.climb * DT;
                if self.altitude >= target {
                    self.altitude = target;
                    self.climb = 0.0;
                    self.stabilizing = 0;
                    self.landing = LandingState::Stabilization;
                }
            }
            LandingState::Stabilization => {
                self.stabilizing += 1;
                if self.stabilizing >= STABILIZATION_TICKS {
                    self.landing = LandingState::Flight;
                }
            }
            LandingState::Flight | LandingState::Unknown(_) => {
                if self.controller != Controller::Manual {
                    let error = self.altitude_setpoint - self.altitude;
                    self.climb = (GAIN * error).clamp(-CLIMB_RATE, CLIMB_RATE);
                    self.altitude = (self.altitude + self.climb * DT).max(0.0);
                }
            }
        }
    }

    fn step_position(&mut self) {
        let steering = self.landing == LandingState::Flight && self.controller == Controller::Mpc;
        for axis in 0..2 {
            let speed = if steering {
                (GAIN * (self.setpoint[axis] - self.position[axis])).clamp(-MAX_SPEED, MAX_SPEED)
            } else {
                0.0
            };
            self.acceleration[axis] = (speed - self.speed[axis]) / DT;
            self.speed[axis] = speed;
            self.position[axis] += speed * DT;
        }
    }

    /// The altitude a take-off climbs to: the setpoint, or the cruise altitude if the
    /// setpoint is on the ground.
    fn take_off_altitude(&self) -> f32 {
        if self.altitude_setpoint > 0.0 {
            self.altitude_setpoint
        } else {
            CRUISE_ALTITUDE
        }
    }

    /// The latest waypoint whose time has come.
    fn active_waypoint(&self) -> Option<Waypoint> {
        let now = self.time();
        self.trajectory
            .get(..self.trajectory_len)
            .unwrap_or_default()
            .iter()
            .filter(|w| w.time <= now)
            .max_by_key(|w| w.time)
            .copied()
    }

    /// The altitude, m.
    pub fn altitude(&self) -> f32 {
        self.altitude
    }

    /// The elevator and aileron positions, m.
    pub fn position(&self) -> [f32; 2] {
        self.position
    }

    /// Throttle: hover plus the altitude controller's climb command.
    fn throttle(&self) -> f32 {
        match self.landing {
            LandingState::OnGround => 0.0,
            _ => HOVER_THROTTLE + self.climb,
        }
    }

    /// Tilt that produces a horizontal acceleration, radians (small-angle).
    fn tilt(acceleration: f32) -> f32 {
        acceleration / G
    }
}

impl Vehicle for FlightModel {
    fn landing_state(&self) -> LandingState {
        self.landing
    }

    fn set_landing(&mut self, on: bool) {
        use LandingState::*;
        self.landing = match (on, self.landing) {
            (true, Flight | TakeOff | Stabilization) => Landing,
            (false, Landing | OnGround) => TakeOff,
            (_, state) => state,
        };
    }

    fn controller(&self) -> Controller {
        self.controller
    }

    fn set_controller(&mut self, controller: Controller) {
        if let Controller::Manual | Controller::Altitude | Controller::Mpc = controller {
            self.controller = controller;
        }
    }

    fn time(&self) -> u32 {
        let elapsed = self.ticks.wrapping_sub(self.time_tick) / TICK_HZ;
        self.time_base.wrapping_add(elapsed)
    }

    fn set_time(&mut self, time: u32) {
        self.time_base = time;
        self.time_tick = self.ticks;
    }

    fn set_position(&mut self, elevator: f32, aileron: f32) {
        let new = [elevator, aileron];
        for (axis, &value) in new.iter().enumerate() {
            self.shift[axis] += value - self.position[axis];
        }
        self.position = new;
        self.setpoint = new;
    }

    fn telemetry(&self, id: TelemetryId) -> f32 {
        use TelemetryId::*;
        let [elevator, aileron] = self.position;
        let [elevator_speed, aileron_speed] = self.speed;
        let [elevator_acceleration, aileron_acceleration] = self.acceleration;
        match id {
            EstimatedAltitude | Altitude | BlobAltitude => self.altitude,
            ElevatorSpeed | EstimatedElevatorSpeed => elevator_speed,
            AileronSpeed | EstimatedAileronSpeed => aileron_speed,
            ElevatorPosition | BlobElevator => elevator,
            AileronPosition | BlobAileron => aileron,
            AltitudeControllerOutput | AltitudeSpeed => self.climb,
            ElevatorControllerOutput | OutputElevator => elevator_speed,
            AileronControllerOutput | OutputAileron => aileron_speed,
            AltitudeSetpoint => self.altitude_setpoint,
            ElevatorPositionSetpoint => self.setpoint[0],
            AileronPositionSetpoint => self.setpoint[1],
            ElevatorAcceleration | ElevatorAccelerationInput => elevator_acceleration,
            AileronAcceleration | AileronAccelerationInput => aileron_acceleration,
            ValidBlob => 1.0,
            OutputThrottle => self.throttle(),
            PitchAngle => Self::tilt(elevator_acceleration),
            RollAngle => Self::tilt(aileron_acceleration),
            ElevatorShift => self.shift[0],
            AileronShift => self.shift[1],
            OutputRudder | ElevatorAccelerationError | AileronAccelerationError => 0.0,
            Unknown(_) => 0.0,
        }
    }

    fn set_trajectory(&mut self, waypoints: Waypoints<&[u8]>) {
        self.trajectory_len = 0;
        for (slot, waypoint) in self.trajectory.iter_mut().zip(waypoints.iter()) {
            *slot = waypoint;
            self.trajectory_len += 1;
        }
    }

    fn waypoint(&self, index: usize) -> Option<Waypoint> {
        self.trajectory
            .get(..self.trajectory_len)
            .and_then(|t| t.get(index))
            .copied()
    }
}
