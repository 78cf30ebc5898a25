//! End to end: the MAV firmware of `examples/firmware`, built for the LM3S6965 and run
//! in QEMU's `lm3s6965evb`, driven over its UART the way its XBee would.
//!
//! The test plays the MAV's XBee: it sends Receive Packets (0x90) holding MCP commands
//! into the firmware's UART0 and reads the Transmit Requests (0x10) the firmware writes
//! back, all in API mode 1.
//!
//! Needs `qemu-system-arm` and the `thumbv7m-none-eabi` target (`rustup target add
//! thumbv7m-none-eabi`): where either is absent the tests print why and pass without
//! running, unless `MCP_REQUIRE_FIRMWARE_TESTS` is set (as CI does), which makes that a
//! failure. The firmware is built by the test (`cargo build --release` in
//! `examples/firmware`, into that directory's own `target/`). Set `MCP_FIRMWARE_ELF` to
//! the path of an ELF built beforehand to skip that build, and the need for the target.
//!
//! Waiting is on frames only; the timeouts are failure guards, never synchronisation.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader, ErrorKind, Read, Write};
use std::net::{Ipv4Addr, TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::sync::{Arc, Mutex, OnceLock};
use std::thread;
use std::time::{Duration, Instant};

use mcp_core::{
    Address, Command as McpCommand, Controller, LandingState, Packet, Report, SlaveAddresses, Slot,
    StatusRequest, TelemetryId, TrajectoryBuilder, Waypoint, parse,
};
use xbee_api::{
    Address16, Address64, ApiMode, Decoder, EncodeFrame, Frame, RawFrame, ReceivePacketRepr,
};

const QEMU: &str = "qemu-system-arm";
/// How long any one expected frame may take: generous, as CI machines are slow and
/// QEMU shares two cores with the build. Only a guard against hanging forever.
const FRAME_TIMEOUT: Duration = Duration::from_secs(20);
/// The firmware's first frame once its UART is up.
const STARTUP_MESSAGE: &[u8] = b"mMAV started";
/// Largest MCP payload the firmware takes (unicast, unfragmented).
const MAX_PAYLOAD: usize = 84;

/// The firmware's target.
const TARGET: &str = "thumbv7m-none-eabi";

/// `true` if QEMU can run and the firmware can be had (built beforehand, or its target
/// installed); otherwise prints why the test is skipped, or fails where
/// `MCP_REQUIRE_FIRMWARE_TESTS` is set. The message goes straight to the process's
/// stderr, past the test harness's output capture, so it shows in every run.
fn qemu_available(test: &str) -> bool {
    let missing = match Command::new(QEMU).arg("--version").output() {
        Ok(out) if out.status.success() => firmware_target_missing(),
        _ => Some(format!(
            "`{QEMU}` not found (Debian: `apt-get install qemu-system-arm`)"
        )),
    };
    let Some(missing) = missing else {
        return true;
    };
    assert!(
        std::env::var_os("MCP_REQUIRE_FIRMWARE_TESTS").is_none(),
        "{test}: {missing}, and MCP_REQUIRE_FIRMWARE_TESTS is set"
    );
    let _ = writeln!(
        std::io::stderr(),
        "SKIPPED {test}: {missing}: the firmware end-to-end tests need it"
    );
    false
}

/// Why the firmware cannot be built here, if it cannot: no `MCP_FIRMWARE_ELF`, and the
/// standard library of its target is not installed (rustup installs it at
/// `rustc --print target-libdir --target thumbv7m-none-eabi`). A `rustc` that cannot
/// say is left to the build to try.
fn firmware_target_missing() -> Option<String> {
    if std::env::var_os("MCP_FIRMWARE_ELF").is_some() {
        return None;
    }
    let out = Command::new("rustc")
        .args(["--print", "target-libdir", "--target", TARGET])
        .output()
        .ok()
        .filter(|out| out.status.success())?;
    let dir = PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
    (!dir.is_dir()).then(|| {
        format!(
            "the `{TARGET}` target is not installed (`rustup target add {TARGET}`, or set \
             MCP_FIRMWARE_ELF to a firmware built beforehand)"
        )
    })
}

/// The firmware ELF: `MCP_FIRMWARE_ELF`, or built once per test process.
fn firmware_elf() -> PathBuf {
    static ELF: OnceLock<Result<PathBuf, String>> = OnceLock::new();
    ELF.get_or_init(|| match std::env::var_os("MCP_FIRMWARE_ELF") {
        Some(path) => Ok(PathBuf::from(path)),
        None => build_firmware(),
    })
    .clone()
    .unwrap_or_else(|e| panic!("{e}"))
}

/// Runs `cargo build --release` in `examples/firmware`, which is its own workspace
/// with its own `.cargo/config.toml` (target, linker script), so the build runs from
/// that directory with the environment of the outer build removed.
fn build_firmware() -> Result<PathBuf, String> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/firmware");
    let dir = dir
        .canonicalize()
        .map_err(|e| format!("firmware directory {}: {e}", dir.display()))?;
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let status = Command::new(cargo)
        .args(["build", "--release", "--bin", "mav-firmware"])
        .current_dir(&dir)
        .env_remove("CARGO_TARGET_DIR")
        .env_remove("CARGO_BUILD_TARGET_DIR")
        .env_remove("CARGO_BUILD_TARGET")
        .env_remove("RUSTFLAGS")
        .env_remove("CARGO_ENCODED_RUSTFLAGS")
        .env_remove("CARGO_BUILD_RUSTFLAGS")
        .stdout(Stdio::inherit())
        .stderr(Stdio::inherit())
        .status()
        .map_err(|e| format!("running cargo to build the firmware: {e}"))?;
    let elf = dir.join(format!("target/{TARGET}/release/mav-firmware"));
    if !status.success() || !elf.is_file() {
        return Err(format!(
            "building the firmware failed ({status}); build it by hand with\n  \
             rustup target add {TARGET}\n  \
             cd {} && cargo build --release\nor set MCP_FIRMWARE_ELF to a prebuilt ELF",
            dir.display()
        ));
    }
    Ok(elf)
}

/// QEMU running the firmware; killed when dropped, so a failing test cleans up.
struct Qemu {
    child: Child,
    port: u16,
    stderr: Arc<Mutex<String>>,
}

impl Drop for Qemu {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Qemu {
    /// Starts QEMU with UART0 on a TCP server socket, waiting (`wait=on`) for the test
    /// to connect before the firmware starts. Returns once QEMU listens.
    fn start(elf: &Path) -> Qemu {
        let mut last_error = String::new();
        for _ in 0..5 {
            // A port free a moment ago; if QEMU loses the race for it, try another.
            let port = TcpListener::bind((Ipv4Addr::LOCALHOST, 0))
                .and_then(|l| l.local_addr())
                .expect("bind a local port")
                .port();
            let mut child = Command::new(QEMU)
                .args(["-machine", "lm3s6965evb", "-nographic", "-monitor", "none"])
                .arg("-serial")
                .arg(format!("tcp:127.0.0.1:{port},server,wait=on"))
                .arg("-kernel")
                .arg(elf)
                .stdin(Stdio::null())
                .stdout(Stdio::null())
                .stderr(Stdio::piped())
                .spawn()
                .expect("start qemu-system-arm");
            let stderr = Arc::new(Mutex::new(String::new()));
            let (listening_tx, listening_rx) = mpsc::channel();
            let pipe = child.stderr.take().expect("piped stderr");
            let log = Arc::clone(&stderr);
            thread::spawn(move || {
                for line in BufReader::new(pipe).lines().map_while(Result::ok) {
                    if line.contains("waiting for connection") {
                        let _ = listening_tx.send(());
                    }
                    let mut log = log.lock().unwrap();
                    log.push_str(&line);
                    log.push('\n');
                }
            });
            let qemu = Qemu {
                child,
                port,
                stderr,
            };
            // QEMU says it listens on stderr; the channel closes if it exits instead.
            match listening_rx.recv_timeout(FRAME_TIMEOUT) {
                Ok(()) => return qemu,
                Err(_) => last_error = qemu.stderr.lock().unwrap().clone(),
            }
        }
        panic!("QEMU did not start listening:\n{last_error}");
    }
}

/// A frame the firmware wrote, checked to be a Transmit Request to the coordinator.
fn transmit_payload(frame: &[u8]) -> Vec<u8> {
    let raw = RawFrame::new(frame).expect("non-empty frame");
    match Frame::parse(raw) {
        Ok(Frame::TransmitRequest(tx)) => {
            assert_eq!(tx.frame_id, 0, "no transmit status asked");
            assert_eq!(tx.dst64, Address64::COORDINATOR, "sent to the coordinator");
            assert_eq!(tx.dst16, Address16::UNKNOWN, "16-bit address FFFE");
            assert_eq!(tx.options, 0x01, "transmit options");
            assert!(tx.data.len() <= MAX_PAYLOAD, "payload fits unfragmented");
            tx.data.to_vec()
        }
        other => panic!("the firmware wrote {other:?}, not a Transmit Request"),
    }
}

/// `payload` in a Receive Packet from the coordinator, as the MAV's XBee writes it to
/// the UART (API mode 1).
fn receive_frame(payload: &[u8]) -> Vec<u8> {
    let frame = ReceivePacketRepr {
        src64: Address64::COORDINATOR,
        src16: Address16::COORDINATOR,
        options: 0x01,
        data: payload,
    };
    let mut wire = vec![0; frame.encoded_len(ApiMode::Unescaped)];
    let n = frame.encode(ApiMode::Unescaped, &mut wire).unwrap();
    wire.truncate(n);
    wire
}

/// An MCP command in a Receive Packet from the coordinator.
fn command_frame(command: McpCommand<&[u8]>) -> Vec<u8> {
    let mut buf = [0; MAX_PAYLOAD];
    let n = command.encode(&mut buf).expect("command fits");
    receive_frame(&buf[..n])
}

/// The test's side of the UART: the MAV's XBee.
struct Xbee {
    stream: TcpStream,
    decoder: Decoder,
    /// Payloads of Transmit Requests received and not yet taken.
    payloads: VecDeque<Vec<u8>>,
    /// Keeps QEMU alive as long as the link; dropped last.
    qemu: Qemu,
}

impl Xbee {
    /// Boots the firmware and waits for its start-up message.
    fn boot() -> Xbee {
        let qemu = Qemu::start(&firmware_elf());
        let stream = TcpStream::connect((Ipv4Addr::LOCALHOST, qemu.port)).expect("connect");
        stream
            .set_read_timeout(Some(Duration::from_millis(200)))
            .unwrap();
        let mut xbee = Xbee {
            stream,
            decoder: Decoder::new(ApiMode::Unescaped),
            payloads: VecDeque::new(),
            qemu,
        };
        assert_eq!(xbee.next_payload(), STARTUP_MESSAGE);
        xbee
    }

    /// Delivers `payload` to the firmware in a Receive Packet from the coordinator.
    fn send(&mut self, payload: &[u8]) {
        self.stream
            .write_all(&receive_frame(payload))
            .expect("write to the UART");
    }

    /// Encodes and delivers an MCP command.
    fn command(&mut self, command: McpCommand<&[u8]>) {
        self.stream
            .write_all(&command_frame(command))
            .expect("write to the UART");
    }

    /// The next payload the firmware sends, telemetry included.
    fn next_payload(&mut self) -> Vec<u8> {
        let deadline = Instant::now() + FRAME_TIMEOUT;
        loop {
            if let Some(p) = self.payloads.pop_front() {
                return p;
            }
            assert!(
                Instant::now() < deadline,
                "no frame from the firmware within {FRAME_TIMEOUT:?}; QEMU said:\n{}",
                self.qemu.stderr.lock().unwrap()
            );
            self.read_some();
        }
    }

    /// Reads what the UART has and decodes the frames in it.
    fn read_some(&mut self) {
        let mut buf = [0u8; 1024];
        let n = match self.stream.read(&mut buf) {
            Ok(0) => panic!("QEMU closed the UART"),
            Ok(n) => n,
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => return,
            Err(e) => panic!("reading the UART: {e}"),
        };
        let mut input = &buf[..n];
        loop {
            let (consumed, event) = self.decoder.decode(input);
            input = &input[consumed..];
            match event {
                Some(Ok(frame)) => {
                    let payload = transmit_payload(frame.data());
                    self.payloads.push_back(payload);
                }
                Some(Err(e)) => panic!("the firmware wrote a bad frame: {e}"),
                None => break,
            }
        }
    }

    /// The next payload for which `wanted` holds, skipping others for at most
    /// [`FRAME_TIMEOUT`].
    fn next_where(&mut self, what: &str, wanted: impl Fn(&[u8]) -> bool) -> Vec<u8> {
        let deadline = Instant::now() + FRAME_TIMEOUT;
        loop {
            let p = self.next_payload();
            if wanted(&p) {
                return p;
            }
            assert!(
                Instant::now() < deadline,
                "no {what} within {FRAME_TIMEOUT:?}"
            );
        }
    }

    /// The next packet that is not telemetry.
    fn next_non_telemetry(&mut self) -> Vec<u8> {
        self.next_where("packet other than telemetry", |p| p.first() != Some(&b't'))
    }

    /// The next non-telemetry packet, which must be a report.
    fn next_report(&mut self) -> Report<Vec<u8>> {
        let payload = self.next_non_telemetry();
        match parse(&payload) {
            Ok(Packet::Report(report)) => report.map_bytes(<[u8]>::to_vec),
            other => panic!("expected a report, got {other:?} from {payload:02x?}"),
        }
    }

    /// Asks for a status and returns the report.
    fn request(&mut self, request: StatusRequest) -> Report<Vec<u8>> {
        self.command(McpCommand::StatusRequest(request));
        let report = self.next_report();
        assert_eq!(
            report_type(&report),
            request.command_type(),
            "the report answers the request {request:?}"
        );
        report
    }
}

fn report_type<B: AsRef<[u8]>>(report: &Report<B>) -> mcp_core::CommandType {
    use mcp_core::CommandType as T;
    match report {
        Report::TelemetryToCoordinator { .. } => T::TelemetryToCoordinator,
        Report::Landing(_) => T::Landing,
        Report::Controllers(_) => T::Controllers,
        Report::TrajectorySet(_) => T::TrajectorySet,
        Report::PositionSlaveSet(_) => T::PositionSlaveSet,
        Report::Time(_) => T::Time,
    }
}

/// A telemetry packet's records as (id byte, value).
fn telemetry_records(payload: &[u8]) -> Vec<(u8, f32)> {
    match parse(payload) {
        Ok(Packet::Telemetry(t)) => t.iter().map(|r| (u8::from(r.id), r.value)).collect(),
        other => panic!("expected telemetry, got {other:?}"),
    }
}

/// The next telemetry packet's records, skipping anything else.
fn next_telemetry(xbee: &mut Xbee) -> Vec<(u8, f32)> {
    telemetry_records(&xbee.next_where("telemetry", |p| p.first() == Some(&b't')))
}

fn waypoint(time: u32, n: f32) -> Waypoint {
    Waypoint {
        time,
        elevator: n,
        aileron: -n,
        altitude: 1.0 + n,
    }
}

#[test]
fn every_status_request_gets_its_report_and_set_commands_take_effect() {
    if !qemu_available("every_status_request_gets_its_report_and_set_commands_take_effect") {
        return;
    }
    let mut xbee = Xbee::boot();

    // Start-up state.
    assert_eq!(
        xbee.request(StatusRequest::Landing),
        Report::Landing(LandingState::Flight)
    );
    assert_eq!(
        xbee.request(StatusRequest::Controllers),
        Report::Controllers(Controller::Altitude)
    );
    let Report::TrajectorySet(empty) = xbee.request(StatusRequest::TrajectorySet) else {
        unreachable!()
    };
    assert!(empty.is_empty());
    assert_eq!(
        xbee.request(StatusRequest::PositionSlaveSet),
        Report::PositionSlaveSet(SlaveAddresses::Slots([Address([0; 8]); 4]))
    );
    assert_eq!(
        xbee.request(StatusRequest::TelemetryToCoordinator(TelemetryId::Altitude)),
        Report::TelemetryToCoordinator {
            on: false,
            id: TelemetryId::Altitude
        }
    );

    // Time: set, then read back; the MAV clock only moves forward from the set value.
    xbee.command(McpCommand::Time(1_700_000_000));
    let Report::Time(t) = xbee.request(StatusRequest::Time) else {
        unreachable!()
    };
    assert!((1_700_000_000..1_700_000_000 + 60).contains(&t), "time {t}");

    // Position slave set, the specification's form (slot 0) and the firmware's form.
    let a = Address(0x0013_A200_40B5_99BF_u64.to_be_bytes());
    let b = Address(0x0013_A200_40B5_99BD_u64.to_be_bytes());
    xbee.command(McpCommand::PositionSlaveSet {
        slot: None,
        address: a,
    });
    xbee.command(McpCommand::PositionSlaveSet {
        slot: Slot::new(2),
        address: b,
    });
    let zero = Address([0; 8]);
    assert_eq!(
        xbee.request(StatusRequest::PositionSlaveSet),
        Report::PositionSlaveSet(SlaveAddresses::Slots([a, zero, b, zero]))
    );

    // Controllers: a change is reported unsolicited, then confirmed by the status.
    xbee.command(McpCommand::Controllers(Controller::Mpc));
    assert_eq!(xbee.next_report(), Report::Controllers(Controller::Mpc));
    assert_eq!(
        xbee.request(StatusRequest::Controllers),
        Report::Controllers(Controller::Mpc)
    );
    // An id the MAV does not have is refused: no change, no report.
    xbee.command(McpCommand::Controllers(Controller::Unknown(0x09)));
    assert_eq!(
        xbee.request(StatusRequest::Controllers),
        Report::Controllers(Controller::Mpc)
    );

    // Telemetry to coordinator, status per id.
    xbee.command(McpCommand::TelemetryToCoordinator {
        on: true,
        id: TelemetryId::PitchAngle,
    });
    assert_eq!(
        xbee.request(StatusRequest::TelemetryToCoordinator(
            TelemetryId::PitchAngle
        )),
        Report::TelemetryToCoordinator {
            on: true,
            id: TelemetryId::PitchAngle
        }
    );
    xbee.command(McpCommand::TelemetryToCoordinator {
        on: false,
        id: TelemetryId::PitchAngle,
    });
    assert_eq!(
        xbee.request(StatusRequest::TelemetryToCoordinator(
            TelemetryId::PitchAngle
        )),
        Report::TelemetryToCoordinator {
            on: false,
            id: TelemetryId::PitchAngle
        }
    );

    // Landing: the state change is reported, and the status agrees.
    xbee.command(McpCommand::Landing { on: true });
    assert_eq!(xbee.next_report(), Report::Landing(LandingState::Landing));
}

#[test]
fn telemetry_carries_exactly_the_enabled_ids_in_ascending_order() {
    if !qemu_available("telemetry_carries_exactly_the_enabled_ids_in_ascending_order") {
        return;
    }
    let mut xbee = Xbee::boot();
    // Enabled out of order, one of them outside table 29.
    let ids = [0x19u8, 0x01, 0x06, 0x40, 0x07, 0x1B];
    for id in ids {
        xbee.command(McpCommand::TelemetryToCoordinator {
            on: true,
            id: TelemetryId::from(id),
        });
    }
    // Each command reaches the firmware in order; a status request after the last one
    // fences them, so every telemetry packet after its answer has all six ids.
    xbee.request(StatusRequest::TelemetryToCoordinator(TelemetryId::from(
        0x1B,
    )));
    let mut sorted = ids;
    sorted.sort_unstable();
    for _ in 0..3 {
        let records = next_telemetry(&mut xbee);
        let got: Vec<u8> = records.iter().map(|r| r.0).collect();
        assert_eq!(got, sorted);
    }

    // Position set moves the MAV; telemetry shows the new position and the shift.
    xbee.command(McpCommand::PositionSet {
        elevator: 2.5,
        aileron: -1.25,
    });
    xbee.request(StatusRequest::Time);
    let records = next_telemetry(&mut xbee);
    let value = |id: u8| records.iter().find(|r| r.0 == id).map(|r| r.1);
    assert_eq!(value(0x06), Some(2.5), "elevator position");
    assert_eq!(value(0x07), Some(-1.25), "aileron position");
    assert_eq!(value(0x1B), Some(2.5), "elevator shift");
    assert_eq!(value(0x40), Some(0.0), "an id outside table 29 reads 0");
    assert_eq!(value(0x01), Some(1.0), "hovering at the cruise altitude");

    // Turned off: telemetry stops.
    for id in ids {
        xbee.command(McpCommand::TelemetryToCoordinator {
            on: false,
            id: TelemetryId::from(id),
        });
    }
    // Telemetry sent before the last command was handled may still come before the
    // time report; after it there is none: the next frame answers the next request.
    xbee.request(StatusRequest::Time);
    xbee.command(McpCommand::StatusRequest(StatusRequest::Landing));
    assert_eq!(
        parse(&xbee.next_payload()).unwrap(),
        Packet::Report(Report::Landing(LandingState::Flight))
    );
}

#[test]
fn landing_and_take_off_report_every_state_change() {
    if !qemu_available("landing_and_take_off_report_every_state_change") {
        return;
    }
    let mut xbee = Xbee::boot();
    xbee.command(McpCommand::TelemetryToCoordinator {
        on: true,
        id: TelemetryId::Altitude,
    });
    xbee.command(McpCommand::Landing { on: true });
    assert_eq!(xbee.next_report(), Report::Landing(LandingState::Landing));
    assert_eq!(xbee.next_report(), Report::Landing(LandingState::OnGround));
    assert_eq!(
        xbee.request(StatusRequest::Landing),
        Report::Landing(LandingState::OnGround)
    );
    assert_eq!(next_telemetry(&mut xbee), [(0x01, 0.0)], "on the ground");

    // Landing again on the ground changes nothing.
    xbee.command(McpCommand::Landing { on: true });
    assert_eq!(
        xbee.request(StatusRequest::Landing),
        Report::Landing(LandingState::OnGround)
    );

    xbee.command(McpCommand::Landing { on: false });
    assert_eq!(xbee.next_report(), Report::Landing(LandingState::TakeOff));
    assert_eq!(
        xbee.next_report(),
        Report::Landing(LandingState::Stabilization)
    );
    assert_eq!(xbee.next_report(), Report::Landing(LandingState::Flight));
    assert_eq!(next_telemetry(&mut xbee), [(0x01, 1.0)], "back at cruise");
}

#[test]
fn trajectory_set_is_answered_by_a_trajectory_report() {
    if !qemu_available("trajectory_set_is_answered_by_a_trajectory_report") {
        return;
    }
    let mut xbee = Xbee::boot();
    // Far in the future, so the waypoints do not steer the MAV during the test.
    let future = 4_000_000_000;
    let set = |xbee: &mut Xbee, waypoints: &[Waypoint]| {
        let mut buf = [0; MAX_PAYLOAD];
        let mut builder = TrajectoryBuilder::command(&mut buf).unwrap();
        for &w in waypoints {
            builder.push(w).unwrap();
        }
        let n = builder.finish();
        xbee.send(&buf[..n]);
        match xbee.next_report() {
            Report::TrajectorySet(w) => w.iter().collect::<Vec<_>>(),
            other => panic!("expected a trajectory report, got {other:?}"),
        }
    };

    let two = [waypoint(future, 1.0), waypoint(future + 10, 2.0)];
    assert_eq!(set(&mut xbee, &two), two);
    // Five fill one unfragmented payload: the most a trajectory set can carry.
    let five: Vec<Waypoint> = (0..5).map(|i| waypoint(future + i, i as f32)).collect();
    assert_eq!(set(&mut xbee, &five), five);
    let Report::TrajectorySet(stored) = xbee.request(StatusRequest::TrajectorySet) else {
        unreachable!()
    };
    assert_eq!(stored.iter().collect::<Vec<_>>(), five);
    // An empty trajectory clears it.
    assert_eq!(set(&mut xbee, &[]), []);
    let Report::TrajectorySet(stored) = xbee.request(StatusRequest::TrajectorySet) else {
        unreachable!()
    };
    assert!(stored.is_empty());
}

#[test]
fn garbage_other_frames_and_invalid_packets_are_ignored() {
    if !qemu_available("garbage_other_frames_and_invalid_packets_are_ignored") {
        return;
    }
    let mut xbee = Xbee::boot();
    let stream = &mut xbee.stream;
    // Line noise, a Modem Status frame, a frame with a bad checksum, a frame too long
    // for the firmware's buffer.
    stream.write_all(&[0x00, 0x7E, 0xFF, 0x13]).unwrap();
    stream
        .write_all(&[0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F])
        .unwrap();
    stream
        .write_all(&[0x7E, 0x00, 0x02, 0x8A, 0x06, 0x00])
        .unwrap();
    // Invalid MCP payloads: unknown category, wrong length, a report (the MAV takes
    // only commands), a message.
    xbee.send(b"x");
    xbee.send(b"c\x06\x01");
    xbee.send(b"r\x02\x04");
    xbee.send(b"mhello");
    // A 200-byte payload: oversize for the firmware (84 at most), dropped whole.
    xbee.send(&[b'm'; 200]);
    // Still in service: the next request is answered, and nothing came before it.
    xbee.command(McpCommand::StatusRequest(StatusRequest::Landing));
    assert_eq!(
        parse(&xbee.next_payload()).unwrap(),
        Packet::Report(Report::Landing(LandingState::Flight))
    );
}

/// The whole chain: a ground station (`mcp_host::connect`, `CommandSender`) on the
/// coordinator of the virtual XBee network, whose node 0013A20040B599B9 is the
/// firmware's UART in QEMU.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn ground_station_commands_the_firmware_through_the_radio_network() {
    use futures::StreamExt;
    use mcp_host::radio::{Network, NetworkConfig, NodeOptions};
    use mcp_host::{DeliveryReport, Event, LinkOptions, PacketStream};

    if !qemu_available("ground_station_commands_the_firmware_through_the_radio_network") {
        return;
    }
    const MAV: Address64 = Address64(0x0013_A200_40B5_99B9);

    /// The next packet from the MAV for which `wanted` holds (other events skipped).
    async fn next_from_mav(
        stream: &mut PacketStream,
        what: &str,
        wanted: impl Fn(&Packet<bytes::Bytes>) -> bool,
    ) -> Packet<bytes::Bytes> {
        let deadline = tokio::time::Instant::now() + FRAME_TIMEOUT;
        loop {
            let event = tokio::time::timeout_at(deadline, stream.next())
                .await
                .unwrap_or_else(|_| panic!("no {what} from the MAV within {FRAME_TIMEOUT:?}"))
                .expect("the packet stream stays open");
            if let Event::Packet(received) = event {
                if received.origin.src64 == MAV && wanted(&received.packet) {
                    return received.packet;
                }
            }
        }
    }

    let elf = tokio::task::spawn_blocking(firmware_elf).await.unwrap();
    let qemu = tokio::task::spawn_blocking(move || Qemu::start(&elf))
        .await
        .unwrap();

    // The coordinator's radio, and the ground station on it.
    let network = Network::new(NetworkConfig::default());
    let coordinator = network
        .add_link(
            Address64::COORDINATOR,
            &"tcp-listen:127.0.0.1:0".parse().unwrap(),
            NodeOptions::default(),
        )
        .await
        .expect("coordinator link");
    let gs_link = format!("tcp:{}", coordinator.local_addr.expect("bound address"));
    let (mut stream, sender) = mcp_host::connect(&gs_link.parse().unwrap(), LinkOptions::default())
        .await
        .expect("ground station connects");
    assert!(network.connected(Address64::COORDINATOR).await);

    // The MAV's radio: its link is the firmware's UART; connecting starts QEMU's CPU.
    let mav_link = format!("tcp:127.0.0.1:{}", qemu.port);
    network
        .add_link(
            MAV,
            &mav_link.parse().unwrap(),
            NodeOptions::with_mode(ApiMode::Unescaped),
        )
        .await
        .expect("MAV link");
    let started = next_from_mav(&mut stream, "start-up message", |p| {
        matches!(p, Packet::Message(_))
    })
    .await;
    let Packet::Message(text) = started else {
        unreachable!()
    };
    assert_eq!(text.as_bytes(), &STARTUP_MESSAGE[1..]);

    // Status requests, answered through the network.
    let landing = sender.request(MAV, StatusRequest::Landing).await.unwrap();
    assert_eq!(landing, Report::Landing(LandingState::Flight));
    let controllers = sender
        .request(MAV, StatusRequest::Controllers)
        .await
        .unwrap();
    assert_eq!(controllers, Report::Controllers(Controller::Altitude));

    // A set command is delivered (Transmit Status from the radio) and takes effect.
    let delivery = sender
        .send(MAV, &McpCommand::time(1_800_000_000))
        .await
        .unwrap();
    assert!(
        matches!(delivery, DeliveryReport::Delivered { .. }),
        "{delivery:?}"
    );
    let Report::Time(t) = sender.request(MAV, StatusRequest::Time).await.unwrap() else {
        unreachable!()
    };
    assert!((1_800_000_000..1_800_000_000 + 60).contains(&t), "time {t}");

    // Trajectory set: the trajectory report comes back on the stream.
    let waypoints = [waypoint(4_000_000_000, 1.0), waypoint(4_000_000_001, 2.0)];
    let mut buf = [0; MAX_PAYLOAD];
    let mut builder = TrajectoryBuilder::command(&mut buf).unwrap();
    for w in waypoints {
        builder.push(w).unwrap();
    }
    let n = builder.finish();
    let Ok(Packet::Command(set)) = parse(&buf[..n]) else {
        unreachable!()
    };
    sender.send(MAV, &set).await.unwrap();
    let report = next_from_mav(&mut stream, "trajectory report", |p| {
        matches!(p, Packet::Report(Report::TrajectorySet(_)))
    })
    .await;
    let Packet::Report(Report::TrajectorySet(got)) = report else {
        unreachable!()
    };
    assert_eq!(got.iter().collect::<Vec<_>>(), waypoints);

    // Telemetry: exactly the enabled ids, ascending.
    for id in [TelemetryId::PitchAngle, TelemetryId::Altitude] {
        sender
            .send(MAV, &McpCommand::telemetry_to_coordinator(true, id))
            .await
            .unwrap();
    }
    sender
        .request(
            MAV,
            StatusRequest::TelemetryToCoordinator(TelemetryId::Altitude),
        )
        .await
        .unwrap();
    let telemetry = next_from_mav(
        &mut stream,
        "telemetry",
        |p| matches!(p, Packet::Telemetry(t) if t.len() == 2),
    )
    .await;
    let Packet::Telemetry(t) = telemetry else {
        unreachable!()
    };
    let ids: Vec<TelemetryId> = t.iter().map(|r| r.id).collect();
    assert_eq!(ids, [TelemetryId::Altitude, TelemetryId::PitchAngle]);

    // Landing: the unsolicited reports reach the ground station.
    sender.send(MAV, &McpCommand::landing(true)).await.unwrap();
    for state in [LandingState::Landing, LandingState::OnGround] {
        let report = next_from_mav(&mut stream, "landing report", |p| {
            matches!(p, Packet::Report(Report::Landing(_)))
        })
        .await;
        assert_eq!(report, Packet::Report(Report::Landing(state)));
    }
    network.shutdown();
    drop(qemu);
}

#[test]
fn a_burst_of_requests_is_answered_in_full_and_in_order() {
    if !qemu_available("a_burst_of_requests_is_answered_in_full_and_in_order") {
        return;
    }
    let mut xbee = Xbee::boot();
    // 60 requests in one write: far more than the firmware queues at once, arriving
    // faster than it handles them (QEMU's UART has no baud-rate pacing).
    let ids: Vec<u8> = (0..60).map(|i| i * 4).collect();
    let mut burst = Vec::new();
    for &id in &ids {
        let request = McpCommand::status_request(StatusRequest::TelemetryToCoordinator(
            TelemetryId::from(id),
        ));
        burst.extend(command_frame(request));
    }
    xbee.stream.write_all(&burst).unwrap();
    for &id in &ids {
        assert_eq!(
            xbee.next_report(),
            Report::TelemetryToCoordinator {
                on: false,
                id: TelemetryId::from(id)
            }
        );
    }
}

#[test]
fn frames_found_inside_a_failed_candidate_are_all_answered() {
    if !qemu_available("frames_found_inside_a_failed_candidate_are_all_answered") {
        return;
    }
    let mut xbee = Xbee::boot();
    // Five time requests (19 bytes each) inside a candidate that claims all 95 bytes
    // and ends with a wrong checksum: API mode 1 scans again from the byte after its
    // start delimiter and finds the five at once, one more than the firmware queues.
    let inner = command_frame(McpCommand::status_request(StatusRequest::Time)).repeat(5);
    assert_eq!(inner.len(), 95);
    let mut wire = vec![0x7E, 0x00, 95];
    wire.extend_from_slice(&inner);
    wire.push(0x00);
    xbee.stream.write_all(&wire).unwrap();
    for i in 0..5 {
        let report = xbee.next_report();
        assert!(matches!(report, Report::Time(_)), "answer {i}: {report:?}");
    }
}

#[test]
fn a_stray_start_delimiter_holds_back_no_command_for_long() {
    if !qemu_available("a_stray_start_delimiter_holds_back_no_command_for_long") {
        return;
    }
    let mut xbee = Xbee::boot();
    // Noise that reads as a start delimiter and a length of 95, then one time request
    // and nothing more: in API mode 1 the request lies inside the candidate, which
    // would wait for 95 bytes. The line goes quiet: the firmware gives the candidate up
    // and finds the request in its bytes.
    let mut wire = vec![0x7E, 0x00, 95];
    wire.extend_from_slice(&command_frame(McpCommand::status_request(
        StatusRequest::Time,
    )));
    xbee.stream.write_all(&wire).unwrap();
    let report = xbee.next_report();
    assert!(matches!(report, Report::Time(_)), "{report:?}");
}
