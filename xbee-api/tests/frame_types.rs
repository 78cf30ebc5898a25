//! Which frame answers which request under its frame id, for every frame type byte:
//! the table of Digi's API reference (XBee/XBee-PRO Zigbee, DigiMesh, 802.15.4, Wi-Fi
//! and Cellular user guides).

use xbee_api::frame::frame_type::{answer_type, carries_frame_id, is_answer, is_from_radio};

/// Requests answered under their frame id, and the frame type of the answer.
const ANSWERED: [(u8, u8); 9] = [
    (0x00, 0x89), // TX Request 64-bit address: TX Status
    (0x01, 0x89), // TX Request 16-bit address: TX Status
    (0x08, 0x88), // AT Command: AT Command Response
    (0x09, 0x88), // AT Command - Queue Parameter Value: AT Command Response
    (0x10, 0x8B), // Transmit Request: Transmit Status
    (0x11, 0x8B), // Explicit Addressing Command: Transmit Status
    (0x17, 0x97), // Remote AT Command: Remote AT Command Response
    (0x20, 0x89), // Transmit Request IPv4: TX Status
    (0x24, 0xA4), // Register Joining Device: Register Joining Device Status
];

#[test]
fn every_frame_type_byte_is_a_request_answered_an_answer_or_neither() {
    for frame_type in 0..=u8::MAX {
        let answered = ANSWERED.iter().find(|(request, _)| *request == frame_type);
        assert_eq!(
            answer_type(frame_type),
            answered.map(|(_, answer)| *answer),
            "0x{frame_type:02X}"
        );
        let answers = ANSWERED.iter().any(|(_, answer)| *answer == frame_type);
        assert_eq!(is_answer(frame_type), answers, "0x{frame_type:02X}");
        assert_eq!(
            carries_frame_id(frame_type),
            answered.is_some() || answers,
            "0x{frame_type:02X}"
        );
        assert_eq!(
            is_from_radio(frame_type),
            frame_type >= 0x80,
            "0x{frame_type:02X}"
        );
        // A request is sent to the radio, its answer comes from it.
        if let Some(answer) = answer_type(frame_type) {
            assert!(!is_from_radio(frame_type) && is_from_radio(answer));
        }
    }
}
