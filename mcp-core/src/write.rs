//! A bounds-checked output cursor for the encoders.

use crate::MAX_PAYLOAD;
use crate::error::BufferTooSmall;
use crate::id::Category;

/// `buf` as the room of a packet of `category` built item by item: its category byte
/// written, and cut at the 255-byte payload limit ([`MAX_PAYLOAD`]). Fails if `buf` is
/// empty.
pub(crate) fn packet_room(buf: &mut [u8], category: Category) -> Result<&mut [u8], BufferTooSmall> {
    let available = buf.len();
    let first = buf.first_mut().ok_or(BufferTooSmall {
        needed: 1,
        available,
    })?;
    *first = category.into();
    Ok(buf
        .get_mut(..available.min(MAX_PAYLOAD))
        .unwrap_or_default())
}

/// Writes a packet of known length into a caller buffer.
pub(crate) struct Writer<'a> {
    buf: &'a mut [u8],
    pos: usize,
    overflow: bool,
}

impl<'a> Writer<'a> {
    /// Starts a packet of `len` bytes, failing if `buf` cannot hold it.
    pub(crate) fn new(buf: &'a mut [u8], len: usize) -> Result<Self, BufferTooSmall> {
        if buf.len() < len {
            return Err(BufferTooSmall {
                needed: len,
                available: buf.len(),
            });
        }
        Ok(Writer {
            buf,
            pos: 0,
            overflow: false,
        })
    }

    /// Appends bytes.
    pub(crate) fn bytes(&mut self, data: &[u8]) -> &mut Self {
        // Sliced as `[pos..][..len]` so that the compiler sees the destination is exactly
        // `data.len()` long: `copy_from_slice` then keeps no panic path (a range ending
        // at `pos + len` did, behind the saturating add).
        let dst = self
            .buf
            .get_mut(self.pos..)
            .and_then(|rest| rest.get_mut(..data.len()));
        match dst {
            Some(dst) => {
                dst.copy_from_slice(data);
                self.pos += data.len();
            }
            None => self.overflow = true,
        }
        self
    }

    /// Appends one byte.
    pub(crate) fn u8(&mut self, value: u8) -> &mut Self {
        self.bytes(&[value])
    }

    /// Appends a little-endian `u32`.
    pub(crate) fn u32(&mut self, value: u32) -> &mut Self {
        self.bytes(&value.to_le_bytes())
    }

    /// Appends a little-endian binary32.
    pub(crate) fn f32(&mut self, value: f32) -> &mut Self {
        self.bytes(&value.to_le_bytes())
    }

    /// Appends an on/off byte (0x00 or 0x01).
    pub(crate) fn on_off(&mut self, on: bool) -> &mut Self {
        self.u8(u8::from(on))
    }

    /// The number of bytes written, or an error if a write did not fit (which the
    /// length given to [`Writer::new`] rules out when it is right).
    pub(crate) fn finish(&self) -> Result<usize, BufferTooSmall> {
        if self.overflow {
            Err(BufferTooSmall {
                needed: self.buf.len() + 1,
                available: self.buf.len(),
            })
        } else {
            Ok(self.pos)
        }
    }
}
