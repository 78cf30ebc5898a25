//! Host side of the MAV communication protocol (MCP): links to an XBee radio.
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod link;
pub mod options;
pub mod transport;

pub use link::{Link, LinkParseError};
pub use options::{LinkOptions, ReconnectPolicy};
pub use transport::{Connector, LinkError, Transport};
