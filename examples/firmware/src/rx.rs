//! The receive path: UART0 bytes, the XBee API mode 1 decoder, Receive Packet
//! payloads queued for the main loop.
//!
//! The UART0 interrupt drains the RX FIFO into the byte-at-a-time decoder; the
//! [`Inbox`] keeps the MCP payload (RF data) of every Receive Packet (0x90) in a small
//! queue. The main loop takes the payloads with [`take`] and parses
//! them in place.
//!
//! The shared state is borrowed with `try_borrow_mut`/`try_borrow`, never
//! `borrow_mut`: no borrow outlives its critical section, so they never fail, but only
//! the `try_` forms leave no panic path in the built firmware (`RefCell::borrow_mut`
//! keeps one, `core::cell::panic_already_borrowed`).

use core::cell::RefCell;

use critical_section::{CriticalSection, Mutex};
use heapless::{Deque, Vec};
use xbee_api::{
    ApiMode, Decoder, Mode1, RawFrame, ReceivePacket, ReceivePacketRepr, TransmitRequestRepr,
    decoder_buffer_len,
};

use crate::hw::{self, RxError};

/// Largest MCP payload taken: the XBee RF payload limit for unicast without
/// fragmentation. Longer frames are dropped by the decoder as oversize.
pub const MAX_PAYLOAD: usize = TransmitRequestRepr::MAX_UNICAST_DATA;

/// Receive Packet frame data before the payload: type, 64-bit and 16-bit source
/// addresses, options.
pub const RECEIVE_HEADER_LEN: usize = ReceivePacketRepr::HEADER_LEN;

/// Decoder buffer: in API mode 1 it holds the whole frame, delimiter, length and
/// checksum (4 bytes) included: 100 bytes for frame data of 96, exactly a Receive
/// Packet with an 84-byte payload.
pub const DECODER_CAPACITY: usize =
    decoder_buffer_len(RECEIVE_HEADER_LEN + MAX_PAYLOAD, ApiMode::Unescaped);

/// Payloads waiting for the main loop.
pub const QUEUE_LEN: usize = 4;

/// SysTick ticks (50 ms each) a frame in progress may wait for its next byte before it
/// is given up. The radio writes a frame's bytes back to back: a line quiet this long
/// part way through one has lost the rest. In API mode 1 this matters beyond the one
/// frame: a stray 0x7E (noise, a frame cut off) starts a candidate whose length field
/// may reach past the real frames behind it, which would wait until that many more
/// bytes came.
pub const STALE_TICKS: u32 = 2;

/// One received MCP payload.
pub type Payload = Vec<u8, MAX_PAYLOAD>;

/// The decoder the firmware runs: API mode 1, fixed in its type, so that no mode 2
/// code is linked.
pub type XbeeDecoder = Decoder<DECODER_CAPACITY, Mode1>;

/// Counters of the receive path, past the decoder's own.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct RxStats {
    /// Receive Packets queued.
    pub packets: u32,
    /// Valid frames of other types (modem status, AT responses...), ignored.
    pub other_frames: u32,
    /// Receive Packets dropped because the queue was full.
    pub dropped: u32,
    /// Bytes received with a UART error (framing, parity, break, overrun), dropped.
    pub uart_errors: u32,
}

/// The payload queue and the receive counters.
#[derive(Debug)]
pub struct Inbox {
    queue: Deque<Payload, QUEUE_LEN>,
    stats: RxStats,
    /// The decoder may hold events not taken yet (in API mode 1 one byte can end a
    /// failed candidate and release several frames found inside it).
    pending: bool,
    /// The tick at which the last byte came.
    last_byte: u32,
}

impl Default for Inbox {
    fn default() -> Self {
        Self::new()
    }
}

impl Inbox {
    /// An empty inbox.
    pub const fn new() -> Self {
        Inbox {
            queue: Deque::new(),
            stats: RxStats {
                packets: 0,
                other_frames: 0,
                dropped: 0,
                uart_errors: 0,
            },
            pending: false,
            last_byte: 0,
        }
    }

    /// Feeds one byte from the UART to `decoder`, queueing the payload of the Receive
    /// Packet it completes; [`drain`](Self::drain) takes the events it leaves pending.
    /// Call it only after `drain` found room in the queue.
    pub fn push(&mut self, decoder: &mut XbeeDecoder, byte: Result<u8, RxError>) {
        let Ok(byte) = byte else {
            self.stats.uart_errors = self.stats.uart_errors.wrapping_add(1);
            return;
        };
        let event = decoder.push(byte);
        self.pending = event.is_some();
        // Decode errors are counted by the decoder; it resynchronises by itself.
        if let Some(Ok(frame)) = event {
            self.accept(frame);
        }
    }

    /// Takes the decoder's pending events while the queue has room: the others wait in
    /// the decoder (no byte is pushed meanwhile), so that no frame is dropped for want
    /// of a slot.
    pub fn drain(&mut self, decoder: &mut XbeeDecoder) {
        while self.pending && self.has_room() {
            match decoder.poll() {
                Some(Ok(frame)) => self.accept(frame),
                Some(Err(_)) => {}
                None => self.pending = false,
            }
        }
    }

    /// Gives up the frame in progress if no byte came for [`STALE_TICKS`] up to `now`,
    /// as at the end of the input: in API mode 1 the bytes after its start delimiter
    /// are scanned again, and the frames among them are taken as `drain` takes them.
    pub fn give_up_stale(&mut self, decoder: &mut XbeeDecoder, now: u32) {
        let quiet = now.wrapping_sub(self.last_byte) >= STALE_TICKS;
        if !quiet || self.pending || !self.has_room() || decoder.is_idle() {
            return;
        }
        if let Some(Ok(frame)) = decoder.finish() {
            self.accept(frame);
        }
        // The rescan's frames, as many as the queue has room for; the rest wait.
        self.pending = true;
        self.drain(decoder);
    }

    /// Queues the payload of a Receive Packet; counts anything else.
    fn accept(&mut self, frame: RawFrame<'_>) {
        let stats = &mut self.stats;
        let Ok(packet) = ReceivePacket::new_checked(frame.data()) else {
            stats.other_frames = stats.other_frames.wrapping_add(1);
            return;
        };
        // The decoder's capacity bounds the payload to MAX_PAYLOAD bytes.
        let Ok(payload) = Payload::from_slice(packet.data()) else {
            stats.dropped = stats.dropped.wrapping_add(1);
            return;
        };
        if self.queue.push_back(payload).is_err() {
            stats.dropped = stats.dropped.wrapping_add(1);
        } else {
            stats.packets = stats.packets.wrapping_add(1);
        }
    }

    /// The oldest queued payload.
    pub fn pop(&mut self) -> Option<Payload> {
        self.queue.pop_front()
    }

    /// `true` if a payload is queued.
    pub fn is_pending(&self) -> bool {
        !self.queue.is_empty()
    }

    /// `true` if the queue can take another payload.
    pub fn has_room(&self) -> bool {
        !self.queue.is_full()
    }

    /// The receive path's counters.
    pub fn stats(&self) -> RxStats {
        self.stats
    }
}

// The decoder's RAM is the goal's: under 300 bytes.
const _: () = assert!(core::mem::size_of::<XbeeDecoder>() < 300);

/// The decoder, in its own static so that its RAM shows in the symbol table.
static DECODER: Mutex<RefCell<XbeeDecoder>> = Mutex::new(RefCell::new(Decoder::fixed()));

static INBOX: Mutex<RefCell<Inbox>> = Mutex::new(RefCell::new(Inbox::new()));

/// The UART0 interrupt: drains the RX FIFO through the decoder into the inbox.
///
/// When the inbox is full it stops, leaving the bytes in the RX FIFO, and turns the
/// receive interrupts off until [`take`] makes room: the UART then holds the sender
/// back (in QEMU, where bytes arrive without baud-rate pacing, nothing is lost; on
/// the board, the main loop empties a slot long before the FIFO overruns).
pub fn on_uart0_interrupt() {
    critical_section::with(|cs| {
        let Ok(mut decoder) = DECODER.borrow(cs).try_borrow_mut() else {
            return;
        };
        let Ok(mut inbox) = INBOX.borrow(cs).try_borrow_mut() else {
            return;
        };
        // Bytes came (the receive interrupts), or a slot was freed for those held back
        // (`take` raises it, and it runs before the main loop's next tick): the line is
        // not quiet. Once an interrupt, not once a byte.
        inbox.last_byte = crate::clock::ticks();
        loop {
            // Frames the decoder still holds come before new bytes.
            inbox.drain(&mut decoder);
            if !inbox.has_room() {
                break;
            }
            let Some(byte) = hw::uart0_read() else { break };
            inbox.push(&mut decoder, byte);
        }
        if !inbox.has_room() {
            hw::uart0_rx_interrupts(false);
        }
    });
}

/// Takes the oldest received payload, turns the receive interrupts back on and raises
/// the interrupt: the decoder may still hold frames for the slot freed, and no new byte
/// may come to raise it.
pub fn take() -> Option<Payload> {
    critical_section::with(|cs| {
        let payload = INBOX.borrow(cs).try_borrow_mut().ok()?.pop();
        if payload.is_some() {
            hw::uart0_rx_interrupts(true);
            hw::uart0_pend();
        }
        payload
    })
}

/// On a SysTick tick: a frame in progress on a line quiet for [`STALE_TICKS`] is given
/// up ([`Inbox::give_up_stale`]). The time is read here, with the UART interrupt
/// masked, so that the last byte's tick is never later than it (a main loop behind
/// its ticks would otherwise see a byte from the future as one long ago).
pub fn on_tick() {
    critical_section::with(|cs| {
        let Ok(mut decoder) = DECODER.borrow(cs).try_borrow_mut() else {
            return;
        };
        let Ok(mut inbox) = INBOX.borrow(cs).try_borrow_mut() else {
            return;
        };
        inbox.give_up_stale(&mut decoder, crate::clock::ticks());
    });
}

/// `true` if a payload is waiting (for the idle check, inside a critical section).
pub fn is_pending(cs: CriticalSection<'_>) -> bool {
    INBOX
        .borrow(cs)
        .try_borrow()
        .is_ok_and(|inbox| inbox.is_pending())
}

/// The receive counters and the decoder's.
pub fn stats() -> (RxStats, xbee_api::Stats) {
    critical_section::with(|cs| {
        let inbox = INBOX.borrow(cs).try_borrow().map(|inbox| inbox.stats());
        let decoder = DECODER
            .borrow(cs)
            .try_borrow()
            .map(|decoder| *decoder.stats());
        (inbox.unwrap_or_default(), decoder.unwrap_or_default())
    })
}
