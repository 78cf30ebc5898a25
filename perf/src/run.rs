//! The measured loops, each over a whole stream with a fresh decoder.
//!
//! They are not inlined, so that instruction counters can collect exactly them
//! (`callgrind.sh` toggles collection on `run_*`).

use mcp_core::Packet;
use xbee_api::{
    ApiMode, DEFAULT_CAPACITY, DecodeEvent, Decoder, DecoderMode, Mode1, Mode2, ReceivePacket,
};

use crate::Totals;
use crate::floor::{EscapedSplitter, LengthSplitter};

/// Frame type of a Receive Packet.
const RECEIVE_PACKET: u8 = 0x90;

/// The XBee slice decoder alone ([`Decoder::decode_each`] over the whole stream):
/// frames and frame data bytes.
///
/// # Panics
///
/// On a decode error: the streams hold none.
#[inline(never)]
pub fn run_slice(stream: &[u8], mode: ApiMode) -> Totals {
    let mut decoder: Decoder = Decoder::new(mode);
    let mut totals = Totals::default();
    decoder.decode_each(stream, |event| count(event, &mut totals));
    finish(&mut decoder);
    totals
}

/// [`run_slice`] with one [`Decoder::decode`] call per frame, as a tokio codec does.
///
/// # Panics
///
/// On a decode error: the streams hold none.
#[inline(never)]
pub fn run_slice_calls(stream: &[u8], mode: ApiMode) -> Totals {
    let mut decoder: Decoder = Decoder::new(mode);
    let mut input = stream;
    let mut totals = Totals::default();
    loop {
        let (consumed, event) = decoder.decode(input);
        input = input.get(consumed..).unwrap_or_default();
        match event {
            Some(Ok(frame)) => {
                totals.frames += 1;
                totals.data_bytes += frame.len();
            }
            Some(Err(error)) => panic!("{error}"),
            None => return totals,
        }
    }
}

/// [`run_slice`] with the stream fed in chunks of `chunk` bytes, as a UART FIFO or a DMA
/// buffer with idle-line detection hands them over in an interrupt handler: frames and
/// frame data bytes.
///
/// # Panics
///
/// On a decode error: the streams hold none.
#[inline(never)]
pub fn run_fifo(stream: &[u8], mode: ApiMode, chunk: usize) -> Totals {
    // The mode fixed in the decoder's type, as a firmware that knows its radio's has it.
    match mode {
        ApiMode::Unescaped => fifo_all(
            &mut Decoder::<DEFAULT_CAPACITY, Mode1>::fixed(),
            stream,
            chunk,
        ),
        ApiMode::Escaped => fifo_all(
            &mut Decoder::<DEFAULT_CAPACITY, Mode2>::fixed(),
            stream,
            chunk,
        ),
    }
}

/// The loop of [`run_fifo`].
#[inline(always)]
fn fifo_all<M: DecoderMode>(
    decoder: &mut Decoder<DEFAULT_CAPACITY, M>,
    stream: &[u8],
    chunk: usize,
) -> Totals {
    let mut totals = Totals::default();
    for input in stream.chunks(chunk.max(1)) {
        decoder.decode_each(input, |event| count(event, &mut totals));
    }
    finish(decoder);
    totals
}

/// Counts a frame and its data bytes.
///
/// # Panics
///
/// On a decode error: the streams hold none.
#[inline(always)]
fn count(event: DecodeEvent<'_>, totals: &mut Totals) {
    match event {
        Ok(frame) => {
            totals.frames += 1;
            totals.data_bytes += frame.len();
        }
        Err(error) => panic!("{error}"),
    }
}

/// Ends a stream that holds no partial frame.
fn finish<M: DecoderMode>(decoder: &mut Decoder<DEFAULT_CAPACITY, M>) {
    if let Some(event) = decoder.finish() {
        panic!("stream ends inside a frame: {event:?}");
    }
}

/// The XBee byte-at-a-time decoder alone ([`Decoder::push`], the interrupt path):
/// frames and frame data bytes.
///
/// # Panics
///
/// On a decode error: the streams hold none.
#[inline(never)]
pub fn run_push(stream: &[u8], mode: ApiMode) -> Totals {
    // The mode fixed in the decoder's type, as a firmware that knows its radio's has it.
    match mode {
        ApiMode::Unescaped => push_all(&mut Decoder::<DEFAULT_CAPACITY, Mode1>::fixed(), stream),
        ApiMode::Escaped => push_all(&mut Decoder::<DEFAULT_CAPACITY, Mode2>::fixed(), stream),
    }
}

/// The loop of [`run_push`].
#[inline(always)]
fn push_all<M: DecoderMode>(decoder: &mut Decoder<DEFAULT_CAPACITY, M>, stream: &[u8]) -> Totals {
    let mut totals = Totals::default();
    for &byte in stream {
        match decoder.push(byte) {
            Some(Ok(frame)) => {
                totals.frames += 1;
                totals.data_bytes += frame.len();
            }
            Some(Err(error)) => panic!("{error}"),
            None => {}
        }
    }
    totals
}

/// The floor under [`run_push`]: [`LengthSplitter`] (API mode 1) or [`EscapedSplitter`]
/// (API mode 2), which split the stream into frames by their length field (mode 2:
/// escapes undone) and do nothing else, one call a byte with the same loop around them:
/// frames and frame data bytes.
#[inline(never)]
pub fn run_floor(stream: &[u8], mode: ApiMode) -> Totals {
    match mode {
        ApiMode::Unescaped => {
            let mut splitter: LengthSplitter<512> = LengthSplitter::new();
            split(stream, |byte| splitter.push(byte).map(<[u8]>::len))
        }
        ApiMode::Escaped => {
            let mut splitter: EscapedSplitter<512> = EscapedSplitter::new();
            split(stream, |byte| splitter.push(byte).map(<[u8]>::len))
        }
    }
}

/// The loop of [`run_floor`] around a splitter's `push`, which gives the length of the
/// frame data a byte ends.
#[inline(always)]
fn split(stream: &[u8], mut push: impl FnMut(u8) -> Option<usize>) -> Totals {
    let mut totals = Totals::default();
    for &byte in stream {
        if let Some(len) = push(byte) {
            totals.frames += 1;
            totals.data_bytes += len;
        }
    }
    totals
}

/// Adds the telemetry values of one frame's data to `totals`: a Receive Packet view,
/// its payload parsed as an MCP packet, each telemetry record's value.
#[inline(always)]
fn telemetry(data: &[u8], totals: &mut Totals) {
    totals.frames += 1;
    totals.data_bytes += data.len();
    if data.first() != Some(&RECEIVE_PACKET) {
        return;
    }
    let Ok(rx) = ReceivePacket::new_checked(data) else {
        return;
    };
    if let Ok(Packet::Telemetry(telemetry)) = mcp_core::parse(rx.data()) {
        for record in &telemetry {
            totals.values += 1;
            totals.sum += f64::from(record.value);
        }
    }
}

/// The whole receive path with the slice decoder ([`Decoder::decode_each`]): XBee
/// frames, Receive Packet views, MCP packets, and every telemetry record's `f32` value,
/// summed.
///
/// # Panics
///
/// On a decode error: the streams hold none.
#[inline(never)]
pub fn run_pipeline(stream: &[u8], mode: ApiMode) -> Totals {
    let mut decoder: Decoder = Decoder::new(mode);
    let mut totals = Totals::default();
    decoder.decode_each(stream, |event| match event {
        Ok(frame) => telemetry(frame.data(), &mut totals),
        Err(error) => panic!("{error}"),
    });
    finish(&mut decoder);
    totals
}

/// [`run_pipeline`] with the byte-at-a-time decoder.
///
/// # Panics
///
/// On a decode error: the streams hold none.
#[inline(never)]
pub fn run_pipeline_push(stream: &[u8], mode: ApiMode) -> Totals {
    let mut decoder: Decoder = Decoder::new(mode);
    let mut totals = Totals::default();
    for &byte in stream {
        match decoder.push(byte) {
            Some(Ok(frame)) => telemetry(frame.data(), &mut totals),
            Some(Err(error)) => panic!("{error}"),
            None => {}
        }
    }
    totals
}

/// [`run_pipeline`] under a shorter name, for doc examples.
pub fn pipeline(stream: &[u8], mode: ApiMode) -> Totals {
    run_pipeline(stream, mode)
}
