//! A small flight model behind [`mcp_core::mav::Mav`]: the landing state machine, the
//! controller, the MAV clock, a 5-waypoint trajectory and the altitude, stepped at
//! [`TICK_HZ`].

use mcp_core::mav::Vehicle;
use mcp_core::{Controller, LandingState, TelemetryId, Waypoint, Waypoints};

/// The model step and telemetry rate.
pub const TICK_HZ: u32 = 20;
/// Waypoints kept: 5 fill an 84-byte trajectory report (3 + 5 * 16 = 83 bytes).
pub const TRAJECTORY_CAPACITY: usize = 5;
/// Climb and descent rate, metres a tick (0.5 m/s).
const CLIMB_PER_TICK: f32 = 0.5 / TICK_HZ as f32;
/// Altitude of a take-off, m.
const CRUISE_ALTITUDE: f32 = 1.0;
/// Ticks spent in `Stabilization` after a take-off: one second.
const STABILIZATION_TICKS: u32 = TICK_HZ;

/// What a firmware's aircraft does besides answering the MAV state machine: one step of
/// its model, on each tick.
pub trait Model: Vehicle {
    /// Advances the model one tick.
    fn step(&mut self);
}

/// The aircraft.
#[derive(Debug, Clone)]
pub struct FlightModel {
    landing: LandingState,
    controller: Controller,
    ticks: u32,
    stable_ticks: u32,
    time_base: u32,
    time_tick: u32,
    altitude: f32,
    position: [f32; 2],
    trajectory: [Waypoint; TRAJECTORY_CAPACITY],
    waypoints: usize,
}

impl Default for FlightModel {
    fn default() -> Self {
        Self::new()
    }
}

const NO_WAYPOINT: Waypoint = Waypoint {
    time: 0,
    elevator: 0.0,
    aileron: 0.0,
    altitude: 0.0,
};

impl FlightModel {
    /// On the ground, manual control, time 0.
    pub const fn new() -> Self {
        FlightModel {
            landing: LandingState::OnGround,
            controller: Controller::Manual,
            ticks: 0,
            stable_ticks: 0,
            time_base: 0,
            time_tick: 0,
            altitude: 0.0,
            position: [0.0; 2],
            trajectory: [NO_WAYPOINT; TRAJECTORY_CAPACITY],
            waypoints: 0,
        }
    }

    /// The altitude, m.
    pub fn altitude(&self) -> f32 {
        self.altitude
    }
}

impl Model for FlightModel {
    fn step(&mut self) {
        self.ticks = self.ticks.wrapping_add(1);
        match self.landing {
            LandingState::Landing => {
                self.altitude = (self.altitude - CLIMB_PER_TICK).max(0.0);
                if self.altitude <= 0.0 {
                    self.landing = LandingState::OnGround;
                }
            }
            LandingState::TakeOff => {
                self.altitude = (self.altitude + CLIMB_PER_TICK).min(CRUISE_ALTITUDE);
                if self.altitude >= CRUISE_ALTITUDE {
                    self.landing = LandingState::Stabilization;
                    self.stable_ticks = 0;
                }
            }
            LandingState::Stabilization => {
                self.stable_ticks += 1;
                if self.stable_ticks >= STABILIZATION_TICKS {
                    self.landing = LandingState::Flight;
                }
            }
            _ => {}
        }
    }
}

impl Vehicle for FlightModel {
    fn landing_state(&self) -> LandingState {
        self.landing
    }

    fn set_landing(&mut self, on: bool) {
        self.landing = match (on, self.landing) {
            (true, LandingState::OnGround) => LandingState::OnGround,
            (true, _) => LandingState::Landing,
            (false, LandingState::Landing | LandingState::OnGround) => LandingState::TakeOff,
            (false, state) => state,
        };
    }

    fn controller(&self) -> Controller {
        self.controller
    }

    fn set_controller(&mut self, controller: Controller) {
        if !matches!(controller, Controller::Unknown(_)) {
            self.controller = controller;
        }
    }

    fn time(&self) -> u32 {
        let seconds = self.ticks.wrapping_sub(self.time_tick) / TICK_HZ;
        self.time_base.wrapping_add(seconds)
    }

    fn set_time(&mut self, time: u32) {
        self.time_base = time;
        self.time_tick = self.ticks;
    }

    fn set_position(&mut self, elevator: f32, aileron: f32) {
        self.position = [elevator, aileron];
    }

    fn telemetry(&self, id: TelemetryId) -> f32 {
        match id {
            TelemetryId::Altitude => self.altitude,
            _ => 0.0,
        }
    }

    fn set_trajectory(&mut self, waypoints: Waypoints<&[u8]>) {
        self.waypoints = 0;
        for (slot, waypoint) in self.trajectory.iter_mut().zip(waypoints.iter()) {
            *slot = waypoint;
            self.waypoints += 1;
        }
    }

    fn waypoint(&self, index: usize) -> Option<Waypoint> {
        self.trajectory.get(..self.waypoints)?.get(index).copied()
    }
}
