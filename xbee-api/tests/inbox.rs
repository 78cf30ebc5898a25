//! `Inbox`: the payloads a decoder yields, queued in a fixed queue. Whatever the queue's
//! size and whenever the main loop empties it, the inbox hands over exactly the
//! payloads that a decoder feeding an unbounded list would, in order; a quiet line
//! gives up the frame in progress at the second tick, never while the queue is full.

mod common;

use common::encode;
use proptest::prelude::*;
use xbee_api::{
    Address16, Address64, AnyMode, ApiMode, Decoder, ExplicitRxIndicatorRepr, FixedMode, Inbox,
    InboxFull, InboxStats, Mode1, Mode2, ModemStatus, ModemStatusRepr, ReceivePacket,
    ReceivePacketRepr, Received, ReceivedError, decoder_buffer_len,
};

const PAYLOAD: usize = 84;
const N1: usize = decoder_buffer_len(ReceivePacketRepr::HEADER_LEN + PAYLOAD, ApiMode::Unescaped);
const N2: usize = decoder_buffer_len(ReceivePacketRepr::HEADER_LEN + PAYLOAD, ApiMode::Escaped);

fn receive(src: u64, data: &[u8], mode: ApiMode) -> Vec<u8> {
    encode(
        &ReceivePacketRepr {
            src64: Address64(src),
            src16: Address16(0x1234),
            options: 0x01,
            data,
        },
        mode,
    )
}

/// What a plain decoder fed the whole stream, then given up at its end, yields: the
/// payloads of the Receive Packets of at most `PAYLOAD` bytes, with their senders.
fn reference<const N: usize, M: FixedMode>(stream: &[u8]) -> Vec<(u64, Vec<u8>)> {
    let mut decoder: Decoder<N, M> = Decoder::fixed();
    let mut out = Vec::new();
    let mut take = |event: Option<xbee_api::DecodeEvent<'_>>| {
        let Some(event) = event else { return false };
        if let Ok(frame) = event {
            if let Ok(rx) = ReceivePacket::new_checked(frame.data()) {
                if rx.data().len() <= PAYLOAD {
                    out.push((rx.src64().0, rx.data().to_vec()));
                }
            }
        }
        true
    };
    for &byte in stream {
        let mut more = take(decoder.push(byte));
        while more {
            more = take(decoder.poll());
        }
    }
    while take(decoder.finish()) {}
    out
}

/// The inbox fed `stream` from a FIFO of `fifo` bytes refilled between main-loop turns,
/// the main loop popping `pops[i]` payloads on turn `i` (cycled); at the end of the
/// stream, ticks until the decoder is idle.
fn through_inbox<const N: usize, M: FixedMode, const Q: usize>(
    stream: &[u8],
    pops: &[usize],
) -> (Vec<(u64, Vec<u8>)>, Inbox<N, M, PAYLOAD, Q>) {
    let mut inbox: Inbox<N, M, PAYLOAD, Q> = Inbox::new();
    let mut out = Vec::new();
    let mut bytes = stream.iter().copied().peekable();
    let mut turn = 0;
    let mut pop = |inbox: &mut Inbox<N, M, PAYLOAD, Q>, n: usize| {
        for _ in 0..n {
            if let Some(received) = inbox.pop() {
                out.push((received.src64().0, received.data().to_vec()));
            }
        }
    };
    while bytes.peek().is_some() {
        let full = inbox.read_from(|| bytes.next()).is_err();
        assert_eq!(full, inbox.is_full());
        // The main loop's turn; it must make progress when the queue is full.
        let n = pops[turn % pops.len()];
        turn += 1;
        pop(&mut inbox, if full { n.max(1) } else { n });
    }
    // The line goes quiet: ticks give up what is left, the main loop taking it all.
    for _ in 0..1000 {
        if inbox.decoder().is_idle() && inbox.is_empty() && inbox.ready() {
            break;
        }
        inbox.tick();
        pop(&mut inbox, Q);
    }
    assert!(inbox.decoder().is_idle() && inbox.is_empty());
    (out, inbox)
}

/// A stream of Receive Packets (payloads of 0..=PAYLOAD+4 bytes, escapable bytes
/// likely) and noise (stray delimiters, cut frames, bad checksums).
fn stream(mode: ApiMode) -> impl Strategy<Value = Vec<u8>> {
    let byte = prop_oneof![any::<u8>(), Just(0x7E), Just(0x7D), Just(0x11), Just(0x13)];
    let payload = prop::collection::vec(byte.clone(), 0..=PAYLOAD + 4);
    let piece = prop_oneof![
        6 => (any::<u64>(), payload.clone()).prop_map(move |(src, data)| receive(src, &data, mode)),
        1 => prop::collection::vec(byte, 1..6),
        1 => (any::<u64>(), payload.clone(), any::<prop::sample::Index>()).prop_map(
            move |(src, data, cut)| {
                let wire = receive(src, &data, mode);
                wire[..cut.index(wire.len())].to_vec()
            }
        ),
        1 => (any::<u64>(), payload).prop_map(move |(src, data)| {
            let mut wire = receive(src, &data, mode);
            *wire.last_mut().unwrap() ^= 0x01;
            wire
        }),
    ];
    prop::collection::vec(piece, 0..24).prop_map(|pieces| pieces.concat())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Mode 1, a queue of 1, 2 or 4: the inbox gives exactly the reference's payloads.
    #[test]
    fn mode1_loses_nothing_whatever_the_queue(
        stream in stream(ApiMode::Unescaped),
        pops in prop::collection::vec(0usize..4, 1..8),
    ) {
        let expected = reference::<N1, Mode1>(&stream);
        prop_assert_eq!(&through_inbox::<N1, Mode1, 1>(&stream, &pops).0, &expected);
        prop_assert_eq!(&through_inbox::<N1, Mode1, 2>(&stream, &pops).0, &expected);
        let (got, inbox) = through_inbox::<N1, Mode1, 4>(&stream, &pops);
        prop_assert_eq!(&got, &expected);
        prop_assert_eq!(inbox.stats().queued as usize, expected.len());
    }

    /// Mode 2, the same.
    #[test]
    fn mode2_loses_nothing_whatever_the_queue(
        stream in stream(ApiMode::Escaped),
        pops in prop::collection::vec(0usize..4, 1..8),
    ) {
        let expected = reference::<N2, Mode2>(&stream);
        prop_assert_eq!(&through_inbox::<N2, Mode2, 1>(&stream, &pops).0, &expected);
        let (got, inbox) = through_inbox::<N2, Mode2, 3>(&stream, &pops);
        prop_assert_eq!(&got, &expected);
        prop_assert_eq!(inbox.stats().queued as usize, expected.len());
    }
}

/// The frame `c 02 FF` from 0013A20040522BAA, mode 1.
fn status_request() -> Vec<u8> {
    receive(0x0013A20040522BAA, b"c\x02\xff", ApiMode::Unescaped)
}

type Rx = Inbox<N1, Mode1, PAYLOAD, 2>;

#[test]
fn a_stray_delimiter_holds_frames_until_the_second_quiet_tick() {
    let mut inbox = Rx::new();
    // Noise reading as a delimiter and a length of 64, then a whole frame.
    let mut line = vec![0x7E, 0x00, 0x40];
    line.extend(status_request());
    let mut fifo = line.into_iter();
    inbox.read_from(|| fifo.next()).unwrap();
    assert!(inbox.is_empty());
    inbox.tick();
    assert!(inbox.is_empty(), "given up at the first tick");
    // A byte between the ticks: the line is not quiet.
    inbox.push(0x00).unwrap();
    inbox.tick();
    assert!(inbox.is_empty(), "given up with a byte between the ticks");
    inbox.tick();
    assert_eq!(inbox.len(), 1);
    assert_eq!(inbox.pop().unwrap().data(), b"c\x02\xff");
    assert_eq!(inbox.decoder().stats().truncated, 1);
}

#[test]
fn a_full_queue_takes_no_byte_and_gives_nothing_up() {
    let mut inbox = Rx::new();
    let frame = status_request();
    let mut line = [frame.as_slice(), &frame, &frame].concat();
    let third = line.split_off(2 * frame.len());
    let mut fifo = line.into_iter().chain(third[..5].iter().copied());
    assert_eq!(inbox.read_from(|| fifo.next()), Err(InboxFull));
    assert!(inbox.is_full());
    assert_eq!(inbox.push(0x7E), Err(InboxFull));
    assert_eq!(fifo.clone().count(), 5, "bytes taken while full");
    // The bytes wait in the UART: however long, the frame in progress stays.
    for _ in 0..5 {
        inbox.tick();
    }
    assert!(inbox.decoder().is_idle(), "a frame begun while full");
    inbox.pop().unwrap();
    assert_eq!(inbox.read_from(|| fifo.next()), Ok(()));
    assert!(!inbox.decoder().is_idle());
}

/// Mode 1, a queue of one: a stray delimiter whose length covers two frames, given up
/// at the second quiet tick, has queued the first; the second waits in the decoder.
fn full_with_a_frame_held() -> Inbox<N1, Mode1, PAYLOAD, 1> {
    let mut inbox = Inbox::new();
    let frame = status_request();
    let line = [&[0x7E, 0x00, 0x42][..], &frame, &frame].concat();
    let mut fifo = line.into_iter();
    inbox.read_from(|| fifo.next()).unwrap();
    inbox.tick();
    inbox.tick();
    assert!(inbox.is_full() && !inbox.ready());
    inbox
}

#[test]
fn a_tick_while_full_gives_up_no_frame_the_decoder_holds() {
    // More ticks while the queue is full must not give the held frame up (into a queue
    // with no room).
    let mut inbox = full_with_a_frame_held();
    for _ in 0..3 {
        inbox.tick();
    }
    assert_eq!(inbox.pop().unwrap().data(), b"c\x02\xff");
    // Room: the frame held comes out of the decoder, and fills the queue again.
    assert!(!inbox.ready());
    assert_eq!(inbox.pop().unwrap().data(), b"c\x02\xff");
    assert_eq!(inbox.stats().queued, 2);
    assert_eq!(inbox.decoder().stats().frames_ok, 2);
}

#[test]
fn a_pop_from_a_full_queue_counts_the_quiet_ticks_from_nought() {
    // Mode 1, a queue of one: giving up a stray delimiter queues a frame and leaves the
    // next one begun, its rest in the UART while the queue is full. The pop that makes
    // room starts the count again: the next tick gives nothing up.
    let mut inbox: Inbox<N1, Mode1, PAYLOAD, 1> = Inbox::new();
    let frame = status_request();
    let line = [&[0x7E, 0x00, 0x42][..], &frame, &frame[..5]].concat();
    let mut fifo = line.into_iter();
    inbox.read_from(|| fifo.next()).unwrap();
    inbox.tick();
    inbox.tick();
    assert!(inbox.is_full());
    assert!(!inbox.decoder().is_idle(), "the second frame begun");
    let errors = inbox.decoder().stats().errors(); // the stray delimiter's
    inbox.pop().unwrap();
    inbox.tick();
    assert!(
        !inbox.decoder().is_idle(),
        "given up one tick after the pop"
    );
    let mut rest = frame[5..].iter().copied();
    assert_eq!(inbox.read_from(|| rest.next()), Err(InboxFull));
    assert_eq!(inbox.pop().unwrap().data(), b"c\x02\xff");
    assert_eq!(inbox.decoder().stats().errors(), errors);
}

#[test]
fn popping_a_full_queue_resets_the_quiet_count() {
    let mut inbox = Rx::new();
    let frame = status_request();
    let mut fifo = [frame.as_slice(), &frame, &frame[..7]].concat().into_iter();
    // Two frames fill the queue; the third's first bytes wait in the FIFO.
    assert_eq!(inbox.read_from(|| fifo.next()), Err(InboxFull));
    inbox.tick();
    inbox.tick();
    inbox.pop().unwrap();
    // A tick comes before the interrupt reads the waiting bytes: nothing is given up.
    inbox.tick();
    inbox.read_from(|| fifo.next()).unwrap();
    assert!(!inbox.decoder().is_idle());
    inbox.tick();
    assert!(
        !inbox.decoder().is_idle(),
        "given up one tick after its bytes"
    );
    inbox.tick();
    assert!(inbox.decoder().is_idle());
}

#[test]
fn events_released_by_a_byte_wait_in_the_decoder_for_room() {
    // Mode 1: a stray delimiter whose length covers three frames; giving it up releases
    // them together, into a queue of one.
    let mut inbox: Inbox<N1, Mode1, PAYLOAD, 1> = Inbox::new();
    let frame = status_request();
    let mut line = vec![0x7E, 0x00, 0x50];
    for _ in 0..3 {
        line.extend(&frame);
    }
    let mut fifo = line.into_iter();
    inbox.read_from(|| fifo.next()).unwrap();
    inbox.tick();
    inbox.tick();
    let mut got = 0;
    while let Some(received) = inbox.pop() {
        assert_eq!(received.data(), b"c\x02\xff");
        got += 1;
        // Room: the next frame comes out of the decoder.
        assert_eq!(inbox.ready(), got == 3);
    }
    assert_eq!(got, 3);
    assert_eq!(inbox.stats().queued, 3);
}

#[test]
fn explicit_rx_indicators_other_frames_and_long_payloads() {
    let mode = ApiMode::Escaped;
    let explicit = encode(
        &ExplicitRxIndicatorRepr {
            src64: Address64(0x0013A200400A0127),
            src16: Address16(0xFFFE),
            src_endpoint: 0xE8,
            dst_endpoint: 0xE8,
            cluster_id: 0x0011,
            profile_id: 0xC105,
            options: 0x02,
            data: b"t\x01",
        },
        mode,
    );
    let modem = encode(
        &ModemStatusRepr {
            status: ModemStatus::from(0x06),
        },
        mode,
    );
    let long = receive(7, &[0x55; 9], mode);
    let short = receive(8, &[0x55; 8], mode);
    let mut inbox: Inbox<64, Mode2, 8, 4> = Inbox::new();
    let mut fifo = [explicit, modem, long, short].concat().into_iter();
    inbox.read_from(|| fifo.next()).unwrap();
    assert_eq!(
        inbox.stats(),
        InboxStats {
            queued: 2,
            other_frames: 1,
            too_long: 1,
        }
    );
    let first = inbox.pop().unwrap();
    assert_eq!(
        (first.src64(), first.src16(), first.options(), first.data()),
        (
            Address64(0x0013A200400A0127),
            Address16(0xFFFE),
            0x02,
            &b"t\x01"[..]
        )
    );
    assert_eq!(first.frame_type(), 0x91);
    let second = inbox.pop().unwrap();
    assert_eq!(second.frame_type(), 0x90);
    assert_eq!(
        (second.src64(), second.data()),
        (Address64(8), &[0x55; 8][..])
    );
    assert_eq!(second.src16(), Address16(0x1234));
    assert_eq!(second.options(), 0x01);
}

#[test]
fn an_inbox_with_its_mode_set_at_run_time() {
    let mut inbox: Inbox<N1, AnyMode, PAYLOAD, 2> =
        Inbox::with_decoder(Decoder::new(ApiMode::Escaped));
    assert_eq!(inbox.mode(), ApiMode::Escaped);
    let mut fifo = receive(1, b"t", ApiMode::Escaped).into_iter();
    inbox.read_from(|| fifo.next()).unwrap();
    assert_eq!(inbox.pop().unwrap().data(), b"t");
}

#[test]
fn full_says_what_to_do() {
    assert_eq!(
        InboxFull.to_string(),
        "the inbox is full: pop a payload before taking another byte"
    );
    let inbox = Rx::new();
    let debug = format!("{inbox:?}");
    assert!(
        debug.starts_with("Inbox { decoder: Decoder { mode: Unescaped, capacity: 96")
            && debug.ends_with("queued: 0, pending: false, quiet_ticks: 0, stats: InboxStats { queued: 0, other_frames: 0, too_long: 0 }, .. }"),
        "{debug}"
    );
}

#[test]
fn a_tick_takes_the_pending_events_before_it_gives_up() {
    // Mode 1, a queue of one: a stray delimiter holds two frames and a lone delimiter;
    // the main loop only pops and the timer only ticks (no byte comes to take the
    // events pending).
    let mut inbox: Inbox<N1, Mode1, PAYLOAD, 1> = Inbox::new();
    let frame = status_request();
    let line = [&[0x7E, 0x00, 0x42][..], &frame, &frame, &[0x7E]].concat();
    let mut fifo = line.into_iter();
    inbox.read_from(|| fifo.next()).unwrap();
    let mut got = 0;
    for _ in 0..8 {
        inbox.tick();
        got += usize::from(inbox.pop().is_some());
    }
    assert_eq!(got, 2);
    assert!(inbox.decoder().is_idle(), "{inbox:?}");
    assert_eq!(inbox.decoder().stats().truncated, 2);
}

#[test]
fn reset_drops_the_queue_the_frame_in_progress_and_the_pending_events() {
    let mut inbox = full_with_a_frame_held();
    let frame = status_request();
    inbox.reset();
    assert!(inbox.is_empty() && inbox.ready() && inbox.decoder().is_idle());
    assert_eq!(inbox.stats().queued, 1, "the counters are kept");
    // A new frame comes out alone.
    let mut fifo = frame.into_iter();
    assert_eq!(inbox.read_from(|| fifo.next()), Err(InboxFull)); // a queue of one
    assert_eq!(inbox.pop().unwrap().data(), b"c\x02\xff");
    assert!(inbox.ready() && inbox.pop().is_none());
}

/// `Received::from_frame`, for a firmware that reads frames itself: what an inbox would
/// queue, or why not (a frame of another type, or cut short; a payload too long).
#[test]
fn a_received_payload_from_a_frame_is_what_an_inbox_queues() {
    let mode = ApiMode::Unescaped;
    let frames = [
        receive(7, b"c\x02\x01", mode),
        receive(8, &[0x55; 9], mode),
        encode(
            &ModemStatusRepr {
                status: ModemStatus::from(0x06),
            },
            mode,
        ),
    ];
    let mut decoder: Decoder<64, Mode1> = Decoder::fixed();
    let mut made = Vec::new();
    for wire in &frames {
        let (_, event) = decoder.decode(wire);
        let frame = event.expect("a frame").expect("whole");
        made.push(Received::<8>::from_frame(frame));
    }
    let first = made[0].clone().expect("a Receive Packet");
    assert_eq!(
        (
            first.frame_type(),
            first.src64(),
            first.src16(),
            first.options(),
            first.data()
        ),
        (
            0x90,
            Address64(7),
            Address16(0x1234),
            0x01,
            &b"c\x02\x01"[..]
        )
    );
    assert_eq!(
        made[1],
        Err(ReceivedError::TooLong {
            len: 9,
            capacity: 8
        })
    );
    assert_eq!(
        made[2],
        Err(ReceivedError::NotReceived { frame_type: 0x8A })
    );
    // Cut short of its fixed fields: no Receive Packet.
    let cut = xbee_api::RawFrame::new(&[0x90, 0x00, 0x13]).unwrap();
    assert_eq!(
        Received::<8>::from_frame(cut),
        Err(ReceivedError::NotReceived { frame_type: 0x90 })
    );
    assert_eq!(
        ReceivedError::TooLong {
            len: 9,
            capacity: 8
        }
        .to_string(),
        "a payload of 9 bytes is longer than the 8 a Received holds"
    );
    // The inbox queues the same.
    let mut inbox: Inbox<64, Mode1, 8, 4> = Inbox::new();
    let mut fifo = frames.concat().into_iter();
    inbox.read_from(|| fifo.next()).unwrap();
    assert_eq!(inbox.pop(), Some(first));
    assert_eq!(inbox.pop(), None);
}
