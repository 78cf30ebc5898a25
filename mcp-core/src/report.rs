//! Report packets (`r`, tables 18 to 23).

use nom::{Parser, combinator::all_consuming};

use crate::{
    address::Address,
    command::waypoints_checked,
    error::{BufferTooSmall, Error, ErrorKind, Expected, check_category},
    field,
    id::{Category, CommandType, Controller, LandingState, TelemetryId},
    read,
    trajectory::Waypoints,
    write::Writer,
};

/// A report packet: one variant per report type (table 17).
///
/// `B` holds the bytes of the only variable-length report, trajectory set.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Report<B> {
    /// `r 01 on/off id` (table 18): whether telemetry `id` is sent.
    TelemetryToCoordinator {
        /// Sent (any non-zero byte decodes as on).
        on: bool,
        /// Which telemetry.
        id: TelemetryId,
    },
    /// `r 02 state` (table 19): the landing state.
    Landing(LandingState),
    /// `r 03 id` (table 20): the active controller, 0x00-0xFE. `Controller::Unknown(0xFF)`
    /// encodes a packet that parsers refuse ([`ErrorKind::InvalidController`]).
    Controllers(Controller),
    /// `r 04 size waypoints...` (table 21): the trajectory.
    TrajectorySet(Waypoints<B>),
    /// `r 05 ...` (table 22): the slave address(es).
    PositionSlaveSet(SlaveAddresses),
    /// `r 06 time` (table 23): the MAV time (POSIX seconds).
    Time(u32),
}

/// The content of a position slave set report, in one of its two forms.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SlaveAddresses {
    /// Spec form (table 22): `r 05 addr[8]`, 10 bytes.
    Single(Address),
    /// Firmware form: `r 05 addr[8]x4`, 34 bytes, the addresses of slots 0 to 3.
    Slots([Address; 4]),
}

/// Reports that carry no bytes, built without naming `B`: `Report::Landing(state)`
/// alone leaves the type of the trajectory bytes open (`Report::<&[u8]>::Landing(state)`
/// names it), `Report::landing(state)` does not.
///
/// ```
/// use mcp_core::{Controller, LandingState, Report, TelemetryId};
/// let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
///
/// let len = Report::landing(LandingState::Flight).encode(&mut buf)?;
/// assert_eq!(&buf[..len], b"r\x02\x04");
/// let len = Report::telemetry_to_coordinator(true, TelemetryId::Altitude).encode(&mut buf)?;
/// assert_eq!(&buf[..len], b"r\x01\x01\x01");
/// assert_eq!(Report::controllers(Controller::Mpc), Report::Controllers(Controller::Mpc));
/// assert_eq!(Report::time(5), Report::Time(5));
/// # Ok::<(), mcp_core::BufferTooSmall>(())
/// ```
impl Report<&'static [u8]> {
    /// [`Report::TelemetryToCoordinator`]: whether telemetry `id` is sent.
    pub const fn telemetry_to_coordinator(on: bool, id: TelemetryId) -> Self {
        Report::TelemetryToCoordinator { on, id }
    }

    /// [`Report::Landing`]: the landing state.
    pub const fn landing(state: LandingState) -> Self {
        Report::Landing(state)
    }

    /// [`Report::Controllers`]: the active controller.
    pub const fn controllers(controller: Controller) -> Self {
        Report::Controllers(controller)
    }

    /// [`Report::PositionSlaveSet`]: the slave address(es), in either form.
    pub const fn position_slave_set(addresses: SlaveAddresses) -> Self {
        Report::PositionSlaveSet(addresses)
    }

    /// [`Report::Time`]: the MAV time (POSIX seconds).
    pub const fn time(seconds: u32) -> Self {
        Report::Time(seconds)
    }
}

/// A length error for a report of type `t`.
fn wrong_length(t: CommandType, expected: Expected, got: usize) -> Error {
    let offset = expected.offset(got);
    Error::new(
        ErrorKind::WrongLength {
            category: Category::Report,
            packet_type: Some(t),
            status_request: false,
            expected,
            got,
        },
        offset,
    )
}

/// Four addresses in a row.
fn four_addresses(i: &[u8]) -> read::Res<'_, [Address; 4]> {
    let (i, (a, b, c, d)) =
        (read::address, read::address, read::address, read::address).parse(i)?;
    Ok((i, [a, b, c, d]))
}

impl<'a> Report<&'a [u8]> {
    /// Parses a report packet, its `r` included: any other packet is an error
    /// ([`ErrorKind::WrongCategory`], or [`ErrorKind::Empty`]).
    ///
    /// ```
    /// use mcp_core::{ErrorKind, LandingState, Report};
    /// assert_eq!(Report::parse(b"r\x02\x01"), Ok(Report::Landing(LandingState::Landing)));
    /// let command = Report::parse(b"c\x02\x01").unwrap_err();
    /// assert!(matches!(command.kind(), ErrorKind::WrongCategory { found: b'c', .. }));
    /// ```
    pub fn parse(bytes: &'a [u8]) -> Result<Self, Error> {
        check_category(bytes, Category::Report)?;
        Self::parse_typed(bytes)
    }

    /// [`parse`](Self::parse) of a packet whose category byte was read already.
    pub(crate) fn parse_typed(bytes: &'a [u8]) -> Result<Self, Error> {
        let len = bytes.len();
        let Some(&type_byte) = bytes.get(field::TYPE) else {
            return Err(Error::new(
                ErrorKind::MissingType(Category::Report),
                field::TYPE,
            ));
        };
        let t = CommandType::from(type_byte);
        let body = bytes.get(field::ARG..).unwrap_or_default();
        // Parses the body after checking the packet length; the parser then cannot fail.
        let fixed = |want: usize, parser: fn(&'a [u8]) -> read::Res<'a, Self>| {
            if len != want {
                return Err(wrong_length(t, Expected::Exactly(want), len));
            }
            all_consuming(parser)
                .parse(body)
                .map(|(_, r)| r)
                .map_err(|_| wrong_length(t, Expected::Exactly(want), len))
        };
        match t {
            CommandType::TelemetryToCoordinator => fixed(field::TTC_LEN, |i| {
                let (i, (on, id)) = (read::on_off, read::u8).parse(i)?;
                Ok((i, Report::TelemetryToCoordinator { on, id: id.into() }))
            }),
            CommandType::Landing => fixed(field::ONE_BYTE_LEN, |i| {
                let (i, state) = read::u8(i)?;
                Ok((i, Report::Landing(state.into())))
            }),
            // 0xFF, the status request's byte in a command, is no controller.
            CommandType::Controllers if body == [field::STATUS_REQUEST] => Err(Error::new(
                ErrorKind::InvalidController(field::STATUS_REQUEST),
                field::ARG,
            )),
            CommandType::Controllers => fixed(field::ONE_BYTE_LEN, |i| {
                let (i, c) = read::u8(i)?;
                Ok((i, Report::Controllers(c.into())))
            }),
            CommandType::TrajectorySet => {
                let multiple = Expected::Multiple {
                    base: field::WAYPOINTS,
                    stride: field::waypoint::LEN,
                };
                let Some(&size) = bytes.get(field::ARG) else {
                    return Err(wrong_length(t, multiple, len));
                };
                waypoints_checked(bytes, size, |got| wrong_length(t, multiple, got))
                    .map(Report::TrajectorySet)
            }
            CommandType::PositionSlaveSet => match len {
                field::SLAVE_LEN => fixed(field::SLAVE_LEN, |i| {
                    let (i, a) = read::address(i)?;
                    Ok((i, Report::PositionSlaveSet(SlaveAddresses::Single(a))))
                }),
                field::SLAVES_LEN => fixed(field::SLAVES_LEN, |i| {
                    let (i, a) = four_addresses(i)?;
                    Ok((i, Report::PositionSlaveSet(SlaveAddresses::Slots(a))))
                }),
                _ => Err(wrong_length(
                    t,
                    Expected::Either(field::SLAVE_LEN, field::SLAVES_LEN),
                    len,
                )),
            },
            CommandType::Time => fixed(field::TIME_LEN, |i| {
                let (i, time) = read::u32(i)?;
                Ok((i, Report::Time(time)))
            }),
            CommandType::PositionSet | CommandType::Unknown(_) => Err(Error::new(
                ErrorKind::UnknownType {
                    category: Category::Report,
                    value: type_byte,
                },
                field::TYPE,
            )),
        }
    }

    /// Moves the bytes to another storage, e.g. `|s| bytes.slice_ref(s)`.
    pub fn map_bytes<U>(self, f: impl FnOnce(&'a [u8]) -> U) -> Report<U> {
        match self {
            Report::TrajectorySet(w) => Report::TrajectorySet(w.map_bytes(f)),
            Report::TelemetryToCoordinator { on, id } => Report::TelemetryToCoordinator { on, id },
            Report::Landing(s) => Report::Landing(s),
            Report::Controllers(c) => Report::Controllers(c),
            Report::PositionSlaveSet(s) => Report::PositionSlaveSet(s),
            Report::Time(t) => Report::Time(t),
        }
    }
}

impl<B: AsRef<[u8]>> Report<B> {
    /// The report type.
    pub fn report_type(&self) -> CommandType {
        match self {
            Report::TelemetryToCoordinator { .. } => CommandType::TelemetryToCoordinator,
            Report::Landing(_) => CommandType::Landing,
            Report::Controllers(_) => CommandType::Controllers,
            Report::TrajectorySet(_) => CommandType::TrajectorySet,
            Report::PositionSlaveSet(_) => CommandType::PositionSlaveSet,
            Report::Time(_) => CommandType::Time,
        }
    }

    /// The packet length.
    pub fn encoded_len(&self) -> usize {
        match self {
            Report::TelemetryToCoordinator { .. } => field::TTC_LEN,
            Report::Landing(_) | Report::Controllers(_) => field::ONE_BYTE_LEN,
            Report::TrajectorySet(w) => w.encoded_len(),
            Report::PositionSlaveSet(SlaveAddresses::Single(_)) => field::SLAVE_LEN,
            Report::PositionSlaveSet(SlaveAddresses::Slots(_)) => field::SLAVES_LEN,
            Report::Time(_) => field::TIME_LEN,
        }
    }

    /// Writes the packet into `buf`, returning its length. On/off bytes are written
    /// as 0x00/0x01.
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, BufferTooSmall> {
        if let Report::TrajectorySet(w) = self {
            return w.encode_as(Category::Report, buf);
        }
        let mut w = Writer::new(buf, self.encoded_len())?;
        w.u8(Category::Report.into()).u8(self.report_type().into());
        match self {
            Report::TelemetryToCoordinator { on, id } => w.on_off(*on).u8((*id).into()),
            Report::Landing(s) => w.u8((*s).into()),
            Report::Controllers(c) => w.u8((*c).into()),
            Report::TrajectorySet(_) => &mut w,
            Report::PositionSlaveSet(SlaveAddresses::Single(a)) => w.bytes(&a.0),
            Report::PositionSlaveSet(SlaveAddresses::Slots(all)) => {
                for a in all {
                    w.bytes(&a.0);
                }
                &mut w
            }
            Report::Time(time) => w.u32(*time),
        };
        w.finish()
    }

    /// A report borrowing this one's bytes.
    pub fn as_borrowed(&self) -> Report<&[u8]> {
        match self {
            Report::TrajectorySet(w) => Report::TrajectorySet(w.as_borrowed()),
            Report::TelemetryToCoordinator { on, id } => {
                Report::TelemetryToCoordinator { on: *on, id: *id }
            }
            Report::Landing(s) => Report::Landing(*s),
            Report::Controllers(c) => Report::Controllers(*c),
            Report::PositionSlaveSet(s) => Report::PositionSlaveSet(*s),
            Report::Time(t) => Report::Time(*t),
        }
    }
}
