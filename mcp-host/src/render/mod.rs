//! How frames and packets are shown: one line of text ([`text`]) or one JSON object
//! ([`json`]) each, as the `mcp-gs` ground station prints them.

pub mod json;
pub mod text;
