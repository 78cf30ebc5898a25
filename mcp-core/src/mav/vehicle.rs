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
///
/// A vehicle without position control or trajectories implements the six required
/// methods alone: [`set_position`](Self::set_position),
/// [`set_trajectory`](Self::set_trajectory) and [`set_slave`](Self::set_slave) do
/// nothing by default, and [`waypoint`](Self::waypoint) has none.
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
    /// Sets the MAV position in a new coordinate system. Does nothing by default, for a
    /// vehicle without position control.
    fn set_position(&mut self, elevator: f32, aileron: f32) {
        let _ = (elevator, aileron);
    }
    /// The current value of a telemetry quantity (any id 0-255 may be asked for).
    fn telemetry(&self, id: TelemetryId) -> f32;
    /// Replaces the trajectory with these waypoints (at most 254; the vehicle may
    /// keep fewer if its storage is smaller). Keeps none by default, for a vehicle
    /// that flies no trajectory: its trajectory report, in answer to the set command
    /// and to the status request, is then empty, which tells the ground station that
    /// none was taken.
    fn set_trajectory(&mut self, waypoints: Waypoints<&[u8]>) {
        let _ = waypoints;
    }
    /// The trajectory waypoint at `index`, `None` past the last one. `None` by default
    /// (no trajectory kept): implement it together with
    /// [`set_trajectory`](Self::set_trajectory).
    fn waypoint(&self, index: usize) -> Option<Waypoint> {
        let _ = index;
        None
    }
    /// Sets the slave MAV address of a slot, for coordinate system distribution. The
    /// MAV keeps the four addresses itself; this is for the effect. Does nothing by
    /// default.
    fn set_slave(&mut self, slot: Slot, address: Address) {
        let _ = (slot, address);
    }
}
