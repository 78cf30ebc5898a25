//! Command packets (`c`, tables 3 to 15).

use nom::{Parser, combinator::all_consuming};

use crate::{
    address::{Address, Slot},
    error::{BufferTooSmall, Error, ErrorKind, Expected, check_category},
    field,
    id::{Category, CommandType, Controller, TelemetryId},
    read,
    trajectory::Waypoints,
    write::Writer,
};

/// A command packet: one variant per command type, plus the status requests.
///
/// `B` holds the bytes of the only variable-length command, trajectory set.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Command<B> {
    /// `c 01 on/off id` (table 3): start or stop sending telemetry `id`.
    TelemetryToCoordinator {
        /// Send it (any non-zero byte decodes as on).
        on: bool,
        /// Which telemetry.
        id: TelemetryId,
    },
    /// `c 02 on/off` (table 5): turn autonomous landing on or off. (Byte 0xFF is
    /// the landing status request.)
    Landing {
        /// Land (any non-zero byte other than 0xFF decodes as on).
        on: bool,
    },
    /// `c 03 id` (table 7): switch to a controller. `Controller::Unknown(0xFF)`
    /// would encode as the controllers status request: use
    /// [`StatusRequest::Controllers`] for that.
    Controllers(Controller),
    /// `c 04 size waypoints...` (table 9): set trajectory waypoints. To send one,
    /// write the packet with [`TrajectoryBuilder::command`](crate::TrajectoryBuilder::command)
    /// (waypoint by waypoint into a buffer) and send those bytes as they are, or parse
    /// them back into a `Command`; in mcp-host, `CommandSender::send_trajectory` takes
    /// the waypoints.
    TrajectorySet(Waypoints<B>),
    /// Position slave set: spec form `c 05 addr[8]` (table 11) when `slot` is
    /// `None`, firmware form `c 05 slot addr[8]` when it is `Some`.
    PositionSlaveSet {
        /// The slot, for the firmware form.
        slot: Option<Slot>,
        /// The slave MAV address.
        address: Address,
    },
    /// `c 06 time` (table 13): set the MAV time (POSIX seconds).
    Time(u32),
    /// `c 07 elevator aileron` (table 15): set the MAV position. This type has no
    /// status request: a 0xFF byte is float data.
    PositionSet {
        /// New elevator position.
        elevator: f32,
        /// New aileron position.
        aileron: f32,
    },
    /// A status request (byte 3 is 0xFF), answered by the matching report.
    StatusRequest(StatusRequest),
}

/// A status request command (tables 4, 6, 8, 10, 12, 14).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StatusRequest {
    /// `c 01 FF id`: is telemetry `id` sent?
    TelemetryToCoordinator(TelemetryId),
    /// `c 02 FF`: the landing state.
    Landing,
    /// `c 03 FF`: the active controller.
    Controllers,
    /// `c 04 FF`: the trajectory.
    TrajectorySet,
    /// `c 05 FF`: the slave addresses.
    PositionSlaveSet,
    /// `c 06 FF`: the MAV time.
    Time,
}

impl StatusRequest {
    /// The command type asked about, which is also the type of the answering report.
    pub fn command_type(&self) -> CommandType {
        match self {
            StatusRequest::TelemetryToCoordinator(_) => CommandType::TelemetryToCoordinator,
            StatusRequest::Landing => CommandType::Landing,
            StatusRequest::Controllers => CommandType::Controllers,
            StatusRequest::TrajectorySet => CommandType::TrajectorySet,
            StatusRequest::PositionSlaveSet => CommandType::PositionSlaveSet,
            StatusRequest::Time => CommandType::Time,
        }
    }

    /// The status request for a command type, if the type has one. The
    /// telemetry-to-coordinator request also needs a telemetry id.
    pub fn for_type(command_type: CommandType, id: TelemetryId) -> Option<Self> {
        Some(match command_type {
            CommandType::TelemetryToCoordinator => StatusRequest::TelemetryToCoordinator(id),
            CommandType::Landing => StatusRequest::Landing,
            CommandType::Controllers => StatusRequest::Controllers,
            CommandType::TrajectorySet => StatusRequest::TrajectorySet,
            CommandType::PositionSlaveSet => StatusRequest::PositionSlaveSet,
            CommandType::Time => StatusRequest::Time,
            CommandType::PositionSet | CommandType::Unknown(_) => return None,
        })
    }
}

/// A length error for a command of type `t`.
fn wrong_length(t: CommandType, status_request: bool, expected: Expected, got: usize) -> Error {
    let offset = expected.offset(got);
    Error::new(
        ErrorKind::WrongLength {
            category: Category::Command,
            packet_type: Some(t),
            status_request,
            expected,
            got,
        },
        offset,
    )
}

/// Commands that carry no bytes, built without naming `B`: `Command::Time(5)` alone
/// leaves the type of the trajectory bytes open (`Command::<&[u8]>::Time(5)` names
/// it), `Command::time(5)` does not.
///
/// ```
/// use mcp_core::{Command, Controller, StatusRequest, TelemetryId};
/// let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
///
/// let len = Command::telemetry_to_coordinator(true, TelemetryId::Altitude).encode(&mut buf)?;
/// assert_eq!(&buf[..len], b"c\x01\x01\x01");
/// let len = Command::time(1_700_000_000).encode(&mut buf)?;
/// assert_eq!(&buf[..len], b"c\x06\x00\xf1\x53\x65");
/// let len = Command::status_request(StatusRequest::Landing).encode(&mut buf)?;
/// assert_eq!(&buf[..len], b"c\x02\xff");
/// assert_eq!(Command::controllers(Controller::Mpc), Command::Controllers(Controller::Mpc));
/// # Ok::<(), mcp_core::BufferTooSmall>(())
/// ```
impl Command<&'static [u8]> {
    /// [`Command::TelemetryToCoordinator`]: start (`on`) or stop sending telemetry `id`.
    pub const fn telemetry_to_coordinator(on: bool, id: TelemetryId) -> Self {
        Command::TelemetryToCoordinator { on, id }
    }

    /// [`Command::Landing`]: turn autonomous landing on or off.
    pub const fn landing(on: bool) -> Self {
        Command::Landing { on }
    }

    /// [`Command::Controllers`]: switch to `controller`.
    pub const fn controllers(controller: Controller) -> Self {
        Command::Controllers(controller)
    }

    /// [`Command::PositionSlaveSet`]: the slave MAV, in the spec form (`slot` `None`)
    /// or the firmware form.
    pub const fn position_slave_set(slot: Option<Slot>, address: Address) -> Self {
        Command::PositionSlaveSet { slot, address }
    }

    /// [`Command::Time`]: set the MAV time (POSIX seconds).
    pub const fn time(seconds: u32) -> Self {
        Command::Time(seconds)
    }

    /// [`Command::PositionSet`]: set the MAV position.
    pub const fn position_set(elevator: f32, aileron: f32) -> Self {
        Command::PositionSet { elevator, aileron }
    }

    /// [`Command::StatusRequest`]: ask for a status report.
    pub const fn status_request(request: StatusRequest) -> Self {
        Command::StatusRequest(request)
    }
}

impl<B> From<StatusRequest> for Command<B> {
    fn from(request: StatusRequest) -> Self {
        Command::StatusRequest(request)
    }
}

impl<'a> Command<&'a [u8]> {
    /// Parses a command packet, its `c` included: any other packet is an error
    /// ([`ErrorKind::WrongCategory`], or [`ErrorKind::Empty`]). A MAV that acts on
    /// commands alone links less code with this than with [`parse`](crate::parse), which
    /// reads every category.
    ///
    /// ```
    /// use mcp_core::{Command, ErrorKind};
    /// assert_eq!(Command::parse(b"c\x02\x01"), Ok(Command::Landing { on: true }));
    /// // A landing report holds the same bytes after its `r`: no command.
    /// let report = Command::parse(b"r\x02\x01").unwrap_err();
    /// assert!(matches!(report.kind(), ErrorKind::WrongCategory { found: b'r', .. }));
    /// ```
    pub fn parse(bytes: &'a [u8]) -> Result<Self, Error> {
        check_category(bytes, Category::Command)?;
        Self::parse_typed(bytes)
    }

    /// [`parse`](Self::parse) of a packet whose category byte was read already.
    pub(crate) fn parse_typed(bytes: &'a [u8]) -> Result<Self, Error> {
        let len = bytes.len();
        let Some(&type_byte) = bytes.get(field::TYPE) else {
            return Err(Error::new(
                ErrorKind::MissingType(Category::Command),
                field::TYPE,
            ));
        };
        let t = CommandType::from(type_byte);
        let arg = bytes.get(field::ARG).copied();
        let is_status = arg == Some(field::STATUS_REQUEST);
        let body = bytes.get(field::ARG..).unwrap_or_default();
        // Parses the body after checking the packet length; the parser then cannot fail.
        let fixed = |want: usize, status: bool, parser: fn(&'a [u8]) -> read::Res<'a, Self>| {
            if len != want {
                return Err(wrong_length(t, status, Expected::Exactly(want), len));
            }
            all_consuming(parser)
                .parse(body)
                .map(|(_, c)| c)
                .map_err(|_| wrong_length(t, status, Expected::Exactly(want), len))
        };
        match t {
            CommandType::TelemetryToCoordinator if is_status => fixed(field::TTC_LEN, true, |i| {
                let (i, (_, id)) = (read::u8, read::u8).parse(i)?;
                Ok((
                    i,
                    Command::StatusRequest(StatusRequest::TelemetryToCoordinator(id.into())),
                ))
            }),
            CommandType::TelemetryToCoordinator => fixed(field::TTC_LEN, false, |i| {
                let (i, (on, id)) = (read::on_off, read::u8).parse(i)?;
                Ok((i, Command::TelemetryToCoordinator { on, id: id.into() }))
            }),
            CommandType::Landing if is_status => fixed(field::STATUS_REQUEST_LEN, true, |i| {
                let (i, _) = read::u8(i)?;
                Ok((i, Command::StatusRequest(StatusRequest::Landing)))
            }),
            CommandType::Landing => fixed(field::ONE_BYTE_LEN, false, |i| {
                let (i, on) = read::on_off(i)?;
                Ok((i, Command::Landing { on }))
            }),
            CommandType::Controllers if is_status => fixed(field::STATUS_REQUEST_LEN, true, |i| {
                let (i, _) = read::u8(i)?;
                Ok((i, Command::StatusRequest(StatusRequest::Controllers)))
            }),
            CommandType::Controllers => fixed(field::ONE_BYTE_LEN, false, |i| {
                let (i, c) = read::u8(i)?;
                Ok((i, Command::Controllers(c.into())))
            }),
            CommandType::TrajectorySet => parse_trajectory(bytes),
            CommandType::PositionSlaveSet => match len {
                field::STATUS_REQUEST_LEN if is_status => {
                    Ok(Command::StatusRequest(StatusRequest::PositionSlaveSet))
                }
                field::SLAVE_LEN => fixed(field::SLAVE_LEN, false, |i| {
                    let (i, address) = read::address(i)?;
                    Ok((
                        i,
                        Command::PositionSlaveSet {
                            slot: None,
                            address,
                        },
                    ))
                }),
                field::SLOT_SLAVE_LEN => {
                    let slot = arg.unwrap_or_default();
                    if Slot::new(slot).is_none() {
                        return Err(Error::new(ErrorKind::InvalidSlot(slot), field::ARG));
                    }
                    fixed(field::SLOT_SLAVE_LEN, false, |i| {
                        let (i, (slot, address)) = (read::u8, read::address).parse(i)?;
                        let slot = Slot::new(slot);
                        Ok((i, Command::PositionSlaveSet { slot, address }))
                    })
                }
                // Byte 3 is 0xFF: the status request, or the spec form with an address
                // starting with 0xFF (the firmware form has no slot 0xFF).
                _ if is_status => Err(wrong_length(
                    t,
                    true,
                    Expected::Either(field::STATUS_REQUEST_LEN, field::SLAVE_LEN),
                    len,
                )),
                _ => Err(wrong_length(
                    t,
                    false,
                    Expected::Either(field::SLAVE_LEN, field::SLOT_SLAVE_LEN),
                    len,
                )),
            },
            // Byte 3 is 0xFF: the status request, or a time whose low byte is 0xFF.
            CommandType::Time if is_status && len != field::TIME_LEN => {
                if len == field::STATUS_REQUEST_LEN {
                    return Ok(Command::StatusRequest(StatusRequest::Time));
                }
                Err(wrong_length(
                    t,
                    true,
                    Expected::Either(field::STATUS_REQUEST_LEN, field::TIME_LEN),
                    len,
                ))
            }
            CommandType::Time => fixed(field::TIME_LEN, false, |i| {
                let (i, time) = read::u32(i)?;
                Ok((i, Command::Time(time)))
            }),
            CommandType::PositionSet => fixed(field::POSITION_LEN, false, |i| {
                let (i, (elevator, aileron)) = (read::f32, read::f32).parse(i)?;
                Ok((i, Command::PositionSet { elevator, aileron }))
            }),
            CommandType::Unknown(value) => Err(Error::new(
                ErrorKind::UnknownType {
                    category: Category::Command,
                    value,
                },
                field::TYPE,
            )),
        }
    }
}

/// Parses a trajectory set command or its status request.
fn parse_trajectory(bytes: &[u8]) -> Result<Command<&[u8]>, Error> {
    let t = CommandType::TrajectorySet;
    let len = bytes.len();
    let multiple = Expected::Multiple {
        base: field::WAYPOINTS,
        stride: field::waypoint::LEN,
    };
    let Some(&size) = bytes.get(field::ARG) else {
        return Err(wrong_length(t, false, multiple, len));
    };
    if size == field::STATUS_REQUEST {
        return if len == field::STATUS_REQUEST_LEN {
            Ok(Command::StatusRequest(StatusRequest::TrajectorySet))
        } else {
            Err(wrong_length(
                t,
                true,
                Expected::Exactly(field::STATUS_REQUEST_LEN),
                len,
            ))
        };
    }
    let waypoints = waypoints_checked(bytes, size, |w| wrong_length(t, false, multiple, w))?;
    Ok(Command::TrajectorySet(waypoints))
}

/// Checks a trajectory packet's length and size byte, returning its waypoints.
/// `wrong_length` builds the error for a length that is not 3 + 16k.
pub(crate) fn waypoints_checked(
    bytes: &[u8],
    size: u8,
    wrong_length: impl FnOnce(usize) -> Error,
) -> Result<Waypoints<&[u8]>, Error> {
    let body = bytes.get(field::WAYPOINTS..).unwrap_or_default();
    let partial = body.len() % field::waypoint::LEN;
    if partial != 0 {
        let err = wrong_length(bytes.len());
        return Err(Error::new(*err.kind(), bytes.len() - partial));
    }
    let count = body.len() / field::waypoint::LEN;
    if usize::from(size) != count {
        return Err(Error::new(
            ErrorKind::SizeMismatch {
                size,
                waypoints: count,
            },
            field::ARG,
        ));
    }
    Waypoints::new_checked(body)
}

impl<B: AsRef<[u8]>> Command<B> {
    /// The command type.
    pub fn command_type(&self) -> CommandType {
        match self {
            Command::TelemetryToCoordinator { .. } => CommandType::TelemetryToCoordinator,
            Command::Landing { .. } => CommandType::Landing,
            Command::Controllers(_) => CommandType::Controllers,
            Command::TrajectorySet(_) => CommandType::TrajectorySet,
            Command::PositionSlaveSet { .. } => CommandType::PositionSlaveSet,
            Command::Time(_) => CommandType::Time,
            Command::PositionSet { .. } => CommandType::PositionSet,
            Command::StatusRequest(r) => r.command_type(),
        }
    }

    /// `true` for a status request.
    pub fn is_status_request(&self) -> bool {
        matches!(self, Command::StatusRequest(_))
    }

    /// The packet length.
    pub fn encoded_len(&self) -> usize {
        match self {
            Command::TelemetryToCoordinator { .. }
            | Command::StatusRequest(StatusRequest::TelemetryToCoordinator(_)) => field::TTC_LEN,
            Command::Landing { .. } | Command::Controllers(_) => field::ONE_BYTE_LEN,
            Command::TrajectorySet(w) => w.encoded_len(),
            Command::PositionSlaveSet { slot: None, .. } => field::SLAVE_LEN,
            Command::PositionSlaveSet { slot: Some(_), .. } => field::SLOT_SLAVE_LEN,
            Command::Time(_) => field::TIME_LEN,
            Command::PositionSet { .. } => field::POSITION_LEN,
            Command::StatusRequest(_) => field::STATUS_REQUEST_LEN,
        }
    }

    /// Writes the packet into `buf`, returning its length. On/off bytes are written
    /// as 0x00/0x01.
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, BufferTooSmall> {
        if let Command::TrajectorySet(w) = self {
            return w.encode_as(Category::Command, buf);
        }
        let mut w = Writer::new(buf, self.encoded_len())?;
        w.u8(Category::Command.into())
            .u8(self.command_type().into());
        match self {
            Command::TelemetryToCoordinator { on, id } => w.on_off(*on).u8((*id).into()),
            Command::Landing { on } => w.on_off(*on),
            Command::Controllers(c) => w.u8((*c).into()),
            Command::TrajectorySet(_) => &mut w,
            Command::PositionSlaveSet { slot, address } => {
                if let Some(slot) = slot {
                    w.u8(slot.get());
                }
                w.bytes(&address.0)
            }
            Command::Time(time) => w.u32(*time),
            Command::PositionSet { elevator, aileron } => w.f32(*elevator).f32(*aileron),
            Command::StatusRequest(r) => {
                w.u8(field::STATUS_REQUEST);
                if let StatusRequest::TelemetryToCoordinator(id) = r {
                    w.u8((*id).into());
                }
                &mut w
            }
        };
        w.finish()
    }

    /// A command borrowing this one's bytes.
    pub fn as_borrowed(&self) -> Command<&[u8]> {
        match self {
            Command::TrajectorySet(w) => Command::TrajectorySet(w.as_borrowed()),
            Command::TelemetryToCoordinator { on, id } => {
                Command::TelemetryToCoordinator { on: *on, id: *id }
            }
            Command::Landing { on } => Command::Landing { on: *on },
            Command::Controllers(c) => Command::Controllers(*c),
            Command::PositionSlaveSet { slot, address } => Command::PositionSlaveSet {
                slot: *slot,
                address: *address,
            },
            Command::Time(t) => Command::Time(*t),
            Command::PositionSet { elevator, aileron } => Command::PositionSet {
                elevator: *elevator,
                aileron: *aileron,
            },
            Command::StatusRequest(r) => Command::StatusRequest(*r),
        }
    }
}

impl<'a> Command<&'a [u8]> {
    /// Moves the bytes to another storage, e.g. `|s| bytes.slice_ref(s)`.
    pub fn map_bytes<U>(self, f: impl FnOnce(&'a [u8]) -> U) -> Command<U> {
        match self {
            Command::TrajectorySet(w) => Command::TrajectorySet(w.map_bytes(f)),
            Command::TelemetryToCoordinator { on, id } => {
                Command::TelemetryToCoordinator { on, id }
            }
            Command::Landing { on } => Command::Landing { on },
            Command::Controllers(c) => Command::Controllers(c),
            Command::PositionSlaveSet { slot, address } => {
                Command::PositionSlaveSet { slot, address }
            }
            Command::Time(t) => Command::Time(t),
            Command::PositionSet { elevator, aileron } => {
                Command::PositionSet { elevator, aileron }
            }
            Command::StatusRequest(r) => Command::StatusRequest(r),
        }
    }
}
