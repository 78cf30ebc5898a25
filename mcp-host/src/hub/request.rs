//! What the hub reads in a client's request: whether it is whole, its AT command,
//! whether it gets several answers, and the answer the hub gives one it did not send.

use xbee_api::frame::frame_type::{
    AT_COMMAND, AT_COMMAND_QUEUE, AT_COMMAND_RESPONSE, EXPLICIT_ADDRESSING_COMMAND,
    REGISTER_JOINING_DEVICE, REMOTE_AT_COMMAND, REMOTE_AT_RESPONSE, TRANSMIT_REQUEST,
    TRANSMIT_STATUS, TX_REQUEST_16, TX_REQUEST_64, TX_REQUEST_IPV4, TX_STATUS,
};

/// Whether a request gets several answers under its id: node discovery, find neighbors
/// and active scan, as local AT (or queued AT) commands or remote ones (a remote radio
/// sends each answer on its own), and any remote AT command to the broadcast address
/// (every radio in range answers).
pub(super) fn answered_many_times(data: &[u8]) -> bool {
    // Command mode takes a command's letters in either case, and a radio may in API
    // frames too: kept open for the window at worst, never cut short.
    let gathers = at_command(data).is_some_and(|command| {
        [b"ND", b"AS", b"FN"]
            .iter()
            .any(|name| command.eq_ignore_ascii_case(*name))
    });
    gathers
        || matches!(
            data,
            [REMOTE_AT_COMMAND, _, 0, 0, 0, 0, 0, 0, 0xFF, 0xFF, ..]
        )
}

/// The AT command of an AT request or answer (frame data): local (0x08, 0x09, 0x88) or
/// remote (0x17, 0x97); `None` for other frames, or one cut short of it.
pub(super) fn at_command(data: &[u8]) -> Option<[u8; 2]> {
    let at = match *data.first()? {
        AT_COMMAND | AT_COMMAND_QUEUE | AT_COMMAND_RESPONSE => 2,
        REMOTE_AT_RESPONSE => 12,
        REMOTE_AT_COMMAND => 13,
        _ => return None,
    };
    data.get(at..at + 2)?.try_into().ok()
}

/// Whether `data`, a request of a type the hub routes (see
/// [`answer_type`](xbee_api::frame::frame_type::answer_type)), holds the fixed fields of
/// its type: a radio drops a request cut short without an answer.
pub(super) fn is_whole_request(data: &[u8]) -> bool {
    match data.first() {
        // 802.15.4 Transmit Request, 64-bit address: type, id, address, options.
        Some(&TX_REQUEST_64) => data.len() >= 11,
        // 16-bit address: type, id, address, options.
        Some(&TX_REQUEST_16) => data.len() >= 5,
        // Transmit Request IPv4: type, id, address, two ports, protocol, options.
        Some(&TX_REQUEST_IPV4) => data.len() >= 12,
        // Register Joining Device: type, id, 64-bit address, 0xFFFE, options (and the
        // key, none to take the device out of the table).
        Some(&REGISTER_JOINING_DEVICE) => data.len() >= 13,
        // The others `xbee-api` types (0x08, 0x09, 0x10, 0x11, 0x17).
        _ => xbee_api::Frame::parse_bytes(data).is_ok(),
    }
}

/// The answer the hub gives a request it did not send
/// ([`REQUEST_WAIT`](super::REQUEST_WAIT)), as the radio answers one it could not carry
/// out, under the client's own id: an AT command `ERROR` (1), a transmission's delivery
/// status 0x32 (resource error: the radio's own word for a lack of buffers; in a Transmit
/// Status 0x8B, or a TX Status 0x89 for the 802.15.4 and IPv4 Transmit Requests), a
/// remote AT command's transmission failure (4). `None` for the other requests (Register
/// Joining Device), and for requests cut short ([`is_whole_request`]), whose clients wait
/// for their own timeouts.
pub(super) fn not_sent_answer(request: &[u8]) -> Option<Vec<u8>> {
    if !is_whole_request(request) {
        return None;
    }
    match request {
        [AT_COMMAND | AT_COMMAND_QUEUE, id, a, b, ..] => {
            Some(vec![AT_COMMAND_RESPONSE, *id, *a, *b, 0x01])
        }
        // Resource error in a TX Status too, as 802.15.4 (S2C) and IPv4 radios give it.
        [TX_REQUEST_64 | TX_REQUEST_16 | TX_REQUEST_IPV4, id, ..] => {
            Some(vec![TX_STATUS, *id, 0x32])
        }
        // The 16-bit address after the 64-bit one; no retries, no discovery.
        [
            TRANSMIT_REQUEST | EXPLICIT_ADDRESSING_COMMAND,
            id,
            rest @ ..,
        ] => {
            let mut answer = vec![TRANSMIT_STATUS, *id];
            answer.extend_from_slice(rest.get(8..10)?);
            answer.extend_from_slice(&[0x00, 0x32, 0x00]);
            Some(answer)
        }
        // The 64- and 16-bit addresses, options, the command.
        [REMOTE_AT_COMMAND, id, rest @ ..] => {
            let (addresses, command) = (rest.get(..10)?, rest.get(11..13)?);
            let mut answer = vec![REMOTE_AT_RESPONSE, *id];
            answer.extend_from_slice(addresses);
            answer.extend_from_slice(command);
            answer.push(0x04);
            Some(answer)
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn discovery_is_answered_many_times_in_either_case_and_other_commands_once() {
        for many in [
            &[0x08, 1, b'N', b'D'][..],
            &[0x08, 1, b'n', b'd'],
            &[0x08, 1, b'F', b'N'],
            &[0x09, 1, b'A', b's', 0],
            // Any remote command to every radio, and a remote radio's discovery.
            &[
                0x17, 1, 0, 0, 0, 0, 0, 0, 0xFF, 0xFF, 0xFF, 0xFE, 0, b'N', b'I',
            ],
            &[
                0x17, 1, 0, 0, 0, 0, 0, 0, 0x12, 0x34, 0xFF, 0xFE, 0, b'f', b'n',
            ],
        ] {
            assert!(answered_many_times(many), "{many:02x?}");
        }
        for once in [
            &[0x08, 1, b'N', b'I'][..],
            &[0x08, 1, b'N'],
            &[0x08, 1],
            &[0x10, 1, b'N', b'D'],
            &[
                0x17, 1, 0, 0, 0, 0, 0, 0, 0x12, 0x34, 0xFF, 0xFE, 0, b'D', b'H',
            ],
            &[0x17, 1, 0, 0, 0, 0, 0, 0, 0x12, 0x34, 0xFF, 0xFE, 0, b'N'],
        ] {
            assert!(!answered_many_times(once), "{once:02x?}");
        }
    }

    #[test]
    fn a_request_not_sent_is_answered_as_the_radio_answers_one_it_could_not_carry_out() {
        use xbee_api::{AtStatus, DeliveryStatus, Frame};
        let at = not_sent_answer(&[0x08, 7, b'N', b'I', b'G', b'S']).unwrap();
        match Frame::parse_bytes(&at) {
            Ok(Frame::AtCommandResponse(r)) => {
                assert_eq!(
                    (r.frame_id, r.command, r.status),
                    (7, *b"NI", AtStatus::Error)
                );
            }
            other => panic!("{other:?}"),
        }
        let mut tx = vec![
            0x10, 9, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0x12, 0x34, 0, 0,
        ];
        tx.extend_from_slice(b"c\x02\x01");
        match Frame::parse_bytes(&not_sent_answer(&tx).unwrap()) {
            Ok(Frame::TransmitStatus(s)) => {
                assert_eq!(s.frame_id, 9);
                assert_eq!(s.dst16.0, 0x1234);
                assert_eq!(s.delivery, DeliveryStatus::ResourceError);
            }
            other => panic!("{other:?}"),
        }
        let remote = [
            0x17, 3, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0x02, b'D', b'H',
        ];
        match Frame::parse_bytes(&not_sent_answer(&remote).unwrap()) {
            Ok(Frame::RemoteAtResponse(r)) => {
                assert_eq!(r.frame_id, 3);
                assert_eq!(r.src64.0, 0x0013_A200_40B5_99B9);
                assert_eq!(r.src16.0, 0xFFFE);
                assert_eq!(r.command, *b"DH");
                assert_eq!(r.status, AtStatus::TxFailure);
            }
            other => panic!("{other:?}"),
        }
        // 802.15.4 (64- and 16-bit addresses) and IPv4 Transmit Requests: TX Status
        // 0x89, the same resource error.
        let tx64 = [
            0x00, 4, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0x00, b'c',
        ];
        let tx16 = [0x01, 5, 0x12, 0x34, 0x00, b'c'];
        let ipv4 = [
            0x20, 6, 10, 0, 0, 2, 0x26, 0x16, 0x26, 0x16, 0x00, 0x00, b'c',
        ];
        for (request, id) in [(&tx64[..], 4), (&tx16[..], 5), (&ipv4[..], 6)] {
            assert_eq!(
                not_sent_answer(request),
                Some(vec![0x89, id, 0x32]),
                "{request:02x?}"
            );
            // Cut short of their fixed fields: no answer, as from the radio.
            let short = &request[..request.len() - 2];
            assert_eq!(not_sent_answer(short), None, "{short:02x?}");
        }
        // Requests cut short, and those of other types, get no answer.
        for none in [
            &[0x08, 1, b'N'][..],
            &tx[..11],
            &remote[..14],
            &[0x24, 1, 0],
            &[
                0x24, 1, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0,
            ],
        ] {
            assert_eq!(not_sent_answer(none), None, "{none:02x?}");
        }
    }
}
