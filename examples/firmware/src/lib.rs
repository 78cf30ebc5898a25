//! MAV firmware for the TI LM3S6965 (Cortex-M3) on the MCP crates.
//!
//! UART0 carries XBee API frames (API mode 1, 115200 8N1) to and from the MAV's XBee.
//! The UART0 receive interrupt feeds [`xbee_api::Decoder`] byte by byte; the payloads
//! of Receive Packets (0x90) are MCP commands, parsed by [`mcp_core::Command::parse`] and
//! handled by [`mcp_core::mav::Mav`] over a small flight model ([`model`]). Answers,
//! unsolicited reports and the 20 Hz telemetry go to the coordinator in Transmit
//! Requests (0x10). No heap; `unsafe` only in [`hw`], for register access.
//!
//! The binaries: `mav-firmware` (the firmware), `rx_path` and `baseline` (the
//! receive path alone and its baseline, to measure its footprint).
#![no_std]
#![deny(missing_docs)]

pub mod app;
pub mod clock;
pub mod hw;
pub mod model;
pub mod rx;
pub mod tx;
