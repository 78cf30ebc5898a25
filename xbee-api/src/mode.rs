//! API operating mode (Digi's `AP` parameter).

use core::fmt;

/// The API operating mode of an XBee (`AP` parameter).
///
/// Its `AP` value is `u8::from(mode)`, 1 or 2. Not `mode as u8`, which gives the
/// discriminant, 0 or 1 (mode 1 is stored as 0, so that a decoder of a fixed mode is
/// all zeros and a `static` of one takes no flash).
///
/// ```
/// use xbee_api::ApiMode;
/// assert_eq!(ApiMode::try_from(2), Ok(ApiMode::Escaped));
/// assert_eq!(u8::from(ApiMode::Unescaped), 1);
/// assert!(ApiMode::try_from(0).is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
// Mode 1 is stored as 0: a decoder of a fixed mode keeps it, and is then all zeros.
#[repr(u8)]
pub enum ApiMode {
    /// API mode 1 (`AP=1`): frames are sent as they are.
    Unescaped = 0,
    /// API mode 2 (`AP=2`): every byte after the start delimiter that is 0x7E, 0x7D, 0x11
    /// or 0x13 is sent as `0x7D, byte ^ 0x20`.
    Escaped,
}

impl ApiMode {
    /// The other mode: where frames read in this one fail, the radio may be in it.
    ///
    /// ```
    /// use xbee_api::ApiMode;
    /// assert_eq!(ApiMode::Unescaped.other(), ApiMode::Escaped);
    /// assert_eq!(ApiMode::Escaped.other(), ApiMode::Unescaped);
    /// ```
    #[must_use]
    pub const fn other(self) -> ApiMode {
        match self {
            ApiMode::Unescaped => ApiMode::Escaped,
            ApiMode::Escaped => ApiMode::Unescaped,
        }
    }
}

/// An `AP` value that is not an API mode with frames (1 or 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct InvalidApiMode(pub u8);

impl fmt::Display for InvalidApiMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "invalid API mode {} (expected 1 or 2)", self.0)
    }
}

impl core::error::Error for InvalidApiMode {}

impl TryFrom<u8> for ApiMode {
    type Error = InvalidApiMode;

    fn try_from(value: u8) -> Result<Self, Self::Error> {
        match value {
            1 => Ok(Self::Unescaped),
            2 => Ok(Self::Escaped),
            other => Err(InvalidApiMode(other)),
        }
    }
}

impl From<ApiMode> for u8 {
    fn from(mode: ApiMode) -> u8 {
        match mode {
            ApiMode::Unescaped => 1,
            ApiMode::Escaped => 2,
        }
    }
}

impl fmt::Display for ApiMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "API mode {}", u8::from(*self))
    }
}
