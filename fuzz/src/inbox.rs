//! `Inbox`: the same stream through an inbox whose queue the main loop empties on a
//! fuzzer-chosen schedule hands over exactly the payloads of the Receive Packets and
//! Explicit Rx Indicators among the decoder's events, in order: a full queue loses
//! none, and ticks at the end of the stream give up what the line left.

use xbee_api::{
    Decoder, DecoderMode, ExplicitRxIndicator, Inbox, ReceivePacket, frame::frame_type,
};

use crate::events::Event;

/// Largest payload the inbox keeps: smaller than the decoders' capacities, so that
/// payloads too long for it are common.
const PAYLOAD: usize = 64;
/// Payloads the inbox queues: few, so that it is often full.
const QUEUE: usize = 2;

/// The payloads among `expected` (a decoder's events for the whole stream, given up at
/// its end) that an inbox queues, and how many it counts as too long.
fn payloads(expected: &[Event]) -> (Vec<Vec<u8>>, u32) {
    let mut out = Vec::new();
    let mut too_long = 0;
    for event in expected {
        let Event::Frame(data) = event else { continue };
        let payload = match data.first().copied() {
            Some(frame_type::RECEIVE_PACKET) => ReceivePacket::new_checked(data.as_slice())
                .ok()
                .map(|rx| rx.data()),
            Some(frame_type::EXPLICIT_RX_INDICATOR) => {
                ExplicitRxIndicator::new_checked(data.as_slice())
                    .ok()
                    .map(|rx| rx.data())
            }
            _ => None,
        };
        match payload {
            Some(p) if p.len() <= PAYLOAD => out.push(p.to_vec()),
            Some(_) => too_long += 1,
            None => {}
        }
    }
    (out, too_long)
}

/// Feeds `stream` to an inbox around `decoder`, the main loop popping `pops[i] % 3`
/// payloads (at least one when the queue is full) after each read of the FIFO, then
/// ticking at the end until the decoder is idle; checks the payloads against
/// `expected`'s.
pub fn check_inbox<const N: usize, M: DecoderMode>(
    decoder: Decoder<N, M>,
    pops: &[u8],
    stream: &[u8],
    expected: &[Event],
) {
    let mut inbox: Inbox<N, M, PAYLOAD, QUEUE> = Inbox::with_decoder(decoder);
    let mut got = Vec::new();
    let mut bytes = stream.iter().copied().peekable();
    let mut turn = 0usize;
    let mut pop = |inbox: &mut Inbox<N, M, PAYLOAD, QUEUE>, n: usize| {
        for _ in 0..n {
            if let Some(received) = inbox.pop() {
                got.push(received.data().to_vec());
            }
        }
    };
    while bytes.peek().is_some() {
        let full = inbox.read_from(|| bytes.next()).is_err();
        assert_eq!(
            full,
            inbox.is_full(),
            "read_from's result and is_full differ"
        );
        let n = pops
            .get(turn % pops.len().max(1))
            .map_or(1, |&p| usize::from(p % 3));
        turn += 1;
        pop(&mut inbox, if full { n.max(1) } else { n });
    }
    // Every tick gives up at most one candidate and releases at most the stream's
    // bytes as events: the stream's length in ticks is enough.
    for _ in 0..2 * stream.len() + 4 {
        if inbox.decoder().is_idle() && inbox.ready() && inbox.is_empty() {
            break;
        }
        inbox.tick();
        pop(&mut inbox, QUEUE);
    }
    assert!(
        inbox.decoder().is_idle() && inbox.is_empty(),
        "inbox not empty after the line went quiet"
    );
    let (want, too_long) = payloads(expected);
    assert_eq!(got, want, "inbox payloads differ from the decoder's");
    let stats = inbox.stats();
    assert_eq!(stats.queued as usize, want.len(), "inbox payloads counted");
    assert_eq!(stats.too_long, too_long, "inbox payloads counted too long");
}
