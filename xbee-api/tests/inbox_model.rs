//! `Inbox` under any interleaving of its calls (`read_from`, `push` checked with `ready`
//! or not, `pop`, `tick`, `give_up`, `ready`), any queue size, either mode, a limited
//! decoder, payloads too long, Explicit Rx Indicators and other frames: it hands over
//! exactly what a plain decoder fed the same bytes yields when it calls `finish` once
//! where the documented model says the inbox gives a frame up (the second tick with no
//! byte pushed and no pop from a full queue between, the queue not full), in order,
//! with the same counters; and it never gets stuck.

mod common;

use common::encode;
use proptest::prelude::*;
use xbee_api::{
    Address16, Address64, AnyMode, ApiMode, DecodeEvent, Decoder, DecoderMode, ExplicitRxIndicator,
    ExplicitRxIndicatorRepr, Inbox, Mode1, Mode2, ModemStatus, ModemStatusRepr, ReceivePacket,
    ReceivePacketRepr, decoder_buffer_len,
};

/// The inbox's payload size: small, so that payloads too long are common.
const P: usize = 16;
/// A payload handed over: sender's addresses, options, data.
type Item = (u64, u16, u8, Vec<u8>);

/// A piece of the stream: a Receive Packet or an Explicit Rx Indicator (payloads up to
/// `P + 6` bytes), a Modem Status, noise, a stray delimiter with a length, a frame cut.
fn piece(mode: ApiMode) -> impl Strategy<Value = Vec<u8>> {
    let byte = prop_oneof![any::<u8>(), Just(0x7E), Just(0x7D), Just(0x11)];
    let payload = prop::collection::vec(byte.clone(), 0..=P + 6);
    let receive = move |src64: u64, src16: u16, options: u8, data: &[u8]| {
        let frame = ReceivePacketRepr {
            src64: Address64(src64),
            src16: Address16(src16),
            options,
            data,
        };
        encode(&frame, mode)
    };
    let explicit = move |src64: u64, data: &[u8]| {
        let frame = ExplicitRxIndicatorRepr {
            src64: Address64(src64),
            src16: Address16(0xFFFE),
            src_endpoint: 0xE8,
            dst_endpoint: 0xE8,
            cluster_id: 0x11,
            profile_id: 0xC105,
            options: 2,
            data,
        };
        encode(&frame, mode)
    };
    let modem = encode(
        &ModemStatusRepr {
            status: ModemStatus::from(0x06),
        },
        mode,
    );
    prop_oneof![
        4 => (any::<u64>(), any::<u16>(), any::<u8>(), payload.clone())
            .prop_map(move |(src64, src16, options, data)| receive(src64, src16, options, &data)),
        2 => (any::<u64>(), payload.clone()).prop_map(move |(src64, data)| explicit(src64, &data)),
        1 => Just(modem),
        1 => prop::collection::vec(byte, 1..5),
        1 => any::<u8>().prop_map(|len| vec![0x7E, 0x00, len]),
        1 => (any::<u64>(), payload, any::<prop::sample::Index>()).prop_map(
            move |(src64, data, cut)| {
                let wire = receive(src64, 1, 1, &data);
                wire[..cut.index(wire.len())].to_vec()
            }
        ),
    ]
}

/// One call, by the interrupt, the main loop or the timer.
#[derive(Debug, Clone)]
enum Op {
    /// `read_from` a FIFO holding up to this many bytes.
    Read(usize),
    /// `push` of the next byte after `ready` said yes.
    Push,
    /// `push` of the next byte without asking (refused while full).
    PushBlind,
    /// This many `pop`s.
    Pop(usize),
    Tick,
    GiveUp,
    Ready,
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        3 => (1usize..40).prop_map(Op::Read),
        3 => Just(Op::Push),
        1 => Just(Op::PushBlind),
        3 => (0usize..3).prop_map(Op::Pop),
        3 => Just(Op::Tick),
        1 => Just(Op::GiveUp),
        1 => Just(Op::Ready),
    ]
}

/// Takes a plain decoder's event into `out` as the inbox would queue it; `false` for no
/// event.
fn take(out: &mut Vec<Item>, ev: Option<DecodeEvent<'_>>) -> bool {
    let Some(ev) = ev else { return false };
    if let Ok(f) = ev {
        let d = f.data();
        let item = match d.first() {
            Some(0x90) => ReceivePacket::new_checked(d)
                .ok()
                .map(|r| (r.src64().0, r.src16().0, r.options(), r.data().to_vec())),
            Some(0x91) => ExplicitRxIndicator::new_checked(d)
                .ok()
                .map(|r| (r.src64().0, r.src16().0, r.options(), r.data().to_vec())),
            _ => None,
        };
        if let Some(i) = item {
            if i.3.len() <= P {
                out.push(i)
            }
        }
    }
    true
}

/// Runs `ops` over and over until the stream is fed (the main loop popping when the queue
/// is full), then ticks and pops until the inbox is idle; compares with the reference.
fn run<const N: usize, M: DecoderMode, const Q: usize>(
    mk: impl Fn() -> Decoder<N, M>,
    stream: &[u8],
    ops: &[Op],
) -> Result<(), TestCaseError> {
    let mut inbox: Inbox<N, M, P, Q> = Inbox::with_decoder(mk());
    let mut reference = mk();
    let mut expected = Vec::new();
    let mut got: Vec<Item> = Vec::new();
    let mut quiet = 0u32; // the documented model
    let mut i = 0;
    let feed_ref = |reference: &mut Decoder<N, M>, expected: &mut Vec<Item>, b: u8| {
        let mut more = take(expected, reference.push(b));
        while more {
            more = take(expected, reference.poll());
        }
    };
    let give_up = |inbox: &mut Inbox<N, M, P, Q>,
                   reference: &mut Decoder<N, M>,
                   expected: &mut Vec<Item>,
                   via_tick: bool| {
        let eff = inbox.ready() && !inbox.decoder().is_idle();
        if via_tick {
            inbox.tick()
        } else {
            inbox.give_up()
        }
        if eff {
            let mut more = take(expected, reference.finish());
            while more {
                more = take(expected, reference.poll());
            }
        }
    };
    let pop = |inbox: &mut Inbox<N, M, P, Q>, got: &mut Vec<Item>, quiet: &mut u32| {
        let was_full = inbox.is_full();
        // What `peek` and `iter` show is what `pop` then takes, in its order.
        let peeked = inbox.peek().cloned();
        let queued: Vec<_> = inbox.iter().cloned().collect();
        assert_eq!(queued.len(), inbox.len());
        assert_eq!(queued.first(), peeked.as_ref());
        assert_eq!(inbox.iter().next_back(), queued.last());
        let popped = inbox.pop();
        assert_eq!(popped, peeked);
        assert!(inbox.iter().eq(&queued[queued.len().min(1)..]));
        if let Some(r) = popped {
            if was_full {
                *quiet = 0
            }
            got.push((r.src64().0, r.src16().0, r.options(), r.data().to_vec()));
        }
    };
    let mut turns = 0usize;
    let mut ops = ops.to_vec();
    ops.push(Op::Read(1));
    loop {
        for o in &ops {
            match o {
                Op::Read(k) => {
                    let mut n = 0;
                    let mut taken = Vec::new();
                    let r = inbox.read_from(|| {
                        if n < *k && i < stream.len() {
                            n += 1;
                            i += 1;
                            taken.push(stream[i - 1]);
                            Some(stream[i - 1])
                        } else {
                            None
                        }
                    });
                    if !taken.is_empty() {
                        quiet = 0
                    }
                    for b in taken {
                        feed_ref(&mut reference, &mut expected, b)
                    }
                    prop_assert_eq!(r.is_err(), inbox.is_full());
                }
                Op::Push | Op::PushBlind => {
                    if i < stream.len() && (matches!(o, Op::PushBlind) || inbox.ready()) {
                        if inbox.push(stream[i]).is_ok() {
                            quiet = 0;
                            feed_ref(&mut reference, &mut expected, stream[i]);
                            i += 1;
                        } else {
                            prop_assert!(inbox.is_full());
                        }
                    }
                }
                Op::Pop(n) => {
                    for _ in 0..*n {
                        pop(&mut inbox, &mut got, &mut quiet)
                    }
                }
                Op::Tick => {
                    quiet += 1;
                    if quiet >= 2 {
                        give_up(&mut inbox, &mut reference, &mut expected, true)
                    } else {
                        let before = inbox.decoder().stats().truncated;
                        inbox.tick();
                        prop_assert_eq!(
                            before,
                            inbox.decoder().stats().truncated,
                            "gave up at first tick"
                        );
                    }
                }
                Op::GiveUp => give_up(&mut inbox, &mut reference, &mut expected, false),
                Op::Ready => {
                    inbox.ready();
                }
            }
        }
        turns += 1;
        if i >= stream.len() || turns > 10_000 {
            break;
        }
        // main loop must pop something eventually when full
        if inbox.is_full() {
            pop(&mut inbox, &mut got, &mut quiet)
        }
    }
    prop_assert!(i >= stream.len(), "stuck feeding");
    // quiet line at end
    for _ in 0..10_000 {
        if inbox.decoder().is_idle() && inbox.is_empty() && inbox.ready() {
            break;
        }
        quiet += 1;
        if quiet >= 2 {
            give_up(&mut inbox, &mut reference, &mut expected, true)
        } else {
            inbox.tick()
        }
        for _ in 0..Q {
            pop(&mut inbox, &mut got, &mut quiet)
        }
    }
    prop_assert!(
        inbox.decoder().is_idle() && inbox.is_empty(),
        "stuck: {:?}",
        inbox
    );
    while take(&mut expected, reference.finish()) {}
    prop_assert_eq!(&got, &expected);
    prop_assert_eq!(inbox.stats().queued as usize, got.len());
    let s = inbox.stats();
    prop_assert_eq!(
        s.queued + s.other_frames + s.too_long,
        inbox.decoder().stats().frames_ok
    );
    prop_assert_eq!(inbox.decoder().stats(), reference.stats());
    Ok(())
}

const N1: usize = decoder_buffer_len(18 + P + 4, ApiMode::Unescaped);
const N2: usize = decoder_buffer_len(18 + P + 4, ApiMode::Escaped);

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    #[test]
    fn mode1(pieces in prop::collection::vec(piece(ApiMode::Unescaped), 0..20), ops in prop::collection::vec(op(), 1..12)) {
        let s = pieces.concat();
        run::<N1, Mode1, 1>(Decoder::fixed, &s, &ops)?;
        run::<N1, Mode1, 2>(Decoder::fixed, &s, &ops)?;
        run::<N1, Mode1, 3>(|| Decoder::fixed_with_max_len(20), &s, &ops)?;
        run::<N1, AnyMode, 2>(|| Decoder::new(ApiMode::Unescaped), &s, &ops)?;
    }
    #[test]
    fn mode2(pieces in prop::collection::vec(piece(ApiMode::Escaped), 0..20), ops in prop::collection::vec(op(), 1..12)) {
        let s = pieces.concat();
        run::<N2, Mode2, 1>(Decoder::fixed, &s, &ops)?;
        run::<N2, Mode2, 3>(|| Decoder::fixed_with_max_len(20), &s, &ops)?;
    }
}
