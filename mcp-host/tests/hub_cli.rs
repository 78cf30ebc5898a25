//! `mcp-gs hub` as an operator sees it: argument errors, the radio's outages said at
//! the default log level, and a client's node discovery and broadcast remote AT command
//! answered through it.

mod common;

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

use common::Running;
use std::sync::mpsc;
use std::time::Duration;

/// Failure guard only: every wait ends on a line long before this.
const GUARD: Duration = Duration::from_secs(20);

#[test]
fn a_listen_address_without_a_host_is_a_usage_error() {
    let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["hub", "--link", "tcp:127.0.0.1:9", "--listen", "9750"])
        .env_remove("MCP_LOG")
        .output()
        .expect("run mcp-gs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("expected ADDR:PORT, e.g. 127.0.0.1:9750"),
        "{stderr}"
    );
    assert!(!stderr.contains("cannot listen"), "{stderr}");
}

#[cfg(unix)]
#[test]
fn a_listen_address_that_cannot_be_had_says_why() {
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let taken = taken.local_addr().unwrap().to_string();
    // 192.0.2.1 (TEST-NET-1) is no address of this machine.
    for (listen, hint) in [
        (
            taken.as_str(),
            "another hub serves there or holds the port while its radio is away",
        ),
        (
            "192.0.2.1:9750",
            "no network interface of this machine has that address",
        ),
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
            .args(["hub", "--link", "pty", "--listen", listen])
            .env_remove("MCP_LOG")
            .output()
            .expect("run mcp-gs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(3), "{stderr}");
        assert!(
            stderr.starts_with(&format!("mcp-gs: cannot listen on {listen}: ")),
            "{stderr}"
        );
        assert!(stderr.contains(hint), "{stderr}");
    }
}

/// The lines a stream gives, as they come.
fn lines(stream: impl std::io::Read + Send + 'static) -> mpsc::Receiver<String> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stream).lines() {
            let Ok(line) = line else { return };
            if tx.send(line).is_err() {
                return;
            }
        }
    });
    rx
}

/// The next line of `lines` containing `text` (the lines before it, if it never comes, in
/// the failure).
fn line_with(lines: &mpsc::Receiver<String>, text: &str) -> String {
    let mut before = Vec::new();
    loop {
        let line = lines
            .recv_timeout(GUARD)
            .unwrap_or_else(|e| panic!("no line with {text:?}: {e}; before: {before:#?}"));
        if line.contains(text) {
            return line;
        }
        before.push(line);
    }
}

/// Sends Ctrl-C (SIGINT) to the hub.
#[cfg(unix)]
fn sigint(hub: &Running) {
    signal(hub, libc::SIGINT);
}

/// Sends `signal` to the hub.
#[cfg(unix)]
fn signal(hub: &Running, signal: libc::c_int) {
    let pid = i32::try_from(hub.0.id()).expect("pid");
    // SAFETY: kill(2) with the pid of a child of this process and a valid signal.
    assert_eq!(unsafe { libc::kill(pid, signal) }, 0);
}

/// Ctrl-C to the hub: it exits with status 0; its `stopped:` summary line, from `out`.
#[cfg(unix)]
fn stop_hub(hub: &mut Running, out: &mpsc::Receiver<String>) -> String {
    sigint(hub);
    assert_eq!(hub.0.wait().unwrap().code(), Some(0));
    line_with(out, "stopped:")
}

/// A hub on `radio`, listening on a free port of 127.0.0.1: the process, and its
/// standard output and error line by line.
fn start_hub(radio: &str) -> (Running, mpsc::Receiver<String>, mpsc::Receiver<String>) {
    start_hub_with(radio, &[])
}

/// [`start_hub`], with more arguments.
fn start_hub_with(
    radio: &str,
    more: &[&str],
) -> (Running, mpsc::Receiver<String>, mpsc::Receiver<String>) {
    start_hub_logging(radio, more, None)
}

/// [`start_hub_with`], logging what `MCP_LOG=log` selects.
fn start_hub_logging(
    radio: &str,
    more: &[&str],
    log: Option<&str>,
) -> (Running, mpsc::Receiver<String>, mpsc::Receiver<String>) {
    let mut command = Command::new(env!("CARGO_BIN_EXE_mcp-gs"));
    command.args(["hub", "--link", radio, "--listen", "127.0.0.1:0"]);
    match log {
        Some(log) => command.env("MCP_LOG", log),
        None => command.env_remove("MCP_LOG"),
    };
    let mut child = command
        .args(more)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run mcp-gs");
    let out = lines(child.stdout.take().unwrap());
    let err = lines(child.stderr.take().unwrap());
    (Running(child), out, err)
}

/// The hub's "serving RADIO on ADDR:PORT: give other commands ..." line (or "will
/// serve RADIO on ADDR:PORT once a radio is there: ..."), and the address in it.
fn serving(out: &mpsc::Receiver<String>) -> (String, String) {
    let serving = line_with(out, "serv");
    let addr = serving
        .split(" on ")
        .nth(1)
        .and_then(|rest| rest.split(": ").next())
        .and_then(|rest| rest.split(" once").next())
        .unwrap_or_else(|| panic!("{serving}"))
        .to_owned();
    (serving, addr)
}

/// Asserts that `line` is `mcp-gs: HH:MM:SS.mmm` followed by `then`, as every hub line
/// is: a line read back after an outage needs its time.
fn assert_timed(line: &str, then: &str) {
    let time = line
        .strip_prefix("mcp-gs: ")
        .and_then(|rest| rest.split_once(then))
        .map(|(time, _)| time)
        .unwrap_or_else(|| panic!("{line}"));
    let shape: String = time
        .chars()
        .map(|c| if c.is_ascii_digit() { '9' } else { c })
        .collect();
    assert_eq!(shape, "99:99:99.999", "{line}");
}

#[test]
fn the_hub_says_when_the_radio_is_lost_and_when_it_is_back() {
    let radio = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let radio_addr = radio.local_addr().unwrap();
    let (_hub, out, err) = start_hub(&format!("tcp:{radio_addr}"));
    let (socket, _) = radio.accept().unwrap();
    let (serving, addr) = serving(&out);
    drop(socket);
    let lost = line_with(&err, "radio lost");
    assert!(
        lost.contains("clients disconnected, and none accepted until it is back")
            && !lost.contains(") ("),
        "{lost}"
    );
    // A warning like the command's own, not a log record, with the time of day (UTC) for
    // an outage read back later: `mcp-gs: HH:MM:SS.mmm warning: hub: radio lost`.
    assert_timed(&lost, " warning: hub: radio lost");
    let (_socket, _) = radio.accept().unwrap();
    let back = line_with(&err, "radio back");
    // A status line, not a warning.
    assert!(
        back.starts_with("mcp-gs: ")
            && back.ends_with(&format!(" hub: radio back: listening on {addr}"))
            && !back.contains("warning"),
        "{back} ({serving})"
    );
}

#[cfg(target_os = "linux")]
#[test]
fn a_hub_on_a_pty_listens_once_a_radio_is_there() {
    let (_hub, out, err) = start_hub("pty");
    // "pseudo-terminal: PATH ..." names the far end, where the radio goes.
    let far_end = line_with(&err, "/dev/pts/");
    let path = far_end
        .split_whitespace()
        .find(|word| word.starts_with("/dev/pts/"))
        .map(|word| word.trim_end_matches([',', ';', ':', ')']))
        .unwrap_or_else(|| panic!("{far_end}"))
        .to_owned();
    let (announced, addr) = serving(&out);
    assert!(
        announced.starts_with(&format!("will serve pty on {addr} once a radio is there")),
        "{announced}"
    );
    let waiting = line_with(&err, "no radio on pty yet");
    assert!(waiting.contains("clients are refused"), "{waiting}");
    // A status line like the "radio there" that follows it.
    assert_timed(&waiting, " hub: no radio on pty yet");
    // Nothing to serve yet: a client is refused, not accepted and left without answers.
    let refused = std::net::TcpStream::connect(&addr).unwrap_err();
    assert_eq!(refused.kind(), std::io::ErrorKind::ConnectionRefused);
    // A radio opens the far end: the hub listens on the address it printed.
    let _radio = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(&path)
        .unwrap();
    // It says nothing, not even to the hub's AT AP: the hub says so, then listens.
    let silent = line_with(&err, "hub: the radio did not answer AT AP");
    assert!(silent.contains("transparent mode (AP=0)"), "{silent}");
    assert!(!silent.contains("serves another connection"), "{silent}");
    let there = line_with(&err, "radio there");
    assert!(there.contains(&format!("listening on {addr}")), "{there}");
    std::net::TcpStream::connect(&addr).unwrap();
}

/// A simulated network (`sim`, its coordinator on TCP, in API mode `mode`), the link
/// to its radio, and its standard output (kept read, so that it can write on).
fn sim_on_tcp(mode: &str) -> (Running, String, mpsc::Receiver<String>) {
    let mut sim = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args([
            "sim",
            "--link",
            "tcp-listen:127.0.0.1:0",
            "--mavs",
            "2",
            "--api-mode",
            mode,
        ])
        .env_remove("MCP_LOG")
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("run mcp-gs sim");
    let sim_out = lines(sim.stdout.take().unwrap());
    let announced = line_with(&sim_out, "(connect with ");
    let radio = announced
        .split("(connect with ")
        .nth(1)
        .and_then(|rest| rest.split(')').next())
        .unwrap_or_else(|| panic!("{announced}"))
        .to_owned();
    (Running(sim), radio, sim_out)
}

#[test]
fn a_hub_in_another_api_mode_than_its_radio_says_so_at_once() {
    // The radio in API mode 2, the hub in mode 1 (the default): it asks the radio's AP
    // before it listens, and warns, at the default log level.
    let (_sim, radio, _sim_out) = sim_on_tcp("2");
    let (_hub, out, err) = start_hub(&radio);
    let warning = line_with(&err, "hub: the radio is in API mode 2 (AP=2)");
    assert!(
        warning.contains("the hub speaks API mode 1") && warning.contains("API mode 2"),
        "{warning}"
    );
    // Once the radio's escaped frames come (telemetry, asked through the hub), the hub
    // says too that it drops them.
    let (_, addr) = serving(&out);
    let send = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["send", "--link", &format!("tcp:{addr}"), "--timeout", "3"])
        .args(["--to", "0013A20040B599B9", "telemetry", "on", "pitch_angle"])
        .env_remove("MCP_LOG")
        .output()
        .expect("run mcp-gs send");
    let dropping = line_with(&err, "frames cannot be read and are dropped");
    assert_timed(
        &dropping,
        " warning: hub: the radio's frames cannot be read",
    );
    assert!(
        dropping.contains("failed the checksum") && dropping.contains("try --api-mode 2"),
        "{dropping} ({send:?})"
    );
}

#[test]
fn a_report_lost_by_a_hub_in_another_api_mode_is_not_blamed_on_the_mav() {
    // The radio in API mode 2, the hub and the client in mode 1: the status request
    // goes out and is delivered, but the MAV's report (from 0013A2..., escaped) is
    // dropped by the hub. The client asks the radio's AP and says what to fix.
    let (_sim, radio, _sim_out) = sim_on_tcp("2");
    let (_hub, out, _err) = start_hub(&radio);
    let (_, addr) = serving(&out);
    let stderr = status_timing_out(&addr, "2");
    assert!(
        stderr.contains("the MAV did not answer, or its report was lost on the way"),
        "{stderr}"
    );
    assert!(
        stderr.contains("the radio is in API mode 2 (AP=2) but --api-mode is 1")
            && stderr.contains("the hub itself must be started with --api-mode 2"),
        "{stderr}"
    );
}

/// `mcp-gs status` of the landing state through the hub at `addr`, with `timeout`
/// seconds, which must time out (exit 4): its standard error.
fn status_timing_out(addr: &str, timeout: &str) -> String {
    let status = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args([
            "status",
            "--link",
            &format!("tcp:{addr}"),
            "--timeout",
            timeout,
        ])
        .args(["--to", "0013A20040B599B9", "landing"])
        .env_remove("MCP_LOG")
        .output()
        .expect("run mcp-gs status");
    let stderr = String::from_utf8_lossy(&status.stderr).into_owned();
    assert_eq!(status.status.code(), Some(4), "{stderr}");
    stderr
}

#[test]
fn a_hub_with_wait_waits_for_its_radio_refusing_clients_meanwhile() {
    // Nothing listens on the radio's port yet (a bridge not started).
    let reserved = common::ReservedPort::new();
    let radio = format!("tcp:127.0.0.1:{}", reserved.port);
    // A recording of yesterday's flight, to be overwritten: kept until a radio is there.
    let dir = tempfile::tempdir().unwrap();
    let record = dir.path().join("flight.mcprec");
    std::fs::write(&record, b"yesterday's flight").unwrap();
    let path = record.to_str().unwrap();
    let (_hub, out, err) = start_hub_with(&radio, &["--wait", "--record", path, "--force"]);
    let (announced, addr) = serving(&out);
    assert!(announced.starts_with("will serve"), "{announced}");
    line_with(&err, "link not there yet: waiting for it");
    let refused = std::net::TcpStream::connect(&addr).unwrap_err();
    assert_eq!(refused.kind(), std::io::ErrorKind::ConnectionRefused);
    assert_eq!(std::fs::read(&record).unwrap(), b"yesterday's flight");
    // The radio comes: the hub listens.
    let listener = reserved.listen();
    let (_radio, _) = listener.accept().unwrap();
    let there = line_with(&err, "radio there");
    assert!(there.contains(&format!("listening on {addr}")), "{there}");
    std::net::TcpStream::connect(&addr).unwrap();
}

#[test]
fn node_discovery_and_a_broadcast_at_command_are_answered_through_the_hub() {
    // A simulated network of two MAVs, its coordinator on TCP.
    let (_sim, radio, _sim_out) = sim_on_tcp("1");
    let (_hub, out, _err) = start_hub(&radio);
    let (_, addr) = serving(&out);
    let nodes = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["nodes", "--link", &format!("tcp:{addr}"), "--window", "2"])
        .env_remove("MCP_LOG")
        .output()
        .expect("run mcp-gs nodes");
    let stdout = String::from_utf8_lossy(&nodes.stdout);
    assert!(nodes.status.success(), "{nodes:?}");
    // Both MAVs' answers come back to the client that asked, under its own frame id.
    let found: Vec<&str> = stdout.lines().collect();
    assert_eq!(found.len(), 2, "{stdout}");
    assert!(
        found.iter().all(|line| line.contains(") router \" \"")),
        "{stdout}"
    );
    // So does the answer a Zigbee radio hands over to a broadcast remote AT command.
    let at = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["at", "--link", &format!("tcp:{addr}")])
        .args(["--to", "000000000000ffff", "--window", "2", "VR"])
        .env_remove("MCP_LOG")
        .output()
        .expect("run mcp-gs at");
    let stdout = String::from_utf8_lossy(&at.stdout);
    assert!(at.status.success(), "{at:?}");
    assert_eq!(
        stdout, "0013a20040b599b9: VR = 4060 (0x4060, 16480)\n",
        "{at:?}"
    );
}

#[test]
fn a_hub_whose_tcp_peer_says_nothing_names_a_peer_busy_with_another_connection() {
    // A peer that takes the connection and never answers, as a simulator serving
    // another ground station lets the next one wait.
    let (link, _peer) = common::silent_peer(1);
    let (_hub, out, err) = start_hub(&link);
    let silent = line_with(&err, "hub: the radio did not answer AT AP");
    assert!(
        silent.contains("or the peer on the other end of the tcp: link serves another connection"),
        "{silent}"
    );
    // A client of the hub hears nothing either: it is pointed at the hub's lines too,
    // not only at a peer that serves another connection.
    let (_, addr) = serving(&out);
    let stderr = status_timing_out(&addr, "1");
    assert!(
        stderr.contains("nothing at all came from the radio")
            && stderr.contains(
                "if the peer is mcp-gs hub, its own lines say whether it hears its radio"
            ),
        "{stderr}"
    );
}

#[cfg(unix)]
#[test]
fn frames_that_come_while_the_hub_asks_its_radio_for_its_mode_are_not_lost_behind() {
    // A radio that sends a burst of 3000 frames at once and never answers AT AP: the
    // hub asks it for its mode (and waits) before it reads the link's events.
    let modem_status = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];
    let (link, _radio) = common::talking_peer(modem_status.repeat(3000));
    let (mut hub, out, err) = start_hub(&link);
    line_with(&err, "hub: the radio did not answer AT AP");
    serving(&out);
    // Those the link lost, had it no room for them, it counted as they came, before
    // the hub served: said when it stops.
    let stopped = stop_hub(&mut hub, &out);
    let rest: Vec<String> = out.iter().collect();
    assert!(
        !rest.iter().any(|line| line.contains("fell behind")),
        "{stopped}\n{rest:?}"
    );
}

#[cfg(unix)]
#[test]
fn a_hub_stopped_a_while_says_for_how_long_to_the_millisecond() {
    let (link, _radio) = common::silent_peer(1);
    let (mut hub, out, err) = start_hub(&link);
    serving(&out);
    signal(&hub, libc::SIGSTOP);
    // The stall itself, not a wait for something: the hub sees it on its clock.
    std::thread::sleep(Duration::from_millis(2500));
    signal(&hub, libc::SIGCONT);
    // Its line (after any of a stall of its own on a busy machine), each to the
    // millisecond.
    loop {
        let stalled = line_with(&err, "hub: it could read nothing for ");
        let seconds = stalled
            .split("could read nothing for ")
            .nth(1)
            .and_then(|rest| rest.split(" s:").next())
            .unwrap_or_else(|| panic!("{stalled}"));
        let decimals = seconds.split('.').nth(1).map_or(0, str::len);
        assert!(decimals <= 3, "{stalled}");
        // The stop lasts 2.5 s by this clock; the hub's last beat before it may come a
        // little after the signal was sent, on a busy machine.
        if seconds.parse::<f64>().is_ok_and(|s| s >= 2.4) {
            break;
        }
    }
    stop_hub(&mut hub, &out);
}

/// A radio played by threads: it answers each AT command at once (AP as 1), and sends
/// a burst of 200 000 Modem Status frames once told to on the sender it returns, whole
/// frames never cut by an answer. Its `tcp:` link.
#[cfg(unix)]
fn bursting_radio() -> (String, mpsc::Sender<()>) {
    use std::sync::{Arc, Mutex};
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", listener.local_addr().unwrap());
    let (go, burst) = mpsc::channel::<()>();
    std::thread::spawn(move || {
        let (radio, _) = listener.accept().unwrap();
        let mut reading = radio.try_clone().unwrap();
        let writing = Arc::new(Mutex::new(radio));
        let bursting = Arc::clone(&writing);
        std::thread::spawn(move || {
            if burst.recv().is_ok() {
                let modem_status = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];
                let chunk = modem_status.repeat(1000);
                for _ in 0..200 {
                    let mut radio = bursting.lock().unwrap();
                    if std::io::Write::write_all(&mut *radio, &chunk).is_err() {
                        return;
                    }
                }
            }
        });
        let mut decoder: xbee_api::Decoder = xbee_api::Decoder::new(xbee_api::ApiMode::Unescaped);
        let mut buf = [0u8; 4096];
        while let Ok(n @ 1..) = std::io::Read::read(&mut reading, &mut buf) {
            let mut rest = &buf[..n];
            while !rest.is_empty() {
                let (used, event) = decoder.decode(rest);
                rest = &rest[used..];
                let Some(Ok(frame)) = event else { continue };
                if let [0x08, id, a, b, ..] = frame.data()[..] {
                    let answer = [0x88, id, a, b, 0x00, 0x01];
                    let sum = answer.iter().fold(0u8, |s, b| s.wrapping_add(*b));
                    let mut bytes = vec![0x7E, 0x00, 0x06];
                    bytes.extend(answer);
                    bytes.push(0xFF - sum);
                    let mut radio = writing.lock().unwrap();
                    if std::io::Write::write_all(&mut *radio, &bytes).is_err() {
                        return;
                    }
                }
            }
        }
    });
    (link, go)
}

#[cfg(unix)]
#[test]
fn frames_dropped_for_a_client_that_does_not_read_are_said_while_the_hub_runs() {
    // A radio that sends a burst once told to: more frames than the client's queue at
    // the hub and its connection's buffers hold.
    let (link, go) = bursting_radio();
    // With the hub's info lines, to know when it has the client.
    let (mut hub, out, err) = start_hub_logging(&link, &[], Some("mcp_host::hub=info"));
    let (_, addr) = serving(&out);
    // A client that reads nothing.
    let _client = std::net::TcpStream::connect(&addr).unwrap();
    line_with(&err, "hub: client connected");
    go.send(()).unwrap();
    let dropped = line_with(&err, "more slowly than they come");
    assert!(dropped.contains("WARN"), "{dropped}");
    assert!(
        dropped.ends_with(
            "takes the radio's frames more slowly than they come: 1 dropped for it so far \
             (those that come while 1024 wait for it)"
        ),
        "{dropped}"
    );
    let stopped = stop_hub(&mut hub, &out);
    assert!(
        !stopped.contains(" 0 dropped for slow clients"),
        "{stopped}"
    );
}

/// A hub served beyond this machine is warned about: it has no authentication.
#[cfg(unix)]
#[test]
fn a_hub_that_listens_beyond_this_machine_warns_that_anyone_may_use_the_radio() {
    let (_sim, radio, _sim_out) = sim_on_tcp("1");
    let mut child = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["hub", "--link", &radio, "--listen", "0.0.0.0:0"])
        .env_remove("MCP_LOG")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run mcp-gs");
    let out = lines(child.stdout.take().unwrap());
    let err = lines(child.stderr.take().unwrap());
    let mut hub = Running(child);
    let warned = line_with(&err, "no authentication");
    assert!(
        warned.starts_with("mcp-gs: warning: serving on 0.0.0.0:")
            && warned.ends_with(
                "reached from other machines: the hub has no authentication, and every host \
                 that reaches it can send the radio any frame, AT commands that change or \
                 reset it included (listen on 127.0.0.1, or on a network whose every host \
                 you trust)"
            ),
        "{warned}"
    );
    serving(&out);
    stop_hub(&mut hub, &out);
}

/// `data` as an API mode 1 frame.
#[cfg(unix)]
fn api_frame(data: &[u8]) -> Vec<u8> {
    let sum = data.iter().fold(0u8, |s, b| s.wrapping_add(*b));
    let len = u16::try_from(data.len()).unwrap().to_be_bytes();
    [&[0x7E, len[0], len[1]][..], data, &[0xFF - sum]].concat()
}

/// A client that reads nothing, behind the radio's frames, sends 100 requests made by
/// `request` (of frame ids 1 to 100): the answers beyond those that wait for it (64)
/// are dropped, and said.
#[cfg(unix)]
fn answers_dropped_are_said(request: impl Fn(u8) -> Vec<u8>) {
    let (link, go) = bursting_radio();
    let (mut hub, out, err) = start_hub_logging(&link, &[], Some("mcp_host::hub=info"));
    let (_, addr) = serving(&out);
    let mut client = std::net::TcpStream::connect(&addr).unwrap();
    line_with(&err, "hub: client connected");
    go.send(()).unwrap();
    line_with(&err, "more slowly than they come");
    for id in 1..=100u8 {
        std::io::Write::write_all(&mut client, &api_frame(&request(id))).unwrap();
    }
    let dropped = line_with(&err, "an answer to a request");
    assert!(dropped.contains("WARN"), "{dropped}");
    let peer = client.local_addr().unwrap();
    assert!(
        dropped.ends_with(&format!(
            "hub: an answer to a request of client {peer} dropped: 64 of its answers wait \
             for it to read them"
        )),
        "{dropped}"
    );
    stop_hub(&mut hub, &out);
}

/// The radio's answers: 100 `AT AP`, answered at once.
#[cfg(unix)]
#[test]
fn answers_dropped_for_a_client_that_does_not_read_are_said() {
    answers_dropped_are_said(|id| vec![0x08, id, b'A', b'P']);
}

/// The hub's own: 100 Transmit Requests that the radio never answers, so that all but
/// the client's first 16 wait for a place, 5 s, and are refused, each answered as
/// failed by the hub.
#[cfg(unix)]
#[test]
fn answers_of_refused_requests_dropped_for_a_client_that_does_not_read_are_said() {
    answers_dropped_are_said(|id| {
        let mut request = vec![
            0x10, id, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0, 0,
        ];
        request.push(b'm');
        request
    });
}

#[cfg(unix)]
#[test]
fn a_hub_records_what_its_radio_heard_and_said_for_every_client() {
    let (_sim, radio, _sim_out) = sim_on_tcp("1");
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("flight.mcprec");
    let path = file.to_str().unwrap();
    let (mut hub, out, _err) = start_hub_with(&radio, &["--api-mode", "1", "--record", path]);
    let (_, addr) = serving(&out);
    // A client asks the radio its firmware version through the hub.
    let at = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args([
            "at",
            "--link",
            &format!("tcp:{addr}"),
            "--api-mode",
            "1",
            "VR",
        ])
        .env_remove("MCP_LOG")
        .output()
        .expect("run mcp-gs at");
    assert!(at.status.success(), "{at:?}");

    // Ctrl-C: the hub stops, and says what it recorded.
    sigint(&hub);
    let recorded = line_with(&out, "recorded ");
    assert_eq!(recorded, format!("recorded 5 frames to {path}"));
    assert_eq!(hub.0.wait().unwrap().code(), Some(0));

    // From the link's first frame: the radio's Modem Status as it came up and the
    // hub's own AT AP with its answer (in either order), then the client's request as
    // the radio got it (under the hub's frame id), and its answer.
    let decoded = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["decode", path, "--format", "json"])
        .output()
        .expect("run mcp-gs decode");
    assert!(decoded.status.success(), "{decoded:?}");
    let frames: Vec<serde_json::Value> = String::from_utf8_lossy(&decoded.stdout)
        .lines()
        .map(|line| serde_json::from_str(line).unwrap())
        .collect();
    assert_eq!(frames.len(), 5, "{frames:?}");
    let mut first: Vec<String> = frames[..3]
        .iter()
        .map(|f| format!("{} {} {}", f["direction"], f["frame"], f["command"]))
        .collect();
    first.sort();
    assert_eq!(
        first,
        [
            r#""rx" "at_response" "AP""#,
            r#""rx" "modem_status" null"#,
            r#""tx" "at" "AP""#
        ],
        "{frames:?}"
    );
    let (request, answer) = (&frames[3], &frames[4]);
    assert_eq!(
        (
            &request["direction"],
            &request["frame"],
            &request["command"]
        ),
        (&"tx".into(), &"at".into(), &"VR".into()),
        "{request}"
    );
    assert_eq!(
        (&answer["direction"], &answer["frame"], &answer["data"]),
        (&"rx".into(), &"at_response".into(), &"4060".into()),
        "{answer}"
    );
    assert_eq!(request["id"], answer["id"]);

    // An existing recording is kept, unless --force.
    let refused = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args([
            "hub",
            "--link",
            &radio,
            "--listen",
            "127.0.0.1:0",
            "--record",
            path,
        ])
        .env_remove("MCP_LOG")
        .output()
        .expect("run mcp-gs hub");
    assert_eq!(refused.status.code(), Some(2), "{refused:?}");
    assert!(
        String::from_utf8_lossy(&refused.stderr).contains("exists: choose another file"),
        "{refused:?}"
    );
}

#[cfg(target_os = "linux")]
#[test]
fn a_recording_that_cannot_be_written_stops_and_the_hub_goes_on_serving() {
    let (_sim, radio, _sim_out) = sim_on_tcp("1");
    // Every write to /dev/full fails: no space left on device.
    let (mut hub, out, err) = start_hub_with(
        &radio,
        &["--api-mode", "1", "--record", "/dev/full", "--force"],
    );
    let (_, addr) = serving(&out);
    let link = format!("tcp:{addr}");
    for _ in 0..2 {
        let at = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
            .args(["at", "--link", &link, "--api-mode", "1", "VR"])
            .env_remove("MCP_LOG")
            .output()
            .expect("run mcp-gs at");
        assert!(at.status.success(), "{at:?}");
    }
    let warning = line_with(&err, "recording");
    assert!(
        warning.starts_with("mcp-gs: warning: cannot write to /dev/full: ")
            && warning.ends_with(": the recording stops here, the hub goes on serving"),
        "{warning}"
    );
    sigint(&hub);
    // Said again at the end, and the exit status says it.
    let said = line_with(&err, "cannot write to /dev/full");
    assert!(
        said.starts_with("mcp-gs: cannot write to /dev/full: "),
        "{said}"
    );
    assert_eq!(hub.0.wait().unwrap().code(), Some(1));
}

/// Ctrl-C while the hub asks its radio for its API mode (a radio that does not answer
/// takes two seconds): the hub stops at once.
#[cfg(unix)]
#[test]
fn ctrl_c_stops_a_hub_still_asking_its_radio() {
    // The hub's own check, and `--api-mode auto` finding the mode out first.
    for mode in ["1", "auto"] {
        let radio = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let link = format!("tcp:{}", radio.local_addr().unwrap());
        let (mut hub, out, _err) = start_hub_with(&link, &["--api-mode", mode]);
        let (_socket, _) = radio.accept().unwrap();
        sigint(&hub);
        assert_eq!(common::exit_code(&mut hub.0), Some(0), "{mode}");
        assert_eq!(
            line_with(&out, "stopped"),
            "stopped: Ctrl-C before the hub served"
        );
    }
}

/// A recording into a pipe whose reader stopped taking: the file falls behind, never
/// the hub, which takes Ctrl-C, stops, and says what the recording holds and misses.
#[cfg(target_os = "linux")]
#[test]
fn a_hub_recording_into_a_stuck_pipe_still_stops_on_ctrl_c() {
    let dir = tempfile::tempdir().unwrap();
    let (fifo, reader) = common::stuck_fifo(dir.path());
    let path = fifo.to_str().unwrap();
    let radio = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", radio.local_addr().unwrap());
    let (mut hub, out, _err) = start_hub_with(&link, &["--api-mode", "1", "--record", path]);
    let (mut socket, _) = radio.accept().unwrap();
    common::fill_the_pipe(&mut socket, &reader);
    sigint(&hub);
    assert_eq!(common::exit_code(&mut hub.0), Some(0));
    let recorded = line_with(&out, "recorded ");
    // "recorded N frames to PATH (M frames lost while writing the file fell behind)",
    // maybe with frames lost before the file ("..., while the recording fell behind
    // the link") too.
    let count = |text: &str| text.split(' ').next()?.parse::<u64>().ok();
    let (written, lost) = recorded
        .strip_prefix("recorded ")
        .and_then(|rest| rest.split_once(&format!(" to {path} (")))
        .and_then(|(written, lost)| {
            let lost = lost
                .strip_suffix(')')?
                .split(", ")
                .find(|part| part.ends_with(" lost while writing the file fell behind"))?;
            Some((count(written)?, count(lost)?))
        })
        .unwrap_or_else(|| panic!("{recorded}"));
    assert!(lost >= 1, "{recorded}");
    // What the pipe holds: the frames said written, each whole.
    let mut held = Vec::new();
    std::io::Read::read_to_end(&mut &reader, &mut held).unwrap();
    let mut records = mcp_host::record::RecordReader::new(held.as_slice()).unwrap();
    let mut whole = 0;
    while records.next_record().unwrap().is_some() {
        whole += 1;
    }
    assert_eq!(whole, written, "{recorded}");
    drop(reader);
}

#[cfg(unix)]
#[test]
fn frames_a_radio_sends_replayed_onto_the_hub_are_refused_and_said() {
    let (_sim, radio, _sim_out) = sim_on_tcp("1");
    let (mut hub, out, err) = start_hub(&radio);
    let (_, addr) = serving(&out);
    // A recording of what a radio said: three modem statuses, received.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("heard.mcprec");
    let mut bytes = b"MCPREC\x01\x00".to_vec();
    for micros in 0..3u64 {
        bytes.extend_from_slice(&micros.to_le_bytes());
        bytes.push(0);
        bytes.extend_from_slice(&2u16.to_le_bytes());
        bytes.extend_from_slice(&[0x8A, 0x06]);
    }
    std::fs::write(&file, bytes).unwrap();
    let replay = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["replay", file.to_str().unwrap(), "--speed", "0"])
        .args(["--link", &format!("tcp:{addr}")])
        .output()
        .unwrap();
    // The replay is warned of where its frames go.
    let replayed = String::from_utf8_lossy(&replay.stderr);
    assert!(
        replayed.contains("warning: --frames rx, the default, plays what a radio said"),
        "{replayed}"
    );
    // The hub says the first refusal at once, with its time, as its other lines.
    let refused = line_with(&err, "a client's frame refused");
    assert_timed(&refused, " warning: hub: a client's frame refused");
    assert!(
        refused.contains("type 0x8a (modem_status) is a frame a radio sends"),
        "{refused}"
    );
    // The next ones together once they stop coming, and every one counted.
    line_with(
        &err,
        "hub: 2 more frames of clients refused since the last such warning",
    );
    let stopped = stop_hub(&mut hub, &out);
    assert!(
        stopped.ends_with(" 3 frames from clients refused"),
        "{stopped}"
    );
}

#[cfg(unix)]
#[test]
fn a_client_turned_away_is_said_at_once_and_counted_when_the_hub_stops() {
    let (_sim, radio, _sim_out) = sim_on_tcp("1");
    let (mut hub, out, err) = start_hub(&radio);
    let (_, addr) = serving(&out);
    // As many clients as the hub serves, none behind (the radio sends nothing unasked):
    // the next is turned away.
    let clients: Vec<_> = (0..mcp_host::hub::MAX_CLIENTS)
        .map(|_| std::net::TcpStream::connect(&addr).unwrap())
        .collect();
    let mut late = std::net::TcpStream::connect(&addr).unwrap();
    let mut byte = [0u8; 1];
    late.set_read_timeout(Some(GUARD)).unwrap();
    assert!(matches!(
        std::io::Read::read(&mut late, &mut byte),
        Ok(0) | Err(_)
    ));
    let turned = line_with(&err, "turned away");
    assert_timed(&turned, " warning: hub: ");
    let stopped = stop_hub(&mut hub, &out);
    assert!(stopped.contains(": 64 clients, "), "{stopped}");
    let summary = line_with(&out, "clients: ");
    assert_eq!(summary, "clients: 1 client turned away (64 connected)");
    drop(clients);
}

#[cfg(unix)]
#[test]
fn a_clients_frame_that_fails_its_checksum_is_refused_and_said_with_the_hubs_mode() {
    let (_sim, radio, _sim_out) = sim_on_tcp("1");
    let (mut hub, out, err) = start_hub(&radio);
    let (_, addr) = serving(&out);
    // `AT AP` with its checksum byte off by one, as a client in the other API mode (or
    // a noisy bridge) would send it.
    let mut client = std::net::TcpStream::connect(&addr).unwrap();
    std::io::Write::write_all(
        &mut client,
        &[0x7E, 0x00, 0x04, 0x08, 0x01, b'A', b'P', 0x66],
    )
    .unwrap();
    let refused = line_with(&err, "a client's frame refused");
    assert_timed(&refused, " warning: hub: a client's frame refused");
    assert!(
        refused.contains("bad checksum")
            && refused.contains("(the hub speaks API mode 1: is the client in the other?)"),
        "{refused}"
    );
    let stopped = stop_hub(&mut hub, &out);
    assert!(
        stopped.ends_with(" 1 frame from clients refused"),
        "{stopped}"
    );
}

#[cfg(unix)]
#[test]
fn a_clients_bytes_that_begin_no_frame_are_said_once_and_counted() {
    let (_sim, radio, _sim_out) = sim_on_tcp("1");
    let (mut hub, out, err) = start_hub(&radio);
    let (_, addr) = serving(&out);
    // Text typed into a connection, as into `nc`: the hub reads frames, not lines.
    let mut client = std::net::TcpStream::connect(&addr).unwrap();
    std::io::Write::write_all(&mut client, b"ATAP\r").unwrap();
    let skipped = line_with(&err, "bytes skipped");
    assert_timed(
        &skipped,
        " warning: hub: a client's bytes skipped: 5 bytes that began no frame (the hub \
         takes XBee API frames in API mode 1, each from a 0x7E: is the client sending \
         text, or in transparent mode?); all the client's are counted when it goes",
    );
    let peer = client.local_addr().unwrap().to_string();
    assert!(skipped.ends_with(&format!("(peer {peer})")), "{skipped}");
    // The client is still served; what it sends later is counted, not said. (Its
    // answer comes once the hub has read the bytes before the request.)
    answered_at_ap(&mut client, 1);
    std::io::Write::write_all(&mut client, b"ATNI\r").unwrap();
    answered_at_ap(&mut client, 2);
    stop_hub(&mut hub, &out);
    let summary = line_with(&out, "clients: ");
    assert_eq!(summary, "clients: 10 bytes that began no frame skipped");
    let said: Vec<String> = err.try_iter().filter(|l| l.contains("skipped")).collect();
    assert!(said.is_empty(), "{said:?}");
}

/// Sends `AT AP` under `id` (API mode 1) on `client` and reads frames until its answer:
/// the hub served the client.
#[cfg(unix)]
fn answered_at_ap(client: &mut std::net::TcpStream, id: u8) {
    use std::io::{Read, Write};
    let sum = [0x08, id, b'A', b'P']
        .iter()
        .fold(0u8, |s, b| s.wrapping_add(*b));
    client
        .write_all(&[0x7E, 0x00, 0x04, 0x08, id, b'A', b'P', 0xFF - sum])
        .unwrap();
    client.set_read_timeout(Some(GUARD)).unwrap();
    loop {
        let mut head = [0u8; 3];
        client.read_exact(&mut head[..1]).expect("a frame");
        if head[0] != 0x7E {
            continue;
        }
        client.read_exact(&mut head[1..]).expect("a frame's length");
        let mut data = vec![0; usize::from(u16::from_be_bytes([head[1], head[2]])) + 1];
        client.read_exact(&mut data).expect("a frame's data");
        if data.starts_with(&[0x88, id, b'A', b'P']) {
            return;
        }
    }
}

#[cfg(unix)]
#[test]
fn a_hub_out_of_file_descriptors_says_so_serves_its_clients_and_takes_the_next_once_it_can() {
    use std::os::unix::process::CommandExt;
    let (_sim, radio, _sim_out) = sim_on_tcp("1");
    let mut command = Command::new(env!("CARGO_BIN_EXE_mcp-gs"));
    command
        .args(["hub", "--link", &radio, "--listen", "127.0.0.1:0"])
        .env_remove("MCP_LOG")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    // Room for a few clients: the hub takes about a dozen file descriptors itself
    // (standard streams, tokio's, its radio's link, its listener). Those the test
    // process leaves open in it are kept whatever their number.
    // SAFETY: setrlimit(2) alone between fork and exec, with a valid limit.
    unsafe {
        command.pre_exec(|| {
            let limit = libc::rlimit {
                rlim_cur: 24,
                rlim_max: 24,
            };
            match libc::setrlimit(libc::RLIMIT_NOFILE, &limit) {
                0 => Ok(()),
                _ => Err(std::io::Error::last_os_error()),
            }
        });
    }
    let mut child = command.spawn().expect("run mcp-gs");
    let out = lines(child.stdout.take().unwrap());
    let err = lines(child.stderr.take().unwrap());
    let _hub = Running(child);
    let (_, addr) = serving(&out);
    // More clients than descriptors left: the system takes them all into the
    // listener's queue, the hub accepts the first ones.
    let mut clients: Vec<_> = (0..24)
        .map(|_| std::net::TcpStream::connect(&addr).unwrap())
        .collect();
    let failed = line_with(&err, "accepting a client failed");
    assert_timed(&failed, " warning: hub: accepting a client failed");
    assert!(failed.contains("Too many open files"), "{failed}");
    // The hub tries again and again (every 100 ms), said together at most once a
    // second, and serves the clients it has meanwhile.
    let again = line_with(&err, "hub: accepting a client failed");
    assert!(again.contains(" more times"), "{again}");
    answered_at_ap(&mut clients[0], 1);
    // Clients that go free their descriptors: the last one, still in the queue, is
    // accepted and served.
    let last = clients.pop().unwrap();
    for client in clients.drain(..) {
        // A reset rather than a close: the hub serves a client that closed its
        // connection until its place is taken (it may only have shut its sending side).
        socket2::SockRef::from(&client)
            .set_linger(Some(Duration::ZERO))
            .unwrap();
    }
    let mut last = last;
    answered_at_ap(&mut last, 2);
}

#[test]
fn setup_through_a_hub_that_changes_the_radios_mode_says_to_restart_the_hub() {
    let (_sim, radio, _sim_out) = sim_on_tcp("1");
    let (_hub, out, _err) = start_hub(&radio);
    let (_, addr) = serving(&out);
    let link = format!("tcp:{addr}");
    let setup = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args([
            "setup",
            "--link",
            &link,
            "--api-mode",
            "2",
            "--guard-time",
            "50",
        ])
        .args(["--timeout", "3"])
        .env_remove("MCP_LOG")
        .output()
        .expect("run mcp-gs setup");
    let stderr = String::from_utf8_lossy(&setup.stderr);
    assert!(
        stderr.contains(&format!(
            "mcp-gs: note: if {link} is a hub, restart it with --api-mode 2 --link to the \
             radio"
        )),
        "{stderr}"
    );
}
