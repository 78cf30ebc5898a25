//! A small flight model behind the MAV state machine.

use mcp_core::mav::Vehicle;
use mcp_core::{Controller, LandingState, MAX_WAYPOINTS, TelemetryId, Waypoint, Waypoints};

/// Altitude the vehicle climbs to after take-off, metres.
pub const CRUISE_ALTITUDE: f32 = 1.0;
/// Descent rate of an autonomous landing, metres per second.
pub const LANDING_RATE: f32 = 0.5;
/// How long the vehicle stabilizes after take-off before it is in flight, seconds.
pub const STABILIZATION_TIME: f32 = 0.5;
/// Altitude below which a landing is over, metres.
const TOUCHDOWN: f32 = 0.02;
/// Largest horizontal acceleration the controllers command, m/s².
const MAX_ACCELERATION: f32 = 2.0;
const GRAVITY: f32 = 9.81;

/// A simulated aircraft: altitude and horizontal positions driven by second-order
/// controllers, the landing state machine and a trajectory followed by time.
///
/// - Landing on in flight (or while taking off): `landing`, descending at
///   [`LANDING_RATE`] until touchdown, then `on_ground`.
/// - Landing off on the ground: `take_off`, climbing to [`CRUISE_ALTITUDE`], then
///   `stabilization` for [`STABILIZATION_TIME`], then `flight`. Landing off while landing
///   aborts the landing: `stabilization`, then `flight`.
/// - Controllers: `manual` holds the position, `altitude` holds altitude and position,
///   `mpc` follows the trajectory (waypoints interpolated by MAV time). Unknown
///   controller ids are refused (the controller stays).
/// - Position set moves the coordinate system: the vehicle is now at the given position,
///   its setpoints move with it.
/// - The MAV time advances with [`SimVehicle::step`].
///
/// ```
/// use mcp_host::mcp_core::{mav::Vehicle, LandingState, TelemetryId};
/// use mcp_host::sim::SimVehicle;
///
/// let mut v = SimVehicle::new(1_700_000_000);
/// assert_eq!(v.landing_state(), LandingState::Flight);
/// v.set_landing(true);
/// assert_eq!(v.landing_state(), LandingState::Landing);
/// for _ in 0..200 {
///     v.step(0.05); // 10 s
/// }
/// assert_eq!(v.landing_state(), LandingState::OnGround);
/// assert_eq!(v.telemetry(TelemetryId::Altitude), 0.0);
/// assert_eq!(v.time(), 1_700_000_010);
/// ```
#[derive(Debug, Clone)]
pub struct SimVehicle {
    state: LandingState,
    controller: Controller,
    /// MAV time at the last time set, POSIX seconds.
    clock_base: u32,
    /// Seconds since the last time set.
    clock_elapsed: f64,
    /// Seconds since start, for the sensor noise.
    age: f32,
    stabilizing: f32,
    altitude: f32,
    altitude_speed: f32,
    altitude_acceleration: f32,
    altitude_setpoint: f32,
    /// Elevator, aileron.
    position: [f32; 2],
    speed: [f32; 2],
    acceleration: [f32; 2],
    setpoint: [f32; 2],
    shift: [f32; 2],
    trajectory: Vec<Waypoint>,
}

impl SimVehicle {
    /// A vehicle in flight at [`CRUISE_ALTITUDE`], at position (0, 0), under the
    /// altitude controller, its clock at `time` (POSIX seconds).
    pub fn new(time: u32) -> Self {
        SimVehicle {
            state: LandingState::Flight,
            controller: Controller::Altitude,
            clock_base: time,
            clock_elapsed: 0.0,
            age: 0.0,
            stabilizing: 0.0,
            altitude: CRUISE_ALTITUDE,
            altitude_speed: 0.0,
            altitude_acceleration: 0.0,
            altitude_setpoint: CRUISE_ALTITUDE,
            position: [0.0; 2],
            speed: [0.0; 2],
            acceleration: [0.0; 2],
            setpoint: [0.0; 2],
            shift: [0.0; 2],
            trajectory: Vec::new(),
        }
    }

    /// Advances the model by `dt` seconds (clamped to 0..=1 s per step).
    pub fn step(&mut self, dt: f32) {
        let dt = dt.clamp(0.0, 1.0);
        self.clock_elapsed += f64::from(dt);
        self.age += dt;
        match self.state {
            LandingState::Landing => {
                self.altitude_setpoint = (self.altitude_setpoint - LANDING_RATE * dt).max(0.0);
                if self.altitude_setpoint <= 0.0 && self.altitude <= TOUCHDOWN {
                    self.state = LandingState::OnGround;
                    self.altitude = 0.0;
                    self.altitude_speed = 0.0;
                    self.altitude_acceleration = 0.0;
                    self.speed = [0.0; 2];
                    self.acceleration = [0.0; 2];
                }
            }
            LandingState::TakeOff => {
                self.altitude_setpoint = CRUISE_ALTITUDE;
                if self.altitude >= 0.8 * CRUISE_ALTITUDE {
                    self.state = LandingState::Stabilization;
                    self.stabilizing = 0.0;
                }
            }
            LandingState::Stabilization => {
                self.altitude_setpoint = CRUISE_ALTITUDE;
                self.stabilizing += dt;
                if self.stabilizing >= STABILIZATION_TIME {
                    self.state = LandingState::Flight;
                }
            }
            LandingState::Flight if self.controller == Controller::Mpc => {
                if let Some(target) = self.trajectory_target() {
                    self.setpoint = [target.elevator, target.aileron];
                    self.altitude_setpoint = target.altitude.max(0.0);
                }
            }
            _ => {}
        }
        if self.state == LandingState::OnGround {
            return;
        }
        // Altitude: a damped spring towards the setpoint.
        let error = self.altitude_setpoint - self.altitude;
        self.altitude_acceleration = 4.0 * error - 3.0 * self.altitude_speed;
        self.altitude_speed += self.altitude_acceleration * dt;
        self.altitude = (self.altitude + self.altitude_speed * dt).max(0.0);
        // Horizontal: the same, bounded; manual control lets the speed decay.
        for axis in 0..2 {
            let accel = match self.controller {
                Controller::Manual => -1.5 * self.speed[axis],
                _ => 2.0 * (self.setpoint[axis] - self.position[axis]) - 2.5 * self.speed[axis],
            };
            let accel = accel.clamp(-MAX_ACCELERATION, MAX_ACCELERATION);
            self.acceleration[axis] = accel;
            self.speed[axis] += accel * dt;
            self.position[axis] += self.speed[axis] * dt;
        }
    }

    /// The trajectory point at the current MAV time: before the first waypoint the
    /// first, after the last the last, in between linearly interpolated.
    fn trajectory_target(&self) -> Option<Waypoint> {
        let first = *self.trajectory.first()?;
        let now = f64::from(self.clock_base) + self.clock_elapsed;
        if now <= f64::from(first.time) {
            return Some(first);
        }
        for pair in self.trajectory.windows(2) {
            let [a, b] = [pair[0], pair[1]];
            let (ta, tb) = (f64::from(a.time), f64::from(b.time));
            if now <= tb {
                let span = tb - ta;
                let k = if span > 0.0 {
                    ((now - ta) / span) as f32
                } else {
                    1.0
                };
                let lerp = |x: f32, y: f32| x + (y - x) * k;
                return Some(Waypoint {
                    time: b.time,
                    elevator: lerp(a.elevator, b.elevator),
                    aileron: lerp(a.aileron, b.aileron),
                    altitude: lerp(a.altitude, b.altitude),
                });
            }
        }
        self.trajectory.last().copied()
    }

    /// Small deterministic sensor noise.
    fn noise(&self, phase: f32) -> f32 {
        0.01 * (self.age * 7.0 + phase).sin()
    }

    fn airborne(&self) -> bool {
        self.state != LandingState::OnGround
    }

    /// The elevator and aileron positions.
    pub fn position(&self) -> [f32; 2] {
        self.position
    }

    /// The altitude, metres.
    pub fn altitude(&self) -> f32 {
        self.altitude
    }
}

impl Vehicle for SimVehicle {
    fn landing_state(&self) -> LandingState {
        self.state
    }

    fn set_landing(&mut self, on: bool) {
        use LandingState::*;
        self.state = match (on, self.state) {
            (true, Flight | TakeOff | Stabilization) => Landing,
            (false, OnGround) => TakeOff,
            (false, Landing) => {
                self.altitude_setpoint = CRUISE_ALTITUDE;
                self.stabilizing = 0.0;
                Stabilization
            }
            (_, state) => state,
        };
    }

    fn controller(&self) -> Controller {
        self.controller
    }

    fn set_controller(&mut self, controller: Controller) {
        if matches!(
            controller,
            Controller::Manual | Controller::Altitude | Controller::Mpc
        ) {
            if controller != Controller::Mpc {
                self.setpoint = self.position;
            }
            self.controller = controller;
        }
    }

    fn time(&self) -> u32 {
        // The tolerance absorbs the rounding of many small steps.
        let elapsed = (self.clock_elapsed + 1e-6).floor() as u32;
        self.clock_base.saturating_add(elapsed)
    }

    fn set_time(&mut self, time: u32) {
        self.clock_base = time;
        self.clock_elapsed = 0.0;
    }

    fn set_position(&mut self, elevator: f32, aileron: f32) {
        let delta = [elevator - self.position[0], aileron - self.position[1]];
        for (axis, d) in delta.into_iter().enumerate() {
            self.position[axis] += d;
            self.setpoint[axis] += d;
            self.shift[axis] += d;
        }
    }

    fn telemetry(&self, id: TelemetryId) -> f32 {
        use TelemetryId as T;
        let [e, a] = self.position;
        let [ve, va] = self.speed;
        let [ae, aa] = self.acceleration;
        let pitch = ae.atan2(GRAVITY).to_degrees();
        let roll = aa.atan2(GRAVITY).to_degrees();
        let throttle = if self.airborne() {
            (0.5 + 0.05 * self.altitude_acceleration).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let blob = self.airborne() && self.altitude > 0.1;
        match id {
            T::EstimatedAltitude => self.altitude + self.noise(0.0),
            T::Altitude => self.altitude,
            T::ElevatorSpeed => ve,
            T::AileronSpeed => va,
            T::EstimatedElevatorSpeed => ve + self.noise(1.0),
            T::EstimatedAileronSpeed => va + self.noise(2.0),
            T::ElevatorPosition => e,
            T::AileronPosition => a,
            T::AltitudeControllerOutput => self.altitude_acceleration,
            T::AltitudeSpeed => self.altitude_speed,
            T::AileronControllerOutput => aa,
            T::ElevatorControllerOutput => ae,
            T::AltitudeSetpoint => self.altitude_setpoint,
            T::ElevatorPositionSetpoint => self.setpoint[0],
            T::AileronPositionSetpoint => self.setpoint[1],
            T::ElevatorAcceleration => ae,
            T::AileronAcceleration => aa,
            T::ValidBlob => f32::from(u8::from(blob)),
            T::OutputThrottle => throttle,
            T::OutputElevator => (pitch / 30.0).clamp(-1.0, 1.0),
            T::OutputAileron => (roll / 30.0).clamp(-1.0, 1.0),
            T::OutputRudder => 0.0,
            T::BlobElevator if blob => e + self.noise(3.0),
            T::BlobAileron if blob => a + self.noise(4.0),
            T::BlobAltitude if blob => self.altitude + self.noise(5.0),
            T::PitchAngle => pitch,
            T::RollAngle => roll,
            T::ElevatorShift => self.shift[0],
            T::AileronShift => self.shift[1],
            T::ElevatorAccelerationInput => ae,
            T::ElevatorAccelerationError => self.noise(6.0),
            T::AileronAccelerationInput => aa,
            T::AileronAccelerationError => self.noise(7.0),
            _ => 0.0,
        }
    }

    fn set_trajectory(&mut self, waypoints: Waypoints<&[u8]>) {
        self.trajectory = waypoints.iter().take(MAX_WAYPOINTS).collect();
    }

    fn waypoint(&self, index: usize) -> Option<Waypoint> {
        self.trajectory.get(index).copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(v: &mut SimVehicle, seconds: f32) {
        for _ in 0..(seconds / 0.05) as usize {
            v.step(0.05);
        }
    }

    #[test]
    fn lands_takes_off_and_stabilizes() {
        let mut v = SimVehicle::new(0);
        v.set_landing(true);
        run(&mut v, 5.0);
        assert_eq!(v.landing_state(), LandingState::OnGround);
        v.set_landing(false);
        let mut seen = vec![v.landing_state()];
        for _ in 0..100 {
            v.step(0.05);
            if seen.last() != Some(&v.landing_state()) {
                seen.push(v.landing_state());
            }
        }
        use LandingState::*;
        assert_eq!(seen, [TakeOff, Stabilization, Flight]);
        assert!((v.altitude() - CRUISE_ALTITUDE).abs() < 0.1);
    }

    #[test]
    fn follows_the_trajectory_under_mpc() {
        let mut v = SimVehicle::new(100);
        v.set_controller(Controller::Mpc);
        let w = |time, elevator| Waypoint {
            time,
            elevator,
            aileron: -elevator,
            altitude: 1.5,
        };
        v.trajectory = vec![w(100, 0.0), w(102, 1.0)];
        run(&mut v, 8.0);
        let [e, a] = v.position();
        assert!((e - 1.0).abs() < 0.05 && (a + 1.0).abs() < 0.05, "{e} {a}");
        assert!((v.altitude() - 1.5).abs() < 0.05);
        v.set_controller(Controller::Unknown(9));
        assert_eq!(v.controller(), Controller::Mpc);
    }

    #[test]
    fn position_set_moves_the_coordinate_system() {
        let mut v = SimVehicle::new(0);
        v.set_position(3.0, -2.0);
        run(&mut v, 2.0);
        let [e, a] = v.position();
        assert!((e - 3.0).abs() < 0.01 && (a + 2.0).abs() < 0.01);
        assert_eq!(v.telemetry(TelemetryId::ElevatorShift), 3.0);
    }
}
