//! Digi's xbee-python library (digi-xbee 1.5.0) as a peer, over real pseudo-terminals
//! in both API modes. The MAV's 64-bit address holds 0x13, so in mode 2 every frame that
//! carries it, both ways, has an escape.
//!
//! - As a ground station on the simulated network (`tests/peer/xbee_python_ground.py`):
//!   it opens the simulated coordinator as it opens a real module, sends MCP commands to
//!   a simulated MAV in Transmit Requests, gets their Transmit Statuses, and reads the
//!   MAV's answers from Receive Packets. It names the MAV's radio by a remote AT
//!   command and finds it by node discovery (`ND`), as its `XBeeNetwork` does.
//! - As the radio of our ground station (`tests/peer/xbee_python_radio.py`): it reads
//!   our frames with its own frame reader and parser and answers with frames it builds;
//!   `mcp_host::connect` asks it `AP`, sends commands and gets reports and telemetry.
//!
//! The library runs from a virtual environment made under Cargo's target directory with
//! `pip install digi-xbee==1.5.0` (from PyPI), unless `MCP_XBEE_PYTHON` names a Python
//! interpreter that has it.

use std::path::{Path, PathBuf};
use std::process::{Command as Process, Output};
use std::sync::OnceLock;
use std::time::Duration;

use futures::StreamExt;
use mcp_core::{Command, Packet, Report, StatusRequest, TelemetryId};
use mcp_host::sim::{Simulator, posix_now};
use mcp_host::{DeliveryReport, Event, Link, LinkOptions};
use xbee_api::{Address16, Address64, ApiMode, AtStatus, DiscoveryStatus, Frame, ModemStatus};

/// Failure guard only: the script's own waits end long before this.
const GUARD: Duration = Duration::from_secs(120);
const MAV: Address64 = Address64(0x0013_A200_40B5_99B9);
const LIBRARY: &str = "digi-xbee==1.5.0";

/// A Python interpreter with xbee-python, set up once.
fn python() -> &'static Path {
    static PYTHON: OnceLock<PathBuf> = OnceLock::new();
    PYTHON.get_or_init(|| {
        if let Some(python) = std::env::var_os("MCP_XBEE_PYTHON") {
            return python.into();
        }
        let venv = Path::new(env!("CARGO_TARGET_TMPDIR")).join("xbee-python-1.5.0");
        let python = venv.join("bin").join("python");
        let has_library = |python: &Path| {
            Process::new(python)
                .args(["-c", "import digi.xbee"])
                .output()
                .is_ok_and(|out| out.status.success())
        };
        if !has_library(&python) {
            checked(
                Process::new("python3").args(["-m", "venv"]).arg(&venv),
                "python3 -m venv",
            );
            checked(
                Process::new(&python).args([
                    "-m",
                    "pip",
                    "install",
                    "--quiet",
                    "--disable-pip-version-check",
                    LIBRARY,
                ]),
                "pip install",
            );
        }
        python
    })
}

fn checked(command: &mut Process, what: &str) {
    let out = command.output().unwrap_or_else(|e| {
        panic!("{what}: {e}; this test needs python3 (or MCP_XBEE_PYTHON set to a Python with {LIBRARY})")
    });
    assert!(
        out.status.success(),
        "{what} failed (this test needs python3 with its venv module, on Debian and Ubuntu the package python3-venv, and PyPI for {LIBRARY}; or MCP_XBEE_PYTHON set to a Python that has it):\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn payload(command: &Command<&[u8]>) -> String {
    let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
    let n = command.encode(&mut buf).unwrap();
    hex(&buf[..n])
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

fn script(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/peer")
        .join(name)
}

/// The MCP packet of an `rx SRC64 HEX` line from the MAV.
fn received(line: &str) -> Packet<Vec<u8>> {
    let rest = line
        .strip_prefix("rx 0013A20040B599B9 ")
        .unwrap_or_else(|| panic!("expected a message from the MAV, got {line:?}"));
    let bytes: Vec<u8> = (0..rest.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&rest[i..i + 2], 16).unwrap())
        .collect();
    mcp_core::parse(&bytes[..])
        .unwrap_or_else(|e| panic!("{line}: {e}"))
        .map_bytes(<[u8]>::to_vec)
}

fn on_altitude() -> Command<&'static [u8]> {
    Command::TelemetryToCoordinator {
        on: true,
        id: TelemetryId::Altitude,
    }
}

async fn run_ground_station(mode: ApiMode, steps: &[String]) -> Output {
    let python = python();
    let sim = Simulator::start(&Link::Pty, mode, &[MAV], Simulator::network_config())
        .await
        .unwrap();
    let port = sim.coordinator().pty_path.clone().unwrap();
    let child = tokio::process::Command::new(python)
        .arg(script("xbee_python_ground.py"))
        .arg(&port)
        .arg(MAV.to_string())
        .args(steps)
        .kill_on_drop(true)
        .output();
    let out = tokio::time::timeout(GUARD, child)
        .await
        .expect("xbee-python ground station timed out")
        .unwrap();
    let stats = sim.network().stats(Address64::COORDINATOR).unwrap();
    assert_eq!(stats.decode_errors, 0, "{stats:?}");
    out
}

async fn ground_station_in(mode: ApiMode, mode_name: &str) {
    let time_request = payload(&Command::StatusRequest(StatusRequest::Time));
    let altitude_on = payload(&on_altitude());
    let steps = [
        "send",
        &time_request,
        "read",
        "1",
        "send",
        &altitude_on,
        "read",
        "2",
        "send-to",
        "0013A20000000001",
        &time_request,
    ]
    .map(String::from);
    let before = posix_now();
    let out = run_ground_station(mode, &steps).await;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 7, "{stdout}\n{stderr}");
    // xbee-python read HV, VR, SH, SL, NI, MY and CE and made sense of them.
    assert_eq!(
        lines[0],
        format!("open 0000000000000000 ZIGBEE COORDINATOR {mode_name}")
    );
    assert_eq!(lines[1], "delivered SUCCESS");
    match received(lines[2]) {
        Packet::Report(Report::Time(time)) => {
            assert!((before..=posix_now()).contains(&time), "{time}");
        }
        other => panic!("expected a time report, got {other:?}"),
    }
    assert_eq!(lines[3], "delivered SUCCESS");
    for line in &lines[4..6] {
        let Packet::Telemetry(telemetry) = received(line) else {
            panic!("expected telemetry, got {line}");
        };
        let ids: Vec<TelemetryId> = telemetry.iter().map(|r| r.id).collect();
        assert_eq!(ids, [TelemetryId::Altitude], "{line}");
    }
    // Transmit Status 0x24, address not found, as xbee-python names it.
    assert_eq!(lines[6], "failed ADDRESS_NOT_FOUND");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn xbee_python_ground_station_in_api_mode_1() {
    ground_station_in(ApiMode::Unescaped, "API_MODE").await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn xbee_python_ground_station_in_api_mode_2() {
    ground_station_in(ApiMode::Escaped, "ESCAPED_API_MODE").await;
}

/// xbee-python names the MAV's radio (`NI`, by a Remote AT Command) and finds it by
/// node discovery: it reads `N?` (refused: not a Zigbee command) and `NT` from the
/// coordinator, sends `ND NAME`, and reads the radio out of the answer.
async fn discovery_in(mode: ApiMode) {
    let steps = ["name", "MAV 1", "discover", "MAV 1"].map(String::from);
    let out = run_ground_station(mode, &steps).await;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    let lines: Vec<&str> = stdout.lines().skip(1).collect();
    assert_eq!(
        lines,
        ["named MAV 1", "found 0013A20040B599B9 MAV 1"],
        "{stdout}\n{stderr}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn xbee_python_finds_the_mav_by_node_discovery_in_api_mode_1() {
    discovery_in(ApiMode::Unescaped).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn xbee_python_finds_the_mav_by_node_discovery_in_api_mode_2() {
    discovery_in(ApiMode::Escaped).await;
}

/// Our ground station with xbee-python playing its radio.
async fn radio_in(mode: ApiMode) {
    let python = python();
    let options = LinkOptions {
        api_mode: mode,
        ..LinkOptions::default()
    };
    let (mut stream, sender) = mcp_host::connect(&Link::Pty, options).await.unwrap();
    let port = stream.info().pty_path.clone().unwrap();
    let mut buf = [0u8; 16];
    let n = Report::<&[u8]>::Time(1_700_000_000)
        .encode(&mut buf)
        .unwrap();
    let time_report = hex(&buf[..n]);
    // Telemetry: altitude (0x01) = 1.5, pitch angle (0x19) = -0.25.
    let telemetry = "74 01 0000c03f 19 000080be".replace(' ', "");
    let mode_number = u8::from(mode).to_string();
    let mut radio = tokio::process::Command::new(python)
        .arg(script("xbee_python_radio.py"))
        .arg(&port)
        .args([&mode_number, &time_report, &telemetry])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .kill_on_drop(true)
        .spawn()
        .unwrap();

    let events = async {
        // The radio's first frame: a Modem Status, built by xbee-python.
        loop {
            match stream.next().await.unwrap() {
                Event::Frame(frame) => {
                    let Ok(Frame::ModemStatus(status)) = frame.parse() else {
                        panic!("{frame:?}");
                    };
                    assert_eq!(status.status, ModemStatus::CoordinatorStarted);
                    break;
                }
                Event::Link(_) => {}
                other => panic!("expected the modem status, got {other:?}"),
            }
        }
        let ap = sender.at(*b"AP", &[], None).await.unwrap();
        match ap.parse().unwrap() {
            Frame::AtCommandResponse(r) => {
                assert_eq!(
                    (r.command, r.status, r.data),
                    (*b"AP", AtStatus::Ok, &[u8::from(mode)][..])
                );
            }
            other => panic!("{other:?}"),
        }
        let report = sender.request(MAV, StatusRequest::Time).await.unwrap();
        assert_eq!(report, Report::Time(1_700_000_000));
        let delivery = sender.send(MAV, &on_altitude()).await.unwrap();
        assert!(
            matches!(
                delivery,
                DeliveryReport::Delivered {
                    dst16: Address16(0x7D84),
                    retries: 0,
                    discovery: DiscoveryStatus::NoDiscoveryOverhead,
                    ..
                }
            ),
            "{delivery:?}"
        );
        // The stream saw the report, then the telemetry, both from the MAV.
        let mut packets = Vec::new();
        while packets.len() < 2 {
            match stream.next().await.unwrap() {
                Event::Packet(rx) => {
                    assert_eq!((rx.origin.src64, rx.origin.src16), (MAV, Address16(0x7D84)));
                    packets.push(rx.packet);
                }
                Event::Frame(_) | Event::Link(_) => {}
                other => panic!("{other:?}"),
            }
        }
        assert_eq!(packets[0], Packet::Report(Report::Time(1_700_000_000)));
        let Packet::Telemetry(values) = &packets[1] else {
            panic!("{packets:?}");
        };
        let values: Vec<(TelemetryId, f32)> = values.iter().map(|r| (r.id, r.value)).collect();
        assert_eq!(
            values,
            [
                (TelemetryId::Altitude, 1.5),
                (TelemetryId::PitchAngle, -0.25)
            ]
        );
    };
    // The radio keeps running until its standard input ends: stopping before that is a
    // failure on its side, reported at once with what it printed.
    let stdin = radio.stdin.take();
    let mut radio = tokio::spawn(radio.wait_with_output());
    let exchange = async {
        tokio::select! {
            () = events => {}
            out = &mut radio => {
                let out = out.unwrap().unwrap();
                panic!(
                    "the xbee-python radio stopped early ({}):\n{}\n{}",
                    out.status,
                    String::from_utf8_lossy(&out.stdout),
                    String::from_utf8_lossy(&out.stderr)
                );
            }
        }
    };
    tokio::time::timeout(GUARD, exchange)
        .await
        .expect("the exchange with the xbee-python radio timed out");
    drop(stdin);
    let out = tokio::time::timeout(GUARD, radio)
        .await
        .expect("the xbee-python radio did not stop")
        .unwrap()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    // What xbee-python's parser made of our frames.
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 3, "{stdout}\n{stderr}");
    assert_eq!(lines[0], "at AP");
    for (line, payload) in lines[1..].iter().zip([
        payload(&Command::StatusRequest(StatusRequest::Time)),
        payload(&on_altitude()),
    ]) {
        let fields: Vec<&str> = line.split(' ').collect();
        assert_eq!(fields.len(), 4, "{line}");
        assert_eq!(fields[0], "tx");
        assert_ne!(fields[1], "0", "{line}: a frame id asks for a status");
        assert_eq!(fields[2..], ["0013A20040B599B9", &payload], "{line}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn xbee_python_radio_in_api_mode_1() {
    radio_in(ApiMode::Unescaped).await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn xbee_python_radio_in_api_mode_2() {
    radio_in(ApiMode::Escaped).await;
}
