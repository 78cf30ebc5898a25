//! Encoding frames to the wire: length, checksum and, in API mode 2, escaping.

use crate::wire::{ESCAPE, ESCAPE_XOR, START_DELIMITER, checksum_of_sum, needs_escape, sum};
use crate::{ApiMode, EncodeError};

/// Largest frame data length the 16-bit length field can carry, and so the largest the
/// encoder accepts. Radios take far less (frame data tops out near 273 bytes,
/// [`ExplicitRxIndicatorRepr::MAX_LEN`](crate::ExplicitRxIndicatorRepr::MAX_LEN)), but
/// the encoder only enforces what the wire format can express: size buffers for
/// received frames by that, not by this.
pub const MAX_FRAME_DATA_LEN: usize = 0xFFFF;

/// The most bytes a frame with `frame_data_len` bytes of frame data takes on the wire
/// in `mode`: exact in mode 1; in mode 2 as if every byte after the delimiter were
/// escaped. For buffers sized at compile time; [`EncodeFrame::encoded_len`] is exact.
/// Code generic over the mode's type cannot size an array with `M::MODE` on stable
/// Rust: it sizes for [`ApiMode::Escaped`], the larger.
///
/// ```
/// use xbee_api::{ApiMode, TransmitRequestRepr, max_encoded_len};
/// // A buffer for any Transmit Request of an unfragmented unicast, in API mode 2.
/// const LEN: usize = max_encoded_len(
///     TransmitRequestRepr::HEADER_LEN + TransmitRequestRepr::MAX_UNICAST_DATA,
///     ApiMode::Escaped,
/// );
/// let buffer = [0u8; LEN];
/// assert_eq!(buffer.len(), 1 + 2 * (2 + 98 + 1));
/// assert_eq!(max_encoded_len(98, ApiMode::Unescaped), 102);
/// // A length no buffer holds: no overflow.
/// assert_eq!(max_encoded_len(usize::MAX / 2, ApiMode::Escaped), usize::MAX);
/// ```
pub const fn max_encoded_len(frame_data_len: usize, mode: ApiMode) -> usize {
    // Delimiter, length (2), frame data, checksum; `usize::MAX` for a length no buffer
    // holds, rather than an overflow.
    match mode {
        ApiMode::Unescaped => frame_data_len.saturating_add(4),
        ApiMode::Escaped => frame_data_len
            .saturating_add(3)
            .saturating_mul(2)
            .saturating_add(1),
    }
}

/// Anything that can be written as the frame data of an API frame: typed `*Repr`s,
/// [`Frame`](crate::Frame) and [`RawFrame`](crate::RawFrame).
///
/// Implementors give the unescaped frame data (type byte first) as a sequence of chunks;
/// the provided methods add the start delimiter, the length, the checksum and escaping.
///
/// ```
/// use xbee_api::{ApiMode, EncodeFrame, ModemStatus, ModemStatusRepr};
/// let frame = ModemStatusRepr { status: ModemStatus::CoordinatorStarted };
/// let mut buf = [0u8; 8];
/// let n = frame.encode(ApiMode::Unescaped, &mut buf).unwrap();
/// assert_eq!(&buf[..n], &[0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F]);
/// assert_eq!(frame.encoded_len(ApiMode::Escaped), 6);
/// ```
pub trait EncodeFrame {
    /// Length of the frame data (type byte included): the value of the length field.
    fn frame_data_len(&self) -> usize;

    /// Calls `out` with the unescaped frame data, in order, in one or more chunks whose
    /// lengths add up to [`frame_data_len`](Self::frame_data_len).
    fn write_frame_data<F: FnMut(&[u8])>(&self, out: &mut F);

    /// Exact number of bytes [`encode`](Self::encode) writes in `mode`.
    fn encoded_len(&self, mode: ApiMode) -> usize {
        let len = self.frame_data_len();
        match mode {
            ApiMode::Unescaped => len + 4,
            ApiMode::Escaped => {
                let mut total = 1;
                let mut s = 0u8;
                let [hi, lo] = (len as u16).to_be_bytes();
                total += escaped_len(&[hi, lo]);
                self.write_frame_data(&mut |chunk: &[u8]| {
                    total += escaped_len(chunk);
                    s = s.wrapping_add(sum(chunk));
                });
                total + escaped_len(&[checksum_of_sum(s)])
            }
        }
    }

    /// Encodes the whole frame (delimiter, length, frame data, checksum) into the start
    /// of `buf`, escaped in [`ApiMode::Escaped`]; returns the number of bytes written.
    /// In firmware, take the frame as `buf.get(..n)`: `&buf[..n]` keeps a bounds check
    /// that the compiler cannot always drop, and so a panic path.
    ///
    /// Fails with [`EncodeError::BufferTooSmall`] when `buf` is shorter than
    /// [`encoded_len`](Self::encoded_len) (nothing useful is written then), with
    /// [`EncodeError::FrameTooLong`] above [`MAX_FRAME_DATA_LEN`], and with
    /// [`EncodeError::EmptyFrame`] for no frame data at all.
    fn encode(&self, mode: ApiMode, buf: &mut [u8]) -> Result<usize, EncodeError> {
        let len = self.frame_data_len();
        if len > MAX_FRAME_DATA_LEN {
            return Err(EncodeError::FrameTooLong { len });
        }
        if len == 0 {
            return Err(EncodeError::EmptyFrame);
        }
        let needed = self.encoded_len(mode);
        if buf.len() < needed {
            return Err(EncodeError::BufferTooSmall {
                needed,
                available: buf.len(),
            });
        }
        let mut w = Writer {
            buf,
            pos: 1,
            escape: mode == ApiMode::Escaped,
            overflow: false,
        };
        // Always there: the length check above found room for the whole frame.
        if let Some(first) = w.buf.first_mut() {
            *first = START_DELIMITER;
        }
        w.put(&(len as u16).to_be_bytes());
        let mut s = 0u8;
        let mut written = 0usize;
        self.write_frame_data(&mut |chunk: &[u8]| {
            s = s.wrapping_add(sum(chunk));
            written += chunk.len();
            w.put(chunk);
        });
        w.put(&[checksum_of_sum(s)]);
        if written != len || w.overflow {
            return Err(EncodeError::LengthMismatch {
                announced: len,
                written,
            });
        }
        Ok(w.pos)
    }

    /// Writes the whole frame a byte at a time to `out`, escaped in
    /// [`ApiMode::Escaped`], without a buffer of its own: straight into a UART's transmit
    /// register or a ring buffer. Returns the number of bytes written, as
    /// [`encoded_len`](Self::encoded_len) says.
    ///
    /// Fails before writing anything with [`EncodeError::FrameTooLong`] or
    /// [`EncodeError::EmptyFrame`]; with [`EncodeError::LengthMismatch`] (after
    /// writing) if the implementation wrote other than it announced.
    ///
    /// ```
    /// use xbee_api::{ApiMode, EncodeFrame, ModemStatus, ModemStatusRepr};
    /// let frame = ModemStatusRepr { status: ModemStatus::from(0x11) };
    /// let mut uart = Vec::new();
    /// let n = frame.write_to(ApiMode::Escaped, |byte| uart.push(byte))?;
    /// assert_eq!(uart, [0x7E, 0x00, 0x02, 0x8A, 0x7D, 0x31, 0x64]);
    /// assert_eq!(n, uart.len());
    /// # Ok::<(), xbee_api::EncodeError>(())
    /// ```
    fn write_to<W: FnMut(u8)>(&self, mode: ApiMode, out: W) -> Result<usize, EncodeError> {
        let len = self.frame_data_len();
        if len > MAX_FRAME_DATA_LEN {
            return Err(EncodeError::FrameTooLong { len });
        }
        if len == 0 {
            return Err(EncodeError::EmptyFrame);
        }
        let mut sink = Sink {
            out,
            escape: mode == ApiMode::Escaped,
            written: 0,
        };
        (sink.out)(START_DELIMITER);
        sink.written = 1;
        for b in (len as u16).to_be_bytes() {
            sink.byte(b);
        }
        let mut s = 0u8;
        let mut data = 0usize;
        self.write_frame_data(&mut |chunk: &[u8]| {
            s = s.wrapping_add(sum(chunk));
            data += chunk.len();
            for &b in chunk {
                sink.byte(b);
            }
        });
        sink.byte(checksum_of_sum(s));
        if data != len {
            return Err(EncodeError::LengthMismatch {
                announced: len,
                written: data,
            });
        }
        Ok(sink.written)
    }

    /// Writes the unescaped frame data alone (no delimiter, length or checksum) into the
    /// start of `buf`; returns its length.
    fn emit_frame_data(&self, buf: &mut [u8]) -> Result<usize, EncodeError> {
        let len = self.frame_data_len();
        if buf.len() < len {
            return Err(EncodeError::BufferTooSmall {
                needed: len,
                available: buf.len(),
            });
        }
        let mut w = Writer {
            buf,
            pos: 0,
            escape: false,
            overflow: false,
        };
        self.write_frame_data(&mut |chunk: &[u8]| w.put(chunk));
        if w.pos != len || w.overflow {
            return Err(EncodeError::LengthMismatch {
                announced: len,
                written: w.pos,
            });
        }
        Ok(len)
    }
}

/// Length of `bytes` once escaped for API mode 2.
fn escaped_len(bytes: &[u8]) -> usize {
    bytes.len() + bytes.iter().filter(|b| needs_escape(**b)).count()
}

/// Byte output of [`EncodeFrame::write_to`]: escapes in mode 2 and counts.
struct Sink<W> {
    out: W,
    escape: bool,
    written: usize,
}

impl<W: FnMut(u8)> Sink<W> {
    fn byte(&mut self, b: u8) {
        if self.escape && needs_escape(b) {
            (self.out)(ESCAPE);
            (self.out)(b ^ ESCAPE_XOR);
            self.written += 2;
        } else {
            (self.out)(b);
            self.written += 1;
        }
    }
}

/// Bounds-checked output cursor; a write past the end sets `overflow` instead of
/// panicking.
struct Writer<'b> {
    buf: &'b mut [u8],
    pos: usize,
    escape: bool,
    overflow: bool,
}

impl Writer<'_> {
    fn put(&mut self, bytes: &[u8]) {
        if !self.escape {
            match self.buf.get_mut(self.pos..self.pos + bytes.len()) {
                Some(dst) => {
                    dst.copy_from_slice(bytes);
                    self.pos += bytes.len();
                }
                None => self.overflow = true,
            }
            return;
        }
        for &b in bytes {
            if needs_escape(b) {
                self.byte(ESCAPE);
                self.byte(b ^ ESCAPE_XOR);
            } else {
                self.byte(b);
            }
        }
    }

    fn byte(&mut self, b: u8) {
        match self.buf.get_mut(self.pos) {
            Some(slot) => {
                *slot = b;
                self.pos += 1;
            }
            None => self.overflow = true,
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::{vec, vec::Vec};

    use super::*;
    use crate::RawFrame;

    #[test]
    fn escapes_length_type_and_checksum() {
        // Unknown frame type 0x23 with data 0x11, from Digi's manual.
        let raw = RawFrame::new(&[0x23, 0x11]).unwrap();
        let mut buf = [0u8; 16];
        let n = raw.encode(ApiMode::Unescaped, &mut buf).unwrap();
        assert_eq!(&buf[..n], &[0x7E, 0x00, 0x02, 0x23, 0x11, 0xCB]);
        let n = raw.encode(ApiMode::Escaped, &mut buf).unwrap();
        assert_eq!(&buf[..n], &[0x7E, 0x00, 0x02, 0x23, 0x7D, 0x31, 0xCB]);
        assert_eq!(raw.encoded_len(ApiMode::Escaped), 7);
    }

    #[test]
    fn buffer_too_small_is_exact() {
        let raw = RawFrame::new(&[0x8A, 0x7E]).unwrap();
        let needed = raw.encoded_len(ApiMode::Escaped);
        let mut buf = [0u8; 32];
        assert_eq!(
            raw.encode(ApiMode::Escaped, &mut buf[..needed - 1]),
            Err(EncodeError::BufferTooSmall {
                needed,
                available: needed - 1
            })
        );
        assert_eq!(raw.encode(ApiMode::Escaped, &mut buf[..needed]), Ok(needed));
    }

    struct Liar;

    impl EncodeFrame for Liar {
        fn frame_data_len(&self) -> usize {
            1
        }
        fn write_frame_data<F: FnMut(&[u8])>(&self, out: &mut F) {
            out(&[1, 2, 3, 4, 5, 6, 7, 8]);
        }
    }

    #[test]
    fn inconsistent_writer_is_an_error_not_a_panic() {
        let mut buf = [0u8; 6];
        assert!(matches!(
            Liar.encode(ApiMode::Unescaped, &mut buf),
            Err(EncodeError::LengthMismatch { announced: 1, .. })
        ));
        assert!(Liar.emit_frame_data(&mut buf).is_err());
        assert!(matches!(
            Liar.write_to(ApiMode::Unescaped, |_| {}),
            Err(EncodeError::LengthMismatch {
                announced: 1,
                written: 8
            })
        ));
    }

    /// Announces more frame data than it writes.
    struct Short;

    impl EncodeFrame for Short {
        fn frame_data_len(&self) -> usize {
            4
        }
        fn write_frame_data<F: FnMut(&[u8])>(&self, out: &mut F) {
            out(&[1, 2]);
        }
    }

    #[test]
    fn a_writer_short_of_its_length_is_an_error_not_a_frame_with_a_false_length() {
        let short = Err(EncodeError::LengthMismatch {
            announced: 4,
            written: 2,
        });
        for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
            let mut buf = [0u8; 16];
            assert_eq!(Short.encode(mode, &mut buf), short);
            assert_eq!(Short.write_to(mode, |_| {}), short);
        }
        assert_eq!(Short.emit_frame_data(&mut [0u8; 16]), short);
    }

    struct Nothing;

    impl EncodeFrame for Nothing {
        fn frame_data_len(&self) -> usize {
            0
        }
        fn write_frame_data<F: FnMut(&[u8])>(&self, _: &mut F) {}
    }

    #[test]
    fn no_frame_data_is_an_error_not_a_frame_radios_drop() {
        let mut buf = [0u8; 8];
        for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
            assert_eq!(Nothing.encode(mode, &mut buf), Err(EncodeError::EmptyFrame));
            let mut out = 0;
            assert_eq!(
                Nothing.write_to(mode, |_| out += 1),
                Err(EncodeError::EmptyFrame)
            );
            assert_eq!(out, 0, "nothing written");
        }
    }

    #[test]
    fn too_long() {
        let data = [0u8; MAX_FRAME_DATA_LEN + 1];
        let raw = RawFrame::new(&data).unwrap();
        let mut buf = [0u8; 8];
        let too_long = Err(EncodeError::FrameTooLong { len: data.len() });
        for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
            assert_eq!(raw.encode(mode, &mut buf), too_long);
            let mut written = 0usize;
            assert_eq!(raw.write_to(mode, |_| written += 1), too_long);
            assert_eq!(written, 0, "bytes written of a frame refused");
        }
    }

    #[test]
    fn the_longest_frame_data_encodes_with_length_ffff() {
        let mut data = vec![0u8; MAX_FRAME_DATA_LEN];
        data[0] = 0x10;
        let raw = RawFrame::new(&data).unwrap();
        for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
            let mut buf = vec![0u8; raw.encoded_len(mode)];
            let n = raw.encode(mode, &mut buf).unwrap();
            assert_eq!(n, buf.len());
            assert_eq!(buf[..3], [START_DELIMITER, 0xFF, 0xFF]);
            let mut out = Vec::new();
            assert_eq!(raw.write_to(mode, |byte| out.push(byte)), Ok(n));
            assert_eq!(out, buf);
        }
    }
}
