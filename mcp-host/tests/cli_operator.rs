//! The `mcp-gs` binary as an operator uses it: durations, argument errors, hints, output
//! formats, replays and Ctrl-C, each through real processes, links and signals.

use std::process::{Command, Output};
use std::sync::mpsc::Receiver;

mod common;

use common::{GUARD, Running, exit_code, spawn_lines, stderr_lines, stdout_lines, talking_peer};

/// The demo MAV's address.
const M: &str = "0013a20040b599b9";

fn gs() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
}

fn run(args: &[&str]) -> Output {
    gs().args(args).output().expect("mcp-gs runs")
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

fn stdout(output: &Output) -> String {
    String::from_utf8_lossy(&output.stdout).into_owned()
}

/// The first line from `lines` that contains `what` (failure guard: [`GUARD`]).
fn line_with(lines: &Receiver<String>, what: &str) -> String {
    loop {
        match lines.recv_timeout(GUARD) {
            Ok(line) if line.contains(what) => return line,
            Ok(_) => {}
            Err(e) => panic!("no line with {what:?}: {e}"),
        }
    }
}

/// Every line still to come from `lines`, up to the end of the output.
fn rest(lines: &Receiver<String>) -> Vec<String> {
    let mut all = Vec::new();
    loop {
        match lines.recv_timeout(GUARD) {
            Ok(line) => all.push(line),
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => return all,
            Err(e) => panic!("output did not end: {e}; so far {all:?}"),
        }
    }
}

/// What an operator's Ctrl-C sends.
#[cfg(unix)]
fn interrupt(child: &std::process::Child) {
    send_signal(child, libc::SIGINT);
}

/// Sends `signal` to `child`.
#[cfg(unix)]
fn send_signal(child: &std::process::Child, signal: libc::c_int) {
    let pid = i32::try_from(child.id()).expect("pid");
    // SAFETY: kill(2) with a pid of a child of this process and a valid signal.
    let r = unsafe { libc::kill(pid, signal) };
    assert_eq!(r, 0, "kill -{signal} {pid}");
}

/// The `tcp:` link a line describes (`listening on ADDR (connect with tcp:ADDR)`).
fn tcp_link(line: &str) -> String {
    link_after(line, "connect with ")
}

/// The link a line gives after `words` and up to a closing parenthesis, as in
/// `(connect with tcp:ADDR)` or `(open it as serial:PATH)`.
fn link_after(line: &str, words: &str) -> String {
    let start = line
        .find(words)
        .unwrap_or_else(|| panic!("no {words:?} in {line:?}"))
        + words.len();
    let end = line[start..].find(')').expect("a closing parenthesis");
    line[start..start + end].to_owned()
}

#[cfg(unix)]
#[test]
fn sigterm_and_sighup_stop_a_running_command_as_ctrl_c_does() {
    for signal in [libc::SIGTERM, libc::SIGHUP] {
        let (child, lines) =
            spawn_lines(&["sim", "--link", "tcp-listen:127.0.0.1:0", "--duration", "0"]);
        let mut sim = Running(child);
        let link = tcp_link(&line_with(&lines, "listening on"));
        line_with(&lines, "running; Ctrl-C stops");
        let (child, monitor_lines) = spawn_lines(&["monitor", "--link", &link]);
        let mut monitor = Running(child);
        line_with(&monitor_lines, "link connected");
        send_signal(&monitor.0, signal);
        assert_eq!(exit_code(&mut monitor.0), Some(0), "signal {signal}");
        send_signal(&sim.0, signal);
        // The log's last line says why it ended.
        let name = if signal == libc::SIGTERM {
            "SIGTERM"
        } else {
            "SIGHUP"
        };
        let last = rest(&lines);
        assert!(
            last.last()
                .is_some_and(|l| l.ends_with(&format!(" stopped by {name}"))),
            "{last:?}"
        );
        assert_eq!(exit_code(&mut sim.0), Some(0), "signal {signal}");
    }
}

#[cfg(unix)]
#[test]
fn duration_0_runs_until_ctrl_c_in_sim_and_radio() {
    // sim: a ground station can still ask the MAV once the sim says it is running.
    let (child, lines) =
        spawn_lines(&["sim", "--link", "tcp-listen:127.0.0.1:0", "--duration", "0"]);
    let mut sim = Running(child);
    let link = tcp_link(&line_with(&lines, "listening on"));
    line_with(&lines, "running; Ctrl-C stops");
    let output = run(&["status", "--link", &link, "--to", M, "landing"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    assert!(stdout(&output).contains("report landing"));
    interrupt(&sim.0);
    assert_eq!(exit_code(&mut sim.0), Some(0));

    // radio: the coordinator answers an AT command once it runs.
    let (child, lines) = spawn_lines(&[
        "radio",
        "--coordinator",
        "tcp-listen:127.0.0.1:0",
        "--duration",
        "0",
    ]);
    let mut radio = Running(child);
    let link = tcp_link(&line_with(&lines, "listening on"));
    line_with(&lines, "running; Ctrl-C stops");
    let output = run(&["at", "--link", &link, "AP"]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    assert!(stdout(&output).starts_with("AP = "), "{}", stdout(&output));
    interrupt(&radio.0);
    let last = rest(&lines);
    assert!(
        last.last()
            .is_some_and(|l| l.ends_with(" stopped by Ctrl-C")),
        "{last:?}"
    );
    assert_eq!(exit_code(&mut radio.0), Some(0));

    // The help says so.
    for sub in ["sim", "radio", "demo"] {
        let help = stdout(&run(&[sub, "--help"]));
        assert!(
            help.contains("0") && help.contains("until Ctrl-C"),
            "{help}"
        );
    }
}

#[cfg(unix)]
#[test]
fn ctrl_c_stops_monitor_hub_and_a_timed_sim_cleanly() {
    // Each is interrupted as soon as its output says it runs: Ctrl-C is listened for
    // from then on, with or without a duration.
    let (child, sim_lines) = spawn_lines(&[
        "sim",
        "--link",
        "tcp-listen:127.0.0.1:0",
        "--duration",
        "600",
    ]);
    let mut sim = Running(child);
    let link = tcp_link(&line_with(&sim_lines, "listening on"));
    line_with(&sim_lines, "running for 600 s; Ctrl-C stops it sooner");
    let (child, lines) = spawn_lines(&["monitor", "--link", &link]);
    let mut monitor = Running(child);
    line_with(&lines, "link connected");
    interrupt(&monitor.0);
    assert_eq!(exit_code(&mut monitor.0), Some(0));
    let (child, lines) = spawn_lines(&["hub", "--link", &link, "--listen", "127.0.0.1:0"]);
    let mut hub = Running(child);
    line_with(&lines, "(Ctrl-C stops)");
    interrupt(&hub.0);
    assert_eq!(exit_code(&mut hub.0), Some(0));
    line_with(&lines, "stopped: 0 clients");
    interrupt(&sim.0);
    assert_eq!(exit_code(&mut sim.0), Some(0));
}

#[test]
fn a_status_kind_with_no_status_request_says_why() {
    for kind in ["0", "8", "0xff"] {
        for args in [
            &["status", "--link", "tcp:127.0.0.1:9", "--to", M, kind][..],
            &["encode", "--to", M, "status", kind],
        ] {
            let output = run(args);
            let stderr = stderr(&output);
            assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
            assert!(
                stderr.contains("is not a command type with a status request"),
                "{args:?}: {stderr}"
            );
            assert!(!stderr.contains("the position is in"), "{args:?}: {stderr}");
            assert!(stderr.contains("landing"), "{args:?}: {stderr}");
        }
    }
    // Position set has none for a reason of its own.
    let output = run(&["encode", "--to", M, "status", "7"]);
    assert_eq!(output.status.code(), Some(2));
    assert!(stderr(&output).contains("the position is in the telemetry"));
}

#[test]
fn a_kind_that_takes_no_telemetry_id_says_so_whatever_the_id() {
    // A junk id is no reason to list the telemetry names: the kind takes none.
    for id in ["5", "foo"] {
        for kind in ["controllers", "landing"] {
            for args in [
                &["status", "--link", "tcp:127.0.0.1:9", "--to", M, kind, id][..],
                &["encode", "--to", M, "status", kind, id],
            ] {
                let output = run(args);
                let stderr = stderr(&output);
                assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
                assert!(
                    stderr.contains(&format!("a {kind} status request takes no telemetry id")),
                    "{args:?}: {stderr}"
                );
            }
        }
    }
    // The one kind that takes an id still names them.
    let output = run(&["encode", "--to", M, "status", "telemetry", "foo"]);
    assert_eq!(output.status.code(), Some(2));
    assert!(stderr(&output).contains("`foo` is not a telemetry id: give a name"));
}

#[cfg(unix)]
#[test]
fn a_path_that_is_no_serial_port_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("capture.bin");
    std::fs::write(&file, b"not a radio").unwrap();
    for (path, what) in [
        ("/dev/null", "a device that is no terminal"),
        (file.to_str().unwrap(), "a regular file"),
        (dir.path().to_str().unwrap(), "a directory"),
    ] {
        let output = run(&["monitor", "--link", &format!("serial:{path}")]);
        let stderr = stderr(&output);
        assert_eq!(output.status.code(), Some(3), "{stderr}");
        assert!(
            stderr.contains(&format!("not a serial port ({path} is {what})")),
            "{stderr}"
        );
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
    }
}

#[test]
fn a_silent_radio_asked_its_mode_over_tcp_sends_the_operator_to_its_serial_port() {
    // A peer that takes the connection and never answers (a hub in front of a radio
    // in transparent mode, say).
    let silent = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", silent.local_addr().unwrap());
    let output = run(&[
        "at",
        "--link",
        &link,
        "--api-mode",
        "auto",
        "--timeout",
        "0.3",
        "AP",
    ]);
    let said = stderr(&output);
    assert_eq!(output.status.code(), Some(4), "{said}");
    assert!(said.contains("did not answer AT AP"), "{said}");
    assert!(
        said.contains(&format!(
            "if {link} is a hub, stop it and run `mcp-gs probe` on the radio's serial port; \
             if a serial bridge, `mcp-gs setup --link {link}`"
        )),
        "{said}"
    );
}

#[test]
fn a_baud_rate_no_xbee_is_set_to_is_warned_of() {
    // A zero too many: 96000 for 9600.
    let output = run(&["at", "--link", "serial:/dev/null:96000", "AP"]);
    let warned = stderr(&output);
    assert!(
        warned.starts_with("mcp-gs: warning: 96000 baud is none of the standard XBee rates (1200,"),
        "{warned}"
    );
    // A standard one is not.
    let output = run(&["at", "--link", "serial:/dev/null:9600", "AP"]);
    assert!(!stderr(&output).contains("warning"), "{}", stderr(&output));
}

/// A ground station killed (SIGKILL) while it holds a simulator's pseudo-terminal
/// leaves it free: the next command opens it and talks to the MAV behind it.
#[cfg(target_os = "linux")]
#[test]
fn a_killed_ground_station_leaves_a_pseudo_terminal_free() {
    let (child, sim_lines) = spawn_lines(&["sim", "--link", "pty", "--seed", "1"]);
    let _sim = Running(child);
    let link = link_after(&line_with(&sim_lines, "open it as serial:"), "open it as ");
    let path = std::path::PathBuf::from(link.trim_start_matches("serial:"));

    let (child, lines) = spawn_lines(&["monitor", "--link", &link]);
    let mut monitor = Running(child);
    // Opened, and connected: the port is held as it will be until the end.
    line_with(&lines, "link connected");
    monitor.0.kill().expect("SIGKILL");
    monitor.0.wait().expect("wait");
    assert!(!common::far_end_is_exclusive(&path), "{}", path.display());

    let output = run(&[
        "status",
        "--link",
        &link,
        "--to",
        M,
        "telemetry",
        "altitude",
    ]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    assert!(
        stdout(&output).contains("report telemetry_to_coordinator"),
        "{}",
        stdout(&output)
    );
}

/// `monitor` and `hub` on `tcp-listen:` with port 0 say which port they took, and a
/// radio bridge connects there.
#[test]
fn monitor_and_hub_say_where_they_listen_for_the_radio() {
    for args in [
        &["monitor", "--link", "tcp-listen:127.0.0.1:0"][..],
        &[
            "hub",
            "--link",
            "tcp-listen:127.0.0.1:0",
            "--listen",
            "127.0.0.1:0",
        ],
    ] {
        let mut child = gs()
            .args(args)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .expect("start mcp-gs");
        let lines = stderr_lines(&mut child);
        let _running = Running(child);
        let line = line_with(&lines, "listening for the radio side on");
        let link = tcp_link(&line);
        let addr = link.trim_start_matches("tcp:");
        assert!(!addr.ends_with(":0"), "{args:?}: {line}");
        std::net::TcpStream::connect(addr).unwrap_or_else(|e| panic!("{args:?}: {addr}: {e}"));
    }
}

#[test]
fn a_refused_connection_hints_at_a_hub_without_its_radio() {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", listener.local_addr().unwrap());
    drop(listener);
    let output = run(&["send", "--link", &link, "--to", M, "landing", "on"]);
    let stderr = stderr(&output);
    assert_eq!(output.status.code(), Some(3), "{stderr}");
    assert!(stderr.contains("nothing listens there"), "{stderr}");
    assert!(
        stderr.contains("running? A hub whose radio is disconnected refuses connections"),
        "{stderr}"
    );
}

#[cfg(unix)]
#[test]
fn sim_and_radio_check_their_addresses_before_they_start() {
    let other = "0013a20040b599aa";
    let cut = format!("{other}@1+1");
    let faults = format!("{other}=loss=1");
    let cases: &[(&[&str], &str)] = &[
        (
            &["sim", "--link", "pty", "--address", M, "--address", M],
            "given twice",
        ),
        (
            &["sim", "--link", "pty", "--cut", &cut, "--duration", "1"],
            &format!("--cut {other}: no simulated MAV has that address"),
        ),
        (
            &[
                "sim",
                "--link",
                "pty",
                "--faults",
                &faults,
                "--duration",
                "1",
            ],
            &format!("--faults {other}: no simulated MAV has that address"),
        ),
        (
            &[
                "radio",
                "--coordinator",
                "pty",
                "--cut",
                &cut,
                "--duration",
                "1",
            ],
            "the network has only the coordinator",
        ),
        (
            &[
                "radio",
                "--coordinator",
                "pty",
                "--node",
                &format!("{M}=pty"),
                "--node",
                &format!("{M}=pty"),
            ],
            "given twice",
        ),
    ];
    for (args, message) in cases {
        let output = run(args);
        let stderr = stderr(&output);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(message), "{args:?}: {stderr}");
        // Before anything started: not even the seed.
        assert_eq!(stdout(&output), "", "{args:?}");
    }
    // A default MAV's address is one to cut.
    let output = run(&[
        "sim",
        "--link",
        "pty",
        "--cut",
        &format!("{M}@0+0"),
        "--duration",
        "0.01",
    ]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
}

/// The payload of the frame `encode` printed (after the 17 bytes of header).
fn encoded_payload(output: &Output) -> String {
    assert_eq!(output.status.code(), Some(0), "{}", stderr(output));
    let out = stdout(output);
    let bytes: Vec<&str> = out.split_whitespace().collect();
    bytes[17..bytes.len() - 1].join(" ")
}

#[test]
fn numbers_beyond_an_f32_and_names_in_any_case() {
    for value in ["1e40", "-1e400"] {
        let output = run(&["encode", "--to", M, "position-set", value, "0"]);
        let stderr = stderr(&output);
        assert_eq!(output.status.code(), Some(2), "{stderr}");
        assert!(
            stderr.contains("outside the range of a 32-bit float"),
            "{stderr}"
        );
        assert!(!stderr.contains("not a finite number"), "{stderr}");
    }
    // Too small: sent as 0, with a warning.
    let output = run(&["encode", "--to", M, "position-set", "1e-50", "0"]);
    assert_eq!(encoded_payload(&output), "63 07 00 00 00 00 00 00 00 00");
    assert!(stderr(&output).contains("sent as 0"), "{}", stderr(&output));

    // Names in any case, as `status LANDING` always took.
    for (args, payload) in [
        (&["controller", "MPC"][..], "63 03 03"),
        (&["telemetry", "on", "ALTITUDE"], "63 01 01 01"),
        (&["status", "telemetry", "Pitch_Angle"], "63 01 FF 19"),
        (&["status", "LANDING"], "63 02 FF"),
        (&["controller", "254"], "63 03 FE"),
    ] {
        let mut argv = vec!["encode", "--to", M];
        argv.extend_from_slice(args);
        assert_eq!(encoded_payload(&run(&argv)), payload, "{args:?}");
    }
    let output = run(&[
        "status",
        "--link",
        "tcp:127.0.0.1:9",
        "--to",
        M,
        "telemetry",
        "ALTITUDE",
    ]);
    // Past the arguments: the link is what fails.
    assert_eq!(output.status.code(), Some(3), "{}", stderr(&output));

    // The controllers a command takes: 0 to 254, as the messages say.
    for controller in ["255", "fast"] {
        let output = run(&["encode", "--to", M, "controller", controller]);
        let stderr = stderr(&output);
        assert_eq!(output.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains("0 to 254"), "{stderr}");
        assert!(!stderr.contains("0 to 255"), "{stderr}");
    }
}

#[test]
fn every_json_object_of_monitor_has_a_time() {
    let mut bytes = [
        &[0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F][..], // modem status
        &[0x7E, 0x00, 0x02, 0x8A, 0x06, 0x00],     // bad checksum
        // Receive Packet: landing report "flight".
        &[
            0x7E, 0x00, 0x0F, 0x90, 0x00, 0x13, 0xA2, 0x00, 0x40, 0xB5, 0x99, 0xB9, 0x7D, 0x84,
            0x01, 0x72, 0x02, 0x04,
        ],
    ]
    .concat();
    // The checksum of the Receive Packet.
    let sum = bytes[15..].iter().fold(0u8, |s, b| s.wrapping_add(*b));
    bytes.push(0xFF - sum);
    let (link, peer) = talking_peer(bytes);
    // Three received items; the link's own "connected" line is printed but not counted.
    let output = run(&[
        "monitor", "--link", &link, "--format", "json", "--count", "3",
    ]);
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    let objects: Vec<serde_json::Value> = stdout(&output)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let kinds: Vec<&str> = objects
        .iter()
        .map(|o| {
            o.get("link")
                .or(o.get("frame"))
                .or(o.get("error"))
                .and_then(|v| v.as_str())
                .unwrap_or("?")
        })
        .collect();
    assert_eq!(
        kinds,
        ["connected", "modem_status", "checksum", "receive"],
        "{objects:?}"
    );
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_secs_f64();
    for object in &objects {
        let time = object["time"]
            .as_f64()
            .unwrap_or_else(|| panic!("{object}"));
        assert!((now - time).abs() < 600.0, "{object}");
    }
    peer.join().unwrap();
    // The help says so.
    assert!(stdout(&run(&["monitor", "--help"])).contains("every JSON object carries `time`"));
}

#[test]
fn decode_of_input_with_no_frame_is_an_input_error() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("f");
    std::fs::write(&file, b"MCPRE").unwrap();
    for summary in [false, true] {
        let mut args = vec!["decode", file.to_str().unwrap()];
        args.extend(summary.then_some("--summary"));
        let output = run(&args);
        let stderr = stderr(&output);
        assert_eq!(output.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains("no XBee frame in 5 bytes"), "{stderr}");
    }
    // A capture cut off inside its one frame says so, and sends nobody to the other
    // API mode; the error line tells the checksum byte is what is missing.
    std::fs::write(&file, [0x7E, 0x00, 0x02, 0x8A, 0x06]).unwrap();
    for mode in ["1", "2"] {
        let output = run(&["decode", "--api-mode", mode, file.to_str().unwrap()]);
        let (out, err) = (stdout(&output), stderr(&output));
        assert_eq!(output.status.code(), Some(2), "{err}");
        assert!(err.contains("its one candidate frame is cut off"), "{err}");
        assert!(!err.contains("--api-mode"), "{err}");
        assert!(
            out.contains("truncated before its checksum byte (all 2 data bytes received)"),
            "{out}"
        );
    }
    // One frame of mode 2 whose length holds an escape (17 bytes: 7D 31), read in mode
    // 1, is one candidate cut off; mode 2 finds it whole, and is named.
    let encoded = run(&["encode", "--to", M, "--api-mode", "2", "landing", "on"]);
    assert!(
        stdout(&encoded).starts_with("7E 00 7D 31 "),
        "{}",
        stdout(&encoded)
    );
    std::fs::write(&file, stdout(&encoded)).unwrap();
    let output = run(&["decode", "--hex", file.to_str().unwrap()]);
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(2), "{err}");
    assert!(
        err.contains("if it is in API mode 2, decode it with --api-mode 2"),
        "{err}"
    );
    // One frame whose checksum is wrong (a byte mistyped): said so, not taken for a
    // capture at another baud rate or in the other mode.
    std::fs::write(&file, [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6E]).unwrap();
    let output = run(&["decode", file.to_str().unwrap()]);
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(2), "{err}");
    assert!(
        err.contains("its one candidate frame failed its checksum (a byte of it mistyped?)"),
        "{err}"
    );
    // Empty input holds nothing wrong.
    std::fs::write(&file, b"").unwrap();
    assert_eq!(
        run(&["decode", file.to_str().unwrap()]).status.code(),
        Some(0)
    );
}

/// `decode --hex` of what `encode` printed for `command`, in `format`.
fn encode_then_decode(command: &[&str], format: &str) -> String {
    let mut argv = vec!["encode", "--to", M];
    argv.extend_from_slice(command);
    let frame = stdout(&run(&argv));
    let mut child = gs()
        .args(["decode", "--hex", "--format", format])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::io::Write::write_all(&mut child.stdin.take().unwrap(), frame.as_bytes()).unwrap();
    let output = child.wait_with_output().unwrap();
    assert_eq!(output.status.code(), Some(0), "{}", stderr(&output));
    stdout(&output)
}

#[test]
fn floats_and_text_print_unambiguously() {
    let payload: String = [b'c', 0x07]
        .into_iter()
        .chain(0.999_999_8_f32.to_le_bytes())
        .chain(3.4e38_f32.to_le_bytes())
        .map(|b| format!("{b:02x}"))
        .collect();
    let text = encode_then_decode(&["raw", &payload], "text");
    assert!(
        text.contains("position_set elevator=0.9999998 aileron=3.4e38"),
        "{text}"
    );
    let json = encode_then_decode(&["raw", &payload], "json");
    assert!(json.contains(r#""elevator":0.9999998,"#), "{json}");
    let value: serde_json::Value = serde_json::from_str(json.trim()).unwrap();
    assert_eq!(value["mcp"]["aileron"].as_f64().unwrap() as f32, 3.4e38);
    // Tiny numbers too.
    let payload: String = [b't', 0x01]
        .into_iter()
        .chain(1e-45_f32.to_le_bytes())
        .map(|b| format!("{b:02x}"))
        .collect();
    let text = encode_then_decode(&["raw", &payload], "text");
    assert!(text.contains("telemetry altitude=1e-45"), "{text}");

    // A quote inside a message is escaped, as a backslash is.
    let text = encode_then_decode(&["message", r#"a"b\\c"#], "text");
    assert!(text.contains(r#"message "a\"b\\c""#), "{text}");
}

#[test]
fn a_message_as_decode_prints_it_is_sent_back_byte_for_byte() {
    // Every byte, in two messages: the text `decode` prints (text and JSON), given to
    // `message`, makes the same frame as the bytes given raw.
    for bytes in [0..=127u8, 128..=255] {
        let payload: String = std::iter::once(b'm')
            .chain(bytes)
            .map(|b| format!("{b:02x}"))
            .collect();
        let raw = stdout(&run(&["encode", "--to", M, "raw", &payload]));
        let text = encode_then_decode(&["raw", &payload], "text");
        let (_, quoted) = text.split_once("message \"").expect(&text);
        let printed = quoted.trim_end().strip_suffix('"').expect(&text);
        let json = encode_then_decode(&["raw", &payload], "json");
        let json: serde_json::Value = serde_json::from_str(json.trim()).unwrap();
        let in_json = json["mcp"]["text"].as_str().unwrap();
        for given in [printed, in_json] {
            let output = run(&["encode", "--to", M, "message", given]);
            assert_eq!(stdout(&output), raw, "{given}: {}", stderr(&output));
        }
    }
}

#[test]
fn a_message_is_8_bit_ascii_and_a_character_that_is_not_is_refused() {
    for (given, says) in [
        (
            "café",
            "`é` is not ASCII: the protocol's messages are 8-bit ASCII; give a byte above \
          0x7F as `\\xNN` (for example `\\xe9`",
        ),
        (r"C:\path", "a backslash (at byte 2) starts `\\xNN`"),
        (r"x\x4", "`\\x` takes two hex digits"),
        (r"x\x+1", "`\\x` takes two hex digits"),
    ] {
        let output = run(&["encode", "--to", M, "message", given]);
        assert_eq!(output.status.code(), Some(2), "{given}: {output:?}");
        assert!(
            stderr(&output).contains(says),
            "{given}: {}",
            stderr(&output)
        );
    }
    // Words given apart are one text, with a space between them.
    assert_eq!(
        stdout(&run(&["encode", "--to", M, "message", "hello", "world"])),
        stdout(&run(&["encode", "--to", M, "message", "hello world"]))
    );
    let output = run(&["encode", "--to", M, "message", r#"caf\xe9 \\ \"q\""#]);
    assert!(
        stdout(&output).contains(" 6D 63 61 66 E9 20 5C 20 22 71 22 "),
        "{output:?}"
    );
}

fn posix_now() -> u64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .as_secs()
}

/// Encodes `command`, whose payload carries a time (u32, little-endian) at byte `at`,
/// and checks that the time is `ahead` seconds past this machine's clock as it was
/// while the command was built, with nothing on standard error.
fn assert_time_from_now(command: &[&str], at: usize, ahead: u64) {
    let mut argv = vec!["encode", "--to", M];
    argv.extend_from_slice(command);
    let before = posix_now();
    let output = run(&argv);
    let after = posix_now();
    let bytes: Vec<u8> = encoded_payload(&output)
        .split_whitespace()
        .map(|b| u8::from_str_radix(b, 16).unwrap())
        .collect();
    let sent = u64::from(u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()));
    assert!(
        (before + ahead..=after + ahead).contains(&sent),
        "{command:?}: {sent} not in {}..={}",
        before + ahead,
        after + ahead
    );
    assert_eq!(stderr(&output), "", "{command:?}");
}

#[test]
fn waypoint_times_from_now_and_their_help() {
    for (time, ahead) in [("+10", 10), ("now", 0), ("NOW", 0), ("+0", 0)] {
        let waypoint = format!("{time},0.5,0.5,1");
        // c, 4, count, then the first waypoint's time.
        assert_time_from_now(&["trajectory", "--waypoint", &waypoint], 3, ahead);
    }
    // A time in 1970 is most likely meant from now: sent as given, with a warning.
    let output = run(&[
        "encode",
        "--to",
        M,
        "trajectory",
        "--waypoint",
        "10,0.5,0.5,1",
    ]);
    assert!(encoded_payload(&output).starts_with("63 04 01 0A 00 00 00"));
    assert!(stderr(&output).contains("give +10"), "{}", stderr(&output));
    for bad in [
        "+x,0,0,1",
        "+-1,0,0,1",
        "+4294967295,0,0,1",
        "yesterday,0,0,1",
    ] {
        let output = run(&["encode", "--to", M, "trajectory", "--waypoint", bad]);
        assert_eq!(output.status.code(), Some(2), "{bad}");
    }
    let help = stdout(&run(&["send", "trajectory", "--help"]));
    assert!(
        help.contains("seconds since 1970") && help.contains("+N") && help.contains("now"),
        "{help}"
    );
}

/// `time` takes the times a waypoint takes: `+N` is N seconds from now, not N seconds
/// after 1970.
#[test]
fn the_time_command_takes_times_from_now_as_waypoints_do() {
    for (time, ahead) in [("+10", 10), ("now", 0), ("NOW", 0), ("+0", 0)] {
        // c, 6, then the time.
        assert_time_from_now(&["time", time], 2, ahead);
    }
    // A time in 1970 is most likely meant from now: sent as given, with a warning.
    let output = run(&["encode", "--to", M, "time", "10"]);
    assert_eq!(encoded_payload(&output), "63 06 0A 00 00 00");
    assert!(stderr(&output).contains("give +10"), "{}", stderr(&output));
    for bad in ["+x", "+-1", "++5", "+4294967295", "yesterday"] {
        let output = run(&["encode", "--to", M, "time", bad]);
        assert_eq!(output.status.code(), Some(2), "{bad}: {}", stderr(&output));
    }
    let help = stdout(&run(&["send", "time", "--help"]));
    assert!(help.contains("+N") && help.contains("now"), "{help}");
}

#[test]
fn the_size_warning_names_the_command() {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", listener.local_addr().unwrap());
    drop(listener);
    let long = "x".repeat(44);
    let fits = "x".repeat(43);
    let waypoints = ["--waypoint", "+1,0,0,1"].repeat(3);
    let raw = "00".repeat(45);
    let cases: [(Vec<&str>, Option<&str>); 4] = [
        (
            vec!["message", &long],
            Some("a message of more than 43 bytes"),
        ),
        (vec!["message", &fits], None),
        (
            [&["trajectory"][..], &waypoints].concat(),
            Some("a trajectory of more than 2 waypoints"),
        ),
        (vec!["raw", &raw], Some("a packet of more than 44 bytes")),
    ];
    for (command, warning) in cases {
        let mut argv = vec!["send", "--link", &link, "--to", M];
        argv.extend(&command);
        let output = run(&argv);
        let stderr = stderr(&output);
        // The link is not there: the warning comes first all the same.
        assert_eq!(output.status.code(), Some(3), "{stderr}");
        match warning {
            Some(warning) => {
                assert!(stderr.contains(warning), "{command:?}: {stderr}");
                assert_eq!(stderr.matches("warning").count(), 1, "{stderr}");
            }
            None => assert!(!stderr.contains("warning"), "{command:?}: {stderr}"),
        }
    }
}

#[test]
fn at_no_apply_queues_the_value_on_the_local_radio() {
    // A radio that keeps what it gets and answers nothing.
    let (link, reader) = common::recording_peer();
    let output = run(&[
        "at",
        "--link",
        &link,
        "--timeout",
        "0.3",
        "--no-apply",
        "NI",
        "x",
    ]);
    assert_eq!(output.status.code(), Some(4), "{}", stderr(&output));
    // AT Command - Queue Parameter Value (0x09), frame id 1, NI = "x".
    let wire = reader.join().unwrap();
    assert_eq!(wire, [0x7E, 0x00, 0x05, 0x09, 0x01, b'N', b'I', b'x', 0xE6]);
}

/// A recording of `records` (direction: 0 received, 1 sent; time in µs since 1970),
/// each a modem status frame.
fn recording(records: &[(u8, u64)]) -> Vec<u8> {
    let mut bytes = b"MCPREC\x01\x00".to_vec();
    for &(direction, micros) in records {
        bytes.extend_from_slice(&micros.to_le_bytes());
        bytes.push(direction);
        bytes.extend_from_slice(&2u16.to_le_bytes());
        bytes.extend_from_slice(&[0x8A, 0x06]);
    }
    bytes
}

#[test]
fn replay_of_no_frame_of_the_chosen_direction_says_so_up_front() {
    let dir = tempfile::tempdir().unwrap();
    let received = dir.path().join("monitor.mcprec");
    std::fs::write(&received, recording(&[(0, 1), (0, 2)])).unwrap();
    let sent = dir.path().join("sent.mcprec");
    std::fs::write(&sent, recording(&[(1, 1)])).unwrap();
    let empty = dir.path().join("empty.mcprec");
    std::fs::write(&empty, recording(&[])).unwrap();
    // A link nobody listens on: with the fix, never opened.
    for (file, frames, message) in [
        (&received, "tx", "holds no sent frames"),
        (&sent, "rx", "holds no received frames"),
        (&empty, "both", "holds no frames"),
    ] {
        let output = run(&[
            "replay",
            file.to_str().unwrap(),
            "--link",
            "tcp-listen:127.0.0.1:0",
            "--timeout",
            "5",
            "--frames",
            frames,
        ]);
        let stderr = stderr(&output);
        assert_eq!(output.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(message), "{stderr}");
        assert!(!stderr.contains("waiting"), "{stderr}");
    }
    let output = run(&[
        "replay",
        received.to_str().unwrap(),
        "--link",
        "tcp:127.0.0.1:9",
        "--frames",
        "tx",
    ]);
    assert!(stderr(&output).contains("records received frames only"));
}

/// A recording of `records`: direction (0 received, 1 sent), time in µs since 1970,
/// frame data.
fn recording_of(records: &[(u8, u64, &[u8])]) -> Vec<u8> {
    let mut bytes = b"MCPREC\x01\x00".to_vec();
    for &(direction, micros, frame) in records {
        bytes.extend_from_slice(&micros.to_le_bytes());
        bytes.push(direction);
        bytes.extend_from_slice(&u16::try_from(frame.len()).unwrap().to_le_bytes());
        bytes.extend_from_slice(frame);
    }
    bytes
}

/// `frame` (frame data) on the wire in API mode 1.
fn wire(frame: &[u8]) -> Vec<u8> {
    let mut bytes = vec![0x7E, 0x00, u8::try_from(frame.len()).unwrap()];
    bytes.extend_from_slice(frame);
    bytes.push(0xFF - frame.iter().fold(0u8, |s, b| s.wrapping_add(*b)));
    bytes
}

#[test]
fn replay_of_sent_frames_leaves_the_at_commands_out_unless_asked() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("hub.mcprec");
    // As a hub records: its own AT AP, a client's NI set, a remote AT to a MAV's
    // radio, a landing command, and the radio's answers.
    let remote_at: &[u8] = &[
        0x17, 3, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0x02, b'I', b'D', 7,
    ];
    let landing: &[u8] = &[
        0x10, 4, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0, 0, b'c', 2, 1,
    ];
    let records = [
        (1, 0, &[0x08, 1, b'A', b'P'][..]),
        (0, 1_000, &[0x88, 1, b'A', b'P', 0, 1][..]),
        (1, 2_000, &[0x08, 2, b'N', b'I', b'X'][..]),
        (1, 3_000, remote_at),
        (1, 4_000, landing),
    ];
    std::fs::write(&file, recording_of(&records)).unwrap();
    let (link, peer) = common::recording_peer();
    let path = file.to_str().unwrap();
    // The peer records, and answers nothing: the landing's transmit status is waited
    // for --timeout.
    let output = run(&[
        "replay",
        path,
        "--link",
        &link,
        "--frames",
        "tx",
        "--timeout",
        "1",
    ]);
    let said = stderr(&output);
    assert_eq!(output.status.code(), Some(0), "{said}");
    assert_eq!(peer.join().unwrap(), wire(landing));
    assert!(
        said.contains(
            "replayed 1 frame; of the 1 that asked for a transmit status: 0 delivered, 1 \
             without a transmit status in 1 s\n"
        ),
        "{said}"
    );
    assert!(
        said.contains(
            "3 AT commands to radios in the recording not replayed: they would set the \
             radios' parameters again (--with-at plays them)"
        ),
        "{said}"
    );
    assert!(said.contains("replayed 1 frame"), "{said}");
    // What the commands are, and that they act again, before they are played.
    assert!(
        said.contains(
            "warning: the sent frames hold commands that act on MAVs, landing 1, to 1 MAV \
             (0013a20040b599b9): played, they act again as they did when recorded\n"
        ),
        "{said}"
    );
    // Asked for: every sent frame, in order.
    let (link, peer) = common::recording_peer();
    let output = run(&[
        "replay",
        path,
        "--link",
        &link,
        "--frames",
        "tx",
        "--with-at",
        "--timeout",
        "1",
    ]);
    let said = stderr(&output);
    assert_eq!(output.status.code(), Some(0), "{said}");
    let sent: Vec<u8> = [0, 2, 3, 4]
        .iter()
        .flat_map(|&i| wire(records[i].2))
        .collect();
    assert_eq!(peer.join().unwrap(), sent);
    assert!(!said.contains("not replayed"), "{said}");
    // A recording of AT commands alone: nothing to replay, said before the link opens.
    let at_only = dir.path().join("at.mcprec");
    std::fs::write(&at_only, recording_of(&records[..3])).unwrap();
    let output = run(&[
        "replay",
        at_only.to_str().unwrap(),
        "--link",
        "tcp:127.0.0.1:9",
        "--frames",
        "tx",
    ]);
    let said = stderr(&output);
    assert_eq!(output.status.code(), Some(2), "{said}");
    assert!(
        said.contains("nothing to replay: 2 AT commands to radios in the recording"),
        "{said}"
    );
}

#[test]
fn a_damaged_or_cut_off_recording_plays_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let landing = |on: u8| -> Vec<u8> {
        vec![
            0x10, 0, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0, 0, b'c', 2, on,
        ]
    };
    let time = |s: u64| std::time::UNIX_EPOCH + std::time::Duration::from_secs(1_790_000_000 + s);
    let mut writer = mcp_host::record::RecordWriter::new(Vec::new()).unwrap();
    let sent = mcp_host::record::Direction::Sent;
    writer.write(time(0), sent, &landing(1)).unwrap();
    writer
        .write(
            time(1),
            sent,
            &b"\x10\x00\x00\x13\xa2\x00\x40\xb5\x99\xb9\xff\xfe\x00\x00c\x06\x00\x00\x00\x00"[..],
        )
        .unwrap();
    writer.write(time(2), sent, &landing(0)).unwrap();
    let bytes = writer.into_inner();
    let second = 8 + mcp_host::record::record_len(landing(1).len());
    // A bit flipped in the last record: its `landing off` would read `landing on`.
    let mut damaged = bytes.clone();
    let last = damaged.len() - 5;
    damaged[last] ^= 1;
    let file = dir.path().join("damaged.mcprec");
    std::fs::write(&file, &damaged).unwrap();
    let path = file.to_str().unwrap();
    // Nobody listens there: the replay must stop before it opens the link.
    let output = run(&[
        "replay",
        path,
        "--link",
        "tcp:127.0.0.1:9",
        "--frames",
        "tx",
    ]);
    let said = stderr(&output);
    assert_eq!(output.status.code(), Some(2), "{said}");
    let third = second + mcp_host::record::record_len(20);
    assert!(
        said.contains(&format!(
            "{path}: record at offset {third} is damaged: its CRC is "
        )),
        "{said}"
    );
    assert!(
        said.contains(&format!(
            ": nothing replayed, as a damaged or cut-off recording is not played in part; the \
             2 records before it are whole (`head -c {third} {path}` keeps them)"
        )),
        "{said}"
    );
    assert!(!said.contains("connect"), "{said}");
    // The command offered works in a shell, whatever the file's name.
    let spaced = dir.path().join("flight 2.mcprec");
    std::fs::write(&spaced, &damaged).unwrap();
    let spaced = spaced.to_str().unwrap();
    let output = run(&["replay", spaced, "--link", "tcp:127.0.0.1:9"]);
    assert!(
        stderr(&output).contains(&format!("`head -c {third} '{spaced}'` keeps them")),
        "{}",
        stderr(&output)
    );
    // Cut off in its last record: nothing played either (a damaged length reads as cut
    // off, with whole records after it).
    let cut = dir.path().join("cut.mcprec");
    std::fs::write(&cut, &bytes[..bytes.len() - 3]).unwrap();
    let cut = cut.to_str().unwrap();
    let output = run(&["replay", cut, "--link", "tcp:127.0.0.1:9", "--frames", "tx"]);
    let said = stderr(&output);
    assert_eq!(output.status.code(), Some(2), "{said}");
    assert!(
        said.contains(&format!(
            "{cut}: recording cut off part way through the record at offset {third}"
        )) && said.contains(&format!(
            "nothing replayed, as a damaged or cut-off recording is not played in part; \
             the 2 records before it are whole (`head -c {third} {cut}` keeps them)"
        )),
        "{said}"
    );
    // Whole: played, the time command named among those that act again.
    let whole = dir.path().join("whole.mcprec");
    std::fs::write(&whole, &bytes).unwrap();
    let (link, peer) = common::recording_peer();
    let output = run(&[
        "replay",
        whole.to_str().unwrap(),
        "--link",
        &link,
        "--frames",
        "tx",
        "--speed",
        "0",
        "--timeout",
        "1",
    ]);
    let said = stderr(&output);
    assert_eq!(output.status.code(), Some(0), "{said}");
    assert!(
        said.contains(
            "the sent frames hold commands that act on MAVs, landing 2, time 1, to 1 MAV \
             (0013a20040b599b9): played, they act again as they did when recorded; a time \
             command sets the MAV's clock to the recorded time"
        ),
        "{said}"
    );
    assert_eq!(peer.join().unwrap().len(), 2 * (3 + 17 + 1) + (3 + 20 + 1));
    // From standard input, read once: played up to the damage, then stopped.
    let (link, peer) = common::recording_peer();
    let output = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args([
            "replay", "-", "--link", &link, "--frames", "tx", "--speed", "0",
        ])
        .stdin(std::fs::File::open(&file).unwrap())
        .output()
        .unwrap();
    let said = stderr(&output);
    assert_eq!(output.status.code(), Some(2), "{said}");
    assert!(said.contains("-: record at offset"), "{said}");
    assert!(said.contains("replayed 2 frames before it"), "{said}");
    assert!(
        said.contains("the recorded commands among the sent frames act on the MAVs again"),
        "{said}"
    );
    // The first landing and the time command: 17 and 20 bytes of frame data, framed.
    assert_eq!(peer.join().unwrap().len(), (3 + 17 + 1) + (3 + 20 + 1));
}

#[test]
fn replay_of_sent_frames_says_whether_the_radio_delivered_them() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("commands.mcprec");
    let landing = |id: u8| -> Vec<u8> {
        vec![
            0x10, id, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0, 0, b'c', 2, 1,
        ]
    };
    // Two that ask for a transmit status, one that does not (frame id 0).
    let (one, two, none) = (landing(1), landing(2), landing(0));
    let records = [(1, 0, &one[..]), (1, 1, &none[..]), (1, 2, &two[..])];
    std::fs::write(&file, recording_of(&records)).unwrap();
    let path = file.to_str().unwrap();
    for (delivery, says) in [
        (
            0x00,
            "of the 2 that asked for a transmit status: 2 delivered\n",
        ),
        (
            0x21,
            "of the 2 that asked for a transmit status: 0 delivered, 2 not delivered \
             (network_ack_failure 2)\n",
        ),
    ] {
        let (link, radio) = common::refusing_radio(delivery);
        let output = run(&[
            "replay", path, "--link", &link, "--frames", "tx", "--speed", "0",
        ]);
        let said = stderr(&output);
        assert_eq!(output.status.code(), Some(0), "{said}");
        assert!(
            said.contains(&format!("replayed 3 frames; {says}")),
            "{said}"
        );
        radio.join().unwrap();
    }
}

#[test]
fn a_raw_capture_given_to_replay_is_pointed_to_decode() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("capture.bin");
    std::fs::write(&file, [wire(&[0x8A, 0x06]), wire(&[0x8A, 0x02])].concat()).unwrap();
    let output = run(&[
        "replay",
        file.to_str().unwrap(),
        "--link",
        "tcp:127.0.0.1:9",
    ]);
    let said = stderr(&output);
    assert_eq!(output.status.code(), Some(2), "{said}");
    assert!(
        said.contains("not a recording: no MCPREC header (replay plays recordings, made with --record; `mcp-gs decode` reads a raw capture too)"),
        "{said}"
    );
}

#[test]
fn replay_keeps_its_pace_across_a_clock_set_back_and_max_gap_shortens_the_waits() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("clock.mcprec");
    let hour = 3_600_000_000u64;
    // The clock set back an hour after the second frame, the frames after it 0.3 s
    // apart; a day's silence before the last.
    let times = [
        10 * hour,
        10 * hour + 1_000,
        9 * hour,
        9 * hour + 300_000,
        9 * hour + 600_000,
        33 * hour,
    ];
    let records: Vec<(u8, u64)> = times.iter().map(|&t| (0, t)).collect();
    std::fs::write(&file, recording(&records)).unwrap();
    let (link, peer) = common::recording_peer();
    let start = std::time::Instant::now();
    let output = run(&[
        "replay",
        file.to_str().unwrap(),
        "--link",
        &link,
        "--max-gap",
        "0.5",
    ]);
    // The pace kept after the clock went back (0.6 s), and the day cut to 0.5 s.
    let took = start.elapsed();
    let stderr = stderr(&output);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    assert_eq!(peer.join().unwrap().len(), 6 * 6);
    assert!(
        took >= std::time::Duration::from_millis(1_100),
        "{took:?}: {stderr}"
    );
    assert!(took < std::time::Duration::from_secs(60), "{took:?}");
    assert!(
        stderr.contains(
            "warning: the recording's clock goes back 3600 s before its frame 3: played at \
             once"
        ),
        "{stderr}"
    );
    assert!(stderr.contains("replayed 6 frames"), "{stderr}");
    assert!(!stderr.contains("quiet"), "{stderr}");
}

#[test]
fn replay_of_a_hostile_recording_is_an_input_error_at_a_slow_speed() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("far.mcprec");
    std::fs::write(&file, recording(&[(0, 0), (0, u64::MAX)])).unwrap();
    for speed in ["0.000001", "1", "1e-300", "0.1234567890123"] {
        let (link, reader) = common::recording_peer();
        let output = run(&[
            "replay",
            file.to_str().unwrap(),
            "--link",
            &link,
            "--speed",
            speed,
        ]);
        let stderr = stderr(&output);
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert_eq!(output.status.code(), Some(2), "{speed}: {stderr}");
        assert!(stderr.contains("too far ahead"), "{stderr}");
        // The speed as given, not 1e-300 in 302 digits, nor 1.234567890123e-1.
        assert!(
            stderr.contains(&format!("at --speed {speed} (")),
            "{stderr}"
        );
        assert!(stderr.contains("replayed 1 frame before it"), "{stderr}");
        // The first frame went out.
        assert_eq!(reader.join().unwrap(), [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F]);
    }
}

#[test]
fn replay_says_how_far_it_got_when_its_peer_leaves() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("minute.mcprec");
    // The second frame a minute after the first: the replay is waiting for it when the
    // peer leaves, and says so then, not a minute later.
    std::fs::write(&file, recording(&[(0, 0), (0, 60_000_000)])).unwrap();
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", listener.local_addr().unwrap());
    let peer = std::thread::spawn(move || {
        let (mut socket, _) = listener.accept().unwrap();
        let mut first = [0u8; 6];
        std::io::Read::read_exact(&mut socket, &mut first).unwrap();
        first
    });
    let output = run(&["replay", file.to_str().unwrap(), "--link", &link]);
    let stderr = stderr(&output);
    assert_eq!(peer.join().unwrap(), [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F]);
    assert_eq!(output.status.code(), Some(3), "{stderr}");
    // The wait said as it began.
    assert!(
        stderr.contains(
            "mcp-gs: waiting 60 s: the recording is quiet for 60 s after its frame 1 \
             (--max-gap shortens such waits)"
        ),
        "{stderr}"
    );
    // After the warning that a `tcp:` link is most often a radio's side.
    assert_eq!(
        stderr.trim_end().lines().last(),
        Some("mcp-gs: link closed (replayed 1 frame before it)"),
        "{stderr}"
    );
}

#[cfg(unix)]
#[test]
fn ctrl_c_stops_the_demo_script_at_once() {
    // And a signal to stop does the same, said as what it is.
    for (signal, name) in [(libc::SIGINT, "Ctrl-C"), (libc::SIGTERM, "SIGTERM")] {
        let (child, lines) = spawn_lines(&["demo", "--duration", "0"]);
        let mut demo = Running(child);
        line_with(&lines, "== Clock");
        send_signal(&demo.0, signal);
        let after = rest(&lines);
        assert_eq!(exit_code(&mut demo.0), Some(0), "{after:?}");
        let headings: Vec<&String> = after.iter().filter(|l| l.starts_with("== ")).collect();
        assert_eq!(
            headings.last().map(|h| h.as_str()),
            Some("== Summary"),
            "{after:?}"
        );
        // The script stopped: no later step, and no watching after Ctrl-C.
        for later in ["== Landing", "== Watching"] {
            assert!(
                !headings.iter().any(|h| h.starts_with(later)),
                "{later}: {after:?}"
            );
        }
        let said = format!("stopped by {name}");
        assert!(after.iter().any(|l| l.contains(&said)), "{after:?}");
    }
}

#[test]
fn a_demo_shorter_than_its_script_runs_the_script_to_its_end() {
    // The time is up before the first step: the steps still run, without pauses.
    let (child, lines) = spawn_lines(&["demo", "--duration", "0.001"]);
    let mut demo = Running(child);
    let out = rest(&lines).join("\n");
    assert_eq!(exit_code(&mut demo.0), Some(0), "{out}");
    assert!(out.contains("== Landing"), "{out}");
    assert!(out.contains("== Summary"), "{out}");
    assert!(!out.contains("stopped by Ctrl-C"), "{out}");
    assert!(!out.contains(" 0 commands delivered"), "{out}");
}

/// `mcp-gs decode` with `args`, its standard input a pipe the test writes to, its output
/// line by line on the channel.
fn decode_piped(args: &[&str]) -> (Running, std::process::ChildStdin, Receiver<String>) {
    let mut child = gs()
        .arg("decode")
        .args(args)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .spawn()
        .expect("start mcp-gs");
    let stdin = child.stdin.take().expect("stdin");
    let lines = stdout_lines(&mut child);
    (Running(child), stdin, lines)
}

#[test]
fn decode_from_a_pipe_shows_each_frame_as_it_comes() {
    use std::io::Write;
    // Hex typed or piped in a line at a time, and raw bytes as a serial port gives them:
    // each frame is printed while the input is still open.
    let cases: [(&[&str], &[u8]); 2] = [
        (&["--hex", "-"], b"7E 00 02 8A 06 6F\n"),
        (&["-"], &[0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F]),
    ];
    for (args, frame) in cases {
        let (mut decode, mut stdin, lines) = decode_piped(args);
        for _ in 0..2 {
            stdin.write_all(frame).unwrap();
            stdin.flush().unwrap();
            let line = line_with(&lines, "modem status");
            assert!(line.contains("coordinator_started"), "{args:?}: {line}");
        }
        drop(stdin);
        assert_eq!(rest(&lines), Vec::<String>::new(), "{args:?}");
        assert_eq!(exit_code(&mut decode.0), Some(0), "{args:?}");
    }
    // A line that is not hex is said and skipped, decoding goes on, and the input is an
    // input error at the end.
    let (mut decode, mut stdin, lines) = decode_piped(&["--hex", "-"]);
    stdin
        .write_all(b"7E 00 02 8A 06 6F\n7E 0G\n7E 00 02 8A 06 6F\n")
        .unwrap();
    drop(stdin);
    let out = rest(&lines);
    assert_eq!(out.len(), 3, "{out:?}");
    assert!(out[1].contains("line 2: `0G` is not a hex byte"), "{out:?}");
    assert!(out[2].contains("coordinator_started"), "{out:?}");
    assert_eq!(exit_code(&mut decode.0), Some(2), "{out:?}");
}

#[cfg(unix)]
#[test]
fn decode_on_a_terminal_says_it_waits_for_input() {
    use serialport::SerialPort;
    use std::io::Write;
    for hex in [true, false] {
        // A real terminal on standard input: the far end of a pseudo-terminal.
        let (mut terminal, far) = serialport::TTYPort::pair().expect("pseudo-terminal");
        let far = std::fs::File::open(far.name().expect("far end's path")).unwrap();
        let mut args = vec!["decode"];
        args.extend(hex.then_some("--hex"));
        let mut child = gs()
            .args(&args)
            .stdin(far)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let (out, err) = (stdout_lines(&mut child), stderr_lines(&mut child));
        let note = err.recv_timeout(GUARD).expect("a note on standard error");
        let expected = if hex {
            "decoding hex typed on the terminal"
        } else {
            "give a capture FILE, or --hex"
        };
        assert!(note.contains(expected) && note.contains("Ctrl-D"), "{note}");
        // And what is typed is decoded as each line ends, even a frame of 5 bytes,
        // shorter than a recording's magic number.
        if hex {
            terminal.write_all(b"7E 00 01 8A 75\n").unwrap();
            line_with(&out, "frame type 0x8A needs at least 2 bytes");
            terminal.write_all(b"7E 00 02 8A 06 6F\n").unwrap();
            line_with(&out, "modem status coordinator_started");
        }
        child.kill().unwrap();
        child.wait().unwrap();
    }
    // Nothing is said when the input is not a terminal.
    let output = gs()
        .args(["decode", "--hex"])
        .stdin(std::process::Stdio::null())
        .output()
        .unwrap();
    assert_eq!(stderr(&output), "");
}

#[test]
fn encode_warns_of_a_packet_too_long_for_the_mav_or_for_a_broadcast() {
    let text = "x".repeat(100);
    let warnings = |to: &str| {
        let output = run(&["encode", "--to", to, "message", &text]);
        assert!(output.status.success(), "{output:?}");
        String::from_utf8_lossy(&output.stderr).into_owned()
    };
    let unicast = warnings(M);
    assert!(
        unicast.contains("the deployed MAV firmware drops frames over 60 bytes"),
        "{unicast}"
    );
    assert!(!unicast.contains("broadcast"), "{unicast}");
    let broadcast = warnings("000000000000ffff");
    assert!(
        broadcast.contains(
            "this 101-byte packet is broadcast, and a broadcast carries at most 92 bytes"
        ),
        "{broadcast}"
    );
    // Short enough for both: nothing said.
    let output = run(&["encode", "--to", "000000000000ffff", "landing", "on"]);
    assert!(output.stderr.is_empty(), "{output:?}");
}

#[test]
fn an_io_link_is_a_programs_own_and_refused_as_a_usage_error() {
    // Wherever a link is taken: a link's own option, `sim`, `setup`, `probe`, `radio`.
    for args in [
        &["status", "--link", "io:bluetooth", "--to", M, "landing"][..],
        &["monitor", "--link", "io"],
        &["sim", "--link", "io:bluetooth"],
        &["setup", "--link", "io:bluetooth"],
        &["probe", "--link", "io:bluetooth"],
        &["radio", "--node", "0013a20040b599b9=io:bluetooth"],
    ] {
        let output = run(args);
        // As any other link string mcp-gs cannot take: before anything is opened.
        assert_eq!(output.status.code(), Some(2), "{args:?}: {output:?}");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(
            stderr
                .matches("io: links are for programs that open their stream themselves")
                .count(),
            1,
            "{stderr}"
        );
        assert!(
            stderr.contains("mcp-gs takes serial:, tcp:, tcp-listen: or pty"),
            "{stderr}"
        );
    }
}
