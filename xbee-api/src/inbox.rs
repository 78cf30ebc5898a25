//! A firmware's receive path in one value: the decoder and a fixed queue of the
//! payloads it received.

use core::fmt;

use heapless::{Deque, Vec};

use crate::{
    Address16, Address64, ApiMode, Decoder, DecoderMode, ExplicitRxIndicator, FixedMode, RawFrame,
    ReceivePacket, frame::frame_type,
};

/// Ticks of [`Inbox::tick`] with no byte between them after which a frame in progress
/// is given up: with two, the line was quiet for at least one whole period.
const QUIET_TICKS: u8 = 2;

/// The receive path of a firmware: a [`Decoder`] fed from the UART and a queue of up
/// to `Q` received payloads of up to `P` bytes each, waiting for the main loop, with
/// the rules that make a full queue lose nothing.
///
/// `N` and `M` are the decoder's buffer and mode ([`Decoder<N, M>`]): size `N` with
/// [`decoder_buffer_len`](crate::decoder_buffer_len) for the longest frame taken.
///
/// - **A full queue drops no frame.** Events are taken from the decoder only while the
///   queue has room: when it is full, [`ready`](Self::ready) is `false`, the events the
///   decoder still holds wait there (in API mode 1 one byte can release several frames)
///   and no byte is to be taken off the UART. [`read_from`](Self::read_from) follows
///   these rules; so does a loop of `ready` and [`push`](Self::push). The receive
///   interrupt masks itself when `read_from` says the queue is full; the main loop,
///   once [`pop`](Self::pop) made room, unmasks it and raises it (the decoder may hold
///   frames for the slot freed, and no byte may come to raise it). Meanwhile the bytes
///   wait in the UART's FIFO: with hardware flow control (the radio's `D6=1`, its RTS
///   wired) the radio then holds back; without it, a main loop slower to pop than the
///   FIFO takes to fill (16 bytes: 1.4 ms at 115200 baud) loses bytes in the UART.
/// - **A quiet line gives up the frame in progress.** In API mode 1 a stray 0x7E
///   (noise, a frame cut off) starts a candidate whose length field may reach past the
///   real frames behind it; they would wait until that many more bytes came. Call
///   [`tick`](Self::tick) from a periodic timer: a frame in progress at the second tick
///   with no byte pushed between is given up, its bytes scanned again
///   ([`Decoder::finish`]). Never while the queue is full: bytes wait in the UART
///   then. Only bytes pushed count, so the timer reads the FIFO first (`read_from`,
///   then `tick`), lest bytes that came while the receive interrupt was held off (by a
///   critical section, or by the timer's own interrupt at the same priority) be taken
///   for a quiet line. Harmless in mode 2, where the next start delimiter ends a
///   cut-off frame.
/// - **What is queued.** The RF data of each Receive Packet (0x90) and, for radios
///   set to `AO=1`, Explicit Rx Indicator (0x91), with its source addresses and
///   receive options ([`Received`]). Other valid frames (modem status, AT command
///   responses, and a 0x90 or 0x91 too short for its header) are counted in
///   [`InboxStats::other_frames`], payloads longer than `P` in
///   [`InboxStats::too_long`], bad frames in the decoder's [`stats`](Decoder::stats).
///
/// Its RAM is the decoder's plus `Q` times about `P + 16` bytes. `const` to build, so it
/// can live in a `static` shared by the interrupt handlers and the main loop:
///
/// ```no_run
/// use core::cell::RefCell;
/// use critical_section::Mutex;
/// use xbee_api::{ApiMode, Inbox, Mode2, ReceivePacketRepr, Received, decoder_buffer_len};
///
/// const PAYLOAD: usize = 84;
/// const N: usize = decoder_buffer_len(ReceivePacketRepr::HEADER_LEN + PAYLOAD, ApiMode::Escaped);
/// static INBOX: Mutex<RefCell<Inbox<N, Mode2, PAYLOAD, 4>>> = Mutex::new(RefCell::new(Inbox::new()));
///
/// # fn uart_read() -> Option<u8> { None }
/// # fn uart_rx_interrupt(_on: bool) {}
/// # fn uart_rx_pend() {}
/// # fn wfi() {}
/// /// The UART's receive interrupt: its FIFO while the queue has room.
/// fn on_uart_rx() {
///     critical_section::with(|cs| {
///         let Ok(mut inbox) = INBOX.borrow(cs).try_borrow_mut() else { return };
///         if inbox.read_from(uart_read).is_err() {
///             uart_rx_interrupt(false); // full: the bytes wait in the FIFO
///         }
///     });
/// }
///
/// /// A periodic timer (every 50 ms, say): the FIFO first, then the tick.
/// fn on_timer() {
///     critical_section::with(|cs| {
///         let Ok(mut inbox) = INBOX.borrow(cs).try_borrow_mut() else { return };
///         if inbox.read_from(uart_read).is_err() {
///             uart_rx_interrupt(false);
///         }
///         inbox.tick();
///     });
/// }
///
/// /// The main loop's next payload (an MCP packet in `data()`).
/// fn take() -> Option<Received<PAYLOAD>> {
///     critical_section::with(|cs| {
///         let received = INBOX.borrow(cs).try_borrow_mut().ok()?.pop()?;
///         // Room: the interrupt takes the events the decoder holds and the bytes waiting.
///         uart_rx_interrupt(true);
///         uart_rx_pend();
///         Some(received)
///     })
/// }
///
/// /// The main loop's sleep once it has taken every payload: the queue is looked at
/// /// with interrupts masked, so that a frame queued after the look still wakes the
/// /// core (`wfi`, `cortex_m::asm::wfi` on a Cortex-M, wakes on an interrupt pending
/// /// while masked, which runs when the critical section ends). Looked at before the
/// /// critical section instead, a frame queued between the look and `wfi` would wait
/// /// for the next interrupt: the timer's, or none.
/// fn sleep_if_idle() {
///     critical_section::with(|cs| {
///         if INBOX.borrow(cs).try_borrow().is_ok_and(|inbox| inbox.is_empty()) {
///             wfi();
///         }
///     });
/// }
/// ```
///
/// The same steps, with the UART's FIFO an iterator:
///
/// ```
/// use xbee_api::{Address64, ApiMode, Inbox, Mode1, ReceivePacketRepr, decoder_buffer_len};
///
/// const PAYLOAD: usize = 84; // `TransmitRequestRepr::MAX_UNICAST_DATA`
/// const N: usize = decoder_buffer_len(ReceivePacketRepr::HEADER_LEN + PAYLOAD, ApiMode::Unescaped);
/// // In a firmware: `static INBOX: Mutex<RefCell<Rx>>`, shared with the UART interrupt.
/// type Rx = Inbox<N, Mode1, PAYLOAD, 2>;
/// let mut inbox = Rx::new();
///
/// // Three Receive Packets from 0013A20040522BAA holding `c 02 FF`, in the UART's FIFO.
/// let frame = [
///     0x7E, 0x00, 0x0F, 0x90, 0x00, 0x13, 0xA2, 0x00, 0x40, 0x52, 0x2B, 0xAA, 0xFF, 0xFE,
///     0x01, 0x63, 0x02, 0xFF, 0xF1,
/// ];
/// let mut fifo = frame.iter().chain(&frame).chain(&frame).copied();
///
/// // The receive interrupt: bytes while the queue has room.
/// if inbox.read_from(|| fifo.next()).is_err() {
///     // Full: mask the receive interrupt until the main loop makes room.
/// }
/// assert_eq!(inbox.len(), 2); // the third frame waits in the FIFO
///
/// // The main loop: the payloads, each an MCP packet (`mcp_core::parse`).
/// let first = inbox.pop().unwrap();
/// assert_eq!(first.data(), b"c\x02\xff");
/// assert_eq!(first.src64(), Address64(0x0013A20040522BAA));
/// inbox.pop();
/// // Room again: unmask and raise the receive interrupt, which reads the rest.
/// assert_eq!(inbox.read_from(|| fifo.next()), Ok(()));
/// assert_eq!(inbox.len(), 1);
/// assert_eq!(inbox.stats().queued, 3);
///
/// // A frame cut off, then two timer ticks with no byte between: it is given up.
/// let mut cut = frame[..6].iter().copied();
/// inbox.read_from(|| cut.next()).unwrap();
/// inbox.tick();
/// assert!(!inbox.decoder().is_idle()); // one tick: its rest may be on the way
/// inbox.tick();
/// assert!(inbox.decoder().is_idle());
/// assert_eq!(inbox.decoder().stats().truncated, 1);
/// ```
#[derive(Clone)]
pub struct Inbox<const N: usize, M: DecoderMode, const P: usize, const Q: usize> {
    decoder: Decoder<N, M>,
    queue: Deque<Received<P>, Q>,
    /// The decoder may hold events not taken yet.
    pending: bool,
    /// Ticks since the last byte, up to [`QUIET_TICKS`].
    quiet: u8,
    stats: InboxStats,
}

/// One payload an [`Inbox`] received: the RF data of a Receive Packet (0x90) or an
/// Explicit Rx Indicator (0x91), and who sent it.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Received<const P: usize> {
    frame_type: u8,
    // The addresses as their bytes: an `Address64` would align the payloads queued to 8
    // bytes, and moving them would link a second `memcpy` into a firmware (156 bytes on
    // a Cortex-M3).
    src64: [u8; 8],
    src16: [u8; 2],
    options: u8,
    data: Vec<u8, P>,
}

impl<const P: usize> Received<P> {
    /// The payload of `frame`, a Receive Packet (0x90) or an Explicit Rx Indicator
    /// (0x91), and who sent it: what an [`Inbox`] queues, for a firmware that reads
    /// frames itself (an async task on `io::FrameReader`, feature `embedded-io`, say)
    /// and hands payloads to another task over a channel.
    ///
    /// ```
    /// use xbee_api::{RawFrame, Received, ReceivedError};
    /// // A Receive Packet from 0013A20040522BAA (7D84), acknowledged, payload "Hi".
    /// let data = [0x90, 0x00, 0x13, 0xA2, 0x00, 0x40, 0x52, 0x2B, 0xAA, 0x7D, 0x84, 0x01, b'H', b'i'];
    /// let received: Received<84> = Received::from_frame(RawFrame::new(&data)?)?;
    /// assert_eq!((received.src64().to_string(), received.data()), ("0013a20040522baa".into(), &b"Hi"[..]));
    /// // A payload longer than its room, or a frame of another type, is refused.
    /// let small = Received::<1>::from_frame(RawFrame::new(&data)?);
    /// assert_eq!(small, Err(ReceivedError::TooLong { len: 2, capacity: 1 }));
    /// let status = Received::<84>::from_frame(RawFrame::new(&[0x8A, 0x06])?);
    /// assert_eq!(status, Err(ReceivedError::NotReceived { frame_type: 0x8A }));
    /// # Ok::<(), Box<dyn core::error::Error>>(())
    /// ```
    // Inlined: the inbox ignores the error's fields, which then cost no flash.
    #[inline]
    pub fn from_frame(frame: RawFrame<'_>) -> Result<Self, ReceivedError> {
        let data = frame.data();
        let frame_type = data.first().copied().unwrap_or_default();
        let not_received = ReceivedError::NotReceived { frame_type };
        let (src64, src16, options, payload) = match frame_type {
            frame_type::RECEIVE_PACKET => match ReceivePacket::new_checked(data) {
                Ok(rx) => (rx.src64(), rx.src16(), rx.options(), rx.data()),
                Err(_) => return Err(not_received),
            },
            frame_type::EXPLICIT_RX_INDICATOR => match ExplicitRxIndicator::new_checked(data) {
                Ok(rx) => (rx.src64(), rx.src16(), rx.options(), rx.data()),
                Err(_) => return Err(not_received),
            },
            _ => return Err(not_received),
        };
        let Ok(data) = Vec::from_slice(payload) else {
            return Err(ReceivedError::TooLong {
                len: payload.len(),
                capacity: P,
            });
        };
        Ok(Received {
            frame_type,
            src64: src64.to_bytes(),
            src16: src16.to_bytes(),
            options,
            data,
        })
    }

    /// The type of the frame it came in: 0x90 (Receive Packet) or 0x91 (Explicit Rx
    /// Indicator, from a radio set to `AO=1`; its endpoints and cluster are not kept).
    pub const fn frame_type(&self) -> u8 {
        self.frame_type
    }

    /// The sender's 64-bit address.
    pub const fn src64(&self) -> Address64 {
        Address64::from_bytes(self.src64)
    }

    /// The sender's 16-bit network address.
    pub const fn src16(&self) -> Address16 {
        Address16::from_bytes(self.src16)
    }

    /// The receive options bit field (0x01 acknowledged, 0x02 broadcast...:
    /// [`receive_options`](crate::receive_options)).
    pub const fn options(&self) -> u8 {
        self.options
    }

    /// The RF data: for a MAV, an MCP packet.
    pub fn data(&self) -> &[u8] {
        &self.data
    }
}

/// Why a frame's payload is no [`Received`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ReceivedError {
    /// The frame is no Receive Packet (0x90) or Explicit Rx Indicator (0x91), or is
    /// cut short of its fixed fields.
    NotReceived {
        /// Its frame type (0 for a frame with no byte).
        frame_type: u8,
    },
    /// The payload is longer than a [`Received`] holds.
    TooLong {
        /// The payload's length.
        len: usize,
        /// The most it holds (`P`).
        capacity: usize,
    },
}

impl fmt::Display for ReceivedError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ReceivedError::NotReceived { frame_type } => write!(
                f,
                "frame type 0x{frame_type:02x} is no whole Receive Packet (0x90) or \
                 Explicit Rx Indicator (0x91)"
            ),
            ReceivedError::TooLong { len, capacity } => write!(
                f,
                "a payload of {len} bytes is longer than the {capacity} a Received holds"
            ),
        }
    }
}

impl core::error::Error for ReceivedError {}

#[cfg(feature = "defmt")]
impl<const P: usize> defmt::Format for Received<P> {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(
            f,
            "Received {{ frame_type: {=u8:#x}, src64: {}, src16: {}, options: {=u8:#x}, data: {=[u8]:x} }}",
            self.frame_type,
            self.src64(),
            self.src16(),
            self.options,
            self.data()
        )
    }
}

/// What an [`Inbox`] did with the frames its decoder yielded. Counters wrap at
/// `u32::MAX`; the decoder keeps its own ([`Inbox::decoder`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct InboxStats {
    /// Payloads queued.
    pub queued: u32,
    /// Valid frames of other types (modem status, AT command responses...), and Receive
    /// Packets or Explicit Rx Indicators too short for their header, dropped.
    pub other_frames: u32,
    /// Receive Packets and Explicit Rx Indicators whose payload is longer than the
    /// inbox's `P`, dropped.
    pub too_long: u32,
}

/// The error of [`Inbox::push`] and [`Inbox::read_from`]: the queue is full, and the
/// main loop must [`pop`](Inbox::pop) a payload before another byte is taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct InboxFull;

impl fmt::Display for InboxFull {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("the inbox is full: pop a payload before taking another byte")
    }
}

impl core::error::Error for InboxFull {}

impl<const N: usize, M: FixedMode, const P: usize, const Q: usize> Inbox<N, M, P, Q> {
    /// An empty inbox whose decoder's mode is fixed in its type ([`Decoder::fixed`]).
    pub const fn new() -> Self {
        Self::with_decoder(Decoder::fixed())
    }
}

impl<const N: usize, M: FixedMode, const P: usize, const Q: usize> Default for Inbox<N, M, P, Q> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize, M: DecoderMode, const P: usize, const Q: usize> Inbox<N, M, P, Q> {
    /// An empty inbox around `decoder` (one whose mode is set at run time,
    /// [`Decoder::new`], or limited, [`Decoder::fixed_with_max_len`]).
    pub const fn with_decoder(decoder: Decoder<N, M>) -> Self {
        Inbox {
            decoder,
            queue: Deque::new(),
            pending: false,
            quiet: 0,
            stats: InboxStats {
                queued: 0,
                other_frames: 0,
                too_long: 0,
            },
        }
    }

    /// The API mode the decoder reads.
    pub const fn mode(&self) -> ApiMode {
        self.decoder.mode()
    }

    /// Takes the events the decoder holds while the queue has room; `true` if the
    /// queue can take a byte's frame, so that a byte may be taken off the UART and
    /// [`push`](Self::push)ed.
    pub fn ready(&mut self) -> bool {
        while self.pending && !self.queue.is_full() {
            match self.decoder.poll() {
                Some(event) => {
                    if let Ok(frame) = event {
                        accept(&mut self.queue, &mut self.stats, frame);
                    }
                }
                None => self.pending = false,
            }
        }
        !self.queue.is_full()
    }

    /// Feeds one byte from the UART to the decoder, queueing the payload of a frame it
    /// completes. [`InboxFull`], and the byte not taken, when the queue is full: check
    /// [`ready`](Self::ready) before taking a byte off the UART, or use
    /// [`read_from`](Self::read_from).
    pub fn push(&mut self, byte: u8) -> Result<(), InboxFull> {
        if !self.ready() {
            return Err(InboxFull);
        }
        self.feed(byte);
        Ok(())
    }

    /// [`push`](Self::push) once [`ready`](Self::ready) said yes.
    fn feed(&mut self, byte: u8) {
        self.quiet = 0;
        let event = self.decoder.push(byte);
        self.pending = event.is_some();
        // A bad frame is counted by the decoder, which resynchronises by itself.
        if let Some(Ok(frame)) = event {
            accept(&mut self.queue, &mut self.stats, frame);
        }
    }

    /// Feeds the bytes `read` gives (the UART's receive FIFO, a byte a call) while the
    /// queue has room. `Ok` once `read` gave `None` (the FIFO is empty); [`InboxFull`] when
    /// the queue filled up first, the bytes left in the FIFO: mask the receive
    /// interrupt until [`pop`](Self::pop) makes room.
    ///
    /// `read` is called only when a byte can be taken. A byte received with an error
    /// (framing, parity, overrun) is best counted and skipped inside `read`.
    pub fn read_from(&mut self, mut read: impl FnMut() -> Option<u8>) -> Result<(), InboxFull> {
        while self.ready() {
            let Some(byte) = read() else {
                return Ok(());
            };
            self.feed(byte);
        }
        Err(InboxFull)
    }

    /// One tick of a periodic timer: gives up the frame in progress at the second tick
    /// with no byte pushed between ([`give_up`](Self::give_up)), and, once the line
    /// has been quiet that long, at every tick after (a frame begun among the bytes a
    /// give-up scanned again goes at the next). A byte pushed, or a [`pop`](Self::pop)
    /// that frees a slot in a full queue, starts the count again.
    ///
    /// The period must be longer than the radio's longest pause inside a frame (it
    /// writes a frame's bytes back to back: a few milliseconds leave room) and short
    /// enough for the frames a stray 0x7E holds in API mode 1 to come out in time
    /// (50 ms in `examples/firmware`).
    ///
    /// Only bytes pushed count: read the UART's FIFO into the inbox
    /// ([`read_from`](Self::read_from)) before each tick, or bytes that came while the
    /// receive interrupt was held off (a critical section, the timer's interrupt
    /// itself) would be taken for a quiet line and their frame given up. Ticks that
    /// come back to back (an executor catching up) shorten the quiet time they
    /// measure: call it from a timer interrupt, or count time yourself and call
    /// `give_up`.
    pub fn tick(&mut self) {
        self.quiet = self.quiet.saturating_add(1);
        if self.quiet >= QUIET_TICKS {
            self.give_up();
        }
    }

    /// Gives up the frame in progress now, as at the end of the input: in API mode 1
    /// the bytes after its start delimiter are scanned again and the frames among them
    /// queued while there is room (the rest wait, as [`ready`](Self::ready) says); a
    /// frame begun among them stays for its rest. Takes the events pending first, and
    /// does nothing if the queue is full then: bytes may be waiting in the UART, and
    /// would end the frame.
    pub fn give_up(&mut self) {
        if !self.ready() || self.decoder.is_idle() {
            return;
        }
        if let Some(Ok(frame)) = self.decoder.finish() {
            accept(&mut self.queue, &mut self.stats, frame);
        }
        self.pending = true;
        self.ready();
    }

    /// The oldest payload queued.
    ///
    /// When it frees a slot in a full queue, the line counts as busy from then on for
    /// [`tick`](Self::tick): the bytes held back in the UART meanwhile are still to be
    /// read.
    pub fn pop(&mut self) -> Option<Received<P>> {
        let was_full = self.queue.is_full();
        let received = self.queue.pop_front()?;
        if was_full {
            self.quiet = 0;
        }
        Some(received)
    }

    /// The oldest payload queued, left in the queue: to handle it in place (inside the
    /// critical section that holds the inbox) and [`pop`](Self::pop) it after, rather
    /// than copy it out.
    ///
    /// ```
    /// # use xbee_api::{Inbox, Mode1};
    /// # let frame = [0x7E, 0x00, 0x0F, 0x90, 0x00, 0x13, 0xA2, 0x00, 0x40, 0x52, 0x2B, 0xAA,
    /// #     0xFF, 0xFE, 0x01, 0x63, 0x02, 0xFF, 0xF1];
    /// let mut inbox = Inbox::<32, Mode1, 16, 2>::new();
    /// inbox.read_from({ let mut fifo = frame.iter().copied(); move || fifo.next() })?;
    /// let received = inbox.peek().expect("a payload queued");
    /// assert_eq!(received.data(), b"c\x02\xff");
    /// assert_eq!(inbox.len(), 1); // still queued
    /// # Ok::<(), xbee_api::InboxFull>(())
    /// ```
    pub fn peek(&self) -> Option<&Received<P>> {
        self.queue.front()
    }

    /// The payloads queued, oldest first, left in the queue.
    pub fn iter(&self) -> impl DoubleEndedIterator<Item = &Received<P>> + ExactSizeIterator {
        self.queue.iter()
    }

    /// Payloads queued.
    pub const fn len(&self) -> usize {
        self.queue.len()
    }

    /// `true` if no payload is queued: a main loop's check before it sleeps, made in
    /// the critical section that sleeps ([`Inbox`]'s example, `sleep_if_idle`), when
    /// each `pop` from a full queue raises the receive interrupt (frames may wait in
    /// the decoder, which the interrupt then takes).
    pub const fn is_empty(&self) -> bool {
        self.queue.len() == 0
    }

    /// `true` if the queue is full. Not `false` for "a byte may be taken": frames the
    /// decoder holds may fill a slot freed; ask [`ready`](Self::ready).
    pub const fn is_full(&self) -> bool {
        self.queue.len() == Q
    }

    /// Empties the queue and drops the frame in progress and any events pending (after
    /// a UART break, or the radio reset); keeps the counters.
    pub fn reset(&mut self) {
        self.queue.clear();
        self.decoder.reset();
        self.pending = false;
        self.quiet = 0;
    }

    /// What was done with the frames received.
    pub const fn stats(&self) -> InboxStats {
        self.stats
    }

    /// The decoder: its counters of bad frames ([`Decoder::stats`]), whether a frame is
    /// in progress ([`Decoder::is_idle`]).
    pub const fn decoder(&self) -> &Decoder<N, M> {
        &self.decoder
    }
}

/// The decoder, how many payloads are queued (not their bytes), whether events wait in
/// the decoder, the quiet ticks counted and the counters.
impl<const N: usize, M: DecoderMode, const P: usize, const Q: usize> fmt::Debug
    for Inbox<N, M, P, Q>
{
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Inbox")
            .field("decoder", &self.decoder)
            .field("queued", &self.queue.len())
            .field("pending", &self.pending)
            .field("quiet_ticks", &self.quiet)
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

/// Queues the payload of a Receive Packet or an Explicit Rx Indicator; counts anything
/// else. Called only while the queue has room.
fn accept<const P: usize, const Q: usize>(
    queue: &mut Deque<Received<P>, Q>,
    stats: &mut InboxStats,
    frame: RawFrame<'_>,
) {
    let received = match Received::from_frame(frame) {
        Ok(received) => received,
        Err(ReceivedError::NotReceived { .. }) => return count(&mut stats.other_frames),
        Err(ReceivedError::TooLong { .. }) => return count(&mut stats.too_long),
    };
    // The caller checked for room before it took the event.
    if queue.push_back(received).is_ok() {
        count(&mut stats.queued);
    }
}

fn count(counter: &mut u32) {
    *counter = counter.wrapping_add(1);
}
