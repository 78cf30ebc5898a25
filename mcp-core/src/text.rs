//! Message and warning text (`m` and `w`, table 24).

use core::fmt;

use crate::{error::BufferTooSmall, id::Category, write::Writer};

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
