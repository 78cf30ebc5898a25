//! `mcp-gs radio` and `mcp-gs sim` as processes: they print where to connect, and route.

use std::process::{Child, Command};
use std::sync::mpsc;
use std::time::Duration;

use futures::{SinkExt, StreamExt};
use mcp_core::{LandingState, Report, StatusRequest};
use mcp_host::codec::{CodecItem, XBeeCodec};
use mcp_host::{Link, LinkOptions};
use tokio::net::TcpStream;
use tokio_util::codec::Framed;
use xbee_api::{Address16, Address64, ApiMode, Frame, ModemStatus, TransmitRequestRepr};

mod common;

/// Failure guard only.
const GUARD: Duration = Duration::from_secs(20);

/// A child process, killed when dropped, and its stdout lines.
struct Running {
    child: Child,
    lines: mpsc::Receiver<String>,
}

impl Running {
    fn start(args: &[&str]) -> Self {
        let (child, lines) = common::spawn_lines(args);
        Running { child, lines }
    }

    /// The next line satisfying `f`.
    fn line(&self, mut f: impl FnMut(&str) -> bool) -> String {
        loop {
            let line = self.lines.recv_timeout(GUARD).expect("a line in time");
            if f(&line) {
                return line;
            }
        }
    }

    /// The address in the next `... listening on ADDR (...` line starting with `prefix`.
    fn listening(&self, prefix: &str) -> std::net::SocketAddr {
        let line = self.line(|l| l.starts_with(prefix) && l.contains("listening on "));
        let rest = line.split("listening on ").nth(1).unwrap();
        rest.split(' ').next().unwrap().parse().expect("an address")
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

async fn device(addr: std::net::SocketAddr, mode: ApiMode) -> Framed<TcpStream, XBeeCodec> {
    Framed::new(
        TcpStream::connect(addr).await.unwrap(),
        XBeeCodec::new(mode),
    )
}

async fn next_frame(dev: &mut Framed<TcpStream, XBeeCodec>) -> mcp_host::OwnedFrame {
    match tokio::time::timeout(GUARD, dev.next()).await {
        Ok(Some(Ok(CodecItem::Frame(frame)))) => frame,
        other => panic!("expected a frame, got {other:?}"),
    }
}

#[tokio::test]
async fn radio_routes_between_the_links_it_prints() {
    let radio = Running::start(&[
        "radio",
        "--coordinator",
        "tcp-listen:127.0.0.1:0",
        "--node",
        "0013A20040B599B9=tcp-listen:127.0.0.1:0@2",
        "--seed",
        "7",
        "--duration",
        "120",
    ]);
    radio.line(|l| l.starts_with("seed 7 "));
    let coordinator = radio.listening("coordinator ");
    let node = radio.listening("node 0013a20040b599b9/");
    let mut ground = device(coordinator, ApiMode::Unescaped).await;
    let mut mav = device(node, ApiMode::Escaped).await;
    for (dev, status) in [
        (&mut ground, ModemStatus::CoordinatorStarted),
        (&mut mav, ModemStatus::JoinedNetwork),
    ] {
        match next_frame(dev).await.parse() {
            Ok(Frame::ModemStatus(ms)) => assert_eq!(ms.status, status),
            other => panic!("{other:?}"),
        }
    }
    let tx = TransmitRequestRepr {
        frame_id: 0,
        dst64: Address64::COORDINATOR,
        dst16: Address16::UNKNOWN,
        radius: 0,
        options: 0x01,
        data: b"r\x02\x04",
    };
    mav.send(&tx).await.unwrap();
    match next_frame(&mut ground).await.parse() {
        Ok(Frame::ReceivePacket(rx)) => {
            assert_eq!(rx.src64, Address64(0x0013_A200_40B5_99B9));
            assert_eq!(rx.data, b"r\x02\x04");
        }
        other => panic!("{other:?}"),
    }
    radio.line(|l| l.contains("0013a20040b599b9 connected"));
}

#[tokio::test]
async fn sim_serves_a_fleet_on_the_link_it_prints() {
    let sim = Running::start(&[
        "sim",
        "--link",
        "tcp-listen:127.0.0.1:0",
        "--mavs",
        "2",
        "--duration",
        "120",
    ]);
    let addr = sim.listening("ground station link");
    let fleet = sim.line(|l| l.starts_with("simulating 2 MAVs: "));
    assert!(fleet.contains("0013a20040b599b9/") && fleet.contains("0013a20040b599bf/"));
    let link: Link = format!("tcp:{addr}").parse().unwrap();
    let (_stream, sender) = mcp_host::connect(&link, LinkOptions::default())
        .await
        .unwrap();
    for mav in [0x0013_A200_40B5_99B9, 0x0013_A200_40B5_99BF] {
        let report = sender
            .request_with(Address64(mav), StatusRequest::Landing, Some(GUARD))
            .await
            .unwrap();
        assert_eq!(report, Report::Landing(LandingState::Flight));
    }
}

#[test]
fn a_fleet_is_listed_a_few_mavs_a_line() {
    let sim = Running::start(&["sim", "--link", "tcp-listen:127.0.0.1:0", "--mavs", "9"]);
    sim.line(|l| l == "simulating 9 MAVs:");
    let lines: Vec<String> = (0..3).map(|_| sim.line(|_| true)).collect();
    let addresses: Vec<&str> = lines
        .iter()
        .inspect(|l| assert!(l.starts_with("  "), "{lines:?}"))
        .flat_map(|l| l.trim().split(", "))
        .collect();
    assert_eq!(addresses.len(), 9, "{lines:?}");
    assert!(addresses[0].starts_with("0013a20040b599b9/"), "{lines:?}");
    assert_eq!(lines[2].trim().split(", ").count(), 1, "{lines:?}");
}

#[test]
fn bad_node_arguments_are_input_errors() {
    for args in [
        &["radio", "--coordinator", "pty", "--node", "nonsense"][..],
        &["radio", "--coordinator", "pty@3"],
        &["radio", "--coordinator", "pty", "--loss", "1.5"],
        &[
            "radio",
            "--coordinator",
            "pty",
            "--faults",
            "coordinator=loss=2",
        ],
        &["sim", "--link", "pty", "--address", "0000000000000000"],
        &["sim", "--link", "pty", "--mavs", "0"],
        &[
            "sim",
            "--link",
            "pty",
            "--mavs",
            "1",
            "--address",
            "0013A20040B599BF",
            "--address",
            "0013A20040B599BD",
        ],
        &[
            "radio",
            "--coordinator",
            "pty",
            "--cut",
            "0013A20040B599B9@x+1",
        ],
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
            .args(args)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
    }
}

#[test]
fn nonsense_numbers_are_refused_with_a_reason() {
    for (args, reason) in [
        (
            &["sim", "--link", "pty", "--rx-buffer", "0"][..],
            "drops every command",
        ),
        (
            &["sim", "--link", "pty", "--rx-buffer", "18"],
            "drops every command",
        ),
        (
            &["sim", "--link", "pty", "--rx-buffer=-1"],
            "number of bytes",
        ),
        (&["sim", "--link", "pty", "--duration=-1"], "seconds"),
        (&["sim", "--link", "pty", "--duration", "1e300"], "seconds"),
        (
            &["radio", "--coordinator", "pty", "--duration", "NaN"],
            "seconds",
        ),
        (
            &["sim", "--link", "pty", "--latency", "18446744073709551615"],
            "3600000",
        ),
        (
            &["radio", "--coordinator", "pty", "--jitter", "3600001"],
            "3600000",
        ),
        (
            &[
                "radio",
                "--coordinator",
                "pty",
                "--faults",
                "coordinator=latency=1e300",
            ],
            "milliseconds",
        ),
        (
            &["sim", "--link", "pty", "--mavs", "0"],
            "expected a whole number from 1 to 4096, got `0`",
        ),
        (
            &["sim", "--link", "pty", "--max-unicast", "300"],
            "expected a whole number from 1 to 255, got `300`",
        ),
        (
            &["setup", "--link", "pty", "--guard-time", "0"],
            "expected a whole number from 1 to 10000, got `0`",
        ),
        (
            &["sim", "--link", "pty", "--loss", "2"],
            "a probability from 0 to 1",
        ),
        (
            &["radio", "--coordinator", "pty", "--corrupt", "NaN"],
            "a probability from 0 to 1",
        ),
        (
            &[
                "radio",
                "--coordinator",
                "pty",
                "--faults",
                "coordinator=duplicate=-0.5",
            ],
            "duplicate must be a probability from 0 to 1, got -0.5",
        ),
        (
            &["replay", "--link", "pty", "--speed", "inf", "x"],
            "a speed of 0 (as fast as possible) or more",
        ),
        (
            &["monitor", "--link", "pty", "--count", "0"],
            "a number of received items, 1 or more",
        ),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
            .args(args)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(reason), "{args:?}: {stderr}");
    }
    // The smallest receive buffer that lets a command through is accepted.
    let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args([
            "sim",
            "--link",
            "tcp-listen:127.0.0.1:0",
            "--rx-buffer",
            "19",
        ])
        // (0 would run until Ctrl-C.)
        .args(["--duration", "0.001"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
}

#[tokio::test]
async fn radio_cuts_a_node_on_schedule() {
    let radio = Running::start(&[
        "radio",
        "--coordinator",
        "tcp-listen:127.0.0.1:0",
        "--node",
        "0013A20040B599B9=tcp-listen:127.0.0.1:0",
        "--cut",
        "0013A20040B599B9@0+600",
        "--duration",
        "120",
    ]);
    let coordinator = radio.listening("coordinator ");
    let node = radio.listening("node 0013a20040b599b9/");
    // The date comes before the first line with a time of day.
    let date = radio.line(|l| l.starts_with("-- ") || l.contains("out of range (cut)"));
    assert!(date.ends_with(" (UTC) --"), "{date}");
    radio.line(|l| l.contains("0013a20040b599b9 out of range (cut)"));
    // Both links up: only the cut stands in the way.
    let mut ground = device(coordinator, ApiMode::Unescaped).await;
    assert!(matches!(
        next_frame(&mut ground).await.parse(),
        Ok(Frame::ModemStatus(_))
    ));
    let mut mav = device(node, ApiMode::Unescaped).await;
    assert!(matches!(
        next_frame(&mut mav).await.parse(),
        Ok(Frame::ModemStatus(_))
    ));
    let tx = TransmitRequestRepr {
        frame_id: 5,
        dst64: Address64::COORDINATOR,
        dst16: Address16::UNKNOWN,
        radius: 0,
        options: 0,
        data: b"r\x02\x04",
    };
    mav.send(&tx).await.unwrap();
    match next_frame(&mut mav).await.parse() {
        Ok(Frame::TransmitStatus(st)) => {
            assert_eq!(st.frame_id, 5);
            assert_eq!(st.delivery, xbee_api::DeliveryStatus::NetworkAckFailure);
        }
        other => panic!("{other:?}"),
    }
}

#[tokio::test]
async fn radio_logs_statuses_by_their_snake_case_names() {
    let radio = Running::start(&[
        "radio",
        "--coordinator",
        "tcp-listen:127.0.0.1:0",
        "--verbose",
        "--duration",
        "120",
    ]);
    let coordinator = radio.listening("coordinator ");
    let mut ground = device(coordinator, ApiMode::Unescaped).await;
    assert!(matches!(
        next_frame(&mut ground).await.parse(),
        Ok(Frame::ModemStatus(_))
    ));
    let tx = TransmitRequestRepr {
        frame_id: 1,
        dst64: Address64(0x0013_A200_DEAD_BEEF),
        dst16: Address16::UNKNOWN,
        radius: 0,
        options: 0,
        data: b"c\x02\xff",
    };
    ground.send(&tx).await.unwrap();
    let line = radio.line(|l| l.contains("not delivered"));
    assert!(
        line.ends_with("0013a200deadbeef: 3 bytes not delivered: address_not_found (0x24)"),
        "{line}"
    );
    // The same failure again and again is not printed again at once; another one is.
    for frame_id in 2..12 {
        ground
            .send(&TransmitRequestRepr { frame_id, ..tx })
            .await
            .unwrap();
    }
    let other = TransmitRequestRepr {
        dst64: Address64(0x0013_A200_DEAD_BEE0),
        ..tx
    };
    ground.send(&other).await.unwrap();
    let line = radio.line(|l| l.contains("not delivered"));
    assert!(line.contains("0013a200deadbee0: 3 bytes"), "{line}");
    let at = xbee_api::AtCommandRepr {
        queued: false,
        frame_id: 20,
        command: *b"ZZ",
        parameter: &[],
    };
    ground.send(&at).await.unwrap();
    let line = radio.line(|l| l.contains("AT ZZ"));
    assert!(
        line.ends_with("AT ZZ answered invalid_command (0x02)"),
        "{line}"
    );
}

#[cfg(unix)]
#[test]
fn sim_on_a_pty_is_connected_while_a_ground_station_has_it_open() {
    let sim = Running::start(&["sim", "--link", "pty", "--duration", "120"]);
    let line = sim.line(|l| l.starts_with("ground station link"));
    let path = line
        .split("(open it as serial:")
        .nth(1)
        .and_then(|rest| rest.split(')').next())
        .expect("the pty's path")
        .to_owned();
    let connected = format!("0000000000000000 connected ({path})");
    for _ in 0..2 {
        let port = tokio_serial::new(&path, 115_200)
            .open_native()
            .expect("open the pty");
        sim.line(|l| l.ends_with(&connected));
        drop(port);
        sim.line(|l| l.contains("0000000000000000 disconnected: the peer closed the link"));
    }
}

#[test]
fn a_serial_link_that_is_not_there_fails_at_once() {
    for (args, expected) in [
        (
            &["sim", "--link", "serial:/dev/no-such-port"][..],
            "cannot open serial:/dev/no-such-port:115200: no such device (`mcp-gs ports`",
        ),
        (
            &[
                "radio",
                "--coordinator",
                "pty",
                "--node",
                "0013A20040B599B9=serial:/",
            ][..],
            "cannot open serial:/:115200: / is not a serial device but a directory",
        ),
    ] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
            .args(args)
            .args(["--duration", "5"])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(3), "{args:?}: {err}");
        assert!(out.stdout.is_empty(), "{args:?}: {out:?}");
        assert!(err.contains(expected), "{err}");
    }
}

#[test]
fn the_librarys_warnings_read_as_the_commands_own_lines() {
    // A coordinator link to a port nobody listens on: the network keeps trying, and
    // says so in one plain line, with the error after a colon, and the node and its
    // link as given named.
    let reserved = common::ReservedPort::new();
    let link = format!("tcp:127.0.0.1:{}", reserved.port);
    let mut child = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["sim", "--link", &link, "--duration", "30"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let lines = common::stderr_lines(&mut child);
    let line = loop {
        let line = lines.recv_timeout(GUARD).expect("a warning");
        if line.contains("node link not available yet") {
            break line;
        }
    };
    let _ = child.kill();
    let _ = child.wait();
    assert!(
        line.starts_with("mcp-gs: warning: node link not available yet: cannot connect to ")
            && line.ends_with(&format!(" (node 0000000000000000, link {link})"))
            && !line.contains('='),
        "{line}"
    );
}

#[test]
fn the_seed_is_printed_when_there_are_faults_to_replay() {
    for (faults, seeded) in [(&[][..], false), (&["--loss", "0.1"][..], true)] {
        let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
            .args(["radio", "--coordinator", "tcp-listen:127.0.0.1:0"])
            .args(faults)
            .args(["--duration", "0.5"])
            .output()
            .unwrap();
        assert!(out.status.success(), "{out:?}");
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert_eq!(
            stdout.lines().any(|l| l.starts_with("seed ")),
            seeded,
            "{faults:?}: {stdout}"
        );
    }
}

#[test]
fn a_run_with_a_duration_says_how_long_and_when_it_stopped() {
    for run in [
        &["radio", "--coordinator", "tcp-listen:127.0.0.1:0"][..],
        &["sim", "--link", "tcp-listen:127.0.0.1:0"],
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
            .args(run)
            .args(["--duration", "0.5"])
            .output()
            .unwrap();
        assert!(out.status.success(), "{out:?}");
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            stdout.contains("\nrunning for 0.5 s; Ctrl-C stops it sooner\n"),
            "{run:?}: {stdout}"
        );
        let last = stdout.lines().last().unwrap_or_default();
        assert!(
            last.ends_with(" stopped after 0.5 s (--duration)"),
            "{run:?}: {stdout}"
        );
    }
}

#[test]
fn a_cut_is_said_in_seconds() {
    let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["sim", "--link", "tcp-listen:127.0.0.1:0", "--mavs", "2"])
        .args(["--cut", "0013A20040B599B9@0+100"])
        .args(["--cut", "0013A20040B599BF@0.1+1e-4"])
        .args(["--duration", "0.001"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    for line in [
        "0013a20040b599b9 out of range from 0 s to 100 s after start",
        "0013a20040b599bf out of range from 0.1 s to 0.1001 s after start",
    ] {
        assert!(stdout.to_lowercase().contains(line), "{line}: {stdout}");
    }
}
