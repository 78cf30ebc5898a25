//! Frames over `embedded-io` readers and writers (the `io` module): what is written is
//! what `encode` gives, what is read comes out however the reads fall, and read and
//! write errors are the reader's and writer's, with nothing lost or written after them.

use embedded_io::{ErrorKind, ErrorType, Read, Write};
use proptest::prelude::*;
use xbee_api::io::{
    FrameReader, WriteError, write_encoded, write_encoded_async, write_frame, write_frame_async,
};
use xbee_api::{
    ApiMode, DecodeError, DecodeEvent, DecoderMode, EncodeError, EncodeFrame, Mode1, Mode2,
    RawFrame,
};

/// A UART that hands over at most the next of `sizes` bytes a read (cycling), and fails
/// once, with [`ErrorKind::TimedOut`], where `fail_at` says (before that read).
struct Uart<'a> {
    bytes: &'a [u8],
    sizes: Vec<usize>,
    reads: usize,
    fail_at: Option<usize>,
}

impl<'a> Uart<'a> {
    fn new(bytes: &'a [u8], sizes: &[usize]) -> Self {
        Self {
            bytes,
            sizes: sizes.to_vec(),
            reads: 0,
            fail_at: None,
        }
    }
}

impl ErrorType for Uart<'_> {
    type Error = ErrorKind;
}

impl Read for Uart<'_> {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, ErrorKind> {
        self.reads += 1;
        if self.fail_at.take_if(|at| *at == self.reads).is_some() {
            return Err(ErrorKind::TimedOut);
        }
        let size = self.sizes[self.reads % self.sizes.len()];
        let n = size.min(buf.len()).min(self.bytes.len());
        buf[..n].copy_from_slice(&self.bytes[..n]);
        self.bytes = &self.bytes[n..];
        Ok(n)
    }
}

/// A UART transmitter that takes `room` bytes, at most `step` a write, then fails.
struct Tx {
    sent: Vec<u8>,
    room: usize,
    step: usize,
    flushed: bool,
}

impl ErrorType for Tx {
    type Error = ErrorKind;
}

impl Write for Tx {
    fn write(&mut self, buf: &[u8]) -> Result<usize, ErrorKind> {
        if buf.is_empty() {
            return Ok(0);
        }
        let n = buf.len().min(self.step).min(self.room - self.sent.len());
        if n == 0 {
            return Err(ErrorKind::WriteZero);
        }
        self.sent.extend_from_slice(&buf[..n]);
        Ok(n)
    }

    fn flush(&mut self) -> Result<(), ErrorKind> {
        self.flushed = true;
        Ok(())
    }
}

impl embedded_io_async::Write for Tx {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, ErrorKind> {
        Write::write(self, buf)
    }

    async fn flush(&mut self) -> Result<(), ErrorKind> {
        Write::flush(self)
    }
}

impl embedded_io_async::Read for Uart<'_> {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, ErrorKind> {
        Read::read(self, buf)
    }
}

fn tx(room: usize, step: usize) -> Tx {
    Tx {
        sent: Vec::new(),
        room,
        step,
        flushed: false,
    }
}

/// What a reader's events come to: frame data, or the error.
#[derive(Debug, Clone, PartialEq)]
enum Seen {
    Frame(Vec<u8>),
    Error(DecodeError),
}

fn seen(event: DecodeEvent<'_>) -> Seen {
    match event {
        Ok(frame) => Seen::Frame(frame.data().to_vec()),
        Err(error) => Seen::Error(error),
    }
}

/// Every event of `reader` to the end of its input; read errors are retried.
fn read_all<const N: usize, M: DecoderMode>(
    reader: &mut FrameReader<Uart<'_>, N, M>,
) -> (Vec<Seen>, usize) {
    let mut events = Vec::new();
    let mut errors = 0;
    loop {
        match reader.read_events(|event| events.push(seen(event))) {
            Ok(0) => return (events, errors),
            Ok(_) => {}
            Err(_) => errors += 1,
        }
    }
}

/// How [`read_each`] takes the events.
#[derive(Debug, Clone, Copy)]
enum OneAtATime {
    /// `read_event`.
    Blocking,
    /// `read_event_async`.
    Async,
    /// `read_event` and `read_events` in turn.
    Mixed,
}

/// Every event of `reader` to the end of its input, one a call as `how` says; read
/// errors are retried.
fn read_each<const N: usize, M: DecoderMode>(
    reader: &mut FrameReader<Uart<'_>, N, M>,
    how: OneAtATime,
) -> (Vec<Seen>, usize) {
    let mut events = Vec::new();
    let mut errors = 0;
    for call in 0.. {
        let ended = match how {
            OneAtATime::Mixed if call % 2 == 1 => reader
                .read_events(|event| events.push(seen(event)))
                .map(|n| n == 0),
            OneAtATime::Async => futures::executor::block_on(reader.read_event_async())
                .map(|event| event.map(|e| events.push(seen(e))).is_none()),
            _ => reader
                .read_event()
                .map(|event| event.map(|e| events.push(seen(e))).is_none()),
        };
        match ended {
            Ok(true) => break,
            Ok(false) => {}
            Err(_) => errors += 1,
        }
    }
    (events, errors)
}

fn mode() -> impl Strategy<Value = ApiMode> {
    prop_oneof![Just(ApiMode::Unescaped), Just(ApiMode::Escaped)]
}

proptest! {
    /// Frames written with `write_frame` are the bytes `encode` gives, and read back
    /// whole however the reads split them, a read error in between included.
    #[test]
    fn frames_written_are_read_back(
        frames in prop::collection::vec(prop::collection::vec(any::<u8>(), 1..=100), 1..8),
        mode in mode(),
        sizes in prop::collection::vec(1usize..=40, 1..5),
        step in 1usize..=64,
        fail_at in prop::option::of(1usize..20),
    ) {
        let mut wire = Vec::new();
        for data in &frames {
            let frame = RawFrame::new(data).unwrap();
            let mut out = tx(usize::MAX, step);
            let n = write_frame(&mut out, mode, &frame).unwrap();
            prop_assert!(out.flushed);
            let mut expected = vec![0; frame.encoded_len(mode)];
            frame.encode(mode, &mut expected).unwrap();
            prop_assert_eq!(n, expected.len());
            prop_assert_eq!(&out.sent, &expected);
            wire.extend(out.sent);
        }
        let mut uart = Uart::new(&wire, &sizes);
        uart.fail_at = fail_at;
        let mut reader: FrameReader<_, 128> = FrameReader::new(uart, mode);
        let (events, errors) = read_all(&mut reader);
        let expected: Vec<Seen> = frames.into_iter().map(Seen::Frame).collect();
        prop_assert_eq!(reader.decoder().stats().frames_ok as usize, expected.len());
        prop_assert_eq!(&events, &expected);
        let reads = reader.get_ref().reads;
        prop_assert_eq!(errors, usize::from(fail_at.is_some_and(|at| at <= reads)));

        // A reader whose type fixes the mode reads the same.
        let mut uart = Uart::new(&wire, &sizes);
        uart.fail_at = fail_at;
        let fixed = match mode {
            ApiMode::Unescaped => read_all(&mut FrameReader::<_, 128, Mode1>::fixed(uart)),
            ApiMode::Escaped => read_all(&mut FrameReader::<_, 128, Mode2>::fixed(uart)),
        };
        prop_assert_eq!(&fixed, &(expected.clone(), errors));

        // One event a call, blocking, async or mixed with `read_events`, reads the same:
        // the bytes read past an event wait for the next call.
        for how in [OneAtATime::Blocking, OneAtATime::Async, OneAtATime::Mixed] {
            let mut uart = Uart::new(&wire, &sizes);
            uart.fail_at = fail_at;
            let mut reader: FrameReader<_, 128> = FrameReader::new(uart, mode);
            let got = read_each(&mut reader, how);
            prop_assert_eq!(&got, &fixed, "{:?}", how);
        }
    }

    /// Garbage, damaged frames and frames in any mix, read one event a call or all
    /// events of a read at a time: the same events, as the decoder gives them for the
    /// whole stream at once.
    #[test]
    fn one_event_a_call_is_every_event(
        pieces in prop::collection::vec(
            (prop::collection::vec(any::<u8>(), 1..=40), any::<bool>(), any::<u8>()),
            1..10,
        ),
        mode in mode(),
        sizes in prop::collection::vec(1usize..=40, 1..5),
    ) {
        let mut wire = Vec::new();
        for (data, damaged, noise) in &pieces {
            let frame = RawFrame::new(data).unwrap();
            let mut bytes = vec![0; frame.encoded_len(mode)];
            frame.encode(mode, &mut bytes).unwrap();
            if *damaged {
                // A bad checksum, or a frame cut off by the next one.
                *bytes.last_mut().unwrap() ^= 0x55;
                bytes.truncate(bytes.len() - usize::from(noise % 3));
            }
            wire.extend(bytes);
            wire.push(*noise);
        }
        let mut whole: xbee_api::Decoder<64> = xbee_api::Decoder::new(mode);
        let mut expected = Vec::new();
        whole.decode_each(&wire, |event| expected.push(seen(event)));
        while let Some(event) = whole.finish() {
            expected.push(seen(event));
        }
        let mut reader: FrameReader<_, 64> = FrameReader::new(Uart::new(&wire, &sizes), mode);
        prop_assert_eq!(&read_all(&mut reader).0, &expected);
        for how in [OneAtATime::Blocking, OneAtATime::Async, OneAtATime::Mixed] {
            let mut reader: FrameReader<_, 64> =
                FrameReader::new(Uart::new(&wire, &sizes), mode);
            prop_assert_eq!(&read_each(&mut reader, how).0, &expected, "{:?}", how);
            prop_assert_eq!(reader.decoder().stats(), whole.stats());
        }
    }
}

#[test]
fn a_frame_a_failed_candidate_released_comes_without_another_read() {
    // Mode 1: a candidate of 6 bytes holds a whole frame and fails its checksum; the
    // frame inside it comes out of the rescan, from bytes already read.
    let wire = [0x7E, 0x00, 0x06, 0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F, 0x00];
    for fixed in [false, true] {
        let mut uart = Uart::new(&wire, &[64]);
        // A read now would fail: the frame must come without one.
        uart.fail_at = Some(2);
        let (first, second) = if fixed {
            let mut reader: FrameReader<_, 64, Mode1> = FrameReader::fixed(uart);
            let first = reader.read_event().unwrap().map(seen);
            (first, reader.read_event().unwrap().map(seen))
        } else {
            let mut reader: FrameReader<_, 64> = FrameReader::new(uart, ApiMode::Unescaped);
            let first = reader.read_event().unwrap().map(seen);
            (first, reader.read_event().unwrap().map(seen))
        };
        assert!(
            matches!(first, Some(Seen::Error(DecodeError::BadChecksum { .. }))),
            "{first:?}"
        );
        assert_eq!(second, Some(Seen::Frame(vec![0x8A, 0x06])));
    }
}

#[test]
fn a_frame_given_up_on_a_quiet_line_releases_the_frames_inside_it() {
    // Mode 1: noise that reads as a start delimiter and a length of 64, then two whole
    // frames, in one read; then the line is quiet (a read would fail).
    let status = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];
    let mut wire = vec![0x7E, 0x00, 0x40];
    wire.extend(status);
    wire.extend(status);
    let mut uart = Uart::new(&wire, &[64]);
    uart.fail_at = Some(2);
    let mut reader: FrameReader<_, 128, Mode1> = FrameReader::fixed(uart);
    assert!(
        reader.read_event().is_err(),
        "no frame before the line went quiet"
    );
    let mut events = Vec::new();
    while let Some(event) = reader.drop_partial() {
        events.push(seen(event));
    }
    assert_eq!(
        events,
        [
            Seen::Error(DecodeError::Truncated {
                length: Some(64),
                received: 12
            }),
            Seen::Frame(vec![0x8A, 0x06]),
            Seen::Frame(vec![0x8A, 0x06]),
        ]
    );
    assert!(reader.decoder().is_idle());
    // One frame is given up a sequence of calls: a frame begun among the bytes held
    // is kept for its rest.
    let mut wire = vec![0x7E, 0x00, 0x40];
    wire.extend(status);
    wire.extend(&status[..3]);
    let mut reader: FrameReader<_, 128, Mode1> = FrameReader::fixed(Uart::new(&wire, &[64]));
    reader.read_events(|_| {}).unwrap();
    let mut events = Vec::new();
    while let Some(event) = reader.drop_partial() {
        events.push(seen(event));
    }
    assert_eq!(events.len(), 2, "{events:?}");
    assert_eq!(events[1], Seen::Frame(vec![0x8A, 0x06]));
    assert!(!reader.decoder().is_idle(), "the begun frame is kept");
    // Its rest comes.
    let rest: Vec<u8> = status[3..].to_vec();
    let mut reader = FrameReader::<_, 128, Mode1>::with_decoder(
        Uart::new(&rest, &[64]),
        reader.decoder().clone(),
    );
    assert_eq!(
        reader.read_event().unwrap().map(seen),
        Some(Seen::Frame(vec![0x8A, 0x06]))
    );
    // Bytes read and not decoded yet are decoded first: they may end the frame.
    let mut wire = status.to_vec();
    wire.extend(status);
    let mut reader: FrameReader<_, 64, Mode2> = FrameReader::fixed(Uart::new(&wire, &[64]));
    let first = reader.read_event().unwrap().map(seen);
    assert_eq!(first, Some(Seen::Frame(vec![0x8A, 0x06])));
    assert_eq!(
        reader.drop_partial().map(seen),
        Some(Seen::Frame(vec![0x8A, 0x06]))
    );
    assert_eq!(reader.drop_partial().map(seen), None);
}

#[test]
fn read_events_passes_on_what_read_event_left_before_it_reads() {
    // Two frames in one read; the next read fails.
    let status = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];
    let wire = status.repeat(2);
    let mut uart = Uart::new(&wire, &[64]);
    uart.fail_at = Some(2);
    let mut reader: FrameReader<_, 64, Mode2> = FrameReader::fixed(uart);
    assert!(matches!(reader.read_event(), Ok(Some(Ok(_)))));
    let mut events = Vec::new();
    let read = reader.read_events(|event| events.push(seen(event)));
    assert!(read.is_err(), "the read failed");
    assert_eq!(
        events,
        [Seen::Frame(vec![0x8A, 0x06])],
        "and the frame read before it came"
    );
    assert_eq!(reader.bytes_read(), 12);
}

#[test]
fn a_frame_cut_off_by_the_end_of_input_is_reported_there() {
    let wire = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F, 0x7E, 0x00, 0x05, 0x8A];
    let mut reader: FrameReader<_, 64> = FrameReader::new(Uart::new(&wire, &[3]), ApiMode::Escaped);
    let (events, _) = read_all(&mut reader);
    assert_eq!(
        events,
        [
            Seen::Frame(vec![0x8A, 0x06]),
            Seen::Error(DecodeError::Truncated {
                length: Some(5),
                received: 1
            })
        ]
    );
    assert_eq!(reader.decoder().stats().truncated, 1);
}

#[test]
fn a_write_error_is_the_writers_and_ends_the_frame() {
    // A frame of 80 bytes on the wire, into a transmitter with room for 40.
    let data = [0x41u8; 76];
    let frame = RawFrame::new(&data).unwrap();
    let mut out = tx(40, 7);
    let error = write_frame(&mut out, ApiMode::Unescaped, &frame).unwrap_err();
    assert_eq!(error, WriteError::Io(ErrorKind::WriteZero));
    assert_eq!(error.code(), 0x31);
    assert_eq!(embedded_io::Error::kind(&error), ErrorKind::WriteZero);
    assert_eq!(error.to_string(), "cannot write the frame: WriteZero");
    // The writer's error is in the message, so no source: a report that follows the
    // chain says it once.
    assert!(std::error::Error::source(&error).is_none());
    // The 32-byte chunk that fitted went out, the rest of the frame did not.
    assert_eq!(out.sent.len(), 40);
    assert!(!out.flushed);
}

/// A reply built in place and written, every failure one error: `?` takes the
/// building's [`EncodeError`] as the write's.
fn reply<W: Write>(uart: &mut W, payload: &[u8]) -> Result<usize, WriteError<W::Error>> {
    let mut buf = [0u8; 48];
    let header = xbee_api::TransmitRequestRepr::unicast(xbee_api::Address64::COORDINATOR, &[]);
    let mut frame = xbee_api::InPlaceFrame::new(&mut buf, &header)?;
    let room = frame.data_mut();
    let len = payload.len().min(room.len());
    room[..len].copy_from_slice(&payload[..len]);
    let wire = frame.finish(payload.len(), ApiMode::Escaped)?;
    write_encoded(uart, wire)
}

#[test]
fn building_a_frame_in_place_and_writing_it_fail_as_one_error() {
    let mut out = tx(usize::MAX, 64);
    let n = reply(&mut out, b"r\x02\x01").unwrap();
    assert_eq!(out.sent.len(), n);
    // Too long for the buffer: the building's error, nothing written.
    let mut out = tx(usize::MAX, 64);
    let error = reply(&mut out, &[0x61; 40]).unwrap_err();
    assert!(matches!(error, WriteError::Encode(_)), "{error:?}");
    assert!(out.sent.is_empty());
}

#[test]
fn a_frame_that_cannot_be_encoded_writes_nothing() {
    /// Frame data of no bytes, not even a type byte.
    struct Empty;
    impl EncodeFrame for Empty {
        fn frame_data_len(&self) -> usize {
            0
        }
        fn write_frame_data<F: FnMut(&[u8])>(&self, _: &mut F) {}
    }
    let mut out = tx(usize::MAX, 64);
    let error = write_frame(&mut out, ApiMode::Escaped, &Empty).unwrap_err();
    assert_eq!(error, WriteError::Encode(EncodeError::EmptyFrame));
    assert_eq!(error.code(), EncodeError::EmptyFrame.code());
    assert!(std::error::Error::source(&error).is_none());
    assert_eq!(embedded_io::Error::kind(&error), ErrorKind::InvalidInput);
    assert!(out.sent.is_empty() && !out.flushed);
}

#[test]
fn async_reads_and_writes_match_the_blocking_ones() {
    let data = [0x10, 0x01, 0x7E, 0x7D, 0x11, 0x13, 0x00];
    let frame = RawFrame::new(&data).unwrap();
    for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
        let mut blocking = tx(usize::MAX, 5);
        write_frame(&mut blocking, mode, &frame).unwrap();
        let mut out = tx(usize::MAX, 5);
        let mut buf = [0u8; 32];
        let n = futures::executor::block_on(write_frame_async(&mut out, mode, &frame, &mut buf))
            .unwrap();
        assert_eq!((n, &out.sent), (blocking.sent.len(), &blocking.sent));
        assert!(out.flushed);
        // Too small a buffer: nothing written.
        let mut small = tx(usize::MAX, 5);
        let error = futures::executor::block_on(write_frame_async(
            &mut small,
            mode,
            &frame,
            &mut buf[..n - 1],
        ))
        .unwrap_err();
        assert!(matches!(
            error,
            WriteError::Encode(EncodeError::BufferTooSmall { .. })
        ));
        assert!(small.sent.is_empty());
        // Read back, two bytes a read.
        let mut reader: FrameReader<_, 64> = FrameReader::new(Uart::new(&out.sent, &[2]), mode);
        let mut events = Vec::new();
        while futures::executor::block_on(
            reader.read_events_async(|event| events.push(seen(event))),
        )
        .unwrap()
            > 0
        {}
        assert_eq!(events, [Seen::Frame(data.to_vec())]);
    }
}

/// A transmitter that takes `room` bytes, then takes none (`Ok(0)`) without failing.
struct Full {
    sent: Vec<u8>,
    room: usize,
}

impl ErrorType for Full {
    type Error = ErrorKind;
}

impl Write for Full {
    fn write(&mut self, buf: &[u8]) -> Result<usize, ErrorKind> {
        let n = buf.len().min(self.room - self.sent.len());
        self.sent.extend_from_slice(&buf[..n]);
        Ok(n)
    }

    fn flush(&mut self) -> Result<(), ErrorKind> {
        Ok(())
    }
}

impl embedded_io_async::Write for Full {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, ErrorKind> {
        Write::write(self, buf)
    }

    async fn flush(&mut self) -> Result<(), ErrorKind> {
        Ok(())
    }
}

#[test]
fn a_writer_that_takes_no_byte_is_an_error_not_a_panic() {
    // 80 bytes on the wire into room for 40: 32 go in the first write, 8 in the next.
    let data = [0x41u8; 76];
    let frame = RawFrame::new(&data).unwrap();
    let mut wire = vec![0; frame.encoded_len(ApiMode::Unescaped)];
    frame.encode(ApiMode::Unescaped, &mut wire).unwrap();
    let full = || Full {
        sent: Vec::new(),
        room: 40,
    };
    let expected = WriteError::WriteZero { written: 40 };
    assert_eq!(expected.code(), 0x32);

    let mut out = full();
    assert_eq!(
        write_frame(&mut out, ApiMode::Unescaped, &frame),
        Err(expected)
    );
    assert_eq!(out.sent, wire[..40]);
    let mut out = full();
    assert_eq!(write_encoded(&mut out, &wire), Err(expected));
    let mut out = full();
    let mut buf = [0u8; 128];
    let sent = futures::executor::block_on(write_frame_async(
        &mut out,
        ApiMode::Unescaped,
        &frame,
        &mut buf,
    ));
    assert_eq!(sent, Err(expected));
    let mut out = full();
    let sent = futures::executor::block_on(write_encoded_async(&mut out, &wire));
    assert_eq!(sent, Err(expected));
    assert_eq!(embedded_io::Error::kind(&expected), ErrorKind::WriteZero);
    assert_eq!(
        expected.to_string(),
        "cannot write the frame: the writer took no byte after 40"
    );
}

#[test]
fn bytes_already_encoded_are_written_whole_and_flushed() {
    let data = [0x10, 0x01, 0x7E, 0x7D, 0x11, 0x13, 0x00];
    let frame = RawFrame::new(&data).unwrap();
    let mut wire = vec![0; frame.encoded_len(ApiMode::Escaped)];
    frame.encode(ApiMode::Escaped, &mut wire).unwrap();
    let mut out = tx(usize::MAX, 3);
    assert_eq!(write_encoded(&mut out, &wire), Ok(wire.len()));
    assert_eq!(out.sent, wire);
    assert!(out.flushed);
    let mut out = tx(usize::MAX, 3);
    let sent = futures::executor::block_on(write_encoded_async(&mut out, &wire));
    assert_eq!(sent, Ok(wire.len()));
    assert_eq!(out.sent, wire);
    assert!(out.flushed);
}

#[test]
fn a_reader_says_its_mode() {
    let given: FrameReader<&[u8], 64> = FrameReader::new(&[][..], ApiMode::Escaped);
    let fixed: FrameReader<&[u8], 64, Mode1> = FrameReader::fixed(&[][..]);
    assert_eq!(
        (given.mode(), fixed.mode()),
        (ApiMode::Escaped, ApiMode::Unescaped)
    );
}
