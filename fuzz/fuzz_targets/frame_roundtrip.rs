//! Structured input builds a valid frame of each XBee API frame type and a valid MCP
//! packet of each kind. Each frame is encoded in API modes 1 and 2, decoded (whole, in
//! fuzzer-chosen reads, byte at a time) and typed again: it must come back identical.
//! The MCP packet must parse back to itself, and, carried as the RF data of a Receive
//! Packet and of a Transmit Request, must reach the MCP parser intact through both
//! modes. This is how the fuzzer reaches the MCP layer behind valid checksums.
#![no_main]

use arbitrary::Arbitrary;
use libfuzzer_sys::fuzz_target;
use mcp_core::{
    Address, Command, Controller, LandingState, MAX_PAYLOAD, Packet, Report, SlaveAddresses, Slot,
    StatusRequest, TelemetryBuilder, TelemetryId, Text, TrajectoryBuilder, Waypoint,
};
use mcp_fuzz::wire::roundtrip;
use xbee_api::frame::frame_type;
use xbee_api::{
    Address16, Address64, ApiMode, AtCommandRepr, AtCommandResponseRepr,
    ExplicitAddressingCommandRepr, ExplicitRxIndicatorRepr, Frame, ModemStatusRepr,
    NodeIdentificationIndicatorRepr, NodeInfo, ReceivePacketRepr, RemoteAtCommandRepr,
    RemoteAtResponseRepr, TransmitRequestRepr, TransmitStatusRepr,
};

/// Longest data field generated: every frame type then fits the default decoder in
/// both modes.
const MAX_DATA: usize = 400;

#[derive(Debug, Arbitrary)]
struct Input {
    frame: FrameSpec,
    mcp: McpSpec,
    src64: u64,
    src16: u16,
    options: u8,
    frame_id: u8,
    chunk: u8,
}

#[derive(Debug, Arbitrary)]
enum FrameSpec {
    TransmitRequest {
        frame_id: u8,
        dst64: u64,
        dst16: u16,
        radius: u8,
        options: u8,
        data: Vec<u8>,
    },
    ReceivePacket {
        src64: u64,
        src16: u16,
        options: u8,
        data: Vec<u8>,
    },
    TransmitStatus {
        frame_id: u8,
        dst16: u16,
        retries: u8,
        delivery: u8,
        discovery: u8,
    },
    AtCommand {
        queued: bool,
        frame_id: u8,
        command: [u8; 2],
        parameter: Vec<u8>,
    },
    AtCommandResponse {
        frame_id: u8,
        command: [u8; 2],
        status: u8,
        data: Vec<u8>,
    },
    ModemStatus {
        status: u8,
    },
    ExplicitAddressingCommand {
        frame_id: u8,
        dst64: u64,
        dst16: u16,
        src_endpoint: u8,
        dst_endpoint: u8,
        cluster_id: u16,
        profile_id: u16,
        radius: u8,
        options: u8,
        data: Vec<u8>,
    },
    ExplicitRxIndicator {
        src64: u64,
        src16: u16,
        src_endpoint: u8,
        dst_endpoint: u8,
        cluster_id: u16,
        profile_id: u16,
        options: u8,
        data: Vec<u8>,
    },
    RemoteAtCommand {
        frame_id: u8,
        dst64: u64,
        dst16: u16,
        options: u8,
        command: [u8; 2],
        parameter: Vec<u8>,
    },
    RemoteAtResponse {
        frame_id: u8,
        src64: u64,
        src16: u16,
        command: [u8; 2],
        status: u8,
        data: Vec<u8>,
    },
    NodeIdentificationIndicator {
        src64: u64,
        src16: u16,
        options: u8,
        addr16: u16,
        addr64: u64,
        identifier: Vec<u8>,
        parent: u16,
        device_type: u8,
        event: u8,
        profile_id: u16,
        manufacturer_id: u16,
        device_type_identifier: Option<u32>,
        rssi: Option<u8>,
    },
    Unknown {
        frame_type: u8,
        data: Vec<u8>,
    },
}

#[derive(Debug, Arbitrary)]
struct WaypointSpec {
    time: u32,
    elevator: f32,
    aileron: f32,
    altitude: f32,
}

impl From<&WaypointSpec> for Waypoint {
    fn from(w: &WaypointSpec) -> Self {
        Waypoint {
            time: w.time,
            elevator: w.elevator,
            aileron: w.aileron,
            altitude: w.altitude,
        }
    }
}

#[derive(Debug, Arbitrary)]
enum McpSpec {
    TelemetryToCoordinator { on: bool, id: u8 },
    Landing { on: bool },
    Controllers(u8),
    TrajectorySet(Vec<WaypointSpec>),
    PositionSlaveSet { slot: Option<u8>, address: u64 },
    Time(u32),
    PositionSet { elevator: f32, aileron: f32 },
    StatusRequest { kind: u8, id: u8 },
    ReportTelemetryToCoordinator { on: bool, id: u8 },
    ReportLanding(u8),
    ReportControllers(u8),
    ReportTrajectorySet(Vec<WaypointSpec>),
    ReportSlave(u64),
    ReportSlaves([u64; 4]),
    ReportTime(u32),
    Telemetry(Vec<(u8, f32)>),
    Message(Vec<u8>),
    Warning(Vec<u8>),
}

fn clip(data: &[u8]) -> &[u8] {
    &data[..data.len().min(MAX_DATA)]
}

fn build_frame(spec: &FrameSpec) -> Option<Frame<'_>> {
    use FrameSpec as S;
    Some(match spec {
        S::TransmitRequest {
            frame_id,
            dst64,
            dst16,
            radius,
            options,
            data,
        } => Frame::TransmitRequest(TransmitRequestRepr {
            frame_id: *frame_id,
            dst64: Address64(*dst64),
            dst16: Address16(*dst16),
            radius: *radius,
            options: *options,
            data: clip(data),
        }),
        S::ReceivePacket {
            src64,
            src16,
            options,
            data,
        } => Frame::ReceivePacket(ReceivePacketRepr {
            src64: Address64(*src64),
            src16: Address16(*src16),
            options: *options,
            data: clip(data),
        }),
        S::TransmitStatus {
            frame_id,
            dst16,
            retries,
            delivery,
            discovery,
        } => Frame::TransmitStatus(TransmitStatusRepr {
            frame_id: *frame_id,
            dst16: Address16(*dst16),
            retries: *retries,
            delivery: (*delivery).into(),
            discovery: (*discovery).into(),
        }),
        S::AtCommand {
            queued,
            frame_id,
            command,
            parameter,
        } => Frame::AtCommand(AtCommandRepr {
            queued: *queued,
            frame_id: *frame_id,
            command: *command,
            parameter: clip(parameter),
        }),
        S::AtCommandResponse {
            frame_id,
            command,
            status,
            data,
        } => Frame::AtCommandResponse(AtCommandResponseRepr {
            frame_id: *frame_id,
            command: *command,
            status: (*status).into(),
            data: clip(data),
        }),
        S::ModemStatus { status } => Frame::ModemStatus(ModemStatusRepr {
            status: (*status).into(),
        }),
        S::ExplicitAddressingCommand {
            frame_id,
            dst64,
            dst16,
            src_endpoint,
            dst_endpoint,
            cluster_id,
            profile_id,
            radius,
            options,
            data,
        } => Frame::ExplicitAddressingCommand(ExplicitAddressingCommandRepr {
            frame_id: *frame_id,
            dst64: Address64(*dst64),
            dst16: Address16(*dst16),
            src_endpoint: *src_endpoint,
            dst_endpoint: *dst_endpoint,
            cluster_id: *cluster_id,
            profile_id: *profile_id,
            radius: *radius,
            options: *options,
            data: clip(data),
        }),
        S::ExplicitRxIndicator {
            src64,
            src16,
            src_endpoint,
            dst_endpoint,
            cluster_id,
            profile_id,
            options,
            data,
        } => Frame::ExplicitRxIndicator(ExplicitRxIndicatorRepr {
            src64: Address64(*src64),
            src16: Address16(*src16),
            src_endpoint: *src_endpoint,
            dst_endpoint: *dst_endpoint,
            cluster_id: *cluster_id,
            profile_id: *profile_id,
            options: *options,
            data: clip(data),
        }),
        S::RemoteAtCommand {
            frame_id,
            dst64,
            dst16,
            options,
            command,
            parameter,
        } => Frame::RemoteAtCommand(RemoteAtCommandRepr {
            frame_id: *frame_id,
            dst64: Address64(*dst64),
            dst16: Address16(*dst16),
            options: *options,
            command: *command,
            parameter: clip(parameter),
        }),
        S::RemoteAtResponse {
            frame_id,
            src64,
            src16,
            command,
            status,
            data,
        } => Frame::RemoteAtResponse(RemoteAtResponseRepr {
            frame_id: *frame_id,
            src64: Address64(*src64),
            src16: Address16(*src16),
            command: *command,
            status: (*status).into(),
            data: clip(data),
        }),
        S::NodeIdentificationIndicator {
            src64,
            src16,
            options,
            addr16,
            addr64,
            identifier,
            parent,
            device_type,
            event,
            profile_id,
            manufacturer_id,
            device_type_identifier,
            rssi,
        } => {
            // The identifier ends at its first 0x00 on the wire: it holds none.
            let identifier = clip(identifier);
            let identifier = &identifier[..identifier
                .iter()
                .position(|&b| b == 0)
                .unwrap_or(identifier.len())];
            Frame::NodeIdentificationIndicator(NodeIdentificationIndicatorRepr {
                src64: Address64(*src64),
                src16: Address16(*src16),
                options: *options,
                node: NodeInfo {
                    addr16: Address16(*addr16),
                    addr64: Address64(*addr64),
                    identifier,
                    parent: Address16(*parent),
                    device_type: (*device_type).into(),
                    status: *event,
                    profile_id: *profile_id,
                    manufacturer_id: *manufacturer_id,
                    device_type_identifier: *device_type_identifier,
                    rssi: *rssi,
                },
            })
        }
        S::Unknown { frame_type, data } => {
            if is_known(*frame_type) {
                return None;
            }
            Frame::Unknown {
                frame_type: *frame_type,
                data: clip(data),
            }
        }
    })
}

fn is_known(t: u8) -> bool {
    use frame_type::*;
    [
        AT_COMMAND,
        AT_COMMAND_QUEUE,
        TRANSMIT_REQUEST,
        EXPLICIT_ADDRESSING_COMMAND,
        REMOTE_AT_COMMAND,
        AT_COMMAND_RESPONSE,
        MODEM_STATUS,
        TRANSMIT_STATUS,
        RECEIVE_PACKET,
        EXPLICIT_RX_INDICATOR,
        REMOTE_AT_RESPONSE,
        NODE_IDENTIFICATION_INDICATOR,
    ]
    .contains(&t)
}

/// Encodes the MCP packet the spec describes into `buf` and returns its length,
/// checking that it parses back to what was built (a packet built field by field
/// compares whole; a builder's packet item by item).
fn build_mcp(spec: &McpSpec, buf: &mut [u8; MAX_PAYLOAD]) -> usize {
    use McpSpec as S;
    let packet: Packet<&[u8]> = match spec {
        S::TelemetryToCoordinator { on, id } => Command::TelemetryToCoordinator {
            on: *on,
            id: TelemetryId::from(*id),
        }
        .into(),
        S::Landing { on } => Command::Landing { on: *on }.into(),
        // Table 7 allows controller ids 0x00-0xFE: `c 03 FF` is the status request, and
        // `Command::Controllers` documents that id 0xFF encodes as it.
        S::Controllers(0xFF) => return build_mcp(&S::StatusRequest { kind: 2, id: 0 }, buf),
        S::Controllers(c) => Command::Controllers(Controller::from(*c)).into(),
        S::PositionSlaveSet { slot, address } => Command::PositionSlaveSet {
            slot: slot.and_then(|s| Slot::new(s % 4)),
            address: Address::from(*address),
        }
        .into(),
        S::Time(t) => Command::Time(*t).into(),
        S::PositionSet { elevator, aileron } => Command::PositionSet {
            elevator: *elevator,
            aileron: *aileron,
        }
        .into(),
        S::StatusRequest { kind, id } => {
            let request = match kind % 6 {
                0 => StatusRequest::TelemetryToCoordinator(TelemetryId::from(*id)),
                1 => StatusRequest::Landing,
                2 => StatusRequest::Controllers,
                3 => StatusRequest::TrajectorySet,
                4 => StatusRequest::PositionSlaveSet,
                _ => StatusRequest::Time,
            };
            Command::StatusRequest(request).into()
        }
        S::ReportTelemetryToCoordinator { on, id } => Report::TelemetryToCoordinator {
            on: *on,
            id: TelemetryId::from(*id),
        }
        .into(),
        S::ReportLanding(l) => Report::Landing(LandingState::from(*l)).into(),
        // 0xFF is no controller (table 20): parsers refuse a report of it.
        S::ReportControllers(c) => Report::Controllers(Controller::from((*c).min(0xFE))).into(),
        S::ReportSlave(a) => {
            Report::PositionSlaveSet(SlaveAddresses::Single(Address::from(*a))).into()
        }
        S::ReportSlaves(a) => {
            Report::PositionSlaveSet(SlaveAddresses::Slots(a.map(Address::from))).into()
        }
        S::ReportTime(t) => Report::Time(*t).into(),
        S::Message(text) => Packet::Message(Text::new(&text[..text.len().min(MAX_PAYLOAD - 1)])),
        S::Warning(text) => Packet::Warning(Text::new(&text[..text.len().min(MAX_PAYLOAD - 1)])),
        S::TrajectorySet(points) | S::ReportTrajectorySet(points) => {
            let mut builder = match spec {
                S::TrajectorySet(_) => TrajectoryBuilder::command(buf),
                _ => TrajectoryBuilder::report(buf),
            }
            .expect("a MAX_PAYLOAD buffer holds an empty trajectory");
            let pushed = points
                .iter()
                .take_while(|w| builder.push(Waypoint::from(*w)).is_ok())
                .count();
            assert_eq!(builder.count(), pushed);
            let len = builder.finish();
            let packet = mcp_core::parse(&buf[..len]).expect("built trajectory parses");
            let waypoints = match packet {
                Packet::Command(Command::TrajectorySet(w)) => w,
                Packet::Report(Report::TrajectorySet(w)) => w,
                other => panic!("built trajectory parsed as {other:?}"),
            };
            assert_eq!(usize::from(waypoints.size()), pushed);
            assert!(
                waypoints.iter().map(|w| w.to_bytes()).eq(points[..pushed]
                    .iter()
                    .map(|w| Waypoint::from(w).to_bytes()))
            );
            return len;
        }
        S::Telemetry(records) => {
            let mut builder = TelemetryBuilder::new(buf).expect("a MAX_PAYLOAD buffer holds a t");
            let pushed = records
                .iter()
                .take_while(|(id, value)| builder.push(TelemetryId::from(*id), *value).is_ok())
                .count();
            assert_eq!(builder.count(), pushed);
            let len = builder.finish();
            let Ok(Packet::Telemetry(telemetry)) = mcp_core::parse(&buf[..len]) else {
                panic!("built telemetry does not parse as telemetry");
            };
            assert_eq!(telemetry.len(), pushed);
            assert!(
                telemetry
                    .iter()
                    .map(|r| (u8::from(r.id), r.value.to_bits()))
                    .eq(records[..pushed].iter().map(|(id, v)| (*id, v.to_bits())))
            );
            return len;
        }
    };
    let len = packet
        .encode(buf)
        .expect("every built packet fits MAX_PAYLOAD");
    assert_eq!(len, packet.encoded_len());
    let parsed = mcp_core::parse(&buf[..len]).expect("encoded packet parses");
    assert_eq!(
        format!("{parsed:?}"),
        format!("{packet:?}"),
        "packet parsed to another"
    );
    len
}

fuzz_target!(|input: Input| {
    let chunk = usize::from(input.chunk);
    if let Some(frame) = build_frame(&input.frame) {
        for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
            roundtrip(&frame, mode, chunk);
        }
    }

    let mut buf = [0u8; MAX_PAYLOAD];
    let len = build_mcp(&input.mcp, &mut buf);
    let payload = &buf[..len];
    let expected = format!(
        "{:?}",
        mcp_core::parse(payload).expect("built packet parses")
    );
    let carriers = [
        Frame::ReceivePacket(ReceivePacketRepr {
            src64: Address64(input.src64),
            src16: Address16(input.src16),
            options: input.options,
            data: payload,
        }),
        Frame::TransmitRequest(TransmitRequestRepr {
            frame_id: input.frame_id,
            dst64: Address64(input.src64),
            dst16: Address16(input.src16),
            radius: 0,
            options: input.options,
            data: payload,
        }),
    ];
    for carrier in &carriers {
        for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
            let wire = roundtrip(carrier, mode, chunk);
            // The MCP layer sees the payload as the decoder delivers it.
            let mut decoder: xbee_api::Decoder = xbee_api::Decoder::new(mode);
            let (_, event) = decoder.decode(&wire);
            let raw = event.expect("one event").expect("a frame");
            let data = match Frame::parse(raw).expect("typed") {
                Frame::ReceivePacket(rx) => rx.data,
                Frame::TransmitRequest(tx) => tx.data,
                other => panic!("carrier came back as {other:?}"),
            };
            let seen = mcp_core::parse(data).expect("MCP payload parses after the radio layer");
            assert_eq!(format!("{seen:?}"), expected);
        }
    }
});
