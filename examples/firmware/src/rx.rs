//! The receive path: UART0 bytes into an [`xbee_api::Inbox`] (the XBee API mode 1
//! decoder and a queue of received MCP payloads), taken by the main loop.
//!
//! The UART0 interrupt drains the RX FIFO into the inbox while its queue has room; the
//! main loop takes the payloads with [`take`] and parses them in place; SysTick gives up
//! a frame a quiet line left unfinished ([`on_tick`]).
//!
//! The shared state is borrowed with `try_borrow_mut`/`try_borrow`, never
//! `borrow_mut`: no borrow outlives its critical section, so they never fail, but only
//! the `try_` forms leave no panic path in the built firmware (`RefCell::borrow_mut`
//! keeps one, `core::cell::panic_already_borrowed`).

use core::cell::{Cell, RefCell};

use critical_section::{CriticalSection, Mutex};
use xbee_api::{
    ApiMode, Decoder, Inbox, InboxStats, Mode1, ReceivePacketRepr, Received, TransmitRequestRepr,
    decoder_buffer_len,
};

use crate::hw;

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

/// The decoder the firmware runs: API mode 1, fixed in its type, so that no mode 2
/// code is linked.
pub type XbeeDecoder = Decoder<DECODER_CAPACITY, Mode1>;

/// The receive path: that decoder and [`QUEUE_LEN`] payloads of up to [`MAX_PAYLOAD`]
/// bytes.
pub type XbeeInbox = Inbox<DECODER_CAPACITY, Mode1, MAX_PAYLOAD, QUEUE_LEN>;

/// One received MCP payload and its sender.
pub type Payload = Received<MAX_PAYLOAD>;

// The decoder's RAM is the goal's: under 300 bytes.
const _: () = assert!(core::mem::size_of::<XbeeDecoder>() < 300);

/// The decoder and the payload queue.
static INBOX: Mutex<RefCell<XbeeInbox>> = Mutex::new(RefCell::new(Inbox::new()));

/// Bytes received with a UART error (framing, parity, break, overrun), dropped.
static UART_ERRORS: Mutex<Cell<u32>> = Mutex::new(Cell::new(0));

/// The UART0 interrupt: drains the RX FIFO through the decoder into the inbox.
///
/// When the inbox is full it stops, leaving the bytes in the RX FIFO, and turns the
/// receive interrupts off until [`take`] makes room: the UART then holds the sender
/// back (in QEMU, where bytes arrive without baud-rate pacing, nothing is lost; on
/// the board, the main loop empties a slot long before the FIFO overruns).
pub fn on_uart0_interrupt() {
    critical_section::with(|cs| {
        if let Ok(mut inbox) = INBOX.borrow(cs).try_borrow_mut() {
            read_fifo(&mut inbox, UART_ERRORS.borrow(cs));
        }
    });
}

/// Feeds the RX FIFO to `inbox` while it has room, counting bytes with errors in
/// `errors`; turns the receive interrupts off when it is full. One copy for the two
/// handlers (44 bytes less than in line in each).
#[inline(never)]
fn read_fifo(inbox: &mut XbeeInbox, errors: &Cell<u32>) {
    let read = inbox.read_from(|| {
        loop {
            match hw::uart0_read()? {
                Ok(byte) => return Some(byte),
                Err(hw::RxError) => errors.set(errors.get().wrapping_add(1)),
            }
        }
    });
    if read.is_err() {
        hw::uart0_rx_interrupts(false);
    }
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

/// On a SysTick tick: a frame in progress at the second tick with no byte between is
/// given up ([`Inbox::tick`]). The RX FIFO is read first: SysTick and UART0 share a
/// priority, and when both are pending SysTick runs first, so bytes that came while
/// UART0 was held off would otherwise be taken for a quiet line.
pub fn on_tick() {
    critical_section::with(|cs| {
        if let Ok(mut inbox) = INBOX.borrow(cs).try_borrow_mut() {
            read_fifo(&mut inbox, UART_ERRORS.borrow(cs));
            inbox.tick();
        }
    });
}

/// `true` if a payload is waiting (for the idle check, inside a critical section).
pub fn is_pending(cs: CriticalSection<'_>) -> bool {
    INBOX
        .borrow(cs)
        .try_borrow()
        .is_ok_and(|inbox| !inbox.is_empty())
}

/// The receive counters: the inbox's, the bytes dropped for UART errors and the
/// decoder's.
pub fn stats() -> (InboxStats, u32, xbee_api::DecoderStats) {
    critical_section::with(|cs| {
        let errors = UART_ERRORS.borrow(cs).get();
        match INBOX.borrow(cs).try_borrow() {
            Ok(inbox) => (inbox.stats(), errors, *inbox.decoder().stats()),
            Err(_) => Default::default(),
        }
    })
}
