//! Streaming decoder of API frames with a fixed buffer.

use memchr::{memchr, memchr2};
#[cfg(target_pointer_width = "64")]
use wide::u8x16;

#[cfg(not(target_pointer_width = "64"))]
use crate::unescape::special_in_word;
#[cfg(target_pointer_width = "64")]
use crate::unescape::special_mask;

use crate::unescape::{STEP, is_plain, is_plain_byte, unescape, unescape_byte};
#[cfg(target_pointer_width = "64")]
use crate::window::{DATA, MAX_LEN, WINDOW_ROOM, frame_in_window};
use crate::wire::{ESCAPE, ESCAPE_XOR, START_DELIMITER, checksum_of_sum, needs_escape, sum};
use crate::{AnyMode, ApiMode, DecodeError, DecoderMode, DecoderStats, FixedMode, RawFrame};
use core::fmt;
use core::marker::PhantomData;

/// Default buffer size `N` of [`Decoder`]: 512 bytes. The frame data it takes, its
/// [`capacity`](Decoder::capacity), is 512 bytes in mode 2 and 508 in mode 1, which
/// buffers the 4 framing bytes too ([`decoder_buffer_len`] goes the other way).
///
/// XBee frame data tops out near 273 bytes (a 255-byte fragmented payload plus the
/// Explicit Rx Indicator's 18-byte header,
/// [`ExplicitRxIndicatorRepr::MAX_LEN`](crate::ExplicitRxIndicatorRepr::MAX_LEN)), so
/// 512 leaves room for every frame a radio sends, with margin, in both modes (mode 1
/// also buffers the 4 framing bytes).
pub const DEFAULT_CAPACITY: usize = 512;

/// The buffer size `N` a [`Decoder<N>`](Decoder) needs to take frame data of up to
/// `frame_data_len` bytes in `mode`: mode 2 keeps only the frame data, mode 1 the whole
/// frame (delimiter, length and checksum: 4 bytes more). For decoders sized at compile
/// time; [`Decoder::capacity`] says what a decoder takes. Code generic over the mode's
/// type cannot size an array with `M::MODE` on stable Rust: it sizes for
/// [`ApiMode::Unescaped`], the larger.
///
/// ```
/// use xbee_api::{ApiMode, Decoder, Mode1, ReceivePacketRepr, TransmitRequestRepr, decoder_buffer_len};
/// // A Receive Packet with the largest unfragmented payload: 12 + 84 bytes.
/// const DATA: usize = ReceivePacketRepr::HEADER_LEN + TransmitRequestRepr::MAX_UNICAST_DATA;
/// type FirmwareDecoder = Decoder<{ decoder_buffer_len(DATA, ApiMode::Unescaped) }, Mode1>;
/// assert_eq!(FirmwareDecoder::fixed().capacity(), 96);
/// assert_eq!(decoder_buffer_len(DATA, ApiMode::Unescaped), 100);
/// assert_eq!(decoder_buffer_len(DATA, ApiMode::Escaped), 96);
/// assert_eq!(decoder_buffer_len(usize::MAX, ApiMode::Unescaped), usize::MAX); // no overflow
/// ```
pub const fn decoder_buffer_len(frame_data_len: usize, mode: ApiMode) -> usize {
    // `usize::MAX` for a length no buffer holds, rather than an overflow.
    match mode {
        ApiMode::Unescaped => frame_data_len.saturating_add(4),
        ApiMode::Escaped => frame_data_len,
    }
}

/// What the decoder yields: a frame borrowed from its buffer, or why a candidate frame
/// was dropped. The frame stays valid until the decoder is called again.
pub type DecodeEvent<'a> = Result<RawFrame<'a>, DecodeError>;

/// An event before it borrows the buffer: a frame as a range of the buffer.
pub(crate) type Outcome = Result<(usize, usize), DecodeError>;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
// Stored as 0 when hunting, as a new decoder is: a new decoder of a fixed mode is then
// all zeros.
#[repr(u8)]
enum State {
    /// Looking for a start delimiter.
    Hunt = 0,
    /// Expecting the high byte of the length.
    LenHi,
    /// Expecting the low byte of the length.
    LenLo,
    /// Receiving frame data.
    Data,
    /// Expecting the checksum.
    Checksum,
}

/// A streaming decoder of XBee API frames in mode 1 or 2, with a fixed buffer of `N`
/// bytes and no allocation.
///
/// Feed it bytes one at a time ([`push`](Self::push), cheap enough for a UART interrupt:
/// a byte of frame data is only stored, everything else is done once a frame) or a slice
/// at a time ([`decode`](Self::decode) for one event a call, as a codec wants it, or
/// [`decode_each`](Self::decode_each) for a callback per event, the fastest; both decode
/// a frame lying whole in the slice in one pass, 16 bytes a step, and on 64-bit targets a
/// mode 2 frame of up to 60 bytes of data in one 64-byte window); it yields
/// [`RawFrame`]s borrowed from its buffer (or, from `decode_each`, from the input), or a
/// [`DecodeError`] for each candidate frame it drops, and counts both in
/// [`stats`](Self::stats). At the end of input, call [`finish`](Self::finish) until it
/// returns `None`; on a live line (a UART), call `finish` once when the line goes quiet
/// part way through a frame, then take the rest with [`poll`](Self::poll) (needed in API
/// mode 1, see `finish`).
///
/// # API mode
///
/// `M` says where the decoder takes its API mode from. The default, [`AnyMode`], takes
/// it at run time from [`new`](Decoder::new), as a host reading its radio's `AP`
/// setting does; such a decoder carries the code of both modes. A firmware whose radio
/// is set once fixes it in the type, [`Mode1`](crate::Mode1) or
/// [`Mode2`](crate::Mode2), with [`fixed`](Decoder::fixed): the same events come out,
/// and only that mode's code is linked.
///
/// ```
/// use xbee_api::{ApiMode, Decoder, Mode1};
/// let given: Decoder<64> = Decoder::new(ApiMode::Unescaped);
/// let fixed: Decoder<64, Mode1> = Decoder::fixed();
/// assert_eq!(given.mode(), fixed.mode());
/// ```
///
/// # Guarantee
///
/// No valid frame is lost because of garbage, a corrupt frame or a cut-off frame before
/// it, however the input is split (in mode 1, but behind a corrupt candidate whose
/// checksum matches by chance, below):
///
/// - **Mode 2** (escaped): a raw 0x7E always starts a new frame and aborts a partial one
///   (reported as [`DecodeError::Truncated`], or [`DecodeError::BadEscape`] right after
///   a 0x7D). A byte after 0x7D must be 0x5E, 0x5D, 0x31 or 0x33 (an escaped special
///   byte); anything else is [`DecodeError::BadEscape`] and the decoder hunts for the
///   next 0x7E.
/// - **Mode 1** (unescaped): 0x7E may occur inside frames, so a candidate frame can
///   swallow valid frames behind it. When a candidate fails (bad checksum, oversize or
///   zero length, or truncated at the end of input), the decoder drops it and scans
///   again from the byte right after its start delimiter, out of its buffer. That rescan
///   can find several frames and further failures before any new input is needed, so
///   one input byte can produce several events: drain them as shown below. A corrupt
///   candidate whose checksum matches by chance (1 in 256) is a frame in mode 1; nothing
///   can tell it apart, and the valid frame it reaches into is lost with it (its start
///   taken as the false frame's end): the one way mode 1 loses a valid frame.
///
/// # Worst case
///
/// Mode 2 does a bounded amount of work per input byte. Mode 1 pays for its guarantee:
/// a failed candidate is scanned again from the byte after its start delimiter, so a
/// byte can be read once for every candidate that spans it. Input built for it (a start
/// delimiter and a length near the [`capacity`](Self::capacity) every few bytes, such as
/// `7E 01 F8` over and over for `Decoder<512>`) fails a candidate of about `capacity`
/// bytes every three input bytes: one call to [`push`](Self::push),
/// [`poll`](Self::poll), [`decode`](Self::decode) or [`finish`](Self::finish) (or one
/// event of [`decode_each`](Self::decode_each)) can then do work proportional to the
/// capacity, and throughput falls with it: about 15 MB/s for `Decoder<512>` on a
/// desktop machine, against 1 GB/s and more for ordinary input. The work never exceeds
/// that bound and nothing is lost, but a mode 1 link open to untrusted bytes should not
/// accept longer frames than it carries: build the decoder with
/// [`with_max_len`](Self::with_max_len) set to the largest frame data its radios send
/// (a payload of at most 255 bytes arrives in frame data of at most 273 bytes,
/// [`ExplicitRxIndicatorRepr::MAX_LEN`](crate::ExplicitRxIndicatorRepr::MAX_LEN), so
/// 273 rather than the 508 of `Decoder<512>`), which turns longer length fields into
/// [`DecodeError::Oversize`] as soon as they are read and bounds the rescan by that
/// length instead.
///
/// # Loops
///
/// Slice at a time (the `usize` is how many input bytes were taken; it is 0 while
/// events pending in the buffer are delivered; `None` means all input was taken and
/// nothing is pending):
///
/// ```
/// use xbee_api::{ApiMode, Decoder};
/// let stream = [0x00, 0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F, 0x7E, 0x00];
/// let mut decoder: Decoder = Decoder::new(ApiMode::Escaped);
/// let mut frames = 0;
/// let mut input = &stream[..];
/// loop {
///     let (consumed, event) = decoder.decode(input);
///     input = &input[consumed..];
///     match event {
///         Some(Ok(frame)) => { assert_eq!(frame.data(), &[0x8A, 0x06]); frames += 1 }
///         Some(Err(error)) => panic!("{error}"),
///         None => break,
///     }
/// }
/// // End of input: the cut-off frame at the end is reported.
/// while let Some(event) = decoder.finish() {
///     assert!(event.is_err());
/// }
/// assert_eq!(frames, 1);
/// assert_eq!(decoder.stats().truncated, 1);
/// ```
///
/// Byte at a time (after [`push`](Self::push) returns an event, call
/// [`poll`](Self::poll) until it returns `None` before the next `push`):
///
/// ```
/// use xbee_api::{Decoder, Mode1};
/// let mut decoder: Decoder<64, Mode1> = Decoder::fixed();
/// let mut frames = 0;
/// for byte in [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F] {
///     let mut event = decoder.push(byte);
///     while let Some(e) = event {
///         if e.is_ok() { frames += 1 }
///         event = decoder.poll();
///     }
/// }
/// assert_eq!(frames, 1);
/// ```
///
/// Pushing without draining first is not lost either, as long as the buffer has room:
/// the byte is queued behind the pending ones. Once the buffer is full such a byte is
/// dropped and counted in `bytes_skipped`.
///
/// # Memory
///
/// `size_of::<Decoder<N>>()` is at most `N` plus the cursors and counters, 56 bytes on
/// a 32-bit target and 80 on a 64-bit one, rounded up to a multiple of the pointer size
/// (`Decoder<100>` takes 156 bytes on a Cortex-M, 184 on x86-64; the default
/// `Decoder<512>` 568 and 592), whatever its `M`: fixing the mode saves flash, not
/// RAM. Mode 2 holds frame data of up to `N` bytes; mode 1 holds the whole frame, so
/// frame data of up to `N - 4` bytes ([`capacity`](Self::capacity)).
#[derive(Clone)]
pub struct Decoder<const N: usize = DEFAULT_CAPACITY, M: DecoderMode = AnyMode> {
    buf: [u8; N],
    /// Mode 1: index of the candidate's start delimiter in `buf`.
    start: usize,
    /// Mode 1: next buffered byte to process.
    pos: usize,
    /// Bytes in `buf`. Mode 1: bytes buffered. Mode 2: frame data bytes stored.
    end: usize,
    /// While `end < fill_to`, [`push`](Self::push) stores a byte that is neither 0x7D
    /// nor 0x7E at `end` and does nothing else: the bytes are frame data, summed when
    /// the frame is complete. 0 outside frame data.
    fill_to: usize,
    /// Length field of the current candidate.
    len: usize,
    /// How far the largest length field taken ([`capacity`](Self::capacity)) is below
    /// what the buffer holds: 0 unless set by [`with_max_len`](Self::with_max_len) or
    /// [`fixed_with_max_len`](Self::fixed_with_max_len), so
    /// that a new decoder is all zeros but for its mode (a `static` one needs no
    /// initialiser in flash).
    cut: usize,
    state: State,
    /// Mode 2: the previous byte was 0x7D.
    escaped: bool,
    /// The mode of an [`AnyMode`] decoder. A decoder of a fixed mode reads `M`'s and
    /// keeps mode 1 here, which is 0, so that a new one is all zeros.
    mode: ApiMode,
    stats: DecoderStats,
    _mode: PhantomData<M>,
}

/// The mode, the capacity, where the decoder is, how many bytes it holds and its
/// counters; not the buffer.
///
/// ```
/// use xbee_api::{Decoder, Mode2};
/// let mut decoder: Decoder<64, Mode2> = Decoder::fixed();
/// decoder.push(0x7E);
/// assert_eq!(
///     format!("{decoder:?}"),
///     "Decoder { mode: Escaped, capacity: 64, state: LenHi, buffered: 0, stats: DecoderStats { \
///      frames_ok: 0, bad_checksum: 0, oversize: 0, empty: 0, truncated: 0, bad_escape: 0, \
///      bytes_skipped: 0 }, .. }"
/// );
/// ```
impl<const N: usize, M: DecoderMode> fmt::Debug for Decoder<N, M> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Decoder")
            .field("mode", &self.mode())
            .field("capacity", &self.capacity())
            .field("state", &self.state)
            .field("buffered", &self.end.saturating_sub(self.start))
            .field("stats", &self.stats)
            .finish_non_exhaustive()
    }
}

/// Marks the path that calls it as the rare one, so that the compiler lays out the
/// other straight on. Never in line, or the mark would go with the call.
#[cold]
#[inline(never)]
fn unlikely() {}

/// The length field at the start of `body` when it holds an escape: its value and how
/// many bytes of `body` it takes; `None` if it is cut off or badly escaped.
#[inline(never)]
fn escaped_length(body: &[u8]) -> Option<(usize, usize)> {
    let mut i = 0;
    let hi = unescape_byte(body, &mut i)?;
    let lo = unescape_byte(body, &mut i)?;
    Some((usize::from(u16::from_be_bytes([hi, lo])), i))
}

impl<const N: usize> Decoder<N, AnyMode> {
    /// A decoder for `mode`, hunting for a start delimiter.
    ///
    /// `N` must be at least 8 (checked at compile time).
    ///
    /// `const`, so a decoder can be a `static`. A new decoder in mode 1 is all zeros: a
    /// `static` one goes to `.bss` and takes no flash. In mode 2 its mode byte is not
    /// zero, so a `static` one also takes its size in flash, as the initial image of
    /// `.data`, and so does everything that shares its `static` (a
    /// `Mutex<RefCell<(Decoder, Queue)>>`, or an `Option<Decoder>` set to `None`, whose
    /// tag is not zero either). A firmware that knows its radio's mode should rather
    /// fix it in the type ([`fixed`](Decoder::fixed)): such a decoder is all zeros in
    /// both modes and carries only its own mode's code.
    pub const fn new(mode: ApiMode) -> Self {
        Self::blank(mode)
    }

    /// A decoder for `mode` that takes frame data of at most `max_len` bytes (the
    /// length field), fewer than its buffer could hold: longer frames are
    /// [`DecodeError::Oversize`] as soon as their length field is read, and in mode 1
    /// they are scanned again from the byte after their start delimiter like any other
    /// failed candidate, so no frame inside one is lost. A `max_len` above what the
    /// buffer holds is the buffer's limit. In mode 1 it also bounds what a failed
    /// candidate costs to scan again, so set it to the largest frame data the link
    /// carries (see [Worst case](Self#worst-case)).
    ///
    /// ```
    /// use xbee_api::{ApiMode, DecodeError, Decoder};
    /// // A 12-byte frame (valid, but over the limit) holding a 2-byte one.
    /// let stream = [0x7E, 0x00, 0x0C, 0x23, 0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F,
    ///               0x00, 0x00, 0x00, 0x00, 0x00, 0x5D];
    /// let mut decoder: Decoder = Decoder::with_max_len(ApiMode::Unescaped, 8);
    /// assert_eq!(decoder.capacity(), 8);
    /// let mut events = Vec::new();
    /// decoder.decode_each(&stream, |event| events.push(event.map(|f| f.data().to_vec())));
    /// while let Some(event) = decoder.finish() {
    ///     events.push(event.map(|f| f.data().to_vec()));
    /// }
    /// assert_eq!(events[0], Err(DecodeError::Oversize { length: 12, capacity: 8 }));
    /// assert_eq!(events[1], Ok(vec![0x8A, 0x06]));
    /// ```
    pub const fn with_max_len(mode: ApiMode, max_len: usize) -> Self {
        Self::new(mode).limited(max_len)
    }
}

impl<const N: usize, M: FixedMode> Decoder<N, M> {
    /// A decoder of the mode its type fixes ([`Mode1`](crate::Mode1) or
    /// [`Mode2`](crate::Mode2)), hunting for a start delimiter: it decodes exactly as
    /// [`new`](Decoder::new) with that mode would, and a program that links it carries
    /// only that mode's code (on a Cortex-M3, the firmware example's mode 1 receive path
    /// takes 772 bytes less flash on [`push`](Decoder::push), 6 884 less on
    /// [`decode_each`](Decoder::decode_each)).
    ///
    /// `N` must be at least 8 (checked at compile time). `const`, and all zeros in
    /// either mode: a `static` one goes to `.bss` and takes no flash.
    ///
    /// ```
    /// use xbee_api::{Decoder, Mode2};
    /// // `const`, for a `static` (in a firmware, behind a `Mutex<RefCell<_>>`).
    /// static IDLE: Decoder<64, Mode2> = Decoder::fixed();
    /// assert!(IDLE.is_idle());
    ///
    /// let mut decoder: Decoder<64, Mode2> = Decoder::fixed();
    /// let mut frames = 0;
    /// // A modem status whose data holds an escaped 0x11 (XON).
    /// for byte in [0x7E, 0x00, 0x02, 0x8A, 0x7D, 0x31, 0x64] {
    ///     if let Some(Ok(frame)) = decoder.push(byte) {
    ///         assert_eq!(frame.data(), &[0x8A, 0x11]);
    ///         frames += 1;
    ///     }
    /// }
    /// assert_eq!(frames, 1);
    /// ```
    pub const fn fixed() -> Self {
        Self::blank(ApiMode::Unescaped)
    }

    /// A decoder of the mode its type fixes that takes frame data of at most `max_len`
    /// bytes, as [`with_max_len`](Decoder::with_max_len) does for a mode given at run
    /// time.
    ///
    /// A limit below what the buffer holds is kept in the decoder, so such a decoder is
    /// not all zeros: a `static` one takes its size in flash as well. Where that matters
    /// and only the buffer's length is in question, a smaller `N` with
    /// [`fixed`](Decoder::fixed) saves the flash and the RAM.
    ///
    /// ```
    /// use xbee_api::{Decoder, Mode1};
    /// let decoder: Decoder<100, Mode1> = Decoder::fixed_with_max_len(60);
    /// assert_eq!(decoder.capacity(), 60);
    /// ```
    pub const fn fixed_with_max_len(max_len: usize) -> Self {
        Self::fixed().limited(max_len)
    }
}

/// [`Decoder::fixed`]: a decoder of the mode its type fixes. Not `const`: for a
/// `static`, use `Decoder::fixed()`.
///
/// ```
/// use xbee_api::{ApiMode, Decoder, Mode2};
/// let decoder: Decoder<64, Mode2> = Default::default();
/// assert_eq!(decoder.mode(), ApiMode::Escaped);
/// ```
impl<const N: usize, M: FixedMode> Default for Decoder<N, M> {
    fn default() -> Self {
        Self::fixed()
    }
}

impl<const N: usize, M: DecoderMode> Decoder<N, M> {
    /// A new decoder with `mode` in its mode field (read only by an [`AnyMode`] one).
    const fn blank(mode: ApiMode) -> Self {
        const { assert!(N >= 8, "Decoder capacity N must be at least 8") };
        Self {
            buf: [0; N],
            start: 0,
            pos: 0,
            end: 0,
            fill_to: 0,
            len: 0,
            cut: 0,
            state: State::Hunt,
            escaped: false,
            mode,
            stats: DecoderStats {
                frames_ok: 0,
                bad_checksum: 0,
                oversize: 0,
                empty: 0,
                truncated: 0,
                bad_escape: 0,
                bytes_skipped: 0,
            },
            _mode: PhantomData,
        }
    }

    /// This decoder limited to frame data of at most `max_len` bytes.
    const fn limited(mut self, max_len: usize) -> Self {
        let full = Self::buffer_capacity(self.mode());
        if max_len < full {
            self.cut = full - max_len;
        }
        self
    }

    /// The API mode this decoder reads.
    #[inline(always)]
    pub const fn mode(&self) -> ApiMode {
        match M::FIXED {
            Some(mode) => mode,
            None => self.mode,
        }
    }

    /// The largest frame data a buffer of `N` bytes holds in `mode`.
    const fn buffer_capacity(mode: ApiMode) -> usize {
        match mode {
            ApiMode::Unescaped => N - 4,
            ApiMode::Escaped => N,
        }
    }

    /// Largest frame data length (the length field) this decoder accepts: `N` in mode 2,
    /// `N - 4` in mode 1, or less if set by [`with_max_len`](Self::with_max_len) or
    /// [`fixed_with_max_len`](Self::fixed_with_max_len).
    /// Longer frames are [`DecodeError::Oversize`].
    pub const fn capacity(&self) -> usize {
        Self::buffer_capacity(self.mode()) - self.cut
    }

    /// Counters of frames, errors and skipped bytes so far.
    pub const fn stats(&self) -> &DecoderStats {
        &self.stats
    }

    /// Whether the decoder is between frames with no byte pending: false inside a
    /// candidate frame or while mode 1 holds bytes to scan again.
    pub const fn is_idle(&self) -> bool {
        matches!(self.state, State::Hunt)
            && match self.mode() {
                ApiMode::Unescaped => self.pos == self.end,
                ApiMode::Escaped => !self.escaped,
            }
    }

    /// Drops any partial frame and pending bytes; keeps the counters.
    pub fn reset(&mut self) {
        self.start = 0;
        self.pos = 0;
        self.end = 0;
        self.fill_to = 0;
        self.state = State::Hunt;
        self.escaped = false;
    }

    /// Feeds one byte; returns the event it completes, if any.
    ///
    /// In mode 1 an event can leave more events pending: call [`poll`](Self::poll)
    /// until it returns `None` before pushing the next byte.
    ///
    /// A byte of frame data that is neither 0x7D nor 0x7E is only stored: one compare
    /// of two cursors, one of the byte, a bounds check (none when `N` is a power of two)
    /// and the store. Delimiters, length bytes, escapes and the checksum byte take
    /// one step of the state machine, in line in mode 2 (a few tests each) and out of
    /// line in mode 1; the frame data is summed once, with the checksum.
    #[inline(always)]
    pub fn push(&mut self, byte: u8) -> Option<DecodeEvent<'_>> {
        let end = self.end;
        if end < self.fill_to && is_plain_byte(byte) {
            if let Some(next) = self.store(end, byte) {
                self.end = next;
                return None;
            }
        }
        // On ARM the compiler otherwise lays the store out of the way and branches to it
        // and back on every byte: the mark keeps it straight on (1 instruction a byte on
        // a Cortex-M3). On x86-64 the mark costs more than it saves.
        if cfg!(target_arch = "arm") {
            unlikely();
        }
        let outcome = match self.mode() {
            ApiMode::Escaped => self.step2(byte),
            ApiMode::Unescaped => self.push_slow(byte),
        };
        outcome.map(|o| self.event(o))
    }

    /// Stores a byte of frame data at `at`, below `fill_to`; the cursor after it (`None`
    /// only if `at` were past the buffer, which `fill_to <= N` rules out).
    #[inline(always)]
    fn store(&mut self, at: usize, byte: u8) -> Option<usize> {
        // `at < fill_to <= N`, so the mask changes nothing; it shows the compiler that
        // the index is in bounds when `N` is a power of two.
        let at = if N.is_power_of_two() {
            at & (N - 1)
        } else {
            at
        };
        *self.buf.get_mut(at)? = byte;
        Some(at + 1)
    }

    /// [`push`](Self::push) in mode 1 for every byte but plain frame data.
    #[inline(never)]
    fn push_slow(&mut self, byte: u8) -> Option<Outcome> {
        self.push1(byte)
    }

    /// Delivers the next pending event (mode 1 rescans of buffered bytes) without new
    /// input; `None` when nothing is pending. Always `None` in mode 2.
    pub fn poll(&mut self) -> Option<DecodeEvent<'_>> {
        let outcome = match self.mode() {
            ApiMode::Escaped => None,
            ApiMode::Unescaped => self.drain1(),
        };
        outcome.map(|o| self.event(o))
    }

    /// Feeds bytes from `input` until an event; returns how many bytes it took and the
    /// event. Pending events are delivered first, with 0 bytes taken. `None` means all of
    /// `input` was taken and nothing is pending: feed more, or [`finish`](Self::finish).
    ///
    /// A frame that lies whole in `input` is decoded in one go: unescaped, copied to the
    /// buffer and summed 16 bytes a step (in mode 2 on 64-bit targets, a frame of up to
    /// 60 bytes of data in one 64-byte window, when `input` holds 128 bytes or more and
    /// the buffer `N` is as large). Frames split across calls go through the buffer and
    /// come out the same.
    ///
    /// The bytes taken are the decoder's from then on (a caller holding a `BytesMut` can
    /// advance past them at once).
    pub fn decode(&mut self, input: &[u8]) -> (usize, Option<DecodeEvent<'_>>) {
        let (consumed, outcome) = self.decode_outcome(input);
        (consumed, outcome.map(|o| self.event(o)))
    }

    /// [`decode`](Self::decode), its event not yet borrowing the buffer (a frame is in
    /// the buffer, at the range given): [`event`](Self::event) makes it one.
    pub(crate) fn decode_outcome(&mut self, input: &[u8]) -> (usize, Option<Outcome>) {
        match self.mode() {
            ApiMode::Escaped => self.decode2(input),
            ApiMode::Unescaped => self.decode1(input),
        }
    }

    /// Decodes all of `input`, calling `f` with every event in order; the fastest way
    /// through a slice holding many frames (a capture, a large read).
    ///
    /// The same events as [`decode`](Self::decode) in a loop, without a call and a
    /// returned event per frame. In mode 1, frames that lie whole and valid in `input`
    /// are passed to `f` borrowed from `input`, without a copy; the rest (and every
    /// frame in mode 2, which must be unescaped) come from the decoder's buffer. A frame
    /// cut off at the end of `input` stays in the decoder for the next call; at the end
    /// of the stream call [`finish`](Self::finish). `f` is called from one place only,
    /// so that the compiler can put it in line in the decoding loop, however much it
    /// does with each frame.
    ///
    /// ```
    /// use xbee_api::{ApiMode, Decoder};
    /// // Two frames and a bad checksum between them.
    /// let stream = [
    ///     0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F, // modem status
    ///     0x7E, 0x00, 0x02, 0x8A, 0x06, 0x00, // bad checksum
    ///     0x7E, 0x00, 0x02, 0x8A, 0x00, 0x75, // modem status
    /// ];
    /// let mut decoder: Decoder = Decoder::new(ApiMode::Escaped);
    /// let mut statuses = Vec::new();
    /// decoder.decode_each(&stream, |event| match event {
    ///     Ok(frame) => statuses.push(frame.data()[1]),
    ///     Err(error) => eprintln!("dropped: {error}"),
    /// });
    /// assert_eq!(statuses, [0x06, 0x00]);
    /// assert_eq!(decoder.stats().bad_checksum, 1);
    /// ```
    ///
    /// In an interrupt handler, feed it what the UART's FIFO or the DMA buffer holds (on
    /// an idle line, a half or a full buffer) rather than pushing byte by byte: the same
    /// events come out however the input is split, and a chunk that is all frame data
    /// of the frame in progress (most of them) is stored in line in the caller (16 bytes
    /// a step on 64-bit targets, 4 on 32-bit ones); the rest of a frame split across
    /// chunks is stepped with its cursors in registers. From 16-byte chunks on it costs
    /// less a byte than [`push`](Self::push); single bytes cost more. Instructions a
    /// byte on a stream of 58-byte frames, 16-byte chunks against `push`, the mode fixed
    /// in the type: on a Cortex-M3 16.1 against 17.8 in mode 2 and 13.1 against 20.1 in
    /// mode 1; on x86-64 11.6 against 17.2 in mode 2 and 9.2 against 19.8 in mode 1.
    ///
    /// It costs flash for that: it is put in line in its caller, with the frame loop of
    /// each mode the decoder may read, so fix the mode in the type
    /// ([`fixed`](Decoder::fixed)) to link one. On a Cortex-M3 (`opt-level = "s"`,
    /// LTO) the firmware example's receive path, in a fixed mode 1, takes 4 656 bytes
    /// of flash with `decode_each` against 3 568 with `push` (`examples/firmware`,
    /// `size.sh`, without the firmware's tick that gives up a stale frame); with the
    /// mode a value, `decode_each` takes 11 540. In a fixed mode 2 the difference is
    /// larger: about 3 300 bytes in a firmware like the README's. Each call site is a
    /// copy. Where flash is tight, use `push`.
    ///
    /// `f` cannot stop the loop: it is called for every event the chunk completes. Of
    /// frames (`Ok`) there are at most one for every 5 bytes of `input` and one more (a
    /// frame takes 5 bytes on the wire at least; one begun in an earlier chunk may end
    /// with its first byte), and in mode 1 one for every 5 bytes the decoder held for a
    /// failed candidate scanned again. An inbox the closure copies frames into needs
    /// that many places; where it may be full, take the events one at a time with
    /// [`decode`](Self::decode) or [`push`](Self::push) and [`poll`](Self::poll)
    /// instead. Errors come far more often on noise: a candidate fails 3 bytes in
    /// (`7E 00 00`, an empty frame), and a run of `0x7E` fails once a byte, so count
    /// them (as [`stats`](Self::stats) does) rather than queue each.
    ///
    /// ```
    /// use xbee_api::{Decoder, Mode2};
    /// let stream = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F, 0x7E, 0x00, 0x02, 0x8A, 0x00, 0x75];
    /// let mut decoder: Decoder<64, Mode2> = Decoder::fixed();
    /// let mut frames = 0;
    /// // What the RX FIFO held at each interrupt.
    /// for fifo in stream.chunks(4) {
    ///     decoder.decode_each(fifo, |event| {
    ///         if event.is_ok() {
    ///             frames += 1;
    ///         }
    ///     });
    /// }
    /// assert_eq!(frames, 2);
    /// ```
    #[inline(always)]
    pub fn decode_each<F: FnMut(DecodeEvent<'_>)>(&mut self, input: &[u8], mut f: F) {
        // Most chunks from a UART FIFO or a DMA buffer are frame data of the frame in
        // progress: stored here, in line in the caller, without a call.
        let mut rest = self.fill(input);
        if rest.is_empty() && !input.is_empty() {
            return;
        }
        let escaped = self.mode() == ApiMode::Escaped;
        let limit = self.capacity();
        // Known to be between frames: right after a frame handed over whole.
        let mut between = false;
        // One call of `f` for every event of both modes: the compiler can then put the
        // caller's closure in line in the loop (with more than one call of it, it keeps
        // a closure of any size out of line, and each frame pays for the call).
        while let Some(event) = if escaped {
            self.next2(&mut rest, limit, &mut between)
        } else {
            self.next1(&mut rest, &mut between)
        } {
            f(event);
        }
    }

    /// Stores the frame data of the frame in progress at the start of `input`, as
    /// [`push`](Self::push) would byte by byte; returns the rest. On 64-bit targets 16
    /// bytes or more are taken all at once or not at all: all if they are frame data
    /// (in mode 2, without 0x7D or 0x7E), 16 bytes a step. Elsewhere (microcontrollers)
    /// they go 4 a step up to the first word that is not all frame data. The last
    /// bytes go one at a time, up to the first that is not frame data (in mode 2, or
    /// is 0x7D or 0x7E).
    #[inline(always)]
    fn fill<'i>(&mut self, input: &'i [u8]) -> &'i [u8] {
        let mut end = self.end;
        // `fill_to` is 0 outside frame data and after an escape.
        let fill_to = self.fill_to;
        #[cfg(target_pointer_width = "64")]
        if input.len() >= 16 {
            if end + input.len() > fill_to {
                return input;
            }
            let Some(dst) = self.buf.get_mut(end..end + input.len()) else {
                return input;
            };
            {
                // 16 bytes a step, the last step ending at the end of `input`
                // (overlapping the one before it, which stored the same bytes).
                let last = input.len() - 16;
                let mut specials = 0;
                let mut i = 0;
                loop {
                    let at = i.min(last);
                    if let (Some(step), Some(out)) = (
                        input.get(at..).and_then(<[u8]>::first_chunk::<16>),
                        dst.get_mut(at..).and_then(<[u8]>::first_chunk_mut::<16>),
                    ) {
                        *out = *step;
                        specials |= special_mask(u8x16::new(*step));
                    }
                    if at == last {
                        break;
                    }
                    i += 16;
                }
                if specials != 0 && self.mode() == ApiMode::Escaped {
                    return input;
                }
            }
            self.end = end + input.len();
            return &[];
        }
        // Mode 1 stores 0x7D and 0x7E here too.
        let escaped = self.mode() == ApiMode::Escaped;
        let mut rest = input;
        // Without 16-byte steps: 4 bytes a step while they are frame data (in mode 2,
        // one word tested for 0x7D and 0x7E at once), loaded and stored whole: ARMv7-M
        // takes unaligned words. A call of `memcpy` cost more for such short runs.
        #[cfg(not(target_pointer_width = "64"))]
        while let Some((word, tail)) = rest.split_first_chunk::<4>() {
            let Some(dst) = self.buf.get_mut(end..).and_then(<[u8]>::first_chunk_mut) else {
                break;
            };
            if end + 4 > fill_to || (escaped && special_in_word(u32::from_le_bytes(*word))) {
                break;
            }
            *dst = *word;
            end += 4;
            rest = tail;
        }
        while let Some((&byte, tail)) = rest.split_first() {
            if end >= fill_to || (escaped && !is_plain(byte)) {
                break;
            }
            let Some(next) = self.store(end, byte) else {
                break;
            };
            end = next;
            rest = tail;
        }
        self.end = end;
        rest
    }

    /// The next event of [`decode_each`](Self::decode_each) in mode 2, `input` moved past
    /// what it took; `None` once all of `input` is taken. Between frames, a frame that
    /// lies whole in `input` is taken at once ([`whole2_at`](Self::whole2_at)); the
    /// rest goes through [`feed2`](Self::feed2). `between` says the decoder is known to
    /// be between frames, as a frame taken whole leaves it (it is then left `true`), so
    /// that the state need not be read again; `limit` is [`capacity`](Self::capacity).
    #[inline(always)]
    fn next2<'s>(
        &'s mut self,
        input: &mut &[u8],
        limit: usize,
        between: &mut bool,
    ) -> Option<DecodeEvent<'s>> {
        loop {
            // Between frames (`escaped` is only ever set inside one).
            if *between || (self.state == State::Hunt && !self.escaped) {
                // Short frames, whole in one window (64-bit targets, room permitting).
                #[cfg(target_pointer_width = "64")]
                if let Some((rest, outcome)) = self.window2(input, limit) {
                    *input = rest;
                    *between = true;
                    let data = |len| self.buf.get(DATA..DATA + len).unwrap_or_default();
                    return Some(outcome.map(|len| RawFrame::from_data(data(len))));
                }
                if let Some((rest, outcome)) = self.whole2_at(input, limit) {
                    *input = rest;
                    *between = true;
                    return Some(self.event(outcome));
                }
                *between = false;
                match input.split_first() {
                    None => return None,
                    // A frame that is not whole here (or not valid): byte by byte, but
                    // for a plain length field that the buffer can take, read here.
                    Some((&START_DELIMITER, body)) => {
                        self.begin2();
                        *input = body;
                        if let Some((&[hi, lo], data)) = body.split_first_chunk::<2>() {
                            let len = usize::from(u16::from_be_bytes([hi, lo]));
                            if is_plain(hi) && is_plain(lo) && len != 0 && len <= limit {
                                self.len = len;
                                self.state = State::Data;
                                self.fill_to = len;
                                *input = data;
                            }
                        }
                    }
                    Some(_) => {
                        // Garbage: skip to the next start delimiter and try the frame
                        // there whole.
                        let k = memchr(START_DELIMITER, input).unwrap_or(input.len());
                        self.skipped(k);
                        *input = input.get(k..).unwrap_or_default();
                        continue;
                    }
                }
            }
            let (consumed, outcome) = self.feed2(input);
            *input = input.get(consumed..).unwrap_or_default();
            return outcome.map(|o| self.event(o));
        }
    }

    /// The frame at the start of `input` (between frames) if it lies whole there: the
    /// rest of `input` after it and the outcome. With a plain length field that leaves
    /// the step loop room past its data in the buffer, or through
    /// [`whole2`](Self::whole2).
    /// `None`, with nothing changed but the buffer's content, for a frame that is not
    /// whole or not for the buffer, or has anything but a bad checksum wrong.
    #[inline(always)]
    fn whole2_at<'a>(&mut self, input: &'a [u8], limit: usize) -> Option<(&'a [u8], Outcome)> {
        let (&[START_DELIMITER, hi, lo], rest) = input.split_first_chunk::<3>()? else {
            return None;
        };
        let len = usize::from(u16::from_be_bytes([hi, lo]));
        if is_plain(hi) && is_plain(lo) {
            // The length checked once, here.
            if len.wrapping_sub(1) >= limit.min(N.saturating_sub(STEP)) || rest.len() <= len {
                return None;
            }
            self.whole2_data(rest, len)
        } else {
            // A frame is not whole in fewer bytes than its length field asks for (read
            // raw: an escape there only makes the frame longer, but for lengths from
            // 0x1100 on, which take the byte path).
            if len >= rest.len() {
                return None;
            }
            self.whole2(input.get(1..).unwrap_or_default(), limit)
        }
    }

    /// Mode 2 bytes, as [`push`](Self::push) takes them one at a time but with the
    /// cursors held for the whole of `input`: a byte of frame data that is neither 0x7D
    /// nor 0x7E is only stored; any other byte takes a step of the state machine. On
    /// 64-bit targets frame data goes 16 bytes a step while `input` has them. Stops
    /// after the first event; how many bytes it took and the event.
    #[inline(always)]
    fn feed2(&mut self, input: &[u8]) -> (usize, Option<Outcome>) {
        let mut rest = input;
        let mut end = self.end;
        let mut fill_to = self.fill_to;
        loop {
            // Frame data 16 bytes a step: stored whole (bytes past the frame data are
            // scratch), counted up to the first special byte or the end of the frame
            // data.
            #[cfg(target_pointer_width = "64")]
            while let Some(step) = rest.first_chunk::<16>() {
                let Some(dst) = self
                    .buf
                    .get_mut(end..end + 16)
                    .and_then(<[u8]>::first_chunk_mut::<16>)
                    .filter(|_| end < fill_to)
                else {
                    break;
                };
                *dst = *step;
                let specials = special_mask(u8x16::new(*step));
                let plain = ((specials | 1 << 16).trailing_zeros() as usize).min(fill_to - end);
                end += plain;
                rest = rest.get(plain..).unwrap_or_default();
                if plain < 16 {
                    break;
                }
            }
            loop {
                let Some((&byte, tail)) = rest.split_first() else {
                    self.end = end;
                    return (input.len(), None);
                };
                rest = tail;
                if end < fill_to && is_plain(byte) {
                    if let Some(next) = self.store(end, byte) {
                        end = next;
                        continue;
                    }
                }
                // An escaped byte of frame data, whole in `rest`: stored at once. The
                // test is the one `step2` makes after the escape; a bad escape goes
                // there and is reported by it.
                if byte == ESCAPE && end < fill_to {
                    if let Some((&raw, tail)) = rest.split_first() {
                        let unescaped = raw ^ ESCAPE_XOR;
                        if needs_escape(unescaped) {
                            if let Some(next) = self.store(end, unescaped) {
                                end = next;
                                rest = tail;
                                break;
                            }
                        }
                    }
                }
                self.end = end;
                if let Some(outcome) = self.step2(byte) {
                    return (input.len() - rest.len(), Some(outcome));
                }
                end = self.end;
                fill_to = self.fill_to;
                break;
            }
        }
    }

    /// The next event of [`decode_each`](Self::decode_each) in mode 1, as
    /// [`next2`](Self::next2) gives it in mode 2: a whole valid frame borrowed from
    /// `input` if `between` or the state says the decoder is between frames, else
    /// through [`feed1`](Self::feed1).
    #[inline(always)]
    fn next1<'s, 'i: 's>(
        &'s mut self,
        input: &mut &'i [u8],
        between: &mut bool,
    ) -> Option<DecodeEvent<'s>> {
        if *between || (self.state == State::Hunt && self.pos == self.end) {
            if let Some((n, data)) = self.valid1(input) {
                *input = input.get(n..).unwrap_or_default();
                *between = true;
                return Some(Ok(RawFrame::from_data(data)));
            }
        }
        *between = false;
        let (consumed, event) = self.feed1(input);
        *input = input.get(consumed..).unwrap_or_default();
        event
    }

    /// [`decode`](Self::decode) in mode 1 for input that does not start with a whole valid
    /// frame, with the common steps of a frame split across inputs in line: its header
    /// (if its length is one the buffer can take), its frame data and its checksum byte
    /// buffered at once.
    #[inline(always)]
    fn feed1(&mut self, input: &[u8]) -> (usize, Option<DecodeEvent<'_>>) {
        let mut rest = input;
        if self.state == State::Hunt && self.pos == self.end {
            // As `begin1` and `drain1` would.
            if let Some((&[START_DELIMITER, hi, lo], data)) = rest.split_first_chunk::<3>() {
                let len = usize::from(u16::from_be_bytes([hi, lo]));
                if let (true, Some(header)) = (
                    len != 0 && len <= self.capacity(),
                    self.buf.first_chunk_mut::<3>(),
                ) {
                    *header = [START_DELIMITER, hi, lo];
                    self.start = 0;
                    self.pos = 3;
                    self.end = 3;
                    self.len = len;
                    self.state = State::Data;
                    self.fill_to = 3 + len;
                    rest = data;
                }
            }
        }
        // Frame data of the frame in progress (bytes pending, if any, are frame data
        // too), then the checksum byte.
        if self.state == State::Data && self.end <= self.fill_to {
            let end = self.end;
            let take = (self.fill_to - end).min(rest.len());
            if let (Some(dst), Some((src, tail))) = (
                self.buf.get_mut(end..end + take),
                rest.split_at_checked(take),
            ) {
                dst.copy_from_slice(src);
                self.end = end + take;
                rest = tail;
            }
            if self.end < self.fill_to {
                return (input.len(), None);
            }
            // `fill_to < N` in mode 1: the checksum byte has its place.
            if let (Some((&got, tail)), Some(slot)) =
                (rest.split_first(), self.buf.get_mut(self.end))
            {
                *slot = got;
                self.end += 1;
                rest = tail;
                if let Some(outcome) = self.drain1() {
                    return (input.len() - rest.len(), Some(self.event(outcome)));
                }
            }
        }
        let taken = input.len() - rest.len();
        let (consumed, event) = self.decode(rest);
        (taken + consumed, event)
    }

    /// Ends the input: delivers pending events, then reports a partial frame as
    /// [`DecodeError::Truncated`] (in mode 1 its bytes are then scanned again). Call it
    /// until it returns `None`; the decoder is then idle and can take new input.
    ///
    /// Call it too when the line has gone quiet part way through a frame (no byte for
    /// longer than a frame takes at the baud rate, the decoder not [idle](Self::is_idle)):
    /// a radio writes a frame's bytes back to back, so the rest is lost. In API mode 1
    /// this matters beyond the one frame: a stray 0x7E (noise, a frame cut off) starts
    /// a candidate whose length field may reach past the real frames behind it, and
    /// those come out only once that many more bytes came, or once the candidate is
    /// given up here and its bytes scanned again. For a quiet line, call it once and
    /// take the rest with [`poll`](Self::poll): a frame begun among the bytes held then
    /// stays for its rest (calling `finish` again would give it up too).
    ///
    /// ```
    /// use xbee_api::{DecodeError, Decoder, Mode1};
    /// // Noise that reads as a start delimiter and a length of 64, then a whole frame.
    /// let line = [0x7E, 0x00, 0x40, 0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];
    /// let mut decoder: Decoder<128, Mode1> = Decoder::fixed();
    /// let mut frames = 0;
    /// decoder.decode_each(&line, |event| frames += usize::from(event.is_ok()));
    /// assert_eq!(frames, 0); // held inside the candidate
    /// // The line stays quiet: give the candidate up.
    /// assert!(!decoder.is_idle());
    /// assert!(matches!(decoder.finish(), Some(Err(DecodeError::Truncated { .. }))));
    /// while let Some(event) = decoder.poll() {
    ///     frames += usize::from(event.is_ok());
    /// }
    /// assert_eq!(frames, 1);
    /// ```
    pub fn finish(&mut self) -> Option<DecodeEvent<'_>> {
        self.finish_outcome().map(|o| self.event(o))
    }

    /// [`finish`](Self::finish), its event not yet borrowing the buffer.
    pub(crate) fn finish_outcome(&mut self) -> Option<Outcome> {
        match self.mode() {
            ApiMode::Escaped => {
                if self.state == State::Hunt {
                    self.escaped = false;
                    None
                } else {
                    let error = self.truncated(self.end);
                    self.escaped = false;
                    self.hunt();
                    Some(Err(self.record(error)))
                }
            }
            ApiMode::Unescaped => match self.drain1() {
                Some(outcome) => Some(outcome),
                None if self.state == State::Hunt => None,
                None => {
                    let received = self.pos.saturating_sub(self.start + 3);
                    let error = self.truncated(received);
                    Some(Err(self.fail1(error)))
                }
            },
        }
    }

    /// The event of `outcome`, a frame borrowing the buffer.
    pub(crate) fn event(&self, outcome: Outcome) -> DecodeEvent<'_> {
        outcome
            .map(|(start, end)| RawFrame::from_data(self.buf.get(start..end).unwrap_or_default()))
    }

    /// Back to hunting for a start delimiter; `push` stores nothing on its own.
    fn hunt(&mut self) {
        self.state = State::Hunt;
        self.fill_to = 0;
    }

    fn truncated(&self, received: usize) -> DecodeError {
        DecodeError::Truncated {
            length: match self.state {
                State::Data | State::Checksum => Some(self.len as u16),
                _ => None,
            },
            received,
        }
    }

    /// Counts an error and passes it on.
    fn record(&mut self, error: DecodeError) -> DecodeError {
        let counter = match error {
            DecodeError::BadChecksum { .. } => &mut self.stats.bad_checksum,
            DecodeError::Oversize { .. } => &mut self.stats.oversize,
            DecodeError::EmptyFrame => &mut self.stats.empty,
            DecodeError::Truncated { .. } => &mut self.stats.truncated,
            DecodeError::BadEscape { .. } => &mut self.stats.bad_escape,
        };
        *counter = counter.wrapping_add(1);
        error
    }

    fn skipped(&mut self, n: usize) {
        self.stats.bytes_skipped = self.stats.bytes_skipped.wrapping_add(n as u32);
    }

    /// Checks a complete length field; the error if the frame cannot be taken.
    fn check_len(&self) -> Option<DecodeError> {
        if self.len == 0 {
            Some(DecodeError::EmptyFrame)
        } else if self.len > self.capacity() {
            Some(DecodeError::Oversize {
                length: self.len as u16,
                capacity: self.capacity(),
            })
        } else {
            None
        }
    }

    /// Checks the checksum byte of frame data at `start..start + len` of the buffer;
    /// the frame's range (counted), or the error (not counted yet).
    fn check(&mut self, start: usize, got: u8) -> Outcome {
        let data = self.buf.get(start..start + self.len).unwrap_or_default();
        self.check_sum(sum(data), start, got)
    }

    /// [`check`](Self::check) with the sum of the frame data known.
    fn check_sum(&mut self, sum: u8, start: usize, got: u8) -> Outcome {
        let expected = checksum_of_sum(sum);
        if got == expected {
            self.stats.frames_ok = self.stats.frames_ok.wrapping_add(1);
            Ok((start, start + self.len))
        } else {
            Err(DecodeError::BadChecksum { expected, got })
        }
    }

    // ---- Mode 2: a raw 0x7E always starts a frame, nothing is ever rescanned. ----

    /// A start delimiter was read: expect the length.
    fn begin2(&mut self) {
        self.state = State::LenHi;
        self.escaped = false;
        self.end = 0;
        self.fill_to = 0;
    }

    /// [`step2`](Self::step2) out of line, for the slice path's bytes between bulk runs.
    #[inline(never)]
    fn step2_cold(&mut self, raw: u8) -> Option<Outcome> {
        self.step2(raw)
    }

    /// One raw byte of a mode 2 stream.
    ///
    /// The common bytes first, each with few tests: an escape inside a frame, the byte
    /// after it, frame data, the length bytes and the checksum; errors go out of line.
    /// (Its state tests stay a `match` on purpose: testing frame data first with an
    /// `if`, as one compare, cost `push` a third of its bytes a second on x86-64.)
    #[inline(always)]
    fn step2(&mut self, raw: u8) -> Option<Outcome> {
        let byte = if self.escaped {
            // Only ever set inside a frame. An escaped start delimiter is no special byte.
            self.escaped = false;
            let byte = raw ^ ESCAPE_XOR;
            if !needs_escape(byte) {
                return Some(Err(self.fail2(raw, true)));
            }
            byte
        } else if raw == ESCAPE {
            if self.state != State::Hunt {
                self.escaped = true;
                self.fill_to = 0;
            } else {
                self.skipped(1);
            }
            return None;
        } else if raw == START_DELIMITER {
            return self.delimiter2();
        } else {
            raw
        };
        match self.state {
            // Once `end` reaches the length, frame data is complete and this byte is the
            // checksum.
            State::Data if self.end < self.len => {
                if let Some(slot) = self.buf.get_mut(self.end) {
                    *slot = byte;
                }
                self.end += 1;
                self.fill_to = self.len;
                None
            }
            // Out of line on every target: in line, the sum made `push` 0.7 instructions
            // a byte cheaper on x86-64 but about 1.6 times slower.
            State::Data | State::Checksum => Some(self.checksum2(byte)),
            State::LenHi => {
                self.len = usize::from(byte) << 8;
                self.state = State::LenLo;
                None
            }
            State::LenLo => {
                self.len |= usize::from(byte);
                if self.len == 0 || self.len > self.capacity() {
                    return Some(Err(self.fail2(raw, false)));
                }
                self.state = State::Data;
                self.fill_to = self.len;
                None
            }
            State::Hunt => {
                self.skipped(1);
                None
            }
        }
    }

    /// The checksum byte `got` of a mode 2 frame: the frame, or the error, counted; back
    /// to hunting.
    #[inline(never)]
    fn checksum2(&mut self, got: u8) -> Outcome {
        self.hunt();
        self.check(0, got).map_err(|e| self.record(e))
    }

    /// A raw start delimiter in mode 2: a new frame, and the error of the one it cuts
    /// off, if any.
    #[inline(always)]
    fn delimiter2(&mut self) -> Option<Outcome> {
        if self.state == State::Hunt {
            self.begin2();
            return None;
        }
        Some(Err(self.fail2(START_DELIMITER, false)))
    }

    /// A candidate frame fails in mode 2 at `raw`: the error, counted. After an escape
    /// (cleared by the caller, `escaped` tells) `raw` is not an escaped special byte;
    /// otherwise a start delimiter cuts the frame off, or else the length field just
    /// completed is 0 or over the capacity. A raw start delimiter begins a new frame;
    /// anything else goes back to hunting.
    #[cold]
    #[inline(never)]
    fn fail2(&mut self, raw: u8, escaped: bool) -> DecodeError {
        let error = if escaped {
            DecodeError::BadEscape {
                byte: raw,
                received: self.end,
            }
        } else if raw == START_DELIMITER {
            self.truncated(self.end)
        } else if self.len == 0 {
            DecodeError::EmptyFrame
        } else {
            DecodeError::Oversize {
                length: self.len as u16,
                capacity: N - self.cut,
            }
        };
        if raw == START_DELIMITER {
            self.begin2();
        } else {
            self.hunt();
        }
        self.record(error)
    }

    /// Decodes a frame that lies whole in `body`, the bytes after its start delimiter;
    /// the rest of `body` after the frame and the outcome. `None`, with nothing changed
    /// but the buffer's content, if the frame is not whole in `body` or has anything
    /// but a bad checksum wrong: [`step2`](Self::step2) then reads it byte by byte.
    /// The state is left as it was: the caller goes back to hunting. `limit` is
    /// [`capacity`](Self::capacity), read once by a caller that loops.
    #[inline(always)]
    fn whole2<'a>(&mut self, body: &'a [u8], limit: usize) -> Option<(&'a [u8], Outcome)> {
        // The length bytes, usually both plain: one test for the two.
        let (len, header) = match body.first_chunk::<2>() {
            Some(&[hi, lo]) if is_plain(hi) && is_plain(lo) => {
                (usize::from(u16::from_be_bytes([hi, lo])), 2)
            }
            _ => escaped_length(body)?,
        };
        let rest = body.get(header..)?;
        // Mode 2 takes frame data of up to `N` bytes (its `capacity()`, or less if set).
        if len == 0 || len > limit || rest.len() <= len {
            return None;
        }
        self.whole2_data(rest, len)
    }

    /// The frame at the start of `input` if it lies whole in its first 64 bytes (a
    /// start delimiter first, and at least [`WINDOW_ROOM`] bytes) and the decoder takes
    /// such frames (a buffer of [`WINDOW_ROOM`] bytes or more, and a capacity, `limit`,
    /// of [`MAX_LEN`] or more): the rest of `input` after it and the outcome, a frame as
    /// the length of its data, which is at `buf[DATA..]`. `None`, with nothing changed
    /// but the buffer's content, as for [`whole2`](Self::whole2).
    #[cfg(target_pointer_width = "64")]
    #[inline(always)]
    fn window2<'a>(
        &mut self,
        input: &'a [u8],
        limit: usize,
    ) -> Option<(&'a [u8], Result<usize, DecodeError>)> {
        if N < WINDOW_ROOM || limit < MAX_LEN {
            return None;
        }
        let window = input.first_chunk::<WINDOW_ROOM>()?;
        if window[0] != START_DELIMITER {
            return None;
        }
        let out = self.buf.first_chunk_mut::<WINDOW_ROOM>()?;
        let Some(frame) = frame_in_window(window, out) else {
            // A longer frame, or one with something wrong: rare, out of the way.
            unlikely();
            return None;
        };
        let rest = input.get(frame.taken..)?;
        // Frame data and checksum byte sum to 0xFF: the checksum is right.
        if frame.total == checksum_of_sum(0) {
            self.stats.frames_ok = self.stats.frames_ok.wrapping_add(1);
            return Some((rest, Ok(frame.len)));
        }
        // A bad checksum.
        unlikely();
        let got = *out.get(DATA + frame.len)?;
        self.len = frame.len;
        let outcome = self
            .check_sum(frame.total.wrapping_sub(got), DATA, got)
            .map(|_| frame.len)
            .map_err(|e| self.record(e));
        Some((rest, outcome))
    }

    /// [`whole2`](Self::whole2) after the length field: `rest` holds the frame data
    /// (`len` bytes, `0 < len <= N`) and more; the checksum byte is read after it.
    #[inline(always)]
    fn whole2_data<'a>(&mut self, rest: &'a [u8], len: usize) -> Option<(&'a [u8], Outcome)> {
        let (mut i, sum) = unescape(rest, &mut self.buf, len)?;
        // The checksum byte, usually plain; what follows it is handed back as a slice,
        // so that the caller goes on without a bounds test of its own.
        let (got, after) = match rest.get(i..).and_then(<[u8]>::split_first) {
            Some((&raw, after)) if is_plain(raw) => (raw, after),
            _ => {
                let got = unescape_byte(rest, &mut i)?;
                (got, rest.get(i..)?)
            }
        };
        self.len = len;
        let outcome = self.check_sum(sum, 0, got).map_err(|e| self.record(e));
        Some((after, outcome))
    }

    fn decode2(&mut self, input: &[u8]) -> (usize, Option<Outcome>) {
        // Between frames, at a start delimiter: the whole frame at once if it is there.
        let mut try_whole = true;
        if self.state == State::Hunt {
            #[cfg(target_pointer_width = "64")]
            if let Some((rest, outcome)) = self.window2(input, self.capacity()) {
                let outcome = outcome.map(|len| (DATA, DATA + len));
                return (input.len() - rest.len(), Some(outcome));
            }
            if let Some((&START_DELIMITER, body)) = input.split_first() {
                if let Some((after, outcome)) = self.whole2(body, self.capacity()) {
                    return (input.len() - after.len(), Some(outcome));
                }
                try_whole = false;
            }
        }
        let mut i = 0;
        while let Some(rest) = input.get(i..).filter(|r| !r.is_empty()) {
            match self.state {
                State::Hunt => {
                    let k = match rest.first() {
                        Some(&START_DELIMITER) => 0,
                        _ => match memchr(START_DELIMITER, rest) {
                            Some(k) => k,
                            None => {
                                self.skipped(rest.len());
                                return (input.len(), None);
                            }
                        },
                    };
                    self.skipped(k);
                    i += k + 1;
                    self.begin2();
                    try_whole |= i > 1;
                    continue;
                }
                // Right after a start delimiter: try the whole frame at once.
                State::LenHi if !self.escaped && try_whole => {
                    try_whole = false;
                    if let Some((after, outcome)) = self.whole2(rest, self.capacity()) {
                        self.hunt();
                        return (input.len() - after.len(), Some(outcome));
                    }
                }
                State::Data if !self.escaped && self.end < self.len => {
                    let want = (self.len - self.end).min(rest.len());
                    let chunk = rest.get(..want).unwrap_or_default();
                    let run = memchr2(ESCAPE, START_DELIMITER, chunk).unwrap_or(chunk.len());
                    if run > 0 {
                        let dst = self.buf.get_mut(self.end..self.end + run);
                        if let (Some(dst), Some(src)) = (dst, chunk.get(..run)) {
                            dst.copy_from_slice(src);
                        }
                        self.end += run;
                        i += run;
                        continue;
                    }
                }
                _ => {}
            }
            let byte = input.get(i).copied().unwrap_or(0);
            i += 1;
            if let Some(outcome) = self.step2_cold(byte) {
                return (i, Some(outcome));
            }
        }
        (i.min(input.len()), None)
    }

    // ---- Mode 1: candidates stay in the buffer until they succeed, so that a failed
    // one can be scanned again from the byte after its start delimiter. ----

    /// Moves the candidate (and pending bytes) to the start of the buffer.
    fn compact(&mut self) {
        // A forward byte loop, not `copy_within`: the bytes move towards the front, so
        // it is correct, and it keeps `memmove` (1.6 KiB of flash on a Cortex-M) out of
        // firmware that has no other use for it.
        for i in 0..self.end - self.start {
            let byte = self.buf.get(self.start + i).copied();
            if let (Some(byte), Some(slot)) = (byte, self.buf.get_mut(i)) {
                *slot = byte;
            }
        }
        self.pos -= self.start;
        self.end -= self.start;
        self.fill_to = self.fill_to.saturating_sub(self.start);
        self.start = 0;
    }

    /// Drops the current candidate: scan again from the byte after its delimiter.
    fn fail1(&mut self, error: DecodeError) -> DecodeError {
        self.start += 1;
        self.pos = self.start;
        self.hunt();
        self.record(error)
    }

    /// Processes buffered bytes until an event or until none is left.
    fn drain1(&mut self) -> Option<Outcome> {
        while self.pos < self.end {
            match self.state {
                State::Hunt => {
                    let hay = self.buf.get(self.pos..self.end).unwrap_or_default();
                    match memchr(START_DELIMITER, hay) {
                        Some(k) => {
                            self.skipped(k);
                            self.start = self.pos + k;
                            self.pos = self.start + 1;
                            self.state = State::LenHi;
                        }
                        None => {
                            self.skipped(hay.len());
                            self.pos = self.end;
                        }
                    }
                }
                // `pos < end <= N` here: the bytes read below are always in the buffer
                // (the defaults are never taken).
                State::LenHi => {
                    let hi = self.buf.get(self.pos).copied().unwrap_or_default();
                    self.len = usize::from(hi) << 8;
                    self.pos += 1;
                    self.state = State::LenLo;
                }
                State::LenLo => {
                    let lo = self.buf.get(self.pos).copied().unwrap_or_default();
                    self.len |= usize::from(lo);
                    self.pos += 1;
                    if let Some(error) = self.check_len() {
                        return Some(Err(self.fail1(error)));
                    }
                    if self.start + self.len + 4 > N {
                        self.compact();
                    }
                    self.state = State::Data;
                    self.fill_to = self.start + 3 + self.len;
                }
                // Frame data is summed with the checksum, once it is all there.
                State::Data => {
                    let frame_end = self.start + 3 + self.len;
                    if self.end < frame_end {
                        self.pos = self.end;
                    } else {
                        self.pos = frame_end;
                        self.state = State::Checksum;
                        self.fill_to = 0;
                    }
                }
                State::Checksum => {
                    let got = self.buf.get(self.pos).copied().unwrap_or_default();
                    self.pos += 1;
                    let outcome = self.check(self.start + 3, got);
                    return Some(match outcome {
                        Ok(range) => {
                            self.start = self.pos;
                            self.hunt();
                            Ok(range)
                        }
                        Err(error) => Err(self.fail1(error)),
                    });
                }
            }
        }
        if self.state == State::Hunt {
            self.start = 0;
            self.pos = 0;
            self.end = 0;
        }
        None
    }

    /// Bytes the current mode 1 candidate still needs (header, data and checksum).
    fn needed1(&self) -> usize {
        let have = self.end - self.start;
        match self.state {
            State::LenHi | State::LenLo => 3usize.saturating_sub(have),
            _ => (self.len + 4).saturating_sub(have),
        }
    }

    /// Starts a candidate with a start delimiter from new input (nothing pending).
    fn begin1(&mut self) {
        self.start = 0;
        self.pos = 0;
        self.end = 0;
        if let Some(slot) = self.buf.first_mut() {
            *slot = START_DELIMITER;
            self.pos = 1;
            self.end = 1;
            self.state = State::LenHi;
        }
    }

    fn push1(&mut self, byte: u8) -> Option<Outcome> {
        if self.pos == self.end && self.state == State::Hunt {
            if byte == START_DELIMITER {
                self.begin1();
            } else {
                self.skipped(1);
            }
            return None;
        }
        if self.end == N {
            self.compact();
        }
        match self.buf.get_mut(self.end) {
            Some(slot) => {
                *slot = byte;
                self.end += 1;
            }
            None => self.skipped(1),
        }
        self.drain1()
    }

    /// Decodes a frame that lies whole and valid in `frame` (from its start delimiter)
    /// with nothing pending; how many bytes of `frame` it took and the outcome. `None`,
    /// with nothing changed but the buffer's content, for anything else: the buffered
    /// path then reads it (and rescans it if it fails).
    fn whole1(&mut self, frame: &[u8]) -> Option<(usize, Outcome)> {
        let (n, data) = self.valid1(frame)?;
        // `valid1` takes no more than the capacity, `N - 4`: the data always fits.
        if let Some(dst) = self.buf.get_mut(..data.len()) {
            dst.copy_from_slice(data);
        }
        Some((n, Ok((0, data.len()))))
    }

    /// A frame that lies whole and valid at the start of `input` (from its start
    /// delimiter), counted: how many bytes it takes and its frame data, borrowed from
    /// `input`. `None` for anything else.
    #[inline]
    fn valid1<'i>(&mut self, input: &'i [u8]) -> Option<(usize, &'i [u8])> {
        let (&[START_DELIMITER, hi, lo], rest) = input.split_first_chunk::<3>()? else {
            return None;
        };
        let len = usize::from(u16::from_be_bytes([hi, lo]));
        // Mode 1's capacity.
        if len == 0 || len + self.cut > N - 4 {
            return None;
        }
        let data = rest.get(..len)?;
        if *rest.get(len)? != checksum_of_sum(sum(data)) {
            return None;
        }
        self.stats.frames_ok = self.stats.frames_ok.wrapping_add(1);
        Some((len + 4, data))
    }

    fn decode1(&mut self, input: &[u8]) -> (usize, Option<Outcome>) {
        if let Some(outcome) = self.drain1() {
            return (0, Some(outcome));
        }
        let mut i = 0;
        while let Some(rest) = input.get(i..).filter(|r| !r.is_empty()) {
            // Nothing is pending while hunting here: `drain1` took every buffered byte.
            if self.state == State::Hunt {
                match memchr(START_DELIMITER, rest) {
                    Some(k) => {
                        self.skipped(k);
                        i += k;
                        let candidate = rest.get(k..).unwrap_or_default();
                        if let Some((n, outcome)) = self.whole1(candidate) {
                            return (i + n, Some(outcome));
                        }
                        i += 1;
                        self.begin1();
                    }
                    None => {
                        self.skipped(rest.len());
                        return (input.len(), None);
                    }
                }
                continue;
            }
            let take = self.needed1().min(rest.len());
            if self.end + take > N {
                self.compact();
            }
            match (
                self.buf.get_mut(self.end..self.end + take),
                rest.get(..take),
            ) {
                (Some(dst), Some(src)) => dst.copy_from_slice(src),
                // Unreachable: a candidate always fits once compacted (N >= 8).
                _ => {
                    self.skipped(take);
                    self.reset();
                    i += take;
                    continue;
                }
            }
            self.end += take;
            i += take;
            if let Some(outcome) = self.drain1() {
                return (i, Some(outcome));
            }
        }
        (i.min(input.len()), None)
    }
}
