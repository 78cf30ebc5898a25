//! Digi's xbee-python library (digi-xbee 1.5.0) as a ground station on the simulated
//! network, over a real pseudo-terminal in both API modes
//! (`tests/peer/xbee_python_ground.py`): it opens the simulated coordinator as it opens
//! a real module, sends MCP commands to a simulated MAV in Transmit Requests, gets their
//! Transmit Statuses, and reads the MAV's answers from Receive Packets. The MAV's 64-bit
//! address holds 0x13, so in mode 2 every frame both ways carries an escape.
//!
//! The library runs from a virtual environment made under Cargo's target directory with
//! `pip install digi-xbee==1.5.0` (from PyPI), unless `MCP_XBEE_PYTHON` names a Python
//! interpreter that has it.

use std::path::{Path, PathBuf};
use std::process::{Command as Process, Output};
use std::sync::OnceLock;
use std::time::Duration;

use mcp_core::{Command, Packet, Report, StatusRequest, TelemetryId};
use mcp_host::Link;
use mcp_host::sim::{Simulator, posix_now};
use xbee_api::{Address64, ApiMode};

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
        "{what} failed (this test needs PyPI for {LIBRARY}, or MCP_XBEE_PYTHON set to a Python that has it):\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn payload(command: &Command<&[u8]>) -> String {
    let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
    let n = command.encode(&mut buf).unwrap();
    buf[..n].iter().map(|b| format!("{b:02x}")).collect()
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

async fn run_ground_station(mode: ApiMode, steps: &[String]) -> Output {
    let python = python();
    let sim = Simulator::start(&Link::Pty, mode, &[MAV], Simulator::network_config())
        .await
        .unwrap();
    let port = sim.coordinator().pty_path.clone().unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/peer/xbee_python_ground.py");
    let child = tokio::process::Command::new(python)
        .arg(script)
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
    let altitude_on = payload(&Command::TelemetryToCoordinator {
        on: true,
        id: TelemetryId::Altitude,
    });
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
