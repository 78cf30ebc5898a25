//! The MAV side, `mcp_core::mav::Mav`: the firmware's state machine, fed the RF data of
//! any Receive Packet (untrusted bytes from the air), with reply buffers of any size,
//! interleaved with the main loop's telemetry and `poll_changes`, and the vehicle
//! changing state on its own.
//!
//! Input: a list of steps, each a byte then its operands: `% 5` = 0: a payload (a
//! length byte, that many bytes, a buffer size byte) given to `handle_packet`; 1: the
//! same through `Command::parse` and `handle`; 2: `telemetry` (a buffer size byte,
//! 0-300 across two bytes' worth); 3: `poll_changes` (a buffer size byte) until `None`;
//! 4: the vehicle changes its landing state and controller (two bytes).
//!
//! Checks, against a model of the MAV's state (enabled telemetry ids, slave slots, the
//! reports due): no panic; a length returned is at most the buffer's and
//! `MAX_PAYLOAD`; every reply parses, and is the report the request asks for with the
//! model's (or the vehicle's) values; a trajectory report holds the vehicle's first
//! waypoints, as many as fit; an error only when the reply does not fit; telemetry
//! packets are exactly the model's: the enabled ids in ascending order from where the
//! last packet stopped, as many as fit, each with the vehicle's value, so that every
//! enabled id is sent; `poll_changes` reports each change once, landing first.
#![no_main]

use libfuzzer_sys::fuzz_target;
use mcp_core::mav::{Mav, Vehicle};
use mcp_core::{
    Address, Command, Controller, LandingState, MAX_PAYLOAD, Packet, Report, SlaveAddresses, Slot,
    StatusRequest, TelemetryId, Waypoint, Waypoints,
};

struct Sim {
    landing: LandingState,
    controller: Controller,
    time: u32,
    trajectory: Vec<Waypoint>,
    slaves: [Address; 4],
}

impl Vehicle for Sim {
    fn landing_state(&self) -> LandingState {
        self.landing
    }
    fn set_landing(&mut self, on: bool) {
        self.landing = if on {
            LandingState::Landing
        } else {
            LandingState::Flight
        };
    }
    fn controller(&self) -> Controller {
        self.controller
    }
    fn set_controller(&mut self, c: Controller) {
        self.controller = c;
    }
    fn time(&self) -> u32 {
        self.time
    }
    fn set_time(&mut self, t: u32) {
        self.time = t;
    }
    fn telemetry(&self, id: TelemetryId) -> f32 {
        f32::from(u8::from(id)) * 0.5 + 1.0
    }
    fn set_trajectory(&mut self, waypoints: Waypoints<&[u8]>) {
        self.trajectory = waypoints.iter().collect();
        assert!(self.trajectory.len() <= mcp_core::MAX_WAYPOINTS);
    }
    fn waypoint(&self, index: usize) -> Option<Waypoint> {
        self.trajectory.get(index).copied()
    }
    fn set_slave(&mut self, slot: Slot, address: Address) {
        self.slaves[slot.index()] = address;
    }
}

/// What the MAV's state must be.
struct Model {
    enabled: [bool; 256],
    slaves: [Address; 4],
    /// The landing state and controller last reported.
    landing: LandingState,
    controller: Controller,
    /// Where the next telemetry packet starts.
    from: u8,
}

struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn u8(&mut self) -> Option<u8> {
        let (&b, rest) = self.0.split_first()?;
        self.0 = rest;
        Some(b)
    }
    fn take(&mut self, n: usize) -> &[u8] {
        let (a, b) = self.0.split_at(n.min(self.0.len()));
        self.0 = b;
        a
    }
}

/// Reads the reply `len` of `result` out of `buf`, checking its length.
fn reply(
    result: Result<Option<usize>, mcp_core::BufferTooSmall>,
    buf: &[u8],
) -> Result<Option<&[u8]>, mcp_core::BufferTooSmall> {
    match result {
        Ok(Some(len)) => {
            assert!(
                len <= buf.len() && len <= MAX_PAYLOAD,
                "reply of {len} bytes in a buffer of {}",
                buf.len()
            );
            Ok(Some(&buf[..len]))
        }
        Ok(None) => Ok(None),
        Err(e) => {
            assert!(e.needed > e.available, "error {e:?} yet the reply fits");
            assert_eq!(e.available, buf.len());
            Err(e)
        }
    }
}

fn report(bytes: &[u8]) -> Report<&[u8]> {
    match mcp_core::parse(bytes) {
        Ok(Packet::Report(r)) => r,
        other => panic!("a MAV reply {bytes:02x?} parses as {other:?}"),
    }
}

/// The trajectory report in `bytes` holds the vehicle's first waypoints, as many as fit
/// `buf_len`.
fn check_trajectory(bytes: &[u8], sim: &Sim, buf_len: usize) {
    let Report::TrajectorySet(w) = report(bytes) else {
        panic!("not a trajectory report: {bytes:02x?}");
    };
    let got: Vec<[u8; 16]> = w.iter().map(|w| w.to_bytes()).collect();
    let want: Vec<[u8; 16]> = sim.trajectory.iter().map(|w| w.to_bytes()).collect();
    assert!(
        want.starts_with(&got),
        "trajectory report of other waypoints"
    );
    let room = (buf_len.min(MAX_PAYLOAD) - 3) / 16;
    assert_eq!(
        got.len(),
        want.len().min(room),
        "waypoints left out that fit"
    );
}

fn handle(
    mav: &mut Mav,
    sim: &mut Sim,
    model: &mut Model,
    command: &Command<&[u8]>,
    buf_len: usize,
    result: Result<Option<usize>, mcp_core::BufferTooSmall>,
    buf: &[u8],
) {
    let _ = mav;
    let reply = reply(result, buf);
    match command {
        Command::TelemetryToCoordinator { on, id } => {
            model.enabled[usize::from(u8::from(*id))] = *on;
            assert_eq!(reply, Ok(None));
        }
        Command::PositionSlaveSet { slot, address } => {
            model.slaves[slot.unwrap_or_default().index()] = *address;
            assert_eq!(reply, Ok(None));
        }
        Command::Landing { .. }
        | Command::Controllers(_)
        | Command::Time(_)
        | Command::PositionSet { .. } => assert_eq!(reply, Ok(None)),
        Command::TrajectorySet(_) => match reply {
            Ok(Some(bytes)) => check_trajectory(bytes, sim, buf_len),
            Ok(None) => panic!("trajectory set unanswered"),
            Err(_) => assert!(buf_len < 3),
        },
        Command::StatusRequest(request) => {
            let bytes = match reply {
                Ok(Some(bytes)) => bytes,
                Ok(None) => panic!("status request unanswered"),
                Err(_) => return,
            };
            if *request == StatusRequest::TrajectorySet {
                return check_trajectory(bytes, sim, buf_len);
            }
            let got = report(bytes);
            let want: Report<&[u8]> = match request {
                StatusRequest::TelemetryToCoordinator(id) => Report::TelemetryToCoordinator {
                    on: model.enabled[usize::from(u8::from(*id))],
                    id: *id,
                },
                StatusRequest::Landing => {
                    model.landing = sim.landing;
                    Report::Landing(sim.landing)
                }
                StatusRequest::Controllers => {
                    model.controller = sim.controller;
                    Report::Controllers(sim.controller)
                }
                StatusRequest::PositionSlaveSet => {
                    Report::PositionSlaveSet(SlaveAddresses::Slots(model.slaves))
                }
                StatusRequest::Time => Report::Time(sim.time),
                StatusRequest::TrajectorySet => unreachable!(),
            };
            assert_eq!(format!("{got:?}"), format!("{want:?}"), "status report");
        }
    }
}

fn check_telemetry(mav: &mut Mav, sim: &Sim, model: &mut Model, buf_len: usize) {
    let mut buf = vec![0u8; buf_len];
    let result = mav.telemetry(sim, &mut buf);
    let enabled: Vec<u8> = (0..=255u8)
        .filter(|&id| model.enabled[usize::from(id)])
        .collect();
    let reply = reply(result, &buf);
    if enabled.is_empty() {
        assert_eq!(reply, Ok(None), "telemetry with no id enabled");
        return;
    }
    let room = buf_len.min(MAX_PAYLOAD).saturating_sub(1) / 5;
    if room == 0 {
        assert!(reply.is_err(), "telemetry of no record");
        return;
    }
    let Ok(Some(bytes)) = reply else {
        panic!("telemetry not sent: {reply:?}");
    };
    let Ok(Packet::Telemetry(t)) = mcp_core::parse(bytes) else {
        panic!("telemetry {bytes:02x?} does not parse");
    };
    // The model: from the first enabled id at or after `from` (from the lowest if none).
    let start = enabled.iter().position(|&id| id >= model.from).unwrap_or(0);
    let want: Vec<u8> = enabled[start..].iter().copied().take(room).collect();
    let got: Vec<(u8, u32)> = t
        .iter()
        .map(|r| (u8::from(r.id), r.value.to_bits()))
        .collect();
    let want_values: Vec<(u8, u32)> = want
        .iter()
        .map(|&id| (id, sim.telemetry(TelemetryId::from(id)).to_bits()))
        .collect();
    assert_eq!(got, want_values, "telemetry packet");
    model.from = enabled.get(start + want.len()).copied().unwrap_or(0);
}

fn check_changes(mav: &mut Mav, sim: &Sim, model: &mut Model, buf_len: usize) {
    let mut buf = vec![0u8; buf_len];
    for _ in 0..3 {
        let result = mav.poll_changes(sim, &mut buf);
        let reply = reply(result, &buf);
        let want: Option<Report<&[u8]>> = if sim.landing != model.landing {
            Some(Report::Landing(sim.landing))
        } else if sim.controller != model.controller {
            Some(Report::Controllers(sim.controller))
        } else {
            None
        };
        match (reply, want) {
            (Ok(None), None) => return,
            (Ok(Some(bytes)), Some(want)) => {
                let got = report(bytes);
                assert_eq!(format!("{got:?}"), format!("{want:?}"), "change reported");
                match want {
                    Report::Landing(l) => model.landing = l,
                    Report::Controllers(c) => model.controller = c,
                    _ => unreachable!(),
                }
            }
            (Err(_), Some(_)) => return,
            (got, want) => panic!("poll_changes gave {got:?}, expected {want:?}"),
        }
    }
    panic!("poll_changes still reports after two changes");
}

fuzz_target!(|input: &[u8]| {
    let mut sim = Sim {
        landing: LandingState::Flight,
        controller: Controller::from(0),
        time: 0,
        trajectory: Vec::new(),
        slaves: [Address::from(0u64); 4],
    };
    let mut mav = Mav::new(&sim);
    let mut model = Model {
        enabled: [false; 256],
        slaves: [Address::from(0u64); 4],
        landing: sim.landing,
        controller: sim.controller,
        from: 0,
    };
    let mut input = Bytes(input);
    while let Some(op) = input.u8() {
        match op % 5 {
            0 | 1 => {
                let len = usize::from(input.u8().unwrap_or(0));
                let payload = input.take(len).to_vec();
                let buf_len = usize::from(input.u8().unwrap_or(255));
                let mut buf = vec![0u8; buf_len];
                if op % 5 == 0 {
                    let Ok(packet) = mcp_core::parse(&payload) else {
                        continue;
                    };
                    let result = mav.handle_packet(&mut sim, &packet, &mut buf);
                    match &packet {
                        Packet::Command(c) => {
                            handle(&mut mav, &mut sim, &mut model, c, buf_len, result, &buf)
                        }
                        _ => assert_eq!(result, Ok(None), "a MAV answered a non-command"),
                    }
                } else {
                    let Ok(command) = Command::parse(&payload) else {
                        continue;
                    };
                    let result = mav.handle(&mut sim, &command, &mut buf);
                    handle(
                        &mut mav, &mut sim, &mut model, &command, buf_len, result, &buf,
                    );
                }
            }
            2 => {
                let a = usize::from(input.u8().unwrap_or(255));
                let buf_len = if op & 0x80 != 0 { a + 45 } else { a };
                check_telemetry(&mut mav, &sim, &mut model, buf_len);
            }
            3 => {
                let buf_len = usize::from(input.u8().unwrap_or(255));
                check_changes(&mut mav, &sim, &mut model, buf_len);
            }
            _ => {
                let change = input.u8().unwrap_or(0);
                let l = input.u8().unwrap_or(0);
                let c = input.u8().unwrap_or(0);
                if change & 1 == 1 {
                    sim.landing = LandingState::from(l);
                }
                if change & 2 == 2 {
                    // A controller the vehicle itself runs: 0x00-0xFE.
                    sim.controller = Controller::from(c.min(0xFE));
                }
            }
        }
        assert_eq!(mav.slaves(), model.slaves, "slave slots");
        assert_eq!(sim.slaves, model.slaves, "vehicle told of slots");
        let enabled: Vec<u8> = mav.enabled().iter().map(u8::from).collect();
        let want: Vec<u8> = (0..=255u8)
            .filter(|&id| model.enabled[usize::from(id)])
            .collect();
        assert_eq!(enabled, want, "telemetry ids enabled");
    }
});
