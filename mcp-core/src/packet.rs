//! The top-level packet: any of the five categories.

use crate::{
    command::Command,
    error::{BufferTooSmall, Error, ErrorKind},
    field,
    id::Category,
    report::Report,
    telemetry::Telemetry,
    text::Text,
};

/// An MCP packet of any category.
///
/// `B` is the byte storage of the variable-length parts (telemetry records,
/// trajectory waypoints, text). [`parse`] gives `Packet<&[u8]>`, borrowing the
/// input; [`Packet::map_bytes`] moves it to owned storage.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Packet<B> {
    /// `c`: a command.
    Command(Command<B>),
    /// `t`: telemetry records.
    Telemetry(Telemetry<B>),
    /// `r`: a report.
    Report(Report<B>),
    /// `m`: a text message.
    Message(Text<B>),
    /// `w`: a warning, 8-bit text like a message.
    Warning(Text<B>),
}

impl<B> Packet<B> {
    /// A text message (`m`), as `text` holds it (8-bit characters, no terminator).
    ///
    /// ```
    /// use mcp_core::Packet;
    /// let mut buf = [0u8; 16];
    /// let len = Packet::message(&b"MAV started"[..]).encode(&mut buf)?;
    /// assert_eq!(&buf[..len], b"mMAV started");
    /// # Ok::<(), mcp_core::BufferTooSmall>(())
    /// ```
    pub const fn message(text: B) -> Self {
        Packet::Message(Text::new(text))
    }

    /// A warning (`w`), 8-bit text like a message.
    pub const fn warning(text: B) -> Self {
        Packet::Warning(Text::new(text))
    }
}

/// Parses one MCP packet (an XBee payload).
///
/// Parsing is strict: the category and the command or report type must be known and
/// the length must be exactly that of the type. Identifiers outside the tables
/// (telemetry ids, controllers, landing states) are valid and decode as `Unknown`.
/// Any non-zero on/off byte decodes as on.
///
/// It is always inlined, for the speed of a decode loop: each place that calls it
/// holds its own copy. On a Cortex-M3 (`opt-level = "s"`, LTO) a copy takes about
/// 1.3 KB of flash where only `is_ok()` of the result is used, and 2.3 to 2.9 KB where
/// the packet is, as in a firmware that acts on commands: the optimiser drops the
/// decoding of fields nothing reads. A firmware that parses in several places can call
/// it from one function of its own, marked `#[inline(never)]`, to keep a single copy.
///
/// ```
/// use mcp_core::{parse, Packet, Command, Controller};
/// let p = parse(b"c\x03\x02").unwrap();
/// assert_eq!(p, Packet::Command(Command::Controllers(Controller::Altitude)));
/// ```
// Always inline: telemetry, most of the traffic, is parsed in the caller, which sees
// the view directly instead of a 48-byte `Result` written to memory.
#[inline(always)]
pub fn parse(bytes: &[u8]) -> Result<Packet<&[u8]>, Error> {
    match bytes.split_first() {
        Some((&TELEMETRY, records)) => Telemetry::new_checked(records).map(Packet::Telemetry),
        _ => parse_other(bytes),
    }
}

/// The category byte of telemetry, `t` ([`Category::Telemetry`]).
const TELEMETRY: u8 = b't';

/// [`parse`] for every packet but telemetry, which it also parses (the same way).
///
/// `#[inline]` only makes it available to inline: a host build keeps it a call, as it
/// is too large, while the firmware (LTO, one caller) inlines it, so that the caller's
/// own match drops what it does not use.
#[inline]
fn parse_other(bytes: &[u8]) -> Result<Packet<&[u8]>, Error> {
    let Some(&category) = bytes.get(field::CATEGORY) else {
        return Err(Error::new(ErrorKind::Empty, 0));
    };
    let rest = bytes.get(field::CATEGORY + 1..).unwrap_or_default();
    Ok(match Category::from(category) {
        Category::Command => Packet::Command(Command::parse_typed(bytes)?),
        Category::Report => Packet::Report(Report::parse_typed(bytes)?),
        Category::Telemetry => Packet::Telemetry(Telemetry::new_checked(rest)?),
        Category::Message => Packet::Message(Text::new(rest)),
        Category::Warning => Packet::Warning(Text::new(rest)),
        Category::Unknown(c) => {
            return Err(Error::new(ErrorKind::UnknownCategory(c), field::CATEGORY));
        }
    })
}

impl<'a> Packet<&'a [u8]> {
    /// Parses one MCP packet; the same as [`parse`].
    #[inline]
    pub fn parse(bytes: &'a [u8]) -> Result<Self, Error> {
        parse(bytes)
    }

    /// Moves the bytes to another storage. With `bytes::Bytes`:
    /// `packet.map_bytes(|s| bytes.slice_ref(s))` keeps an owned packet without
    /// parsing again. `f` is called with sub-slices of the parsed input and is
    /// expected to return the same bytes.
    pub fn map_bytes<U: AsRef<[u8]>>(self, f: impl FnMut(&'a [u8]) -> U) -> Packet<U> {
        let mut f = f;
        match self {
            Packet::Command(c) => Packet::Command(c.map_bytes(&mut f)),
            Packet::Telemetry(t) => Packet::Telemetry(t.map_bytes(&mut f)),
            Packet::Report(r) => Packet::Report(r.map_bytes(&mut f)),
            Packet::Message(t) => Packet::Message(t.map_bytes(&mut f)),
            Packet::Warning(t) => Packet::Warning(t.map_bytes(&mut f)),
        }
    }
}

impl<B: AsRef<[u8]>> Packet<B> {
    /// The packet category.
    pub fn category(&self) -> Category {
        match self {
            Packet::Command(_) => Category::Command,
            Packet::Telemetry(_) => Category::Telemetry,
            Packet::Report(_) => Category::Report,
            Packet::Message(_) => Category::Message,
            Packet::Warning(_) => Category::Warning,
        }
    }

    /// The packet length.
    pub fn encoded_len(&self) -> usize {
        match self {
            Packet::Command(c) => c.encoded_len(),
            Packet::Telemetry(t) => t.encoded_len(),
            Packet::Report(r) => r.encoded_len(),
            Packet::Message(t) | Packet::Warning(t) => t.encoded_len(),
        }
    }

    /// Writes the packet into `buf`, returning its length (`encoded_len()`). In
    /// firmware, take the packet as `buf.get(..len)`: `&buf[..len]` keeps a bounds check
    /// that the compiler cannot always drop, and so a panic path.
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, BufferTooSmall> {
        match self {
            Packet::Command(c) => c.encode(buf),
            Packet::Telemetry(t) => t.encode(buf),
            Packet::Report(r) => r.encode(buf),
            Packet::Message(t) => t.encode_as(Category::Message, buf),
            Packet::Warning(t) => t.encode_as(Category::Warning, buf),
        }
    }

    /// A packet borrowing this one's bytes.
    pub fn as_borrowed(&self) -> Packet<&[u8]> {
        match self {
            Packet::Command(c) => Packet::Command(c.as_borrowed()),
            Packet::Telemetry(t) => Packet::Telemetry(t.as_borrowed()),
            Packet::Report(r) => Packet::Report(r.as_borrowed()),
            Packet::Message(t) => Packet::Message(t.as_borrowed()),
            Packet::Warning(t) => Packet::Warning(t.as_borrowed()),
        }
    }
}

impl<B> From<Command<B>> for Packet<B> {
    fn from(value: Command<B>) -> Self {
        Packet::Command(value)
    }
}

impl<B> From<Report<B>> for Packet<B> {
    fn from(value: Report<B>) -> Self {
        Packet::Report(value)
    }
}

impl<B> From<Telemetry<B>> for Packet<B> {
    fn from(value: Telemetry<B>) -> Self {
        Packet::Telemetry(value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The inline telemetry path gives exactly what the general path gives, on
    /// every short input and on telemetry-like inputs of every length up to 255.
    #[test]
    fn fast_path_agrees_with_general_path() {
        let mut buf = [0u8; 255];
        for a in 0..=255u8 {
            for b in 0..=255u8 {
                let bytes = [a, b];
                for n in 0..=2 {
                    assert_eq!(parse(&bytes[..n]), parse_other(&bytes[..n]));
                }
            }
        }
        for category in [b't', b'c', b'r', b'm', b'w', 0] {
            buf[0] = category;
            for (i, byte) in buf.iter_mut().enumerate().skip(1) {
                *byte = i as u8;
            }
            for n in 0..=buf.len() {
                assert_eq!(parse(&buf[..n]), parse_other(&buf[..n]));
            }
        }
    }
}
