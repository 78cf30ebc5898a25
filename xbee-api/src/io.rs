//! Frames over [`embedded_io`] readers and writers: a UART of any HAL that implements
//! the `embedded-io` traits (features `embedded-io`, and `embedded-io-async` for the
//! async ones that Embassy's drivers implement).
//!
//! - [`FrameReader`] reads from a reader and returns the next event (frame or dropped
//!   candidate), or hands every event of a read to a closure.
//! - [`write_frame`] writes a frame to a writer, escaped in API mode 2, through a small
//!   buffer on the stack; [`write_frame_async`] encodes it into a buffer the caller
//!   gives and writes it.
//!
//! Each write function flushes the writer after the frame, so that the frame is on its
//! way when it returns. On most UART drivers (Embassy's `BufferedUartTx`, say) a flush
//! waits until the last byte has left the wire, about 87 µs a byte at 115200 baud: a
//! task that reads the same UART reads nothing meanwhile, and a driver whose receive
//! buffer fills drops bytes. To send frames back to back, or from a task that also
//! reads, write the bytes of each encoded frame ([`EncodeFrame::encode`], or
//! [`InPlaceFrame::finish`](crate::InPlaceFrame::finish)) with the writer's own
//! `write_all`, and flush once, or not at all (a buffered driver sends what it holds),
//! or read in a task of its own.
//!
//! ```
//! use xbee_api::io::{FrameReader, write_frame};
//! use xbee_api::{ApiMode, ModemStatus, ModemStatusRepr};
//!
//! // What a radio wrote to the UART: a modem status, escaped in mode 2.
//! let mut wire = [0u8; 16];
//! let mut uart = &mut wire[..];
//! let frame = ModemStatusRepr { status: ModemStatus::from(0x11) };
//! let n = write_frame(&mut uart, ApiMode::Escaped, &frame)?;
//! assert_eq!(wire[..n], [0x7E, 0x00, 0x02, 0x8A, 0x7D, 0x31, 0x64]);
//!
//! // Read back a read at a time.
//! let mut reader: FrameReader<&[u8], 64> = FrameReader::new(&wire[..n], ApiMode::Escaped);
//! let mut frames = Vec::new();
//! while reader.read_events(|event| frames.extend(event.ok().map(|f| f.data().to_vec())))? > 0 {}
//! assert_eq!(frames, [vec![0x8A, 0x11]]);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use core::fmt;

/// The `embedded-io` crate whose traits this module reads and writes through, at the
/// version it uses.
pub use embedded_io;
/// The `embedded-io-async` crate whose traits the async forms take, at the version
/// they use.
#[cfg(feature = "embedded-io-async")]
pub use embedded_io_async;

use crate::decoder::Outcome;
use crate::{
    AnyMode, ApiMode, DEFAULT_CAPACITY, DecodeEvent, Decoder, DecoderMode, EncodeError,
    EncodeFrame, FixedMode,
};

/// Bytes read from the reader at a time, and written to the writer at a time by
/// [`write_frame`]: a UART FIFO's worth, kept on the stack for the call.
const CHUNK: usize = 32;

/// A [`Decoder`] fed from a reader: the events of the bytes it reads.
///
/// Two ways to take them:
/// - [`read_event`](Self::read_event) (and [`read_event_async`](Self::read_event_async))
///   reads until the next event and returns it, the frame borrowed from the decoder
///   until the next call; bytes read past it wait in the reader. For a loop that
///   answers each frame as it comes, awaiting its writes in async code.
/// - [`read_events`](Self::read_events) (and
///   [`read_events_async`](Self::read_events_async)) reads once and passes every event
///   those bytes complete to a closure, frames borrowed from the decoder's buffer or
///   from the bytes read. Fewer instructions a byte: the whole read goes through
///   [`decode_each`](Decoder::decode_each).
///
/// Each read blocks until the reader has bytes (as `embedded-io` readers do) and takes
/// at most 32. A frame split across reads comes out whole on the read that completes
/// it. At the end of the input (a read of no bytes) the decoder is
/// [finished](Decoder::finish): a frame cut off there is reported. The two ways can be
/// mixed: `read_events` first passes on what `read_event` left.
///
/// In mode 2 one read's 32 bytes complete at most 7 frames (a frame takes 5 bytes on
/// the wire at least, and one begun in an earlier read may end with the read's first
/// byte): an inbox the closure copies payloads into needs no more places than that for
/// one call (and as many more as bytes `read_event` left complete). In mode 1 a failed
/// candidate scanned again can also release frames whose bytes came in earlier reads,
/// at most one for every 5 bytes the decoder holds.
///
/// [`read_events_async`](Self::read_events_async) and
/// [`read_event_async`](Self::read_event_async) are cancel safe: dropped before a read
/// completes (in a `select` with a timer, say), they have taken no byte of it, and
/// nothing is lost as long as the reader's own `read` is cancel safe.
///
/// A line that goes quiet part way through a frame leaves it waiting for its rest:
/// give it up with [`drop_partial`](Self::drop_partial) when no byte came for longer
/// than a frame takes. With that same `select` and a quiet-line timeout started with
/// each wait (a fresh `Timer::after(QUIET)`): note [`bytes_read`](Self::bytes_read)
/// before the wait, and when the timeout wins with no byte read meanwhile, give the
/// frame up (a long frame at a slow baud rate may take longer than the timeout with its
/// bytes still coming: only an unchanged `bytes_read` says the line was quiet). Not a
/// periodic ticker (the 20 Hz telemetry's, say): it may be due already when the wait
/// begins, and would give up a frame whose rest is on its way. In API mode 1 a stray
/// 0x7E can hold real frames back that way (see [`Decoder::finish`]).
///
/// `M` is the decoder's [`DecoderMode`]: a firmware whose radio's API mode is set once
/// fixes it in the type ([`fixed`](FrameReader::fixed)), so that only that mode's code
/// is linked (the reader feeds the decoder with
/// [`decode_each`](Decoder::decode_each), which is put in line once for each mode the
/// decoder may read).
///
/// ```
/// use xbee_api::io::FrameReader;
/// use xbee_api::Mode2;
/// let wire = [0x7E, 0x00, 0x02, 0x8A, 0x7D, 0x31, 0x64];
/// let mut reader: FrameReader<&[u8], 64, Mode2> = FrameReader::fixed(&wire[..]);
/// let mut frames = 0;
/// while reader.read_events(|event| frames += usize::from(event.is_ok()))? > 0 {}
/// assert_eq!(frames, 1);
/// # Ok::<(), core::convert::Infallible>(())
/// ```
#[derive(Debug)]
pub struct FrameReader<R, const N: usize = DEFAULT_CAPACITY, M: DecoderMode = AnyMode> {
    reader: R,
    decoder: Decoder<N, M>,
    /// The last read; `chunk[pos..len]` are its bytes not yet decoded
    /// ([`read_event`](Self::read_event) stops at an event).
    chunk: [u8; CHUNK],
    pos: usize,
    len: usize,
    /// Bytes read so far, wrapping.
    bytes_read: u32,
    /// [`drop_partial`](Self::drop_partial) gave the frame up; the events of its bytes
    /// scanned again follow.
    dropped: bool,
}

impl<R, const N: usize> FrameReader<R, N, AnyMode> {
    /// A reader of frames in `mode` from `reader`.
    pub const fn new(reader: R, mode: ApiMode) -> Self {
        Self::with_decoder(reader, Decoder::new(mode))
    }
}

impl<R, const N: usize, M: FixedMode> FrameReader<R, N, M> {
    /// A reader of frames in the mode its type fixes ([`Mode1`](crate::Mode1) or
    /// [`Mode2`](crate::Mode2)) from `reader`.
    pub const fn fixed(reader: R) -> Self {
        Self::with_decoder(reader, Decoder::fixed())
    }
}

impl<R, const N: usize, M: DecoderMode> FrameReader<R, N, M> {
    /// A reader of frames from `reader` through `decoder` (one made with
    /// [`Decoder::with_max_len`], say).
    pub const fn with_decoder(reader: R, decoder: Decoder<N, M>) -> Self {
        Self {
            reader,
            decoder,
            chunk: [0; CHUNK],
            pos: 0,
            len: 0,
            bytes_read: 0,
            dropped: false,
        }
    }

    /// The API mode the reader reads.
    pub const fn mode(&self) -> ApiMode {
        self.decoder.mode()
    }

    /// The decoder: its [`stats`](Decoder::stats) count frames and errors.
    pub const fn decoder(&self) -> &Decoder<N, M> {
        &self.decoder
    }

    /// The decoder. To start afresh (after the line was reconfigured), use
    /// [`reset`](Self::reset), which also drops the bytes read and not yet decoded.
    pub fn decoder_mut(&mut self) -> &mut Decoder<N, M> {
        &mut self.decoder
    }

    /// Starts afresh, as after the line was reconfigured: the frame in progress and
    /// the bytes read but not yet decoded are dropped (the counters are kept).
    pub fn reset(&mut self) {
        self.decoder.reset();
        self.pos = 0;
        self.len = 0;
        self.dropped = false;
    }

    /// Bytes read from the reader so far (wrapping at `u32::MAX`): compared before and
    /// after a wait, whether any came, for [`drop_partial`](Self::drop_partial).
    pub const fn bytes_read(&self) -> u32 {
        self.bytes_read
    }

    /// The reader.
    pub const fn get_ref(&self) -> &R {
        &self.reader
    }

    /// The reader, to reconfigure it; bytes read from it past this reader are not seen.
    pub fn get_mut(&mut self) -> &mut R {
        &mut self.reader
    }

    /// Gives up the frame in progress, as at the end of the input: its error
    /// ([`DecodeError::Truncated`](crate::DecodeError::Truncated)) and, in API mode 1,
    /// the events of its bytes scanned again (frames a stray 0x7E held back), one a
    /// call; `None` once there are no more (at once if no frame is in progress). Bytes
    /// read and not yet decoded (which [`read_event`](Self::read_event) left) are
    /// decoded first, their events first: they may end the frame. One frame is given
    /// up a sequence of calls: a new candidate the scan starts among the bytes held is
    /// kept, for its rest to come or for the next quiet wait to give it up.
    ///
    /// For a line quiet part way through a frame, from a timer (see [`FrameReader`]).
    ///
    /// ```
    /// use xbee_api::io::FrameReader;
    /// use xbee_api::Mode1;
    /// // Noise that reads as a start delimiter and a length of 64, then a whole frame;
    /// // then the line is quiet.
    /// let line = [0x7E, 0x00, 0x40, 0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];
    /// let mut reader: FrameReader<&[u8], 128, Mode1> = FrameReader::fixed(&line[..]);
    /// let mut frames = 0;
    /// reader.read_events(|event| frames += usize::from(event.is_ok()))?;
    /// assert_eq!(frames, 0); // held inside the candidate
    /// // No event for a while: give the candidate up.
    /// while let Some(event) = reader.drop_partial() {
    ///     frames += usize::from(event.is_ok());
    /// }
    /// assert_eq!(frames, 1);
    /// # Ok::<(), core::convert::Infallible>(())
    /// ```
    pub fn drop_partial(&mut self) -> Option<DecodeEvent<'_>> {
        let outcome = match self.pending_outcome() {
            Some(outcome) => Some(outcome),
            // Given up once: a new candidate the scan starts among the bytes held
            // stays, as a frame begun just before the wait ended may be.
            None if !self.dropped => {
                self.dropped = true;
                self.decoder.finish_outcome()
            }
            None => None,
        };
        if outcome.is_none() {
            self.dropped = false;
        }
        outcome.map(|o| self.decoder.event(o))
    }

    /// The reader back; a partial frame in the decoder, and bytes read but not yet
    /// decoded, are dropped.
    pub fn into_inner(self) -> R {
        self.reader
    }

    /// Passes the events of `bytes`, just read, to `f` (after those of bytes read
    /// earlier that [`read_event`](Self::read_event) left); at the end of the input (no
    /// bytes), those of [`Decoder::finish`].
    fn feed<F: FnMut(DecodeEvent<'_>)>(&mut self, n: usize, mut f: F) {
        self.took(n);
        self.pos = 0;
        self.len = 0;
        if n == 0 {
            while let Some(event) = self.decoder.finish() {
                f(event);
            }
        } else {
            self.decoder
                .decode_each(self.chunk.get(..n).unwrap_or_default(), f);
        }
    }

    /// Passes the events of what [`read_event`](Self::read_event) left (bytes read and
    /// not yet decoded, frames the decoder holds) to `f`, before a read.
    fn pass_left<F: FnMut(DecodeEvent<'_>)>(&mut self, f: &mut F) {
        while let Some(outcome) = self.pending_outcome() {
            f(self.decoder.event(outcome));
        }
    }

    /// Counts `n` bytes read.
    fn took(&mut self, n: usize) {
        // At most a chunk's worth: the cast keeps every bit that counts.
        self.bytes_read = self.bytes_read.wrapping_add(n as u32);
        self.dropped = false;
    }

    /// The next event of the bytes read and not yet decoded (or held in the decoder: in
    /// mode 1, frames a failed candidate released), as a range in the decoder's buffer;
    /// `None` when they hold none (all are then decoded).
    fn pending_outcome(&mut self) -> Option<Outcome> {
        loop {
            let pending = self.chunk.get(self.pos..self.len).unwrap_or_default();
            let (taken, outcome) = self.decoder.decode_outcome(pending);
            self.pos += taken;
            if outcome.is_some() || self.pos >= self.len {
                return outcome;
            }
        }
    }

    /// The next event of `n` bytes just read into the chunk; at the end of the input
    /// (`n` 0), of [`Decoder::finish`].
    fn read_outcome(&mut self, n: usize) -> Option<Outcome> {
        self.took(n);
        self.pos = 0;
        self.len = n.min(CHUNK);
        if n == 0 {
            self.decoder.finish_outcome()
        } else {
            self.pending_outcome()
        }
    }
}

impl<R: embedded_io::Read, const N: usize, M: DecoderMode> FrameReader<R, N, M> {
    /// Reads once and passes every event the bytes read complete to `f`, in order;
    /// returns how many bytes were read. `Ok(0)` is the end of the input, after the
    /// events of a frame cut off by it. What [`read_event`](Self::read_event) left is
    /// passed on first, before the read (which may wait for bytes).
    ///
    /// A read error is returned as it is; the decoder keeps what it had, so the next call
    /// goes on with the frame in progress.
    pub fn read_events<F: FnMut(DecodeEvent<'_>)>(&mut self, mut f: F) -> Result<usize, R::Error> {
        self.pass_left(&mut f);
        let n = self.reader.read(&mut self.chunk)?;
        self.feed(n, f);
        Ok(n)
    }

    /// Reads until the next event and returns it: a frame, borrowed from the decoder,
    /// or a dropped candidate. `Ok(None)` is the end of the input, after the events of
    /// a frame cut off by it.
    ///
    /// One event a call, for a loop that does more with each than a closure can (in
    /// async code, [`read_event_async`](Self::read_event_async), whose caller can
    /// await between frames). Bytes read past the event wait in the reader for the next
    /// call. A read error is returned as it is; the next call goes on with the frame in
    /// progress.
    ///
    /// ```
    /// use xbee_api::io::FrameReader;
    /// use xbee_api::{Frame, Mode1};
    /// // Two modem statuses, a bad checksum between them.
    /// let wire = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F, 0x7E, 0x00, 0x02, 0x8A, 0x06, 0x00,
    ///             0x7E, 0x00, 0x02, 0x8A, 0x00, 0x75];
    /// let mut reader: FrameReader<&[u8], 64, Mode1> = FrameReader::fixed(&wire[..]);
    /// let mut events = Vec::new();
    /// while let Some(event) = reader.read_event()? {
    ///     events.push(event.map(|frame| Frame::parse(frame).map(|f| f.frame_type())));
    /// }
    /// assert_eq!(events.len(), 3);
    /// assert!(events[1].is_err());
    /// # Ok::<(), core::convert::Infallible>(())
    /// ```
    pub fn read_event(&mut self) -> Result<Option<DecodeEvent<'_>>, R::Error> {
        let outcome = loop {
            if let Some(outcome) = self.pending_outcome() {
                break Some(outcome);
            }
            let n = self.reader.read(&mut self.chunk)?;
            if let Some(outcome) = self.read_outcome(n) {
                break Some(outcome);
            }
            if n == 0 {
                break None;
            }
        };
        Ok(outcome.map(|o| self.decoder.event(o)))
    }
}

#[cfg(feature = "embedded-io-async")]
impl<R: embedded_io_async::Read, const N: usize, M: DecoderMode> FrameReader<R, N, M> {
    /// [`read_events`](Self::read_events) from an async reader: waits for the read, then
    /// passes the events to `f`. Cancel safe (see [`FrameReader`]).
    ///
    /// ```
    /// # futures::executor::block_on(async {
    /// use xbee_api::io::FrameReader;
    /// use xbee_api::{Mode2, ReceivePacket};
    /// // A Receive Packet carrying `c 02 FF` (a landing status request), in API mode 2.
    /// let uart: &[u8] = &[0x7E, 0x00, 0x0F, 0x90, 0x00, 0x7D, 0x33, 0xA2, 0x00, 0x40, 0x52,
    ///                     0x2B, 0xAA, 0xFF, 0xFE, 0x01, 0x63, 0x02, 0xFF, 0xF1];
    /// let mut reader: FrameReader<_, 64, Mode2> = FrameReader::fixed(uart);
    /// let mut payloads = Vec::new(); // a `heapless::Deque` on a microcontroller
    /// while reader
    ///     .read_events_async(|event| {
    ///         if let Some(rx) = event.ok().and_then(|f| ReceivePacket::new_checked(f.data()).ok()) {
    ///             payloads.push(rx.data().to_vec());
    ///         }
    ///     })
    ///     .await?
    ///     > 0
    /// {}
    /// assert_eq!(payloads, [b"c\x02\xFF".to_vec()]);
    /// # Ok::<(), core::convert::Infallible>(())
    /// # }).unwrap();
    /// ```
    pub async fn read_events_async<F: FnMut(DecodeEvent<'_>)>(
        &mut self,
        mut f: F,
    ) -> Result<usize, R::Error> {
        self.pass_left(&mut f);
        let n = self.reader.read(&mut self.chunk).await?;
        self.feed(n, f);
        Ok(n)
    }

    /// [`read_event`](Self::read_event) from an async reader: reads until the next
    /// event and returns it, `Ok(None)` at the end of the input. Cancel safe, as
    /// [`read_events_async`](Self::read_events_async) is: dropped while it waits for a
    /// read, it has lost nothing.
    ///
    /// ```
    /// # futures::executor::block_on(async {
    /// use xbee_api::io::FrameReader;
    /// use xbee_api::{Mode2, ReceivePacket};
    /// // A Receive Packet carrying `c 02 FF` (a landing status request), in API mode 2.
    /// let uart: &[u8] = &[0x7E, 0x00, 0x0F, 0x90, 0x00, 0x7D, 0x33, 0xA2, 0x00, 0x40, 0x52,
    ///                     0x2B, 0xAA, 0xFF, 0xFE, 0x01, 0x63, 0x02, 0xFF, 0xF1];
    /// let mut reader: FrameReader<_, 64, Mode2> = FrameReader::fixed(uart);
    /// while let Some(event) = reader.read_event_async().await? {
    ///     let Ok(frame) = event else { continue };
    ///     if let Ok(rx) = ReceivePacket::new_checked(frame.data()) {
    ///         assert_eq!(rx.data(), b"c\x02\xFF");
    ///         // Answer here, awaiting the UART's writes: the frame borrows the reader
    ///         // until the next read.
    ///     }
    /// }
    /// # Ok::<(), core::convert::Infallible>(())
    /// # }).unwrap();
    /// ```
    pub async fn read_event_async(&mut self) -> Result<Option<DecodeEvent<'_>>, R::Error> {
        let outcome = loop {
            if let Some(outcome) = self.pending_outcome() {
                break Some(outcome);
            }
            let n = self.reader.read(&mut self.chunk).await?;
            if let Some(outcome) = self.read_outcome(n) {
                break Some(outcome);
            }
            if n == 0 {
                break None;
            }
        };
        Ok(outcome.map(|o| self.decoder.event(o)))
    }
}

/// A frame that could not be written: it cannot be encoded, or the writer failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum WriteError<E> {
    /// The frame cannot be encoded (nothing was written), or the buffer given to
    /// [`write_frame_async`] is too small for it.
    Encode(EncodeError),
    /// The writer failed; part of the frame may have been written.
    Io(E),
    /// The writer took no byte of a write (`Ok(0)`: a full transmitter that does not
    /// block, say); `written` bytes of the frame had gone out.
    WriteZero {
        /// Bytes of the frame written before.
        written: usize,
    },
}

/// A frame that cannot be encoded, built in place say: `?` turns an
/// [`InPlaceFrame`](crate::InPlaceFrame)'s error into the write's.
impl<E> From<EncodeError> for WriteError<E> {
    fn from(error: EncodeError) -> Self {
        WriteError::Encode(error)
    }
}

impl<E> WriteError<E> {
    /// A one-byte code, among those of [`DecodeError::code`](crate::DecodeError::code):
    /// the [`EncodeError`]'s code for
    /// [`Encode`](Self::Encode), 0x31 for [`Io`](Self::Io) (the writer's error is the
    /// writer's to code) and 0x32 for [`WriteZero`](Self::WriteZero).
    pub const fn code(&self) -> u8 {
        match self {
            Self::Encode(e) => e.code(),
            Self::Io(_) => 0x31,
            Self::WriteZero { .. } => 0x32,
        }
    }
}

impl<E: fmt::Display> fmt::Display for WriteError<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Encode(e) => write!(f, "cannot encode the frame: {e}"),
            Self::Io(e) => write!(f, "cannot write the frame: {e}"),
            Self::WriteZero { written } => write!(
                f,
                "cannot write the frame: the writer took no byte after {written}"
            ),
        }
    }
}

/// The encoder's or writer's error is in the message, so it is no
/// [`source`](core::error::Error::source): a report that follows the chain of sources
/// says it once.
impl<E: fmt::Debug + fmt::Display> core::error::Error for WriteError<E> {}

impl<E: embedded_io::Error + 'static> embedded_io::Error for WriteError<E> {
    fn kind(&self) -> embedded_io::ErrorKind {
        match self {
            Self::Encode(_) => embedded_io::ErrorKind::InvalidInput,
            Self::Io(e) => e.kind(),
            Self::WriteZero { .. } => embedded_io::ErrorKind::WriteZero,
        }
    }
}

/// Writes `frame` to `writer` in `mode` (escaped in [`ApiMode::Escaped`]), 32 bytes at
/// a time from a buffer on the stack, then flushes the writer; returns the number of
/// bytes written, as [`EncodeFrame::encoded_len`] says.
///
/// A frame that cannot be encoded ([`EncodeError::EmptyFrame`],
/// [`EncodeError::FrameTooLong`]) fails before anything is written. After a write
/// error nothing more is written and the error is returned; a writer that takes no
/// byte of a write is [`WriteError::WriteZero`] (never a panic, as `write_all` has it).
pub fn write_frame<W: embedded_io::Write>(
    writer: &mut W,
    mode: ApiMode,
    frame: &impl EncodeFrame,
) -> Result<usize, WriteError<W::Error>> {
    let mut chunk = [0u8; CHUNK];
    let mut len = 0;
    let mut sent = 0;
    let mut failed = None;
    let mut put = |byte: u8| {
        if failed.is_some() {
            return;
        }
        if let Some(slot) = chunk.get_mut(len) {
            *slot = byte;
            len += 1;
        }
        if len == CHUNK {
            match write_all(writer, &chunk, sent) {
                Ok(n) => sent = n,
                Err(e) => failed = Some(e),
            }
            len = 0;
        }
    };
    let written = frame.write_to(mode, &mut put).map_err(WriteError::Encode)?;
    if let Some(e) = failed {
        return Err(e);
    }
    write_all(writer, chunk.get(..len).unwrap_or(&[]), sent)?;
    writer.flush().map_err(WriteError::Io)?;
    Ok(written)
}

/// Writes the bytes of a frame already encoded (by [`EncodeFrame::encode`], or built
/// in its buffer by [`InPlaceFrame::finish`](crate::InPlaceFrame::finish)) to
/// `writer`, then flushes it; returns how many were written, all of them.
///
/// A writer that takes no byte of a write is [`WriteError::WriteZero`].
///
/// ```
/// use xbee_api::io::write_encoded;
/// use xbee_api::{Address64, ApiMode, InPlaceFrame, TransmitRequestRepr};
/// let mut buffer = [0u8; 64];
/// let header = TransmitRequestRepr::unicast(Address64::COORDINATOR, &[]);
/// let mut frame = InPlaceFrame::new(&mut buffer, &header)?;
/// frame.data_mut()[..2].copy_from_slice(b"m!");
/// let wire = frame.finish(2, ApiMode::Escaped)?;
///
/// let mut uart = [0u8; 64];
/// let mut out = &mut uart[..];
/// assert_eq!(write_encoded(&mut out, wire)?, wire.len());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_encoded<W: embedded_io::Write>(
    writer: &mut W,
    bytes: &[u8],
) -> Result<usize, WriteError<W::Error>> {
    let n = write_all(writer, bytes, 0)?;
    writer.flush().map_err(WriteError::Io)?;
    Ok(n)
}

/// Writes all of `bytes`, `sent` bytes of the frame having gone before; the bytes of
/// the frame sent after it.
fn write_all<W: embedded_io::Write>(
    writer: &mut W,
    mut bytes: &[u8],
    mut sent: usize,
) -> Result<usize, WriteError<W::Error>> {
    while !bytes.is_empty() {
        match writer.write(bytes).map_err(WriteError::Io)? {
            0 => return Err(WriteError::WriteZero { written: sent }),
            n => {
                bytes = bytes.get(n..).unwrap_or(&[]);
                sent += n;
            }
        }
    }
    Ok(sent)
}

/// Writes `frame` to an async `writer` in `mode`: encodes it into `buf`, then writes it
/// and flushes the writer; returns the number of bytes written.
///
/// Not cancel safe: dropped part way (in a `select` with a timer, say), it leaves part
/// of a frame on the line, and in API mode 1 the radio reads the next frame as its
/// rest. Await it to the end.
///
/// `buf` must hold the encoded frame: [`max_encoded_len`](crate::max_encoded_len) of
/// the largest frame data sizes one at compile time. A frame that does not fit, or that
/// cannot be encoded, fails with [`WriteError::Encode`] before anything is written; a
/// writer that takes no byte of a write is [`WriteError::WriteZero`].
#[cfg(feature = "embedded-io-async")]
pub async fn write_frame_async<W: embedded_io_async::Write>(
    writer: &mut W,
    mode: ApiMode,
    frame: &impl EncodeFrame,
    buf: &mut [u8],
) -> Result<usize, WriteError<W::Error>> {
    let n = frame.encode(mode, buf).map_err(WriteError::Encode)?;
    write_encoded_async(writer, buf.get(..n).unwrap_or(&[])).await
}

/// [`write_encoded`] to an async `writer`: the bytes of a frame already encoded (an
/// [`InPlaceFrame`](crate::InPlaceFrame)'s, say: the frame goes out from the buffer it
/// was built in), then a flush. Not cancel safe, as [`write_frame_async`] is not.
///
/// ```
/// # futures::executor::block_on(async {
/// use xbee_api::io::write_encoded_async;
/// use xbee_api::{Address64, ApiMode, InPlaceFrame, TransmitRequestRepr};
/// let mut buffer = [0u8; 64];
/// let header = TransmitRequestRepr::unicast(Address64::COORDINATOR, &[]);
/// let mut frame = InPlaceFrame::new(&mut buffer, &header)?;
/// frame.data_mut()[..2].copy_from_slice(b"m!");
/// let wire = frame.finish(2, ApiMode::Escaped)?;
///
/// let mut uart = [0u8; 64];
/// let mut out = &mut uart[..];
/// assert_eq!(write_encoded_async(&mut out, wire).await?, wire.len());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// # }).unwrap();
/// ```
#[cfg(feature = "embedded-io-async")]
pub async fn write_encoded_async<W: embedded_io_async::Write>(
    writer: &mut W,
    mut bytes: &[u8],
) -> Result<usize, WriteError<W::Error>> {
    let mut sent = 0;
    while !bytes.is_empty() {
        match writer.write(bytes).await.map_err(WriteError::Io)? {
            0 => return Err(WriteError::WriteZero { written: sent }),
            n => {
                bytes = bytes.get(n..).unwrap_or(&[]);
                sent += n;
            }
        }
    }
    writer.flush().await.map_err(WriteError::Io)?;
    Ok(sent)
}
