//! How frames and packets are shown: one line of text ([`text`]) or one JSON object
//! ([`json`]) each, as the `mcp-gs` ground station prints them; durations as
//! [`Seconds`].

pub mod json;
mod seconds;
pub mod text;

pub use seconds::Seconds;
