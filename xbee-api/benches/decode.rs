//! Decoder throughput on a ~12 MB mode 2 stream of Receive Packets, each carrying an
//! 8-value MCP telemetry packet, against a plain copy of the same bytes.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use xbee_api::{ApiMode, Decoder};

mod common;

const STREAM_BYTES: usize = 12 * 1024 * 1024;

fn decode(c: &mut Criterion) {
    let (stream, frames) = common::stream(ApiMode::Escaped, STREAM_BYTES);
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
