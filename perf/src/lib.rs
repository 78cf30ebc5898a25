//! Benchmarks of the receive path against memcpy and the `mavlink` crate.
//!
//! The library holds what the benchmark (`benches/pipeline.rs`), the instruction-count
//! examples (`examples/`, run by `callgrind.sh`) and the tests share:
//!
//! - [`mcp_stream`]: a seeded stream of XBee Receive Packets (API mode 1 or 2), each
//!   carrying an MCP telemetry packet of [`VALUES_PER_PACKET`] values;
//! - [`mavlink_stream`]: a MAVLink v2 stream of ATTITUDE messages carrying as many
//!   `f32` values, the same class of traffic in another protocol;
//! - [`Machine`]: the processor and build a table of figures was measured on;
//! - [`floor`]: the least a byte-at-a-time decoder does, to measure `push` against;
//! - [`run`]: the measured loops (slice decoder, byte-at-a-time decoder, the pipeline
//!   to typed telemetry values), each returning [`Totals`] so that nothing is
//!   optimised away and every result can be checked.
//!
//! Without its default `std` feature (the generators) the crate is `no_std`: `run` and
//! [`Totals`] are the same code on a microcontroller (`cortex-m/`).
//!
//! ```
//! use perf::{mcp_stream, run};
//! use xbee_api::ApiMode;
//!
//! let stream = mcp_stream(ApiMode::Escaped, 4096);
//! let totals = run::pipeline(&stream.bytes, ApiMode::Escaped);
//! assert_eq!(totals, stream.totals);
//! ```
#![cfg_attr(not(feature = "std"), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod floor;
#[cfg(feature = "std")]
mod machine;
#[cfg(feature = "std")]
mod mavlink_stream;
#[cfg(feature = "std")]
mod mcp_stream;
mod rng;
pub mod run;
mod totals;

#[cfg(feature = "std")]
pub use machine::Machine;
#[cfg(feature = "std")]
pub use mavlink_stream::{
    ATTITUDE_CRC_EXTRA, ATTITUDE_ID, ATTITUDE_VALUES, crc_x25, mavlink_stream,
};
#[cfg(feature = "std")]
pub use mcp_stream::{VALUES_PER_PACKET, mcp_stream};
pub use rng::Rng;
#[cfg(feature = "std")]
pub use totals::Stream;
pub use totals::Totals;
