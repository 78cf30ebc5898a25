//! Helpers shared by the integration tests (included with `mod common;`).
#![allow(dead_code)]

use xbee_api::{ApiMode, DecodeError, Decoder, DecoderMode, DecoderStats, EncodeFrame};

/// `frame` encoded in `mode`, exactly its `encoded_len` bytes.
pub(crate) fn encode(frame: &impl EncodeFrame, mode: ApiMode) -> Vec<u8> {
    let mut buf = vec![0u8; frame.encoded_len(mode)];
    let n = frame.encode(mode, &mut buf).unwrap();
    assert_eq!(n, buf.len());
    buf
}

/// Reads a file of the repository's `testdata` folder.
pub(crate) fn testdata(name: &str) -> Vec<u8> {
    let path = format!("{}/../testdata/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// One decoded event, owned.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Owned {
    Frame(Vec<u8>),
    Error(DecodeError),
}

/// Decodes `stream` with the slice path, fed in reads of the given sizes (cycled),
/// then finishes.
pub(crate) fn decode_slices<const N: usize>(
    mode: ApiMode,
    stream: &[u8],
    reads: &[usize],
) -> (Vec<Owned>, DecoderStats) {
    decode_slices_with(Decoder::<N>::new(mode), stream, reads)
}

/// [`decode_slices`] with a decoder made by the caller.
pub(crate) fn decode_slices_with<const N: usize, M: DecoderMode>(
    mut decoder: Decoder<N, M>,
    stream: &[u8],
    reads: &[usize],
) -> (Vec<Owned>, DecoderStats) {
    let mut out = Vec::new();
    let mut offset = 0;
    let mut r = 0;
    while offset < stream.len() {
        let size = reads
            .get(r % reads.len().max(1))
            .copied()
            .unwrap_or(1)
            .max(1);
        r += 1;
        let mut input = &stream[offset..(offset + size).min(stream.len())];
        offset += input.len();
        loop {
            let (consumed, event) = decoder.decode(input);
            assert!(consumed <= input.len());
            input = &input[consumed..];
            match event {
                Some(Ok(frame)) => out.push(Owned::Frame(frame.data().to_vec())),
                Some(Err(e)) => out.push(Owned::Error(e)),
                None => break,
            }
        }
        assert!(input.is_empty(), "decode returned None with input left");
    }
    while let Some(event) = decoder.finish() {
        out.push(match event {
            Ok(frame) => Owned::Frame(frame.data().to_vec()),
            Err(e) => Owned::Error(e),
        });
    }
    assert!(decoder.is_idle());
    (out, *decoder.stats())
}

/// Decodes `stream` with [`Decoder::decode_each`], fed in reads of the given sizes
/// (cycled), then finishes.
pub(crate) fn decode_each_slices<const N: usize>(
    mode: ApiMode,
    stream: &[u8],
    reads: &[usize],
) -> (Vec<Owned>, DecoderStats) {
    decode_each_slices_with(Decoder::<N>::new(mode), stream, reads)
}

/// [`decode_each_slices`] with a decoder made by the caller.
pub(crate) fn decode_each_slices_with<const N: usize, M: DecoderMode>(
    mut decoder: Decoder<N, M>,
    stream: &[u8],
    reads: &[usize],
) -> (Vec<Owned>, DecoderStats) {
    let mut out = Vec::new();
    let to_owned = |event: Result<xbee_api::RawFrame<'_>, DecodeError>| match event {
        Ok(frame) => Owned::Frame(frame.data().to_vec()),
        Err(e) => Owned::Error(e),
    };
    let mut offset = 0;
    let mut r = 0;
    while offset < stream.len() {
        let size = reads
            .get(r % reads.len().max(1))
            .copied()
            .unwrap_or(1)
            .max(1);
        r += 1;
        let input = &stream[offset..(offset + size).min(stream.len())];
        offset += input.len();
        decoder.decode_each(input, |event| out.push(to_owned(event)));
    }
    while let Some(event) = decoder.finish() {
        out.push(to_owned(event));
    }
    assert!(decoder.is_idle());
    (out, *decoder.stats())
}

/// Decodes `stream` one byte at a time with `push`/`poll`, then finishes.
pub(crate) fn decode_bytes<const N: usize>(
    mode: ApiMode,
    stream: &[u8],
) -> (Vec<Owned>, DecoderStats) {
    decode_bytes_with(Decoder::<N>::new(mode), stream)
}

/// [`decode_bytes`] with a decoder made by the caller.
pub(crate) fn decode_bytes_with<const N: usize, M: DecoderMode>(
    mut decoder: Decoder<N, M>,
    stream: &[u8],
) -> (Vec<Owned>, DecoderStats) {
    let mut out = Vec::new();
    let to_owned = |event: Result<xbee_api::RawFrame<'_>, DecodeError>| match event {
        Ok(frame) => Owned::Frame(frame.data().to_vec()),
        Err(e) => Owned::Error(e),
    };
    for &byte in stream {
        if let Some(event) = decoder.push(byte) {
            out.push(to_owned(event));
            while let Some(event) = decoder.poll() {
                out.push(to_owned(event));
            }
        }
    }
    while let Some(event) = decoder.finish() {
        out.push(to_owned(event));
    }
    assert!(decoder.is_idle());
    (out, *decoder.stats())
}

/// The frames among `events`.
pub(crate) fn frames(events: &[Owned]) -> Vec<Vec<u8>> {
    events
        .iter()
        .filter_map(|e| match e {
            Owned::Frame(f) => Some(f.clone()),
            Owned::Error(_) => None,
        })
        .collect()
}

/// Parses a hex string with optional spaces.
pub(crate) fn hex(s: &str) -> Vec<u8> {
    let digits: Vec<u8> = s.bytes().filter(|b| !b.is_ascii_whitespace()).collect();
    digits
        .chunks(2)
        .map(|pair| u8::from_str_radix(std::str::from_utf8(pair).unwrap(), 16).unwrap())
        .collect()
}

/// Lowercase hex of bytes.
pub(crate) fn to_hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}
