//! MCP telemetry over XBee: the stream the receive path is measured on.

use xbee_api::{Address16, Address64, ApiMode, EncodeFrame, ReceivePacketRepr};

use crate::{Rng, Stream, Totals};

/// Telemetry values in each packet of [`mcp_stream`].
pub const VALUES_PER_PACKET: usize = 8;

/// A stream of at least `bytes` bytes of XBee Receive Packets (0x90) in `mode`, each
/// carrying an MCP telemetry packet: `t`, then [`VALUES_PER_PACKET`] records of
/// (id `u8`, `f32` little-endian), 41 bytes. Frames are 57 bytes in mode 1, about 58
/// in mode 2 (random addresses and values need escapes now and then).
///
/// ```
/// let s = perf::mcp_stream(xbee_api::ApiMode::Unescaped, 1000);
/// assert_eq!(s.totals.frames, 18);
/// assert_eq!(s.bytes.len(), 18 * 57);
/// ```
pub fn mcp_stream(mode: ApiMode, bytes: usize) -> Stream {
    let mut rng = Rng::new(Rng::SEED);
    let mut out = Vec::with_capacity(bytes + 128);
    let mut totals = Totals::default();
    let mut frame = [0u8; 128];
    let mut payload = [0u8; 1 + 5 * VALUES_PER_PACKET];
    payload[0] = b't';
    while out.len() < bytes {
        for record in payload[1..].chunks_exact_mut(5) {
            let r = rng.next_u64();
            let value = Rng::value(r);
            record[0] = r as u8;
            record[1..].copy_from_slice(&value.to_le_bytes());
            totals.sum += f64::from(value);
        }
        let r = rng.next_u64();
        let packet = ReceivePacketRepr {
            src64: Address64(0x0013_A200_0000_0000 | (r & 0xFFFF_FFFF)),
            src16: Address16((r >> 32) as u16),
            options: 0x01,
            data: &payload,
        };
        let n = packet
            .encode(mode, &mut frame)
            .expect("a 53-byte frame fits in 128");
        out.extend_from_slice(&frame[..n]);
        totals.frames += 1;
        totals.data_bytes += packet.frame_data_len();
        totals.values += VALUES_PER_PACKET;
    }
    Stream { bytes: out, totals }
}
