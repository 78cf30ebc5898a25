//! XBee API frames, API modes 1 and 2, without allocation.
//!
//! An API frame on the wire is `7E | length (u16 big-endian) | frame data | checksum`,
//! where the length counts the frame data only, the frame data starts with the frame
//! type byte, and the checksum is `0xFF - (sum of the frame data bytes & 0xFF)`. In API
//! mode 2 every byte after the start delimiter that is 0x7E, 0x7D, 0x11 or 0x13 is sent
//! as `0x7D, byte ^ 0x20` (length and checksum are computed before escaping).
//!
//! - [`Decoder`]: streaming decoder with a fixed buffer, fed a byte or a slice at a
//!   time, yielding [`RawFrame`]s (untyped frame data) or [`DecodeError`]s. Its API
//!   mode is given at run time ([`Decoder::new`]) or, in a firmware whose radio is set
//!   once, fixed in its type (`Decoder<N, Mode2>` from [`Decoder::fixed`]), which links
//!   only that mode's code.
//! - [`Frame`]: typed frames, parsed from a [`RawFrame`]; unknown frame types pass
//!   through intact. Each frame type has a zero-copy view and a `*Repr` in [`frame`].
//! - [`EncodeFrame`]: encodes any frame into a caller buffer in either mode.
//! - [`InPlaceFrame`]: builds a frame in the buffer it goes out from, the payload
//!   written after the header by the caller, then framed and escaped where it lies.
//! - [`Inbox`]: a firmware's receive path: the decoder and a fixed queue of the
//!   payloads received, fed from the UART's interrupt, emptied by the main loop, that
//!   loses no frame when the queue is full and gives up a frame a quiet line left.
//!
//! ```
//! use xbee_api::{Address16, Address64, ApiMode, Decoder, EncodeFrame, Frame};
//! use xbee_api::frame::transmit_request::TransmitRequestRepr;
//!
//! let request = TransmitRequestRepr {
//!     frame_id: 1,
//!     dst64: Address64(0x0013A200400A0127),
//!     dst16: Address16::UNKNOWN,
//!     radius: 0,
//!     options: 0,
//!     data: b"TxData0A",
//! };
//! let mut wire = [0u8; 64];
//! let n = request.encode(ApiMode::Escaped, &mut wire).unwrap();
//! assert_eq!(n, request.encoded_len(ApiMode::Escaped));
//!
//! let mut decoder: Decoder = Decoder::new(ApiMode::Escaped);
//! let (consumed, event) = decoder.decode(&wire[..n]);
//! assert_eq!(consumed, n);
//! let frame = Frame::parse(event.unwrap().unwrap()).unwrap();
//! assert_eq!(frame, Frame::TransmitRequest(request));
//! ```
//!
//! # On a microcontroller
//!
//! A MAV's receive path feeds each byte from the UART to [`Decoder::push`] and takes
//! whatever else that byte completed with [`Decoder::poll`]; a Receive Packet's view
//! ([`ReceivePacket::new_checked`]) hands over the MCP payload in place. In API mode 1 a
//! timer calls [`Decoder::finish`] once, then `poll`, when the line goes quiet part way
//! through a frame (see `finish`). The reply goes to the coordinator in a Transmit
//! Request ([`TransmitRequestRepr::unicast`]): with a UART written a byte at a time,
//! [`EncodeFrame::write_to`]`(mode, |byte| uart_write(byte))` needs no frame buffer at
//! all; [`EncodeFrame::encode`] writes it into a buffer, and [`InPlaceFrame`] builds it
//! in the buffer it goes out from (for DMA), with the payload written in place.
//! Most firmware wants [`Inbox`] for the receiving, in one value: the decoder, a fixed
//! queue of payloads that a full queue loses none of, and the quiet-line timer (its
//! docs have the interrupt handlers and the main loop's sleep).
//!
//! ```
//! use xbee_api::{
//!     Address64, ApiMode, Decoder, EncodeFrame, Mode2, ReceivePacket, TransmitRequestRepr,
//! };
//!
//! // In a `static`, as `Decoder::fixed` is `const`; the mode fixed in its type.
//! let mut decoder: Decoder<128, Mode2> = Decoder::fixed();
//! // A Receive Packet from 0013A20040522BAA holding `c 02 FF`, as the UART gives it.
//! let uart = [
//!     0x7E, 0x00, 0x0F, 0x90, 0x00, 0x7D, 0x33, 0xA2, 0x00, 0x40, 0x52, 0x2B, 0xAA,
//!     0xFF, 0xFE, 0x01, 0x63, 0x02, 0xFF, 0xF1,
//! ];
//! let mut reply = [0u8; 64];
//! let mut reply_len = 0;
//! for byte in uart {
//!     // The receive interrupt: one byte, then every event it completes.
//!     let mut event = decoder.push(byte);
//!     while let Some(result) = event {
//!         // A bad frame is an `Err` saying why, counted in `decoder.stats()`.
//!         let frame = result.ok();
//!         if let Some(rx) = frame.and_then(|f| ReceivePacket::new_checked(f.data()).ok()) {
//!             // `rx.data()` is the MCP packet (`mcp_core::parse`); answer it.
//!             assert_eq!(rx.data(), b"c\x02\xff");
//!             let answer = TransmitRequestRepr::unicast(Address64::COORDINATOR, b"r\x02\x01");
//!             reply_len = answer.encode(ApiMode::Escaped, &mut reply).unwrap_or(0);
//!         }
//!         event = decoder.poll();
//!     }
//! }
//! // 17 bytes of frame data: the length's 0x11 (XON) goes out escaped in mode 2.
//! assert_eq!(reply.get(..5), Some(&[0x7E, 0x00, 0x7D, 0x31, 0x10][..]));
//! assert_eq!(reply_len, 23); // and its checksum, 0x7D, escaped too
//! ```
//!
//! The repository's README ("On a microcontroller") has a whole interrupt-driven recipe
//! with a fixed-size inbox, its `examples/firmware` a MAV firmware run in QEMU, and
//! `examples/firmware-async` the same MAV as one async task over `embedded-io-async`.
//!
//! # Features
//!
//! - `defmt`: [`defmt::Format`](https://docs.rs/defmt/1/defmt/trait.Format.html) for
//!   the public value types (frames and their views, decode and encode errors, status
//!   codes, addresses, the decoder's counters), for firmware that logs with defmt.
//!   Addresses print in hex, as their `Display` does. Off by default.
//! - `embedded-io`: the `io` module, frames read from and written to any
//!   [`embedded_io`](https://docs.rs/embedded-io/0.7) reader and writer (a HAL's UART):
//!   `io::FrameReader` and `io::write_frame`. `embedded-io-async` adds their async
//!   forms for `embedded_io_async` (Embassy's drivers). Off by default. Both crates are
//!   re-exported in `io` (`io::embedded_io`, `io::embedded_io_async`), so that a
//!   firmware names the traits at the version this crate implements.
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
// On docs.rs (nightly, `--cfg docsrs`): each item says which feature it needs.
#![cfg_attr(docsrs, feature(doc_cfg))]
// No indexing or slicing that could go out of bounds, no unwrap, no panic, whatever the
// input (the lints below). Arithmetic keeps to invariants that the fuzz targets check
// with overflow checks on. The frame views in `frame` index their fields as smoltcp's
// do: in bounds once `check_len` passed (`new_checked`).
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
mod decode_error;
mod decoder;
mod decoder_mode;
mod encode;
mod error;
mod in_place;
mod inbox;
#[macro_use]
mod status;
// After `status`, whose `code_enum!` they use.
#[allow(clippy::indexing_slicing)]
pub mod frame;
#[cfg(feature = "embedded-io")]
pub mod io;
mod mode;
mod node;
mod raw;
mod stats;
mod unescape;
#[cfg(target_pointer_width = "64")]
mod window;
pub mod wire;

pub use address::{Address16, Address64, ParseAddressError};
pub use decode_error::DecodeError;
pub use decoder::{DEFAULT_CAPACITY, DecodeEvent, Decoder, decoder_buffer_len};
pub use decoder_mode::{AnyMode, DecoderMode, FixedMode, Mode1, Mode2};
pub use encode::{EncodeFrame, MAX_FRAME_DATA_LEN, max_encoded_len};
pub use error::{EncodeError, FrameError};
pub use frame::Frame;
pub use frame::at_command::{AtCommand, AtCommandRepr, at_number};
pub use frame::at_command_response::{AtCommandResponse, AtCommandResponseRepr};
pub use frame::explicit_addressing_command::{
    ExplicitAddressingCommand, ExplicitAddressingCommandRepr,
};
pub use frame::explicit_rx_indicator::{ExplicitRxIndicator, ExplicitRxIndicatorRepr};
pub use frame::modem_status::{ModemStatusFrame, ModemStatusRepr};
pub use frame::node_identification_indicator::{
    NodeIdentificationIndicator, NodeIdentificationIndicatorRepr, SourceEvent,
};
pub use frame::receive_packet::{ReceivePacket, ReceivePacketRepr, options as receive_options};
pub use frame::remote_at_command::{RemoteAtCommand, RemoteAtCommandRepr};
pub use frame::remote_at_response::{RemoteAtResponse, RemoteAtResponseRepr};
pub use frame::transmit_request::{
    TransmitRequest, TransmitRequestRepr, options as transmit_options,
};
pub use frame::transmit_status::{TransmitStatus, TransmitStatusRepr};
pub use in_place::InPlaceFrame;
pub use inbox::{Inbox, InboxFull, InboxStats, Received, ReceivedError};
pub use mode::{ApiMode, InvalidApiMode};
pub use node::{DeviceType, NodeInfo, NodeInfoError};
pub use raw::RawFrame;
pub use stats::DecoderStats;
pub use status::{AtStatus, DeliveryStatus, DiscoveryStatus, ModemStatus};

/// This crate's README, its example compiled and run as a doc test.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;
