//! A frame built in its own buffer: the header written first, the payload after it by
//! the caller, then framed (and in API mode 2 escaped) where it lies.

use crate::encode::MAX_FRAME_DATA_LEN;
use crate::wire::{ESCAPE, ESCAPE_XOR, START_DELIMITER, checksum_of_sum, needs_escape, sum};
use crate::{ApiMode, EncodeError, EncodeFrame};

/// Bytes before the frame data: the start delimiter and the length.
const FRAMING: usize = 3;

/// A frame whose trailing data (a Transmit Request's RF payload, say) is written
/// straight into the buffer the frame goes out from, so that a firmware needs no
/// second buffer for the payload: [`new`](Self::new) writes the frame's header,
/// [`data_mut`](Self::data_mut) is where the payload goes (an MCP packet builder
/// writes into it), and [`finish`](Self::finish) adds the delimiter, the length and
/// the checksum, escaping the frame in place in API mode 2, and returns the bytes to
/// send (to a UART's DMA, say).
///
/// The header is any [`EncodeFrame`] whose frame data is what comes before the
/// payload: a [`TransmitRequestRepr`](crate::TransmitRequestRepr) with empty `data`
/// (any `data` it has goes before the payload). What comes out is what encoding that
/// request with the payload as its `data` gives. The mode is an [`ApiMode`], or the
/// [`Mode1`](crate::Mode1) or [`Mode2`](crate::Mode2) a decoder's type fixes.
///
/// The buffer needs room for the escaped frame:
/// [`max_encoded_len`](crate::max_encoded_len) of the header and the largest payload
/// is always enough.
///
/// ```
/// use xbee_api::{
///     Address64, ApiMode, EncodeFrame, InPlaceFrame, TransmitRequestRepr, max_encoded_len,
/// };
///
/// const MODE: ApiMode = ApiMode::Escaped;
/// const FRAME: usize = max_encoded_len(
///     TransmitRequestRepr::HEADER_LEN + TransmitRequestRepr::MAX_UNICAST_DATA,
///     MODE,
/// );
/// let mut buffer = [0u8; FRAME];
///
/// let header = TransmitRequestRepr::unicast(Address64::COORDINATOR, &[]);
/// let mut frame = InPlaceFrame::new(&mut buffer, &header)?;
/// // The payload, written where it goes out from (by an MCP packet builder, say).
/// let payload = b"m\x13 XOFF";
/// frame.data_mut()[..payload.len()].copy_from_slice(payload);
/// let wire = frame.finish(payload.len(), MODE)?;
///
/// // The bytes the request with that payload encodes to.
/// let request = TransmitRequestRepr::unicast(Address64::COORDINATOR, payload);
/// let mut expected = [0u8; FRAME];
/// let n = request.encode(MODE, &mut expected)?;
/// assert_eq!(wire, &expected[..n]);
/// # Ok::<(), xbee_api::EncodeError>(())
/// ```
pub struct InPlaceFrame<'b> {
    buf: &'b mut [u8],
    /// Length of the header's frame data.
    header: usize,
}

impl<'b> InPlaceFrame<'b> {
    /// Writes `header`'s frame data into `buf` after the room for the delimiter and the
    /// length; the payload then goes into [`data_mut`](Self::data_mut).
    ///
    /// Fails with [`EncodeError::BufferTooSmall`] when `buf` cannot hold the header and
    /// the smallest frame around it (the delimiter, the length and the checksum), with
    /// [`EncodeError::FrameTooLong`] for a header longer than [`MAX_FRAME_DATA_LEN`],
    /// and with [`EncodeError::LengthMismatch`] if `header` writes other than it
    /// announces.
    pub fn new<F: EncodeFrame + ?Sized>(
        buf: &'b mut [u8],
        header: &F,
    ) -> Result<Self, EncodeError> {
        let len = header.frame_data_len();
        if len > MAX_FRAME_DATA_LEN {
            return Err(EncodeError::FrameTooLong { len });
        }
        let needed = FRAMING + len + 1;
        if buf.len() < needed {
            return Err(EncodeError::BufferTooSmall {
                needed,
                available: buf.len(),
            });
        }
        let written = header.emit_frame_data(buf.get_mut(FRAMING..).unwrap_or_default())?;
        Ok(Self {
            buf,
            header: written,
        })
    }

    /// Where the payload goes: the buffer after the header, less the checksum's byte.
    /// In API mode 2 the frame also needs room to be escaped into: a payload that fills
    /// all of this fits only if no byte of the frame needs escaping. Write it into
    /// [`data_mut_for`](Self::data_mut_for) to be sure it fits.
    pub fn data_mut(&mut self) -> &mut [u8] {
        let end = self.buf.len().saturating_sub(1);
        self.buf
            .get_mut(FRAMING + self.header..end)
            .unwrap_or_default()
    }

    /// The start of [`data_mut`](Self::data_mut) that any payload can fill and still
    /// fit the buffer once framed in `mode`: in mode 2, as if every byte of the frame
    /// needed escaping. With a buffer of
    /// [`max_encoded_len`](crate::max_encoded_len)`(header + N, mode)` bytes, `N` bytes:
    /// an MCP packet builder given this stops where the frame would no longer fit.
    ///
    /// ```
    /// use xbee_api::{Address64, ApiMode, InPlaceFrame, TransmitRequestRepr, max_encoded_len};
    /// const FRAME: usize = max_encoded_len(TransmitRequestRepr::HEADER_LEN + 84, ApiMode::Escaped);
    /// let mut buffer = [0u8; FRAME];
    /// let header = TransmitRequestRepr::unicast(Address64::COORDINATOR, &[]);
    /// let mut frame = InPlaceFrame::new(&mut buffer, &header)?;
    /// assert_eq!(frame.data_mut_for(ApiMode::Escaped).len(), 84);
    /// assert_eq!(frame.data_mut().len(), FRAME - 4 - 14);
    /// # Ok::<(), xbee_api::EncodeError>(())
    /// ```
    ///
    /// A buffer sized for mode 2 gives more than `N` in mode 1 (nothing needs room to be
    /// escaped into): [`data_mut_capped`](Self::data_mut_capped) keeps a payload to `N`
    /// in either mode.
    pub fn data_mut_for(&mut self, mode: impl Into<ApiMode>) -> &mut [u8] {
        // Mode 2 at worst: the delimiter, then every byte after it twice.
        let frame = match mode.into() {
            ApiMode::Unescaped => self.buf.len(),
            ApiMode::Escaped => self.buf.len().saturating_sub(1) / 2 + 1,
        };
        let end = frame.saturating_sub(1).max(FRAMING + self.header);
        self.buf
            .get_mut(FRAMING + self.header..end)
            .unwrap_or_default()
    }

    /// [`data_mut_for`](Self::data_mut_for) `mode`, no longer than `max` bytes: the room
    /// for a payload that must also fit one radio packet
    /// ([`TransmitRequestRepr::MAX_UNICAST_DATA`](crate::TransmitRequestRepr::MAX_UNICAST_DATA)),
    /// from a buffer sized for the larger frames of API mode 2 or for other frames.
    ///
    /// ```
    /// use xbee_api::{Address64, ApiMode, InPlaceFrame, TransmitRequestRepr, max_encoded_len};
    /// const MAX: usize = TransmitRequestRepr::MAX_UNICAST_DATA;
    /// // Sized for mode 2, used in either mode.
    /// const FRAME: usize = max_encoded_len(TransmitRequestRepr::HEADER_LEN + MAX, ApiMode::Escaped);
    /// let mut buffer = [0u8; FRAME];
    /// let header = TransmitRequestRepr::unicast(Address64::COORDINATOR, &[]);
    /// let mut frame = InPlaceFrame::new(&mut buffer, &header)?;
    /// assert_eq!(frame.data_mut_for(ApiMode::Unescaped).len(), 185);
    /// assert_eq!(frame.data_mut_capped(ApiMode::Unescaped, MAX).len(), 84);
    /// assert_eq!(frame.data_mut_capped(ApiMode::Escaped, MAX).len(), 84);
    /// # Ok::<(), xbee_api::EncodeError>(())
    /// ```
    pub fn data_mut_capped(&mut self, mode: impl Into<ApiMode>, max: usize) -> &mut [u8] {
        let room = self.data_mut_for(mode);
        let len = room.len().min(max);
        room.get_mut(..len).unwrap_or_default()
    }

    /// Frames the header and the first `data_len` bytes of [`data_mut`](Self::data_mut)
    /// in `mode`, in place; returns the frame, from its start delimiter, as it goes on
    /// the wire.
    ///
    /// Fails with [`EncodeError::BufferTooSmall`] when the frame, escaped in mode 2,
    /// does not fit the buffer: `needed` is the buffer it takes, and the buffer then
    /// holds the frame unescaped (a `data_len` past the buffer's end gives the
    /// unescaped frame's length, at least what it takes). Fails with
    /// [`EncodeError::FrameTooLong`] when the header and `data_len` come to more than
    /// [`MAX_FRAME_DATA_LEN`], and with [`EncodeError::EmptyFrame`] for a header and a
    /// payload of no bytes at all.
    pub fn finish(
        self,
        data_len: usize,
        mode: impl Into<ApiMode>,
    ) -> Result<&'b [u8], EncodeError> {
        let mode = mode.into();
        let len = self.header.saturating_add(data_len);
        if len > MAX_FRAME_DATA_LEN {
            return Err(EncodeError::FrameTooLong { len });
        }
        if len == 0 {
            return Err(EncodeError::EmptyFrame);
        }
        // Delimiter, length, frame data, checksum.
        let plain = FRAMING + len + 1;
        if self.buf.len() < plain {
            return Err(EncodeError::BufferTooSmall {
                needed: plain,
                available: self.buf.len(),
            });
        }
        let buf = self.buf;
        let checksum = checksum_of_sum(sum(buf.get(FRAMING..FRAMING + len).unwrap_or_default()));
        if let Some([delimiter, hi, lo]) = buf.first_chunk_mut::<FRAMING>() {
            [*delimiter, *hi, *lo] = [START_DELIMITER, (len >> 8) as u8, len as u8];
        }
        if let Some(slot) = buf.get_mut(FRAMING + len) {
            *slot = checksum;
        }
        if mode == ApiMode::Unescaped {
            return Ok(buf.get(..plain).unwrap_or_default());
        }
        // Everything after the delimiter is escaped: each byte that needs it takes two.
        let escapes = buf
            .get(1..plain)
            .unwrap_or_default()
            .iter()
            .filter(|&&b| needs_escape(b))
            .count();
        let needed = plain + escapes;
        if buf.len() < needed {
            return Err(EncodeError::BufferTooSmall {
                needed,
                available: buf.len(),
            });
        }
        // From the end backwards: a byte's place once escaped is never before its place
        // now, so every byte is read before its place is written.
        let mut to = needed;
        for from in (1..plain).rev() {
            let byte = buf.get(from).copied().unwrap_or_default();
            if needs_escape(byte) {
                to = to.saturating_sub(2);
                if let Some([escape, escaped]) =
                    buf.get_mut(to..).and_then(<[u8]>::first_chunk_mut::<2>)
                {
                    [*escape, *escaped] = [ESCAPE, byte ^ ESCAPE_XOR];
                }
            } else {
                to = to.saturating_sub(1);
                if let Some(slot) = buf.get_mut(to) {
                    *slot = byte;
                }
            }
        }
        Ok(buf.get(..needed).unwrap_or_default())
    }
}

/// The header's length and the buffer's; not the buffer.
impl core::fmt::Debug for InPlaceFrame<'_> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("InPlaceFrame")
            .field("header_len", &self.header)
            .field("buffer_len", &self.buf.len())
            .finish()
    }
}
