//! The benchmark stream: mode 2 Receive Packets, each carrying an 8-value MCP telemetry
//! packet (shared by the criterion bench and the `decode_stream` example).

use xbee_api::{Address16, Address64, ApiMode, EncodeFrame, ReceivePacketRepr};

/// xorshift64*: a small seeded generator, so every run decodes the same stream.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
}

/// A stream of at least `bytes` bytes in `mode`, and the number of frames in it.
pub(crate) fn stream(mode: ApiMode, bytes: usize) -> (Vec<u8>, usize) {
    let mut rng = Rng(0x005E_ED0F_CAFE);
    let mut out = Vec::with_capacity(bytes + 128);
    let mut frames = 0;
    let mut buf = [0u8; 128];
    while out.len() < bytes {
        // MCP telemetry: 't', then 8 x (id u8, f32 little-endian).
        let mut payload = vec![b't'];
        for _ in 0..8 {
            let r = rng.next();
            payload.push(r as u8);
            let value = ((r >> 16) as i32 as f32) / 65536.0;
            payload.extend_from_slice(&value.to_le_bytes());
        }
        let r = rng.next();
        let frame = ReceivePacketRepr {
            src64: Address64(0x0013_A200_0000_0000 | (r & 0xFFFF_FFFF)),
            src16: Address16((r >> 32) as u16),
            options: 0x01,
            data: &payload,
        };
        let n = frame.encode(mode, &mut buf).expect("fits");
        out.extend_from_slice(&buf[..n]);
        frames += 1;
    }
    (out, frames)
}
