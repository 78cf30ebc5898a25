//! Trajectory waypoints (tables 9 and 21): a view over the waypoints and a builder.

use core::iter::FusedIterator;

use nom::Parser;

use crate::{
    MAX_PAYLOAD,
    error::{BufferTooSmall, Error, ErrorKind, Expected, Full},
    field::{self, waypoint},
    id::{Category, CommandType},
    read,
    write::Writer,
};

/// The most waypoints a trajectory packet can hold: size 0xFF is the status request.
pub const MAX_WAYPOINTS: usize = 254;

/// One trajectory waypoint.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Waypoint {
    /// Time of the waypoint (table 9). The protocol gives it no unit; the MAV's clock
    /// counts POSIX seconds ([`Command::Time`](crate::Command::Time)), and `mcp-gs`
    /// reads a waypoint's time so.
    pub time: u32,
    /// Elevator position.
    pub elevator: f32,
    /// Aileron position.
    pub aileron: f32,
    /// Altitude.
    pub altitude: f32,
}

impl Waypoint {
    /// Bytes of one waypoint on the wire.
    pub const LEN: usize = waypoint::LEN;

    /// Bytes of a trajectory set packet of `count` waypoints: the category, type and
    /// size bytes, then the waypoints. Saturates at `usize::MAX` rather than overflow
    /// (no packet holds more than 254 waypoints).
    ///
    /// ```
    /// use mcp_core::Waypoint;
    /// assert_eq!(Waypoint::packet_len(2), 35);
    /// assert_eq!(Waypoint::packet_len(usize::MAX), usize::MAX);
    /// ```
    pub const fn packet_len(count: usize) -> usize {
        field::WAYPOINTS.saturating_add(count.saturating_mul(waypoint::LEN))
    }

    /// The waypoint its 16 wire bytes hold (little-endian `u32` time, then `f32`
    /// elevator, aileron and altitude): the inverse of [`to_bytes`](Self::to_bytes),
    /// for a firmware that keeps a trajectory as bytes.
    ///
    /// ```
    /// use mcp_core::Waypoint;
    /// let w = Waypoint { time: 1_763_683_301, elevator: 0.5, aileron: -0.25, altitude: 12.0 };
    /// assert_eq!(Waypoint::from_bytes(w.to_bytes()), w);
    /// let bytes = [7, 0, 0, 0, 0, 0, 0x80, 0x3F, 0, 0, 0, 0xC0, 0, 0, 0x40, 0x41];
    /// assert_eq!(
    ///     Waypoint::from_bytes(bytes),
    ///     Waypoint { time: 7, elevator: 1.0, aileron: -2.0, altitude: 12.0 }
    /// );
    /// ```
    pub fn from_bytes(bytes: [u8; waypoint::LEN]) -> Self {
        // The four little-endian words, lowest first.
        let n = u128::from_le_bytes(bytes);
        let word = |i: u32| (n >> (32 * i)) as u32;
        Waypoint {
            time: word(0),
            elevator: f32::from_bits(word(1)),
            aileron: f32::from_bits(word(2)),
            altitude: f32::from_bits(word(3)),
        }
    }

    /// The 16 wire bytes of the waypoint.
    pub fn to_bytes(&self) -> [u8; waypoint::LEN] {
        let mut out = [0; waypoint::LEN];
        out[waypoint::TIME].copy_from_slice(&self.time.to_le_bytes());
        out[waypoint::ELEVATOR].copy_from_slice(&self.elevator.to_le_bytes());
        out[waypoint::AILERON].copy_from_slice(&self.aileron.to_le_bytes());
        out[waypoint::ALTITUDE].copy_from_slice(&self.altitude.to_le_bytes());
        out
    }
}

/// The waypoints of a trajectory set command or report: a view over the bytes after
/// the size byte, 16 bytes per waypoint (`u32` time, `f32` elevator, `f32` aileron,
/// `f32` altitude, little-endian). The size byte is not stored: it is the number of
/// waypoints.
///
/// ```
/// use mcp_core::{Waypoints, Waypoint};
/// let bytes = Waypoint { time: 7, elevator: 1.0, aileron: 2.0, altitude: 3.0 }.to_bytes();
/// let w = Waypoints::new_checked(&bytes[..]).unwrap();
/// assert_eq!(w.len(), 1);
/// assert_eq!(w.iter().next().unwrap().time, 7);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Waypoints<B> {
    bytes: B,
}

impl<B> Waypoints<B> {
    /// Wraps waypoint bytes without checking them. Accessors never panic: a trailing
    /// partial waypoint is ignored, and so are waypoints past the 254th.
    pub const fn new_unchecked(bytes: B) -> Self {
        Waypoints { bytes }
    }

    /// The waypoint bytes.
    pub fn into_inner(self) -> B {
        self.bytes
    }
}

impl<B: AsRef<[u8]>> Waypoints<B> {
    /// Wraps the waypoint bytes of a trajectory set command, checking that they are
    /// at most 254 whole waypoints ([`check_len`](Self::check_len)). For a trajectory
    /// report's, use [`new_checked_for`](Self::new_checked_for).
    pub fn new_checked(bytes: B) -> Result<Self, Error> {
        Self::new_checked_for(bytes, Category::Command)
    }

    /// Wraps the waypoint bytes of a trajectory packet of `category`
    /// ([`Category::Command`] or [`Category::Report`]), checking that they are at most
    /// 254 whole waypoints ([`check_len_for`](Self::check_len_for)).
    ///
    /// ```
    /// use mcp_core::{Category, ErrorKind, Waypoints};
    /// let err = Waypoints::new_checked_for(&[0u8; 17][..], Category::Report).unwrap_err();
    /// assert!(matches!(
    ///     err.kind(),
    ///     ErrorKind::WrongLength { category: Category::Report, got: 20, .. }
    /// ));
    /// assert_eq!(
    ///     err.to_string(),
    ///     "wrong length for trajectory_set report: expected 3 + 16k bytes, got 20 (at offset 19)"
    /// );
    /// ```
    pub fn new_checked_for(bytes: B, category: Category) -> Result<Self, Error> {
        let w = Self::new_unchecked(bytes);
        w.check_len_for(category)?;
        Ok(w)
    }

    /// Checks that the bytes are at most 254 whole waypoints, as those of a trajectory
    /// set command: a length error names a command. For a trajectory report's, use
    /// [`check_len_for`](Self::check_len_for).
    pub fn check_len(&self) -> Result<(), Error> {
        self.check_len_for(Category::Command)
    }

    /// Checks that the bytes are at most 254 whole waypoints, as those of a trajectory
    /// packet of `category` ([`Category::Command`] or [`Category::Report`]), which a
    /// length error names. Error offsets count from the packet start, as if the bytes
    /// followed a 3-byte header.
    pub fn check_len_for(&self, category: Category) -> Result<(), Error> {
        let len = self.bytes.as_ref().len();
        let partial = len % waypoint::LEN;
        let got = field::WAYPOINTS + len;
        if partial != 0 {
            return Err(Error::new(
                ErrorKind::WrongLength {
                    category,
                    packet_type: Some(CommandType::TrajectorySet),
                    status_request: false,
                    expected: Expected::Multiple {
                        base: field::WAYPOINTS,
                        stride: waypoint::LEN,
                    },
                    got,
                },
                got - partial,
            ));
        }
        let count = len / waypoint::LEN;
        if count > MAX_WAYPOINTS {
            return Err(Error::new(
                ErrorKind::TooManyWaypoints(count),
                field::WAYPOINTS + MAX_WAYPOINTS * waypoint::LEN,
            ));
        }
        Ok(())
    }

    /// The waypoint bytes.
    pub fn as_bytes(&self) -> &[u8] {
        self.bytes.as_ref()
    }

    /// The number of waypoints (whole ones, at most 254).
    pub fn len(&self) -> usize {
        (self.as_bytes().len() / waypoint::LEN).min(MAX_WAYPOINTS)
    }

    /// `true` if there is no waypoint (a size-0 trajectory).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The size byte of the packet: the number of waypoints.
    pub fn size(&self) -> u8 {
        u8::try_from(self.len()).unwrap_or(u8::MAX - 1)
    }

    /// Iterates over the waypoints.
    pub fn iter(&self) -> WaypointIter<'_> {
        WaypointIter { rest: self.body() }
    }

    /// The waypoint at `index`, if there is one.
    pub fn get(&self, index: usize) -> Option<Waypoint> {
        let start = index.checked_mul(waypoint::LEN)?;
        WaypointIter {
            rest: self.body().get(start..)?,
        }
        .next()
    }

    /// The whole waypoints' bytes.
    fn body(&self) -> &[u8] {
        let len = self.len() * waypoint::LEN;
        self.as_bytes().get(..len).unwrap_or_default()
    }

    /// The length of a trajectory set command or report holding these waypoints.
    pub fn encoded_len(&self) -> usize {
        field::WAYPOINTS + self.len() * waypoint::LEN
    }

    /// Writes a trajectory set packet of `category` (command or report) holding these
    /// waypoints, returning its length.
    pub(crate) fn encode_as(
        &self,
        category: Category,
        buf: &mut [u8],
    ) -> Result<usize, BufferTooSmall> {
        Writer::new(buf, self.encoded_len())?
            .u8(category.into())
            .u8(CommandType::TrajectorySet.into())
            .u8(self.size())
            .bytes(self.body())
            .finish()
    }

    /// A view borrowing this one's bytes.
    pub fn as_borrowed(&self) -> Waypoints<&[u8]> {
        Waypoints::new_unchecked(self.as_bytes())
    }
}

impl<'a> Waypoints<&'a [u8]> {
    /// Moves the bytes to another storage, e.g. `|s| bytes.slice_ref(s)`. `f` is
    /// expected to return the same bytes.
    pub fn map_bytes<U>(self, f: impl FnOnce(&'a [u8]) -> U) -> Waypoints<U> {
        Waypoints::new_unchecked(f(self.bytes))
    }
}

impl<'w, B: AsRef<[u8]>> IntoIterator for &'w Waypoints<B> {
    type Item = Waypoint;
    type IntoIter = WaypointIter<'w>;

    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

/// Iterator over [`Waypoints`].
#[derive(Debug, Clone)]
pub struct WaypointIter<'a> {
    rest: &'a [u8],
}

impl Iterator for WaypointIter<'_> {
    type Item = Waypoint;

    fn next(&mut self) -> Option<Waypoint> {
        match (read::u32, read::f32, read::f32, read::f32).parse(self.rest) {
            Ok((rest, (time, elevator, aileron, altitude))) => {
                self.rest = rest;
                Some(Waypoint {
                    time,
                    elevator,
                    aileron,
                    altitude,
                })
            }
            Err(_) => {
                self.rest = &[];
                None
            }
        }
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = self.rest.len() / waypoint::LEN;
        (n, Some(n))
    }
}

impl ExactSizeIterator for WaypointIter<'_> {}
impl FusedIterator for WaypointIter<'_> {}

/// Builds a trajectory set command or report waypoint by waypoint in a caller
/// buffer, stopping cleanly when the buffer, the 255-byte XBee payload limit (15
/// waypoints) or the 254-waypoint limit is reached.
///
/// ```
/// use mcp_core::{TrajectoryBuilder, Waypoint, MAX_PAYLOAD};
/// let mut buf = [0u8; 512];
/// let mut b = TrajectoryBuilder::command(&mut buf).unwrap();
/// while b.push(Waypoint::default()).is_ok() {}
/// assert_eq!(b.count(), 15);
/// let len = b.finish();
/// assert!(len <= MAX_PAYLOAD);
/// assert_eq!(&buf[..3], b"c\x04\x0f");
/// ```
#[derive(Debug)]
pub struct TrajectoryBuilder<'a> {
    buf: &'a mut [u8],
    len: usize,
}

impl<'a> TrajectoryBuilder<'a> {
    /// Starts a trajectory set command (`c 04 size ...`).
    pub fn command(buf: &'a mut [u8]) -> Result<Self, BufferTooSmall> {
        Self::new(buf, Category::Command)
    }

    /// Starts a trajectory set report (`r 04 size ...`).
    pub fn report(buf: &'a mut [u8]) -> Result<Self, BufferTooSmall> {
        Self::new(buf, Category::Report)
    }

    fn new(buf: &'a mut [u8], category: Category) -> Result<Self, BufferTooSmall> {
        Writer::new(buf, field::WAYPOINTS)?
            .u8(category.into())
            .u8(CommandType::TrajectorySet.into())
            .u8(0)
            .finish()?;
        let cap = buf.len().min(MAX_PAYLOAD);
        Ok(TrajectoryBuilder {
            buf: buf.get_mut(..cap).unwrap_or_default(),
            len: field::WAYPOINTS,
        })
    }

    /// Appends a waypoint, or fails with [`Full`] leaving the packet as it was.
    pub fn push(&mut self, waypoint: Waypoint) -> Result<(), Full> {
        if self.count() >= MAX_WAYPOINTS {
            return Err(Full);
        }
        let end = self.len + waypoint::LEN;
        let dst = self.buf.get_mut(self.len..end).ok_or(Full)?;
        dst.copy_from_slice(&waypoint.to_bytes());
        self.len = end;
        let count = u8::try_from(self.count()).unwrap_or(0);
        if let Some(size) = self.buf.get_mut(field::ARG) {
            *size = count;
        }
        Ok(())
    }

    /// The number of waypoints pushed.
    pub fn count(&self) -> usize {
        (self.len - field::WAYPOINTS) / waypoint::LEN
    }

    /// The packet written so far (its size byte is always up to date).
    pub fn as_bytes(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or_default()
    }

    /// Ends the packet, returning its length: the packet is `buf.get(..len)`, the
    /// bytes [`as_bytes`](Self::as_bytes) gives before `finish`. In firmware, take it
    /// that way rather than as `&buf[..len]`, whose bounds check the compiler cannot
    /// always drop, and so a panic path.
    pub fn finish(self) -> usize {
        self.len
    }
}
