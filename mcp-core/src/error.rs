//! Errors: why a packet was rejected, and why an encoder stopped.

use core::fmt;

use crate::id::{Category, CommandType};

/// Why a packet failed to parse, and at which byte offset.
///
/// Its `Display` says both in words, and costs a firmware that formats it several
/// kilobytes of flash ([`TextBuilder`](crate::TextBuilder) has a measure); the one-byte
/// [`code`](Self::code) and the [`offset`](Self::offset) say the same in two bytes.
///
/// ```
/// use mcp_core::{parse, ErrorKind};
/// let err = parse(b"c\x02\x01\x00").unwrap_err();
/// assert!(matches!(err.kind(), ErrorKind::WrongLength { got: 4, .. }));
/// assert_eq!(err.offset(), 3);
/// assert_eq!(
///     err.to_string(),
///     "wrong length for landing command: expected 3 bytes, got 4 (at offset 3)"
/// );
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[error("{kind} (at offset {offset})")]
pub struct Error {
    kind: ErrorKind,
    offset: usize,
}

impl Error {
    /// An error of `kind` found at byte `offset` of the packet (0: the category byte).
    pub fn new(kind: ErrorKind, offset: usize) -> Self {
        Error { kind, offset }
    }

    /// What was wrong.
    pub fn kind(&self) -> &ErrorKind {
        &self.kind
    }

    /// The one-byte code of its [`kind`](Self::kind) ([`ErrorKind::code`]).
    pub const fn code(&self) -> u8 {
        self.kind.code()
    }

    /// The byte offset in the packet at which the problem was found, counted from 0 (the
    /// category byte; the specification's tables count from 1). For a length
    /// error this is the first missing or the first extra byte.
    pub fn offset(&self) -> usize {
        self.offset
    }
}

/// That `bytes` is a packet of the category `expected`: [`ErrorKind::WrongCategory`]
/// (or [`ErrorKind::Empty`]) if not.
pub(crate) fn check_category(bytes: &[u8], expected: Category) -> Result<(), Error> {
    match bytes.first() {
        None => Err(Error::new(ErrorKind::Empty, 0)),
        Some(&found) if Category::from(found) == expected => Ok(()),
        Some(&found) => Err(Error::new(ErrorKind::WrongCategory { expected, found }, 0)),
    }
}

/// What was wrong with a packet.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ErrorKind {
    /// The packet has no bytes at all.
    Empty,
    /// The first byte is not a known packet category.
    UnknownCategory(u8),
    /// A command or report packet ends before its type byte.
    MissingType(Category),
    /// The type byte of a command or report is not a known type for that category.
    UnknownType {
        /// Command or report.
        category: Category,
        /// The type byte.
        value: u8,
    },
    /// The packet length does not fit its type.
    WrongLength {
        /// The packet's category.
        category: Category,
        /// The command or report type, if the category has types.
        packet_type: Option<CommandType>,
        /// Whether the packet's byte 3 is 0xFF, the status request's. For most types
        /// the packet can then only be a status request, and `expected` is
        /// [`Expected::Exactly`] its length. Time and position slave set commands may
        /// also hold 0xFF there as data (a time's low byte, an address's high byte):
        /// `expected` is then [`Expected::Either`] the status request's length or the
        /// set command's, and the message says "command or its status request".
        status_request: bool,
        /// The lengths the type allows.
        expected: Expected,
        /// The length of the packet.
        got: usize,
    },
    /// A trajectory packet's size byte does not match the number of waypoints the
    /// length holds.
    SizeMismatch {
        /// The size byte.
        size: u8,
        /// The number of waypoints that the packet length holds.
        waypoints: usize,
    },
    /// A trajectory packet holds more than 254 waypoints (size 0xFF): a report read by
    /// [`parse`](crate::Packet::parse), or waypoints checked on their own
    /// ([`Waypoints::new_checked`](crate::Waypoints::new_checked)). In a command, size
    /// 0xFF is the trajectory status request (`c 04 FF`), and
    /// [`WrongLength`](Self::WrongLength) with bytes after it.
    TooManyWaypoints(usize),
    /// A firmware-form position slave set command names a slot other than 0-3.
    InvalidSlot(u8),
    /// [`Command::parse`](crate::Command::parse) or
    /// [`Report::parse`](crate::Report::parse) was given a packet of another category:
    /// a report is no command, however its bytes read.
    WrongCategory {
        /// The category the parser reads.
        expected: Category,
        /// The packet's category byte.
        found: u8,
    },
    /// A controllers report names controller 0xFF, outside the identifiers a
    /// controller can have (0x00-0xFE, table 20): in a command that byte is the
    /// status request.
    InvalidController(u8),
}

impl ErrorKind {
    /// A one-byte code of the error's kind, without its values:
    ///
    /// | code | error |
    /// |---|---|
    /// | 0x41 | [`Empty`](Self::Empty) |
    /// | 0x42 | [`UnknownCategory`](Self::UnknownCategory) |
    /// | 0x43 | [`MissingType`](Self::MissingType) |
    /// | 0x44 | [`UnknownType`](Self::UnknownType) |
    /// | 0x45 | [`WrongLength`](Self::WrongLength) |
    /// | 0x46 | [`SizeMismatch`](Self::SizeMismatch) |
    /// | 0x47 | [`TooManyWaypoints`](Self::TooManyWaypoints) |
    /// | 0x48 | [`InvalidSlot`](Self::InvalidSlot) |
    /// | 0x49 | [`WrongCategory`](Self::WrongCategory) |
    /// | 0x4A | [`InvalidController`](Self::InvalidController) |
    /// | 0x50 | [`BufferTooSmall`] (its own type: [`BufferTooSmall::CODE`]) |
    /// | 0x51 | [`Full`] (its own type: [`Full::CODE`]) |
    ///
    /// Codes are stable (one is never given to another error) and unique across
    /// `mcp-core` (0x40-0x7F) and `xbee-api` (0x01-0x3F, as its `DecodeError::code`
    /// says), 0 being left for "no error": one byte says which error it was, for a
    /// debug UART or a status register, without the flash that formatting the message
    /// takes.
    ///
    /// ```
    /// use mcp_core::parse;
    /// let error = parse(b"c\x02\x01\x00").unwrap_err();
    /// assert_eq!(error.code(), 0x45); // wrong length
    /// assert_eq!(error.offset(), 3);
    /// ```
    pub const fn code(&self) -> u8 {
        match self {
            ErrorKind::Empty => 0x41,
            ErrorKind::UnknownCategory(_) => 0x42,
            ErrorKind::MissingType(_) => 0x43,
            ErrorKind::UnknownType { .. } => 0x44,
            ErrorKind::WrongLength { .. } => 0x45,
            ErrorKind::SizeMismatch { .. } => 0x46,
            ErrorKind::TooManyWaypoints(_) => 0x47,
            ErrorKind::InvalidSlot(_) => 0x48,
            ErrorKind::WrongCategory { .. } => 0x49,
            ErrorKind::InvalidController(_) => 0x4A,
        }
    }
}

/// The packet lengths a type allows (see [`ErrorKind::WrongLength`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Expected {
    /// Exactly this many bytes.
    Exactly(usize),
    /// One of two lengths (the two position slave set forms).
    Either(usize, usize),
    /// `base + stride * k` bytes for some k >= 0.
    Multiple {
        /// The fixed part.
        base: usize,
        /// The size of one repeated item.
        stride: usize,
    },
}

impl Expected {
    /// The offset of the first byte in the way of a packet of `got` bytes: the first
    /// extra one when it is longer than every allowed length, else the first missing one.
    pub(crate) fn offset(self, got: usize) -> usize {
        match self {
            Expected::Exactly(n) if got > n => n,
            Expected::Either(a, b) if got > a.max(b) => a.max(b),
            _ => got,
        }
    }
}

impl fmt::Display for Expected {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Expected::Exactly(n) => write!(f, "{n} bytes"),
            Expected::Either(a, b) => write!(f, "{a} or {b} bytes"),
            Expected::Multiple { base, stride } => write!(f, "{base} + {stride}k bytes"),
        }
    }
}

impl fmt::Display for ErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ErrorKind::Empty => f.write_str("empty packet"),
            ErrorKind::UnknownCategory(c) => write!(f, "unknown packet category {c:#04x}"),
            ErrorKind::WrongCategory { expected, found } => {
                write!(
                    f,
                    "not a {expected} packet: its category byte is {found:#04x}"
                )
            }
            ErrorKind::MissingType(c) => write!(f, "{c} packet ends before its type byte"),
            ErrorKind::UnknownType { category, value } => {
                write!(f, "unknown {category} type {value:#04x}")
            }
            ErrorKind::WrongLength {
                category,
                packet_type,
                status_request,
                expected,
                got,
            } => {
                f.write_str("wrong length for ")?;
                if let Some(t) = packet_type {
                    write!(f, "{t} ")?;
                }
                write!(f, "{category}")?;
                if *status_request {
                    f.write_str(match expected {
                        Expected::Exactly(_) => " status request",
                        _ => " or its status request",
                    })?;
                }
                write!(f, ": expected {expected}, got {got}")
            }
            ErrorKind::SizeMismatch { size, waypoints } => write!(
                f,
                "trajectory size byte {size} does not match the {waypoints} {} in the packet length",
                if *waypoints == 1 {
                    "waypoint"
                } else {
                    "waypoints"
                }
            ),
            ErrorKind::TooManyWaypoints(n) => {
                write!(f, "{n} trajectory waypoints, at most 254 allowed")
            }
            ErrorKind::InvalidSlot(s) => write!(f, "position slave slot {s} is not 0-3"),
            ErrorKind::InvalidController(c) => {
                write!(
                    f,
                    "controller 0x{c:02x} is not 0x00-0xfe (0xff is no controller)"
                )
            }
        }
    }
}

/// The output buffer is too small for the packet being encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[error("buffer too small: {needed} bytes needed, {available} available")]
pub struct BufferTooSmall {
    /// Bytes the packet needs.
    pub needed: usize,
    /// Bytes the buffer has.
    pub available: usize,
}

impl BufferTooSmall {
    /// Its one-byte code, among those of [`ErrorKind::code`].
    pub const CODE: u8 = 0x50;

    /// [`CODE`](Self::CODE), as the other errors of parsing and encoding give theirs.
    pub const fn code(&self) -> u8 {
        Self::CODE
    }
}

/// An incremental builder is full: one more item would overrun the buffer, the
/// 255-byte XBee payload limit ([`MAX_PAYLOAD`](crate::MAX_PAYLOAD)) or the
/// packet's own item limit. The packet built so far is intact.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[error("packet full")]
pub struct Full;

impl Full {
    /// Its one-byte code, among those of [`ErrorKind::code`].
    pub const CODE: u8 = 0x51;

    /// [`CODE`](Self::CODE), as the other errors of parsing and encoding give theirs.
    pub const fn code(&self) -> u8 {
        Self::CODE
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_error_has_its_own_code_in_the_crates_range() {
        let kinds = [
            ErrorKind::Empty,
            ErrorKind::UnknownCategory(b'x'),
            ErrorKind::MissingType(Category::Command),
            ErrorKind::UnknownType {
                category: Category::Report,
                value: 0x33,
            },
            ErrorKind::WrongLength {
                category: Category::Command,
                packet_type: None,
                status_request: false,
                expected: Expected::Exactly(3),
                got: 4,
            },
            ErrorKind::SizeMismatch {
                size: 2,
                waypoints: 1,
            },
            ErrorKind::TooManyWaypoints(300),
            ErrorKind::InvalidSlot(4),
            ErrorKind::WrongCategory {
                expected: Category::Command,
                found: b'r',
            },
            ErrorKind::InvalidController(0xFF),
        ];
        let codes = kinds.map(|kind| kind.code());
        assert_eq!(
            codes,
            [0x41, 0x42, 0x43, 0x44, 0x45, 0x46, 0x47, 0x48, 0x49, 0x4A]
        );
        assert_eq!(Error::new(ErrorKind::InvalidSlot(4), 2).code(), 0x48);
        assert_eq!((BufferTooSmall::CODE, Full::CODE), (0x50, 0x51));
        let small = BufferTooSmall {
            needed: 3,
            available: 2,
        };
        assert_eq!((small.code(), Full.code()), (0x50, 0x51));
    }
}
