//! MAVLink v2 ATTITUDE messages: the same class of traffic in another protocol.

use crate::{Rng, Stream, Totals};

/// MAVLink message id of ATTITUDE.
pub const ATTITUDE_ID: u32 = 30;
/// CRC_EXTRA of ATTITUDE (from its field list), folded into every frame's checksum.
pub const ATTITUDE_CRC_EXTRA: u8 = 39;
/// `f32` values in an ATTITUDE message: roll, pitch, yaw and their speeds.
pub const ATTITUDE_VALUES: usize = 6;

/// MAVLink v2 start marker.
const STX: u8 = 0xFD;
/// Header bytes after the start marker: len, incompat and compat flags, seq, sysid,
/// compid, msgid (3 bytes).
const HEADER: usize = 9;
/// ATTITUDE payload: time_boot_ms (u32), then the six `f32`s.
const PAYLOAD: usize = 4 + 4 * ATTITUDE_VALUES;

/// The MAVLink checksum (CRC-16/MCRF4XX, "X.25" in MAVLink's words) of `bytes`,
/// continuing from `crc` (start with 0xFFFF).
///
/// ```
/// assert_eq!(perf::crc_x25(0xFFFF, b"123456789"), 0x6F91);
/// ```
pub fn crc_x25(mut crc: u16, bytes: &[u8]) -> u16 {
    for &b in bytes {
        let mut t = b ^ crc as u8;
        t ^= t << 4;
        let t = u16::from(t);
        crc = (crc >> 8) ^ (t << 8) ^ (t << 3) ^ (t >> 4);
    }
    crc
}

/// A MAVLink v2 stream of ATTITUDE messages (system 1, component 1) carrying at least
/// `values` `f32` values, [`ATTITUDE_VALUES`] a message. Values come from the same
/// generator as [`mcp_stream`](crate::mcp_stream)'s; payloads have their trailing zero
/// bytes cut, as MAVLink v2 senders do.
///
/// ```
/// let s = perf::mavlink_stream(12);
/// assert_eq!((s.totals.frames, s.totals.values), (2, 12));
/// assert_eq!(s.bytes[0], 0xFD);
/// ```
pub fn mavlink_stream(values: usize) -> Stream {
    let frames = values.div_ceil(ATTITUDE_VALUES);
    let mut rng = Rng::new(Rng::SEED);
    let mut out = Vec::with_capacity(frames * (1 + HEADER + PAYLOAD + 2));
    let mut totals = Totals::default();
    for seq in 0..frames {
        let mut payload = [0u8; PAYLOAD];
        let time_boot_ms = (seq as u32).wrapping_mul(20);
        payload[..4].copy_from_slice(&time_boot_ms.to_le_bytes());
        for field in payload[4..].chunks_exact_mut(4) {
            let value = Rng::value(rng.next_u64());
            field.copy_from_slice(&value.to_le_bytes());
            totals.sum += f64::from(value);
        }
        let len = payload.iter().rposition(|&b| b != 0).map_or(1, |i| i + 1);
        let id = ATTITUDE_ID.to_le_bytes();
        let header = [len as u8, 0, 0, seq as u8, 1, 1, id[0], id[1], id[2]];
        let crc = crc_x25(0xFFFF, &header);
        let crc = crc_x25(crc, &payload[..len]);
        let crc = crc_x25(crc, &[ATTITUDE_CRC_EXTRA]);
        out.push(STX);
        out.extend_from_slice(&header);
        out.extend_from_slice(&payload[..len]);
        out.extend_from_slice(&crc.to_le_bytes());
        totals.frames += 1;
        totals.data_bytes += len;
        totals.values += ATTITUDE_VALUES;
    }
    Stream { bytes: out, totals }
}
