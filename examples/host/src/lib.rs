//! Small complete ground-station programs on `mcp-host`, each a binary of this package.
//! Start a simulated MAV first, then run one:
//!
//! ```sh
//! mcp-gs sim --link tcp-listen:127.0.0.1:9750      # or: cargo run -p mcp-host --bin mcp-gs -- sim ...
//! cargo run -p mcp-host-examples --bin telemetry -- tcp:127.0.0.1:9750
//! ```
//!
//! - `telemetry [LINK] [MAV] [SECONDS]`: a MAV's altitude telemetry, turned on again
//!   each time the link comes back.
//! - `land [LINK] [MAV] [on|off]`: a command, its delivery, and the MAV's report.
//! - `record [LINK] [FILE] [SECONDS]`: every frame of the link, both ways, to a
//!   recording, while asking the MAV's landing state.
//! - `read_recording FILE`: the MCP packets of a recording, with their times.
//! - `watchdog [LINK] [SECONDS] [DISCOVERY_WINDOW]`: every MAV in range, found by node
//!   discovery, a line each a second; a silent one asked its state, and reported lost
//!   if it does not answer; across the link dropping and coming back.
//!
//! Each takes the link as its first argument (`tcp:127.0.0.1:9750` by default;
//! `serial:/dev/ttyUSB0` for a real radio), and a MAV's address where it needs one
//! (the simulator's first MAV, `0013A20040B599B9`, by default).

#![forbid(unsafe_code)]
#![deny(missing_docs)]

use mcp_host::xbee_api::Address64;
use mcp_host::{Link, LinkParseError};

/// The link given as the first argument, or `tcp:127.0.0.1:9750`.
pub fn link(arg: Option<String>) -> Result<Link, LinkParseError> {
    arg.as_deref().unwrap_or("tcp:127.0.0.1:9750").parse()
}

/// The MAV given as an argument, or the simulator's first one.
pub fn mav(arg: Option<String>) -> Result<Address64, Box<dyn std::error::Error>> {
    Ok(arg.as_deref().unwrap_or("0013A20040B599B9").parse()?)
}

/// The workspace's README, its examples compiled and run as doc tests (here, in a
/// package never published, as the README is no part of any crate's).
#[cfg(doctest)]
#[doc = include_str!("../../../README.md")]
pub struct WorkspaceReadmeDoctests;
