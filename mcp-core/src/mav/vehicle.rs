//! What the MAV state machine needs from the aircraft.

use crate::{
    Address, Slot, Waypoint, Waypoints,
    id::{Controller, LandingState, TelemetryId},
};

/// The aircraft behind a [`Mav`](super::Mav): its state and the effects of commands.
/// The firmware or a simulator implements it.
///
/// The trajectory is stored by the implementor (the firmware has no heap): the MAV
/// hands it the waypoints of a trajectory set command, and reads them back one by one
/// with [`Vehicle::waypoint`] to build the trajectory report.
pub trait Vehicle {
    /// The current landing state.
    fn landing_state(&self) -> LandingState;
    /// Turns autonomous landing on or off. If the landing state changes, the MAV
    /// reports it through [`Mav::poll_changes`](super::Mav::poll_changes).
    fn set_landing(&mut self, on: bool);
    /// The active controller.
    fn controller(&self) -> Controller;
    /// Switches the active controller (any id; the vehicle may refuse one it does not
    /// have by keeping the current one).
    fn set_controller(&mut self, controller: Controller);
    /// The MAV time, POSIX seconds.
    fn time(&self) -> u32;
    /// Sets the MAV time, POSIX seconds.
    fn set_time(&mut self, time: u32);
    /// Sets the MAV position in a new coordinate system.
    fn set_position(&mut self, elevator: f32, aileron: f32);
    /// The current value of a telemetry quantity (any id 0-255 may be asked for).
    fn telemetry(&self, id: TelemetryId) -> f32;
    /// Replaces the trajectory with these waypoints (at most 254; the vehicle may
    /// keep fewer if its storage is smaller).
    fn set_trajectory(&mut self, waypoints: Waypoints<&[u8]>);
    /// The trajectory waypoint at `index`, `None` past the last one.
    fn waypoint(&self, index: usize) -> Option<Waypoint>;
    /// Sets the slave MAV address of a slot, for coordinate system distribution. The
    /// MAV keeps the four addresses itself; this is for the effect. Does nothing by
    /// default.
    fn set_slave(&mut self, slot: Slot, address: Address) {
        let _ = (slot, address);
    }
}
