//! The `mavlink` crate parsing a MAVLink v2 stream to typed messages (shared by the
//! bench, the callgrind example and the tests).

use mavlink::dialects::common::MavMessage;
use mavlink::{MavlinkReader, MavlinkVersion};
use perf::Totals;

/// Parses every message of `stream` with the `mavlink` crate's blocking reader and
/// sums the `f32` values of the ATTITUDE messages.
#[inline(never)]
pub(crate) fn run_mavlink(stream: &[u8]) -> Totals {
    let mut reader = MavlinkReader::new(stream);
    let mut totals = Totals::default();
    while let Ok((_, message)) = reader.read_message::<MavMessage>(MavlinkVersion::V2) {
        totals.frames += 1;
        if let MavMessage::ATTITUDE(a) = message {
            for value in [
                a.roll,
                a.pitch,
                a.yaw,
                a.rollspeed,
                a.pitchspeed,
                a.yawspeed,
            ] {
                totals.values += 1;
                totals.sum += f64::from(value);
            }
        }
    }
    totals
}
