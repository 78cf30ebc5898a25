//! The transmit path: MCP payloads to the coordinator in Transmit Requests (0x10).

use xbee_api::frame::transmit_request::options::DISABLE_RETRIES;
use xbee_api::{Address16, Address64, ApiMode, EncodeFrame, TransmitRequestRepr, max_encoded_len};

use crate::hw;
use crate::rx::MAX_PAYLOAD;

/// The longest frame written: delimiter, length, frame data and checksum around an
/// 84-byte payload.
pub const MAX_FRAME_LEN: usize = max_encoded_len(
    TransmitRequestRepr::HEADER_LEN + MAX_PAYLOAD,
    ApiMode::Unescaped,
);

/// Transmit option 0x01: disable retries, as the deployed MAV sends.
pub const TRANSMIT_OPTIONS: u8 = DISABLE_RETRIES;

/// Sends `payload` to the coordinator (64-bit 0000000000000000, 16-bit FFFE), frame
/// id 0 (no transmit status), API mode 1. A payload longer than [`MAX_PAYLOAD`] is not
/// sent; returns whether it was.
pub fn send_to_coordinator(payload: &[u8]) -> bool {
    if payload.len() > MAX_PAYLOAD {
        return false;
    }
    let request = TransmitRequestRepr {
        frame_id: 0,
        dst64: Address64::COORDINATOR,
        dst16: Address16::UNKNOWN,
        radius: 0,
        options: TRANSMIT_OPTIONS,
        data: payload,
    };
    let mut frame = [0u8; MAX_FRAME_LEN];
    match request.encode(ApiMode::Unescaped, &mut frame) {
        Ok(len) => {
            hw::uart0_write(frame.get(..len).unwrap_or_default());
            true
        }
        Err(_) => false,
    }
}
