//! Message and warning text (`m` and `w`, table 24).

use core::fmt;

use crate::{
    error::{BufferTooSmall, Full},
    id::Category,
    write::{Writer, packet_room},
};

/// The text of a message or warning packet: the bytes after the category, 8-bit
/// characters with no terminator. Any bytes are valid, including none and bytes
/// >= 0x80.
///
/// `Display` is lossless and plain ASCII: printable ASCII as is, a backslash as
/// `\\`, every other byte as `\xNN`.
///
/// ```
/// use mcp_core::Text;
/// let t = Text::new(&b"caf\xe9 \\ ok\n"[..]);
/// assert_eq!(t.to_string(), r"caf\xe9 \\ ok\x0a");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Text<B> {
    bytes: B,
}

impl<B> Text<B> {
    /// Wraps text bytes.
    pub const fn new(bytes: B) -> Self {
        Text { bytes }
    }

    /// The text bytes.
    pub fn into_inner(self) -> B {
        self.bytes
    }
}

impl<B: AsRef<[u8]>> Text<B> {
    /// The text bytes.
    pub fn as_bytes(&self) -> &[u8] {
        self.bytes.as_ref()
    }

    /// The text as `&str`, if it is valid UTF-8 (plain ASCII always is).
    pub fn as_str(&self) -> Option<&str> {
        core::str::from_utf8(self.as_bytes()).ok()
    }

    /// The number of bytes.
    pub fn len(&self) -> usize {
        self.as_bytes().len()
    }

    /// `true` if the text has no byte.
    pub fn is_empty(&self) -> bool {
        self.as_bytes().is_empty()
    }

    /// The text between double quotes, as a message packet shows it: escaped as by
    /// `Display`, and each `"` as `\"`, so that it reads back unambiguously.
    ///
    /// ```
    /// use mcp_core::Text;
    /// let t = Text::new(&b"say \"hi\" \\ \xe9"[..]);
    /// assert_eq!(t.quoted().to_string(), r#""say \"hi\" \\ \xe9""#);
    /// ```
    pub fn quoted(&self) -> Quoted<'_, B> {
        Quoted(self)
    }

    /// The length of a message or warning packet carrying this text.
    pub fn encoded_len(&self) -> usize {
        1 + self.len()
    }

    /// Writes a packet of `category` (message or warning) carrying the text.
    pub(crate) fn encode_as(
        &self,
        category: Category,
        buf: &mut [u8],
    ) -> Result<usize, BufferTooSmall> {
        Writer::new(buf, self.encoded_len())?
            .u8(category.into())
            .bytes(self.as_bytes())
            .finish()
    }

    /// A view borrowing this one's bytes.
    pub fn as_borrowed(&self) -> Text<&[u8]> {
        Text::new(self.as_bytes())
    }
}

impl<'a> Text<&'a [u8]> {
    /// Moves the bytes to another storage, e.g. `|s| bytes.slice_ref(s)`.
    pub fn map_bytes<U>(self, f: impl FnOnce(&'a [u8]) -> U) -> Text<U> {
        Text::new(f(self.bytes))
    }
}

/// Builds a message (`m`) or warning (`w`) packet in a caller buffer, from bytes or
/// from formatted text (`write!`, as it implements [`fmt::Write`]), cut at the end of
/// the buffer or at the 255-byte XBee payload limit
/// ([`MAX_PAYLOAD`](crate::MAX_PAYLOAD)). A firmware says what it could not take
/// without a buffer of its own for the text:
///
/// ```
/// use core::fmt::Write as _;
/// use mcp_core::{Packet, TextBuilder, parse};
///
/// let mut buf = [0u8; 84];
/// let error = parse(b"c\x02").unwrap_err();
/// let mut text = TextBuilder::warning(&mut buf).unwrap();
/// let _ = write!(text, "{error}"); // `Err` if the text was cut: what fits is written
/// let len = text.finish();
/// let Some(packet) = buf.get(..len) else { return };
/// assert_eq!(packet, b"wwrong length for landing command: expected 3 bytes, got 2 (at offset 2)");
/// assert!(matches!(parse(packet), Ok(Packet::Warning(_))));
/// ```
///
/// Formatting costs flash: `core::fmt`, and for an error's message the texts of every
/// error it can be. In a small Cortex-M3 MAV firmware (`opt-level = "s"`, LTO), a
/// warning written as `write!(text, "{error}")` took 5.4 KB more than one of two bytes
/// pushed, the error's [`code`](crate::Error::code) and
/// [`offset`](crate::Error::offset); 3.8 KB more where `core::fmt` was linked already.
#[derive(Debug)]
pub struct TextBuilder<'a> {
    buf: &'a mut [u8],
    len: usize,
}

impl<'a> TextBuilder<'a> {
    /// Starts a message packet in `buf` (writes the `m`). Fails if `buf` is empty.
    pub fn message(buf: &'a mut [u8]) -> Result<Self, BufferTooSmall> {
        Self::new(buf, Category::Message)
    }

    /// Starts a warning packet in `buf` (writes the `w`). Fails if `buf` is empty.
    pub fn warning(buf: &'a mut [u8]) -> Result<Self, BufferTooSmall> {
        Self::new(buf, Category::Warning)
    }

    fn new(buf: &'a mut [u8], category: Category) -> Result<Self, BufferTooSmall> {
        Ok(TextBuilder {
            buf: packet_room(buf, category)?,
            len: 1,
        })
    }

    /// Appends `bytes`, as many as fit: [`Full`] if some did not (the packet then holds
    /// those that did, and is whole).
    ///
    /// ```
    /// use mcp_core::{Full, TextBuilder};
    /// let mut buf = [0u8; 6];
    /// let mut text = TextBuilder::message(&mut buf).unwrap();
    /// assert_eq!(text.push(b"abc"), Ok(()));
    /// assert_eq!(text.push(b"defg"), Err(Full));
    /// assert_eq!(text.as_bytes(), b"mabcde");
    /// ```
    pub fn push(&mut self, bytes: &[u8]) -> Result<(), Full> {
        let room = self.buf.get_mut(self.len..).unwrap_or_default();
        let n = bytes.len().min(room.len());
        if let (Some(dst), Some(src)) = (room.get_mut(..n), bytes.get(..n)) {
            dst.copy_from_slice(src);
        }
        self.len += n;
        if n < bytes.len() { Err(Full) } else { Ok(()) }
    }

    /// The number of text bytes written (the packet's length less its category byte).
    pub fn text_len(&self) -> usize {
        self.len - 1
    }

    /// The packet written so far.
    pub fn as_bytes(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or_default()
    }

    /// Ends the packet, returning its length: the packet is `buf.get(..len)` (rather
    /// than `&buf[..len]`, whose bounds check the compiler cannot always drop, and so a
    /// panic path in firmware).
    pub fn finish(self) -> usize {
        self.len
    }
}

/// Appends the text as [`push`](TextBuilder::push) does, failing with [`fmt::Error`]
/// (which stops a `write!`) once it was cut.
impl fmt::Write for TextBuilder<'_> {
    fn write_str(&mut self, s: &str) -> fmt::Result {
        self.push(s.as_bytes()).map_err(|Full| fmt::Error)
    }
}

/// A [`Text`] between double quotes, from [`Text::quoted`].
#[derive(Debug, Clone, Copy)]
pub struct Quoted<'a, B>(pub(crate) &'a Text<B>);

impl<B: AsRef<[u8]>> fmt::Display for Text<B> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let bytes = self.as_bytes();
        let mut start = 0;
        for (i, &b) in bytes.iter().enumerate() {
            if b == b'\\' || !(0x20..0x7F).contains(&b) {
                // Everything before `i` is printable ASCII, hence valid UTF-8.
                f.write_str(printable(bytes.get(start..i)))?;
                if b == b'\\' {
                    f.write_str("\\\\")?;
                } else {
                    write!(f, "\\x{b:02x}")?;
                }
                start = i + 1;
            }
        }
        f.write_str(printable(bytes.get(start..)))
    }
}

/// A run of printable ASCII as text (empty for `None`, which the caller never passes).
fn printable(run: Option<&[u8]>) -> &str {
    run.and_then(|run| core::str::from_utf8(run).ok())
        .unwrap_or_default()
}
