//! Every frame of Digi's manuals (testdata/digi-manual.txt): decodes to the documented
//! fields, and encodes from those fields to the exact bytes, in the mode given.

mod common;

use common::{Owned, decode_bytes, decode_slices, hex, testdata};
use xbee_api::{
    Address16, Address64, ApiMode, AtCommandRepr, AtCommandResponseRepr, AtStatus, DeliveryStatus,
    DiscoveryStatus, EncodeFrame, ExplicitAddressingCommandRepr, ExplicitRxIndicatorRepr, Frame,
    ModemStatus, ModemStatusRepr, ReceivePacketRepr, RemoteAtCommandRepr, RemoteAtResponseRepr,
    TransmitRequestRepr, TransmitStatusRepr,
};

/// The frame each line of digi-manual.txt holds, in file order.
fn expected() -> Vec<Frame<'static>> {
    let tx = Frame::TransmitRequest(TransmitRequestRepr {
        frame_id: 0x01,
        dst64: Address64(0x0013_A200_400A_0127),
        dst16: Address16::UNKNOWN,
        radius: 0,
        options: 0,
        data: b"TxData0A",
    });
    let rx = Frame::ReceivePacket(ReceivePacketRepr {
        src64: Address64(0x0013_A200_4052_2BAA),
        src16: Address16(0x7D84),
        options: 0x01,
        data: b"RxData",
    });
    let explicit = Frame::ExplicitAddressingCommand(ExplicitAddressingCommandRepr {
        frame_id: 0x01,
        dst64: Address64::COORDINATOR,
        dst16: Address16::UNKNOWN,
        src_endpoint: 0xA0,
        dst_endpoint: 0xA1,
        cluster_id: 0x1554,
        profile_id: 0xC105,
        radius: 0,
        options: 0,
        data: b"TxData",
    });
    let unknown = Frame::Unknown {
        frame_type: 0x23,
        data: &[0x11],
    };
    vec![
        tx,
        tx,
        rx,
        rx,
        Frame::TransmitStatus(TransmitStatusRepr {
            frame_id: 0x01,
            dst16: Address16(0x7D84),
            retries: 0,
            delivery: DeliveryStatus::Success,
            discovery: DiscoveryStatus::AddressDiscovery,
        }),
        Frame::TransmitStatus(TransmitStatusRepr {
            frame_id: 0x52,
            dst16: Address16(0x1234),
            retries: 2,
            delivery: DeliveryStatus::Success,
            discovery: DiscoveryStatus::AddressDiscovery,
        }),
        Frame::AtCommand(AtCommandRepr {
            queued: false,
            frame_id: 0x52,
            command: *b"NJ",
            parameter: &[],
        }),
        Frame::AtCommand(AtCommandRepr {
            queued: true,
            frame_id: 0x01,
            command: *b"BD",
            parameter: &[0x07],
        }),
        Frame::AtCommandResponse(AtCommandResponseRepr {
            frame_id: 0x01,
            command: *b"BD",
            status: AtStatus::Ok,
            data: &[],
        }),
        Frame::ModemStatus(ModemStatusRepr {
            status: ModemStatus::CoordinatorStarted,
        }),
        Frame::ExplicitRxIndicator(ExplicitRxIndicatorRepr {
            src64: Address64(0x0013_A200_4052_2BAA),
            src16: Address16(0x7D84),
            src_endpoint: 0xE0,
            dst_endpoint: 0xE0,
            cluster_id: 0x2211,
            profile_id: 0xC105,
            options: 0x02,
            data: b"RxData",
        }),
        Frame::RemoteAtCommand(RemoteAtCommandRepr {
            frame_id: 0x01,
            dst64: Address64(0x0013_A200_4040_1122),
            dst16: Address16::UNKNOWN,
            options: 0x02,
            command: *b"BH",
            parameter: &[0x01],
        }),
        Frame::RemoteAtResponse(RemoteAtResponseRepr {
            frame_id: 0x55,
            src64: Address64(0x0013_A200_4052_2BAA),
            src16: Address16(0x7D84),
            command: *b"SL",
            status: AtStatus::Ok,
            data: &[0x40, 0x52, 0x2B, 0xAA],
        }),
        explicit,
        explicit,
        unknown,
        unknown,
    ]
}

/// (frame type, mode, wire bytes) of each line.
fn lines() -> Vec<(u8, ApiMode, Vec<u8>)> {
    let text = String::from_utf8(testdata("digi-manual.txt")).unwrap();
    text.lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .map(|line| {
            let mut parts = line.splitn(3, ' ');
            let frame_type = u8::from_str_radix(parts.next().unwrap(), 16).unwrap();
            let mode = ApiMode::try_from(parts.next().unwrap().parse::<u8>().unwrap()).unwrap();
            (frame_type, mode, hex(parts.next().unwrap()))
        })
        .collect()
}

#[test]
fn every_manual_frame_decodes_to_its_fields() {
    let lines = lines();
    let expected = expected();
    assert_eq!(lines.len(), expected.len());
    for ((frame_type, mode, wire), want) in lines.iter().zip(&expected) {
        for events in [
            decode_slices::<512>(*mode, wire, &[wire.len()]).0,
            decode_bytes::<512>(*mode, wire).0,
        ] {
            assert_eq!(events.len(), 1, "{wire:02X?}: {events:?}");
            let Owned::Frame(data) = &events[0] else {
                panic!("{wire:02X?}: {events:?}")
            };
            let frame = Frame::parse_bytes(data).unwrap();
            assert_eq!(frame.frame_type(), *frame_type);
            assert_eq!(&frame, want, "{wire:02X?}");
        }
    }
}

#[test]
fn every_manual_frame_encodes_to_its_bytes() {
    for ((_, mode, wire), frame) in lines().iter().zip(expected()) {
        assert_eq!(frame.encoded_len(*mode), wire.len());
        let mut buf = [0u8; 64];
        let n = frame.encode(*mode, &mut buf).unwrap();
        assert_eq!(&buf[..n], &wire[..], "{frame:?} in {mode}");
    }
}

#[test]
fn manual_fields_through_views() {
    use xbee_api::{ExplicitRxIndicator, TransmitStatus};
    let data = hex("91 00 13 A2 00 40 52 2B AA 7D 84 E0 E0 22 11 C1 05 02 52 78 44 61 74 61");
    let view = ExplicitRxIndicator::new_checked(&data[..]).unwrap();
    assert_eq!(view.src64(), Address64(0x0013_A200_4052_2BAA));
    assert_eq!(view.src16(), Address16(0x7D84));
    assert_eq!(view.cluster_id(), 0x2211);
    assert_eq!(view.profile_id(), 0xC105);
    assert_eq!(view.data(), b"RxData");
    let status = hex("8B 52 12 34 02 00 01");
    let view = TransmitStatus::new_checked(&status[..]).unwrap();
    assert_eq!(view.retries(), 2);
    assert_eq!(view.discovery(), DiscoveryStatus::AddressDiscovery);
}

#[test]
fn every_manual_frame_through_embedded_io_is_its_bytes() {
    use xbee_api::io::{FrameReader, write_frame};
    for ((_, mode, wire), frame) in lines().iter().zip(expected()) {
        let mut buf = [0u8; 64];
        let mut uart = &mut buf[..];
        let n = write_frame(&mut uart, *mode, &frame).unwrap();
        assert_eq!(&buf[..n], &wire[..], "{frame:?} in {mode}");
        let mut reader: FrameReader<&[u8], 128> = FrameReader::new(&wire[..], *mode);
        let mut frames = Vec::new();
        while reader
            .read_events(|event| frames.push(event.unwrap().data().to_vec()))
            .unwrap()
            > 0
        {}
        assert_eq!(frames.len(), 1, "{wire:02X?}");
        assert_eq!(Frame::parse_bytes(&frames[0]).unwrap(), frame);
    }
}
