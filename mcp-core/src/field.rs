//! Byte positions of packet fields (offsets from the category byte).

use core::ops::Range;

/// A byte range inside a packet.
pub(crate) type Field = Range<usize>;

/// The packet category.
pub(crate) const CATEGORY: usize = 0;
/// The command or report type.
pub(crate) const TYPE: usize = 1;
/// The first byte after the type: on/off, controller, landing state, trajectory size,
/// slot, or the status request marker.
pub(crate) const ARG: usize = 2;
/// A time command or report's `u32`.
pub(crate) const TIME: Field = 2..6;
/// A position set command's aileron position (the elevator position is at 2..6).
pub(crate) const POSITION_AILERON: Field = 6..10;
/// The slave address of a spec-form position slave set command or report.
pub(crate) const SLAVE_ADDRESS: Field = 2..10;
/// The slave address of a firmware-form position slave set command (after the slot).
pub(crate) const SLOT_ADDRESS: Field = 3..11;
/// The four addresses of a firmware-form position slave set report.
pub(crate) const SLAVE_ADDRESSES: Field = 2..34;
/// Where a trajectory packet's waypoints start.
pub(crate) const WAYPOINTS: usize = 3;
/// Where a telemetry packet's records start.
pub(crate) const RECORDS: usize = 1;

/// Byte 3 of a status request.
pub(crate) const STATUS_REQUEST: u8 = 0xFF;

/// Length of a status request other than telemetry-to-coordinator's.
pub(crate) const STATUS_REQUEST_LEN: usize = 3;
/// Length of a telemetry-to-coordinator command, status request or report.
pub(crate) const TTC_LEN: usize = 4;
/// Length of a landing or controllers command or report.
pub(crate) const ONE_BYTE_LEN: usize = 3;
/// Length of a time command or report.
pub(crate) const TIME_LEN: usize = TIME.end;
/// Length of a position set command.
pub(crate) const POSITION_LEN: usize = POSITION_AILERON.end;
/// Length of a spec-form position slave set command or report.
pub(crate) const SLAVE_LEN: usize = SLAVE_ADDRESS.end;
/// Length of a firmware-form position slave set command.
pub(crate) const SLOT_SLAVE_LEN: usize = SLOT_ADDRESS.end;
/// Length of a firmware-form position slave set report.
pub(crate) const SLAVES_LEN: usize = SLAVE_ADDRESSES.end;

/// Fields of one trajectory waypoint (offsets inside the waypoint).
pub(crate) mod waypoint {
    use super::Field;

    /// Time, `u32`.
    pub(crate) const TIME: Field = 0..4;
    /// Elevator position, `f32`.
    pub(crate) const ELEVATOR: Field = 4..8;
    /// Aileron position, `f32`.
    pub(crate) const AILERON: Field = 8..12;
    /// Altitude, `f32`.
    pub(crate) const ALTITUDE: Field = 12..16;
    /// Length of one waypoint.
    pub(crate) const LEN: usize = ALTITUDE.end;
}

/// Fields of one telemetry record (offsets inside the record).
pub(crate) mod record {
    use super::Field;

    /// Value, `f32` (after the one-byte id).
    pub(crate) const VALUE: Field = 1..5;
    /// Length of one record.
    pub(crate) const LEN: usize = VALUE.end;
}
