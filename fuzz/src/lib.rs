//! Shared checks of the fuzz targets: collecting decoder events as owned values,
//! feeding a stream to the XBee decoder whole, in chunks and a byte at a time, plain
//! reference decoders to compare it with, an `Inbox` on the same stream, and round trips
//! of single frames.
#![forbid(unsafe_code)]

pub mod events;
pub mod inbox;
pub mod reference;
pub mod split;
pub mod wire;
