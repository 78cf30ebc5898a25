//! Shared checks of the fuzz targets: collecting decoder events as owned values, and
//! feeding a stream to the XBee decoder whole, in chunks and a byte at a time.
#![forbid(unsafe_code)]

pub mod events;
pub mod split;
pub mod wire;
