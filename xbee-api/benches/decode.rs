//! Decoder throughput on a ~12 MB mode 2 stream of Receive Packets, each carrying an
//! 8-value MCP telemetry packet, against a plain copy of the same bytes.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use xbee_api::{Address16, Address64, ApiMode, Decoder, EncodeFrame, ReceivePacketRepr};

const STREAM_BYTES: usize = 12 * 1024 * 1024;

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

/// The stream and the number of frames in it.
fn stream() -> (Vec<u8>, usize) {
    let mut rng = Rng(0x005E_ED0F_CAFE);
    let mut out = Vec::with_capacity(STREAM_BYTES + 128);
    let mut frames = 0;
    let mut buf = [0u8; 128];
    while out.len() < STREAM_BYTES {
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
        let n = frame.encode(ApiMode::Escaped, &mut buf).expect("fits");
        out.extend_from_slice(&buf[..n]);
        frames += 1;
    }
    (out, frames)
}

fn decode(c: &mut Criterion) {
    let (stream, frames) = stream();
    let mut group = c.benchmark_group("decode_mode2_telemetry");
    group.throughput(Throughput::Bytes(stream.len() as u64));
    group.sample_size(10);

    group.bench_function("slice", |b| {
        b.iter(|| {
            let mut decoder: Decoder = Decoder::new(ApiMode::Escaped);
            let mut input = &stream[..];
            let mut count = 0usize;
            loop {
                let (consumed, event) = decoder.decode(input);
                input = &input[consumed..];
                match event {
                    Some(Ok(frame)) => count += black_box(frame.data()).len(),
                    Some(Err(e)) => panic!("{e}"),
                    None => break,
                }
            }
            assert_eq!(decoder.stats().frames_ok as usize, frames);
            count
        })
    });

    group.bench_function("byte_at_a_time", |b| {
        b.iter(|| {
            let mut decoder: Decoder = Decoder::new(ApiMode::Escaped);
            let mut count = 0usize;
            for &byte in &stream {
                if let Some(Ok(frame)) = decoder.push(byte) {
                    count += black_box(frame.data()).len();
                }
            }
            assert_eq!(decoder.stats().frames_ok as usize, frames);
            count
        })
    });

    let mut copy = vec![0u8; stream.len()];
    group.bench_function("memcpy_baseline", |b| {
        b.iter(|| {
            copy.copy_from_slice(black_box(&stream));
            black_box(&copy);
        })
    });
    group.finish();
}

criterion_group!(benches, decode);
criterion_main!(benches);
