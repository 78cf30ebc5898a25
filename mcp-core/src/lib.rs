//! The MAV communication protocol (MCP): the packets that micro aerial vehicles and
//! their ground station exchange as XBee payloads.
//!
//! `no_std`, no allocator, no `unsafe`. Untrusted bytes never panic: a bad packet is
//! an [`Error`] saying what was wrong and at which byte.
//!
//! # Modules
//!
//! - Identifiers ([`Category`], [`CommandType`], [`TelemetryId`], [`Controller`],
//!   [`LandingState`]): one-byte enums with an `Unknown(u8)` arm, names, `Display`
//!   and `FromStr`. [`TelemetrySet`] holds a set of telemetry ids in 32 bytes.
//! - [`parse`] turns bytes into a [`Packet`]: a [`Command`], [`Telemetry`], a
//!   [`Report`], or message/warning [`Text`]. Variable-length parts are views over the
//!   input (no copy): [`Telemetry`] iterates [`TelemetryRecord`]s, [`Waypoints`]
//!   iterates [`Waypoint`]s. Views are generic over their storage `B: AsRef<[u8]>`, and
//!   [`Packet::map_bytes`] moves a parsed packet to owned storage.
//! - Encoding: `encoded_len` and `encode` on [`Packet`], [`Command`], [`Report`] and
//!   [`Telemetry`]; [`TelemetryBuilder`] and [`TrajectoryBuilder`] build packets item
//!   by item and stop cleanly at the buffer or the [`MAX_PAYLOAD`] limit, and
//!   [`TextBuilder`] builds a message or warning from formatted text.
//! - `Display` on [`Packet`], [`Command`], [`Report`], [`Telemetry`] and [`Waypoints`]
//!   gives one readable line, e.g. `report landing flight`.
//! - [`mav`]: the MAV side, a state machine that answers commands the way the deployed
//!   MAV does.
//!
//! # Wire format decisions
//!
//! The specification leaves some points open; this crate settles them as the deployed
//! firmware does:
//!
//! - `u32` and `f32` (IEEE-754 binary32) are little-endian.
//! - Warnings (`w`) carry 8-bit text like messages.
//! - On/off bytes: any non-zero byte decodes as on; encoders write 0x00/0x01. This is
//!   the one case where parsing and encoding again does not give the same bytes.
//! - Byte 3 = 0xFF is a status request; telemetry-to-coordinator's carries a 4th byte,
//!   the telemetry id. Position set has no status request (0xFF there is float data).
//! - A trajectory's size byte must equal the number of waypoints in the packet length;
//!   size 0xFF is the status request, so at most 254 waypoints.
//! - A telemetry packet with no record (`t`) and a trajectory with no waypoint are valid.
//! - Position slave set has two forms: the specification's (`c 05 addr`, report
//!   `r 05 addr`) and the deployed firmware's (`c 05 slot addr`, slot 0-3, report
//!   `r 05 addr x4`). Both parse; encoders write whichever form the value holds.
//!   This departs from the specification, which has only the first form.
//!
//! # Parsing
//!
//! ```
//! use mcp_core::{parse, Packet, Report, TelemetryId, LandingState};
//!
//! // A telemetry packet: altitude = 1.5.
//! let bytes = [b't', 0x01, 0x00, 0x00, 0xC0, 0x3F];
//! let Packet::Telemetry(telemetry) = parse(&bytes)? else { panic!("not telemetry") };
//! for record in &telemetry {
//!     assert_eq!(record.id, TelemetryId::Altitude);
//!     assert_eq!(record.value, 1.5);
//! }
//!
//! // A landing report.
//! assert_eq!(parse(b"r\x02\x04")?, Packet::Report(Report::Landing(LandingState::Flight)));
//!
//! // Errors say what and where.
//! let err = parse(b"x").unwrap_err();
//! assert_eq!(err.to_string(), "unknown packet category 0x78 (at offset 0)");
//! # Ok::<(), mcp_core::Error>(())
//! ```
//!
//! # Encoding
//!
//! ```
//! use mcp_core::{Command, Packet, StatusRequest, TelemetryId};
//!
//! let command: Packet<&[u8]> = Packet::Command(Command::TelemetryToCoordinator {
//!     on: true,
//!     id: TelemetryId::PitchAngle,
//! });
//! let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
//! let len = command.encode(&mut buf)?;
//! assert_eq!(&buf[..len], b"c\x01\x01\x19");
//!
//! let request = Command::status_request(StatusRequest::Time);
//! let len = request.encode(&mut buf)?;
//! assert_eq!(&buf[..len], b"c\x06\xff");
//! # Ok::<(), mcp_core::BufferTooSmall>(())
//! ```
//!
//! # Features
//!
//! - `defmt`: [`defmt::Format`](https://docs.rs/defmt/1/defmt/trait.Format.html) for
//!   the public value types (packets and their views, parse errors, identifier enums,
//!   addresses), for firmware that logs with defmt. Addresses print in hex, as their
//!   `Display` does. Off by default.
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
// On docs.rs (nightly, `--cfg docsrs`): each item says which feature it needs.
#![cfg_attr(docsrs, feature(doc_cfg))]
// No indexing or slicing that could go out of bounds, no unwrap, no panic, whatever the
// bytes (the lints below). Arithmetic keeps to invariants that the fuzz targets check
// with overflow checks on.
#![cfg_attr(
    not(test),
    deny(
        clippy::indexing_slicing,
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::unreachable
    )
)]

mod address;
mod command;
mod confirm;
mod display;
mod error;
mod field;
mod id;
pub mod mav;
mod packet;
mod read;
mod report;
mod telemetry;
mod text;
mod trajectory;
mod write;

pub use address::{Address, ParseAddressError, Slot};
pub use command::{Command, StatusRequest};
pub use confirm::{Confirmation, TIME_CONFIRM_WINDOW};
pub use error::{BufferTooSmall, Error, ErrorKind, Expected, Full};
pub use id::{Category, CommandType, Controller, LandingState, ParseIdError, TelemetryId};
pub use mav::{TelemetrySet, TelemetrySetIter};
pub use packet::{Packet, parse};
pub use report::{Report, SlaveAddresses};
pub use telemetry::{Telemetry, TelemetryBuilder, TelemetryIter, TelemetryRecord};
pub use text::{Quoted, Text, TextBuilder};
pub use trajectory::{MAX_WAYPOINTS, TrajectoryBuilder, Waypoint, WaypointIter, Waypoints};

/// The largest MCP packet: the XBee RF payload limit (unicast, API mode, fragmented).
///
/// Without fragmentation a Zigbee XBee carries at most 84 bytes in a unicast
/// ([`MAX_UNFRAGMENTED_PAYLOAD`]), as the deployed MAV's radios do: a firmware sizes
/// the packets it sends by that, and its receive buffers by this only if the ground
/// station may send it more (a long trajectory or message, in fragments).
///
/// The builders ([`TelemetryBuilder`], [`TrajectoryBuilder`]) stop at this limit. The
/// parser and [`Packet::encode`] do not enforce it: a longer packet (read from a radio
/// that carries more, or built by hand) parses and encodes, and it is up to the sender
/// to keep to what its radios carry.
pub const MAX_PAYLOAD: usize = 255;

/// The largest MCP packet a Zigbee XBee carries in one radio packet, without
/// fragmentation: 84 bytes, its `NP` (`xbee_api::TransmitRequestRepr::MAX_UNICAST_DATA`;
/// less with APS encryption or source routing). A MAV that sizes the packets it sends
/// by this (its telemetry buffer, say) keeps each in one radio packet; a longer one
/// goes out in fragments, lost whole if one fragment is.
pub const MAX_UNFRAGMENTED_PAYLOAD: usize = 84;

/// This crate's README, its example compiled and run as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
