//! The transmit path: MCP payloads to the coordinator in Transmit Requests (0x10).

use xbee_api::{Address64, ApiMode, EncodeFrame, TransmitRequestRepr, transmit_options};

use crate::hw;
use crate::rx::MAX_PAYLOAD;

/// Transmit option 0x01: disable retries, as the deployed MAV sends.
pub const TRANSMIT_OPTIONS: u8 = transmit_options::DISABLE_RETRIES;

/// Sends `payload` to the coordinator (64-bit 0000000000000000, 16-bit FFFE), frame
/// id 0 (no transmit status), API mode 1, straight into the UART's transmit FIFO (no
/// frame buffer). A payload longer than [`MAX_PAYLOAD`] is not sent; returns whether
/// it was.
pub fn send_to_coordinator(payload: &[u8]) -> bool {
    if payload.len() > MAX_PAYLOAD {
        return false;
    }
    let request = TransmitRequestRepr {
        options: TRANSMIT_OPTIONS,
        ..TransmitRequestRepr::unicast(Address64::COORDINATOR, payload)
    };
    request
        .write_to(ApiMode::Unescaped, hw::uart0_write_byte)
        .is_ok()
}
