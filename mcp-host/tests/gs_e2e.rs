//! End to end with processes: `mcp-gs sim` on one end of a real TCP connection or
//! pseudo-terminal; `mcp-gs send`, `status` and `monitor` on the other, for every
//! command type.

use std::process::{Child, Command, Output};
use std::time::Duration;

use serde_json::Value;

mod common;

use common::spawn_lines;

const MAV: &str = "0013a20040b599b9";
const SLAVE: &str = "0013a20040b599bf";
/// Failure guard only.
const GUARD: Duration = Duration::from_secs(30);

/// `mcp-gs sim`, killed when dropped.
struct Sim {
    child: Child,
    link: String,
}

impl Sim {
    /// Starts the simulator on `link` and reads the link a ground station opens.
    fn start(link: &str) -> Self {
        Self::start_with(&[], link)
    }

    /// The same, with more `sim` arguments.
    fn start_with(extra: &[&str], link: &str) -> Self {
        let mut args = vec!["sim", "--link", link, "--duration", "300"];
        args.extend_from_slice(extra);
        let (child, rx) = spawn_lines(&args);
        let link = loop {
            let line = rx.recv_timeout(GUARD).expect("sim prints its link");
            if let Some(rest) = line
                .split("(open it as ")
                .nth(1)
                .or_else(|| line.split("(connect with ").nth(1))
            {
                break rest.split(')').next().unwrap().to_string();
            }
        };
        Sim { child, link }
    }

    fn gs(&self, args: &[&str]) -> Output {
        let (sub, rest) = args.split_first().unwrap();
        Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
            .arg(sub)
            .args(["--link", &self.link, "--timeout", "10"])
            .args(rest)
            .output()
            .expect("run mcp-gs")
    }

    fn ok(&self, args: &[&str]) -> String {
        String::from_utf8(succeeded(self.gs(args), args).stdout).unwrap()
    }

    fn send(&self, command: &[&str]) {
        let mut args = vec!["send", "--to", MAV];
        args.extend_from_slice(command);
        let out = self.ok(&args);
        assert!(
            out.starts_with(&format!("delivered to {MAV}/")),
            "{command:?}: {out}"
        );
    }

    fn status(&self, kind: &[&str]) -> Value {
        self.status_with(&[], kind)
    }

    /// [`Sim::status`] with more options (e.g. `--api-mode auto`).
    fn status_with(&self, options: &[&str], kind: &[&str]) -> Value {
        let mut args = vec!["status", "--to", MAV, "--format", "json"];
        args.extend_from_slice(options);
        args.extend_from_slice(kind);
        let out = self.ok(&args);
        let report: Value = serde_json::from_str(out.trim()).expect("one JSON report");
        assert_eq!(report["category"], "report", "{out}");
        // That, which MAV answered, and when.
        assert_eq!(report["result"], "answered", "{out}");
        assert_eq!(report["src64"], MAV.to_lowercase(), "{out}");
        let received_at = report["received_at"].as_f64().expect("received_at");
        let now = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .as_secs_f64();
        assert!(received_at <= now && now - received_at < 60.0, "{out}");
        report
    }
}

/// `out`, after checking that the `mcp-gs` run it came from (with `args`) succeeded.
fn succeeded(out: Output, args: &[&str]) -> Output {
    assert!(
        out.status.success(),
        "mcp-gs {args:?}: {}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// Runs `mcp-gs` with `args` away from any simulator; it must succeed.
fn mcp_gs_ok(args: &[&str]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(args)
        .output()
        .expect("run mcp-gs");
    succeeded(out, args)
}

impl Drop for Sim {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn every_command_and_report(sim: &Sim) {
    // Time.
    sim.send(&["time", "1763683200"]);
    let time = sim.status(&["time"]);
    assert_eq!(time["type"], "time");
    let t = time["time"].as_u64().unwrap();
    assert!((1_763_683_200..1_763_683_200 + 60).contains(&t), "{time}");

    // Controllers: set by name, then by number.
    sim.send(&["controller", "mpc"]);
    assert_eq!(sim.status(&["controllers"])["controller_name"], "mpc");
    sim.send(&["controller", "2"]);
    assert_eq!(sim.status(&["controllers"])["controller"], 2);

    // Trajectory set.
    sim.send(&[
        "trajectory",
        "--waypoint",
        "1763683300,1.5,-2.25,3",
        "--waypoint",
        "1763683310,0.5,0.25,2",
    ]);
    let trajectory = sim.status(&["trajectory_set"]);
    assert_eq!(
        trajectory["waypoints"],
        serde_json::json!([
            {"time": 1763683300u32, "elevator": 1.5, "aileron": -2.25, "altitude": 3.0},
            {"time": 1763683310u32, "elevator": 0.5, "aileron": 0.25, "altitude": 2.0},
        ])
    );

    // Position slave set, in the firmware's slot form and in the specification's form.
    sim.send(&["slave-set", SLAVE, "--slot", "2"]);
    sim.send(&["slave-set", "0013a20040b599bd"]);
    let slaves = sim.status(&["position_slave_set"]);
    let addresses = slaves["addresses"].as_array().expect("four slots");
    assert_eq!(addresses[0], "0013a20040b599bd", "{slaves}");
    assert_eq!(addresses[2], SLAVE, "{slaves}");

    // Position set (no status request: it moves the setpoints seen in telemetry).
    sim.send(&["position-set", "0.5", "-0.5"]);
    assert_eq!(
        sim.gs(&["status", "--to", MAV, "position_set"])
            .status
            .code(),
        Some(2)
    );

    // Telemetry to coordinator: on for one id, then only that id arrives.
    sim.send(&["telemetry", "on", "altitude"]);
    let report = sim.status(&["telemetry_to_coordinator", "altitude"]);
    assert_eq!(
        (report["on"].as_bool(), report["telemetry"].as_u64()),
        (Some(true), Some(1))
    );
    let report = sim.status(&["telemetry_to_coordinator", "0x19"]);
    assert_eq!(report["on"], false);
    let out = sim.ok(&["monitor", "--format", "json", "--count", "3"]);
    let telemetry: Vec<Value> = out
        .lines()
        .map(|l| serde_json::from_str::<Value>(l).unwrap())
        .filter(|v| v["mcp"]["category"] == "telemetry")
        .collect();
    assert!(!telemetry.is_empty(), "{out}");
    for packet in &telemetry {
        assert_eq!(packet["src64"], MAV);
        let values = packet["mcp"]["values"].as_array().unwrap();
        assert_eq!(values.len(), 1, "{packet}");
        assert_eq!(values[0]["name"], "altitude");
    }
    sim.send(&["telemetry", "off", "altitude"]);

    // Landing: on, and the state leaves flight.
    assert_eq!(sim.status(&["landing"])["state_name"], "flight");
    sim.send(&["landing", "on"]);
    let state = sim.status(&["landing"]);
    assert!(
        ["landing", "on_ground"].contains(&state["state_name"].as_str().unwrap()),
        "{state}"
    );

    // A message is delivered too.
    sim.send(&["message", "hello MAV"]);
}

#[test]
fn sim_and_ground_station_over_tcp() {
    let sim = Sim::start("tcp-listen:127.0.0.1:0");
    assert!(sim.link.starts_with("tcp:127.0.0.1:"), "{}", sim.link);
    every_command_and_report(&sim);
}

#[cfg(unix)]
#[test]
fn sim_and_ground_station_over_a_pseudo_terminal() {
    let sim = Sim::start("pty");
    assert!(sim.link.starts_with("serial:/dev/"), "{}", sim.link);
    every_command_and_report(&sim);
}

#[test]
fn a_mav_out_of_reach_or_a_packet_too_large_fails_with_what_to_do() {
    // The MAV's radio cut off from the start: no acknowledgement (network_ack_failure);
    // unicast payloads of 84 bytes at most (no fragments).
    let sim = Sim::start_with(
        &["--cut", "0013A20040B599B9@0+300", "--max-unicast", "84"],
        "tcp-listen:127.0.0.1:0",
    );
    for args in [
        &["send", "--to", MAV, "landing", "on"][..],
        &["status", "--to", MAV, "landing"],
    ] {
        let out = sim.gs(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(5), "{args:?}: {stderr}");
        assert!(stderr.contains("network_ack_failure"), "{stderr}");
        assert!(
            stderr.contains(
                "hint: the MAV's radio did not acknowledge it: it is off, out of range, or in \
                 another network (its ID and CH must be this radio's); `mcp-gs nodes --link tcp:"
            ),
            "{args:?}: {stderr}"
        );
    }
    let text = "x".repeat(100);
    let args = ["send", "--to", SLAVE, "message", &text];
    let out = sim.gs(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(5), "{stderr}");
    assert!(stderr.contains("payload_too_large"), "{stderr}");
    assert!(
        stderr.contains("hint: the packet is larger than the radio carries to that address")
            && stderr.contains("NP` gives the most it sends in one radio packet"),
        "{stderr}"
    );
}

#[test]
fn unknown_mav_is_a_delivery_failure() {
    let sim = Sim::start("tcp-listen:127.0.0.1:0");
    // A command, and a status request: the same failure, the same hint.
    for args in [
        &["send", "--to", "0013a200deadbeef", "landing", "on"][..],
        &["status", "--to", "0013a200deadbeef", "landing"],
    ] {
        let out = sim.gs(args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(5), "{args:?}: {stderr}");
        assert!(stderr.contains("address_not_found"), "{stderr}");
        // Where to find the addresses there are.
        assert!(
            stderr.contains("hint: no radio of the network has that address: `mcp-gs nodes"),
            "{args:?}: {stderr}"
        );
    }
    // In JSON the refusal prints too, and the exit code is the same.
    let out = sim.gs(&[
        "send",
        "--to",
        "0013a200deadbeef",
        "--format",
        "json",
        "landing",
        "on",
    ]);
    assert_eq!(out.status.code(), Some(5));
    let failed: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (
            &failed["result"],
            &failed["delivery_name"],
            &failed["mcp"]["type"]
        ),
        (
            &"failed".into(),
            &"address_not_found".into(),
            &"landing".into()
        ),
        "{failed}"
    );
    // The fields a delivered one has, in the same order.
    let keys: Vec<&str> = failed
        .as_object()
        .unwrap()
        .keys()
        .map(String::as_str)
        .collect();
    assert_eq!(
        keys[..6],
        [
            "result",
            "dst64",
            "id",
            "dst16",
            "delivery",
            "delivery_name"
        ],
        "{failed}"
    );
    assert!(failed["id"].as_u64().is_some_and(|id| id > 0), "{failed}");
}

/// A landing status request to the MAV with a 1 s timeout, which it must hit (exit
/// code 4): the JSON object it prints.
fn status_timeout(sim: &Sim) -> Value {
    let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["status", "--link", &sim.link, "--timeout", "1", "--to", MAV])
        .args(["--format", "json", "landing"])
        .output()
        .expect("run mcp-gs status");
    assert_eq!(out.status.code(), Some(4), "{out:?}");
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

#[test]
fn status_in_json_prints_its_failures_as_send_does() {
    // The MAV's radio is there (its Transmit Status says delivered), but every frame to
    // the MAV is lost: it never answers.
    let sim = Sim::start_with(
        &["--faults", "0013A20040B599B9=loss=1"],
        "tcp-listen:127.0.0.1:0",
    );
    let json = |code: i32, args: &[&str]| {
        let out = sim.gs(args);
        assert_eq!(out.status.code(), Some(code), "{args:?}: {out:?}");
        serde_json::from_slice::<Value>(&out.stdout).expect("one JSON object")
    };
    // Nobody has that address: the object `send` prints for the same status request.
    let nobody = ["--to", "0013a200deadbeef", "--format", "json"];
    let failed = json(5, &[&["status"][..], &nobody, &["landing"]].concat());
    let sent = json(
        5,
        &[&["send"][..], &nobody, &["status", "landing"]].concat(),
    );
    assert_eq!(failed, sent);
    assert_eq!(
        (&failed["result"], &failed["delivery_name"]),
        (&"failed".into(), &"address_not_found".into()),
        "{failed}"
    );
    // No report in time: what was known, that the radio delivered the request.
    let timeout = status_timeout(&sim);
    assert_eq!(
        timeout,
        serde_json::json!({
            "result": "timeout",
            "dst64": MAV,
            "delivered": true,
            "mcp": {"category": "command", "type": "landing", "status_request": true},
        })
    );

    // Every frame to the ground station corrupted: the Transmit Status and the report
    // fail to decode, and the object says frames were lost meanwhile.
    let sim = Sim::start_with(
        &["--faults", "0000000000000000=corrupt=1"],
        "tcp-listen:127.0.0.1:0",
    );
    let timeout = status_timeout(&sim);
    assert_eq!(timeout["delivered"], false, "{timeout}");
    assert!(
        timeout["undecodable"].as_u64().is_some_and(|n| n >= 1),
        "{timeout}"
    );
}

#[test]
fn at_commands_and_api_mode_detection() {
    // The simulator's coordinator radio speaks API mode 2 here.
    let sim = Sim::start_with(&["--api-mode", "2"], "tcp-listen:127.0.0.1:0");
    let out = sim.ok(&["at", "--api-mode", "2", "AP"]);
    assert!(out.starts_with("AP = 02"), "{out}");
    let out = sim.ok(&["at", "--api-mode", "2", "NP"]);
    assert!(out.starts_with("NP = "), "{out}");
    let out = sim.ok(&["at", "--api-mode", "2", "--format", "json", "AP"]);
    let ap: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(
        (&ap["data"], &ap["value"]),
        (&"02".into(), &2.into()),
        "{out}"
    );
    // A command sent without a status, in JSON.
    let args = [
        "send",
        "--api-mode",
        "2",
        "--to",
        MAV,
        "--no-status",
        "--format",
        "json",
        "landing",
        "on",
    ];
    let sent: Value = serde_json::from_str(&sim.ok(&args)).unwrap();
    assert_eq!(
        (
            &sent["result"],
            &sent["id"],
            &sent["mcp"]["type"],
            &sent["mcp"]["on"]
        ),
        (
            &"written".into(),
            &0.into(),
            &"landing".into(),
            &true.into()
        ),
        "{sent}"
    );
    // `auto` asks the radio first and then talks in its mode. The MAV took the landing
    // command sent without a status, although that ground station had left before the
    // simulator served it.
    let report = sim.status_with(&["--api-mode", "auto"], &["landing"]);
    assert_eq!(report["state_name"], "landing");
    // An unknown AT command is refused by the radio: a clear error, bad input.
    let out = sim.gs(&["at", "--api-mode", "2", "ZZ"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("ZZ"),
        "{out:?}"
    );
}

#[test]
fn monitor_in_the_wrong_api_mode_says_so_over_tcp() {
    let sim = Sim::start_with(&["--api-mode", "2"], "tcp-listen:127.0.0.1:0");
    let out = sim.ok(&[
        "send",
        "--api-mode",
        "2",
        "--to",
        MAV,
        "telemetry",
        "on",
        "pitch_angle",
    ]);
    assert!(out.starts_with("delivered"), "{out}");
    let out = sim.gs(&["monitor", "--api-mode", "1", "--count", "20"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    // The radio's answer to AT AP, and the checksum errors of its escaped frames.
    assert!(
        stderr.contains("the radio is in API mode 2 (AP=2) but --api-mode is 1"),
        "{stderr}"
    );
    assert!(stderr.contains("try --api-mode 2"), "{stderr}");

    // A request that times out in the wrong mode says why it may have.
    let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args([
            "status",
            "--link",
            &sim.link,
            "--api-mode",
            "1",
            "--timeout",
            "1",
        ])
        .args(["--to", MAV, "landing"])
        .output()
        .expect("run mcp-gs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(4), "{stderr}");
    assert!(stderr.contains("try --api-mode 2"), "{stderr}");
    // The MAV answered, in frames that could not be read: no blame on the MAV.
    assert!(
        stderr.contains("frames from the radio could not be decoded meanwhile"),
        "{stderr}"
    );
    assert!(!stderr.contains("the MAV did not answer"), "{stderr}");
}

#[test]
fn a_status_request_the_radio_never_answers_points_at_the_api_mode() {
    // The simulator's radio in API mode 1; the request goes out escaped (mode 2), so
    // the radio reads no frame in it and never confirms delivery, while its modem
    // status (nothing to escape) came through.
    let sim = Sim::start("tcp-listen:127.0.0.1:0");
    let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args([
            "status",
            "--link",
            &sim.link,
            "--timeout",
            "1",
            "--api-mode",
            "2",
        ])
        .args(["--to", MAV, "landing"])
        .output()
        .expect("run mcp-gs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(4), "{stderr}");
    assert!(
        stderr.contains("the radio did not confirm delivery"),
        "{stderr}"
    );
    assert!(
        stderr.contains("if the radio is not in API mode 2 (AP=2)"),
        "{stderr}"
    );
}

#[cfg(unix)]
#[test]
fn api_mode_detection_over_a_serial_port() {
    // A serial port is opened for exclusive use: the link that asks the radio its mode
    // must have let go of the port before the link in that mode opens it.
    let sim = Sim::start_with(&["--api-mode", "2"], "pty");
    assert!(sim.link.starts_with("serial:/dev/"), "{}", sim.link);
    for _ in 0..3 {
        let report = sim.status_with(&["--api-mode", "auto"], &["landing"]);
        assert_eq!(report["state_name"], "flight");
    }
    // Closing the link that asked is no warning.
    let args = ["status", "--api-mode", "auto", "--to", MAV, "landing"];
    let out = succeeded(sim.gs(&args), &args);
    assert_eq!(String::from_utf8_lossy(&out.stderr), "");
}

#[test]
fn record_decode_and_replay() {
    let sim = Sim::start("tcp-listen:127.0.0.1:0");
    sim.send(&["telemetry", "on", "pitch_angle"]);
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("flight.mcprec");
    let file = file.to_str().unwrap();
    let live = sim.ok(&[
        "monitor", "--format", "json", "--count", "5", "--record", file,
    ]);
    let live: Vec<Value> = live
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();

    // The recording decodes to the same frames, with direction and time.
    let out = mcp_gs_ok(&["decode", file, "--format", "json"]);
    let decoded: Vec<Value> = String::from_utf8(out.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let live_frames: Vec<&Value> = live.iter().filter(|v| v.get("frame").is_some()).collect();
    assert_eq!(decoded.len(), live_frames.len());
    for (d, l) in decoded.iter().zip(&live_frames) {
        assert_eq!(d["direction"], "rx");
        assert_eq!(d["frame"], l["frame"]);
        assert_eq!(d["mcp"], l["mcp"]);
        // A packet is recorded at the time monitor printed for it: when received.
        if l["frame"] == "receive" {
            assert_eq!(d["time"], l["time"], "{d} {l}");
        }
    }
    // As text: the date first, then for each frame the time and `rx` once (packets say
    // it themselves, other frames get it in front).
    let out = mcp_gs_ok(&["decode", file]);
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.starts_with("-- "), "{text}");
    let lines: Vec<&str> = text.lines().filter(|l| !l.starts_with("-- ")).collect();
    assert_eq!(lines.len(), live_frames.len());
    let mut packets = 0;
    for line in lines {
        let (time, frame) = line.split_once(' ').unwrap();
        assert_eq!(time.len(), "12:00:00.000".len(), "{line}");
        assert!(
            frame.starts_with("rx ") && !frame.contains("rx rx"),
            "{line}"
        );
        packets += usize::from(frame.starts_with(&format!("rx  {MAV}/")));
    }
    assert!(packets > 0, "{text}");

    // Replayed as fast as possible onto a link, the same frames arrive.
    let (link, reader) = common::recording_peer();
    mcp_gs_ok(&["replay", file, "--link", &link, "--speed", "0"]);
    let wire = reader.join().unwrap();
    let mut decoder: xbee_api::Decoder = xbee_api::Decoder::new(xbee_api::ApiMode::Unescaped);
    let mut input = &wire[..];
    let mut frames = 0;
    loop {
        let (consumed, event) = decoder.decode(input);
        input = &input[consumed..];
        match event {
            Some(Ok(_)) => frames += 1,
            Some(Err(e)) => panic!("replayed a bad frame: {e}"),
            None => break,
        }
    }
    assert_eq!(frames, decoded.len());
}

#[test]
fn a_recording_keeps_each_frame_as_it_came() {
    use xbee_api::{Address16, Address64, ApiMode, EncodeFrame, ReceivePacketRepr};
    let explicit = common::explicit_rx(Address64(0x0013_A200_4000_0001), b"r\x03\x03");
    let plain = ReceivePacketRepr {
        src64: Address64(0x0013_A200_4000_0002),
        src16: Address16(0xFFFE),
        options: 0x01,
        data: b"mhello",
    };
    fn frame_data(frame: &impl EncodeFrame) -> Vec<u8> {
        let mut data = vec![0u8; frame.frame_data_len()];
        frame.emit_frame_data(&mut data).unwrap();
        data
    }
    let frames = vec![frame_data(&explicit), frame_data(&plain)];
    let mut wire = vec![0u8; 256];
    let mut n = explicit.encode(ApiMode::Unescaped, &mut wire).unwrap();
    n += plain.encode(ApiMode::Unescaped, &mut wire[n..]).unwrap();
    wire.truncate(n);

    // A radio on TCP that sends the two frames, then waits for the monitor to leave
    // (after the two packets; the link coming up is printed but not counted).
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", listener.local_addr().unwrap());
    let radio = std::thread::spawn(move || {
        let (mut socket, _) = listener.accept().unwrap();
        std::io::Write::write_all(&mut socket, &wire).unwrap();
        let _ = std::io::Read::read_to_end(&mut socket, &mut Vec::new());
    });
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("frames.mcprec");
    mcp_gs_ok(&[
        "monitor",
        "--link",
        &link,
        "--api-mode",
        "1",
        "--count",
        "2",
        "--format",
        "json",
        "--record",
        file.to_str().unwrap(),
    ]);
    radio.join().unwrap();

    let mut reader =
        mcp_host::record::RecordReader::new(std::fs::File::open(&file).unwrap()).unwrap();
    let mut recorded = Vec::new();
    while let Some(record) = reader.next_record().unwrap() {
        assert_eq!(record.direction, mcp_host::record::Direction::Received);
        recorded.push(record.frame);
    }
    // The Explicit Rx Indicator stays one (0x91, with its endpoints and cluster).
    assert_eq!(recorded, frames);
    assert_eq!(recorded[0][0], 0x91);

    // Read back, the recording shows the MCP packet of each as monitor showed it.
    let path = file.to_str().unwrap();
    let text = String::from_utf8(mcp_gs_ok(&["decode", path]).stdout).unwrap();
    assert!(
        text.contains("explicit rx 0013a20040000001/")
            && !text.contains("rx explicit rx")
            && text.contains(": report controllers mpc")
            && text.contains("message \"hello\""),
        "{text}"
    );
    let json = String::from_utf8(mcp_gs_ok(&["decode", path, "--format", "json"]).stdout).unwrap();
    let first: serde_json::Value = serde_json::from_str(json.lines().next().unwrap()).unwrap();
    assert_eq!(first["frame"], "explicit_receive");
    assert_eq!(first["data"], "720303");
    assert_eq!(first["mcp"]["category"], "report", "{first}");
    let summary = String::from_utf8(mcp_gs_ok(&["decode", path, "--summary"]).stdout).unwrap();
    assert!(
        summary.contains("mcp packets:\n  message: 1\n  report: 1\n"),
        "{summary}"
    );
}

#[cfg(unix)]
#[test]
fn a_port_another_program_holds_is_named_as_busy() {
    let sim = Sim::start("pty");
    let (monitor, rx) = spawn_lines(&["monitor", "--link", &sim.link]);
    let _monitor = common::Running(monitor);
    // Its first line (after the date) is printed once it has the port.
    let date = rx.recv_timeout(GUARD).expect("monitor prints a line");
    assert!(date.starts_with("-- "), "{date}");
    let first = rx.recv_timeout(GUARD).expect("monitor prints a line");
    assert!(first.contains("connected"), "{first}");
    let out = sim.gs(&["send", "--to", MAV, "landing", "on"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    assert!(
        stderr.contains("another program has the port open")
            && stderr.contains("stop the other (a hub, say: setup and probe need the port itself)"),
        "{stderr}"
    );
    // A hub is not told to let a hub hold the port: whether its mode is given or asked
    // of the radio (the port opened first for that).
    for args in [
        &["hub", "--link", &sim.link, "--listen", "127.0.0.1:0"][..],
        &[
            "hub",
            "--link",
            &sim.link,
            "--listen",
            "127.0.0.1:0",
            "--api-mode",
            "auto",
        ],
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
            .args(args)
            .output()
            .expect("run mcp-gs");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(3), "{args:?}: {stderr}");
        assert!(
            stderr.contains("another program has the port open")
                && stderr
                    .contains("one program at a time can use a serial port: stop the other first")
                && !stderr.contains("hold it"),
            "{args:?}: {stderr}"
        );
        assert!(
            stderr.contains("a hub that holds it already shares it"),
            "{args:?}: {stderr}"
        );
    }
}

#[test]
fn send_trajectory_checks_the_mavs_report() {
    // The deployed MAV's 60-byte receive buffer takes two waypoints, not three.
    let sim = Sim::start_with(&["--rx-buffer", "60"], "tcp-listen:127.0.0.1:0");
    let waypoint = |i: u32| format!("{},0.5,-0.25,{i}", 1_763_683_300 + i);
    let (w1, w2, w3) = (waypoint(1), waypoint(2), waypoint(3));
    let two = [
        "send",
        "--to",
        MAV,
        "trajectory",
        "--waypoint",
        &w1,
        "--waypoint",
        &w2,
    ];
    let out = succeeded(sim.gs(&two), &two);
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(
        stdout.contains("the MAV reports the trajectory as sent"),
        "{stdout}"
    );
    assert_eq!(String::from_utf8_lossy(&out.stderr), "");
    // In JSON: one object, delivery and check together.
    let json = [&two[..], &["--format", "json"]].concat();
    let out = succeeded(sim.gs(&json), &json);
    let object: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (
            &object["result"],
            &object["dst64"],
            &object["trajectory_confirmed"],
            &object["mcp"]["type"]
        ),
        (
            &"delivered".into(),
            &MAV.into(),
            &true.into(),
            &"trajectory_set".into()
        ),
        "{object}"
    );
    assert!(
        object["retries"].is_u64() && object["id"].as_u64() > Some(0),
        "{object}"
    );
    assert_eq!(object["delivery_name"], "success", "{object}");
    // `result` first, as in the README and as a failure has it.
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.starts_with("{\"result\":\"delivered\","), "{text}");

    let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["send", "--link", &sim.link, "--timeout", "1", "--to", MAV])
        .args([
            "trajectory",
            "--waypoint",
            &w1,
            "--waypoint",
            &w2,
            "--waypoint",
            &w3,
        ])
        .output()
        .expect("run mcp-gs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("drops frames over 60 bytes"), "{stderr}");
    assert!(stderr.contains("no trajectory report"), "{stderr}");
    assert_eq!(out.status.code(), Some(4), "{stderr}");
    // In JSON: delivered, but not confirmed, and no trajectory reported meanwhile.
    let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["send", "--link", &sim.link, "--timeout", "1", "--to", MAV])
        .args(["--format", "json", "trajectory", "--waypoint", &w1])
        .args(["--waypoint", &w2, "--waypoint", &w3])
        .output()
        .expect("run mcp-gs");
    let object: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (
            &object["result"],
            &object["trajectory_confirmed"],
            object.get("trajectory_reported")
        ),
        (&"delivered".into(), &false.into(), Some(&Value::Null)),
        "{object}"
    );
    assert_eq!(out.status.code(), Some(4), "{object}");
    // The MAV kept the two waypoints it took before.
    let report = sim.status(&["trajectory"]);
    assert_eq!(report["waypoints"].as_array().unwrap().len(), 2, "{report}");

    // A status request sent with `send` points to `status`, which prints the report.
    let args = ["send", "--to", MAV, "status", "landing"];
    let out = succeeded(sim.gs(&args), &args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("`mcp-gs status` waits for it"), "{stderr}");
}

#[cfg(unix)]
#[test]
fn a_hub_lets_monitor_and_send_share_the_radio() {
    let sim = Sim::start_with(&["--api-mode", "2"], "pty");
    let (hub, hub_out) = spawn_lines(&[
        "hub",
        "--link",
        &sim.link,
        "--api-mode",
        "2",
        "--listen",
        "127.0.0.1:0",
    ]);
    let first = hub_out.recv_timeout(GUARD).expect("hub prints its address");
    // With the API mode the other commands need.
    assert!(first.contains("--api-mode 2"), "{first}");
    let link = first
        .split("--link ")
        .nth(1)
        .and_then(|rest| rest.split_whitespace().next())
        .unwrap_or_else(|| panic!("{first}"))
        .to_string();
    let _hub = common::Running(hub);
    let (monitor, lines) = spawn_lines(&[
        "monitor",
        "--link",
        &link,
        "--api-mode",
        "2",
        "--format",
        "json",
    ]);
    let _monitor = common::Running(monitor);
    let first = lines.recv_timeout(GUARD).expect("monitor connects");
    assert!(first.contains("connected"), "{first}");
    // While monitor has the hub, send and status go through it too.
    let gs = |args: &[&str]| {
        let (sub, rest) = args.split_first().unwrap();
        let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
            .args([sub, "--link", &link, "--api-mode", "2"])
            .args(rest)
            .output()
            .expect("run mcp-gs");
        String::from_utf8(succeeded(out, args).stdout).unwrap()
    };
    let sent = gs(&["send", "--to", MAV, "telemetry", "on", "pitch_angle"]);
    assert!(sent.starts_with("delivered"), "{sent}");
    let report = gs(&["status", "--to", MAV, "landing"]);
    assert!(report.contains("landing"), "{report}");
    // The telemetry the send turned on reaches the monitor.
    let telemetry = loop {
        let line = lines.recv_timeout(GUARD).expect("telemetry on the monitor");
        if line.contains("\"telemetry\"") {
            break line;
        }
    };
    assert!(telemetry.contains("pitch_angle"), "{telemetry}");

    // Ground stations setting trajectories at once each find the MAV's report of their
    // own among the others'.
    std::thread::scope(|scope| {
        let sends: Vec<_> = (1..=4)
            .map(|i| {
                let gs = &gs;
                scope.spawn(move || {
                    let (w1, w2) = (format!("{i},0.5,0,{i}"), format!("{},0,0.5,1", i + 10));
                    gs(&[
                        "send",
                        "--to",
                        MAV,
                        "trajectory",
                        "--waypoint",
                        &w1,
                        "--waypoint",
                        &w2,
                    ])
                })
            })
            .collect();
        for send in sends {
            let out = send.join().unwrap();
            assert!(
                out.contains("the MAV reports the trajectory as sent"),
                "{out}"
            );
        }
    });
}

#[test]
fn telemetry_to_a_ground_station_gone_is_said_once() {
    // The MAV sends telemetry on after the command's ground station left: every frame
    // to the coordinator fails, which the simulator says once, not every five seconds.
    let (mut sim, lines) =
        spawn_lines(&["sim", "--link", "tcp-listen:127.0.0.1:0", "--duration", "8"]);
    let link = loop {
        let line = lines.recv_timeout(GUARD).expect("sim prints its link");
        if let Some(rest) = line.split("(connect with ").nth(1) {
            break rest.split(')').next().unwrap().to_string();
        }
    };
    succeeded(
        Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
            .args(["send", "--link", &link, "--to", MAV])
            .args(["telemetry", "on", "altitude"])
            .output()
            .expect("run mcp-gs"),
        &["send", "telemetry", "on"],
    );
    // Until the simulator's --duration ends it.
    let mut said = Vec::new();
    loop {
        match lines.recv_timeout(GUARD) {
            Ok(line) if line.contains("not delivered") => said.push(line),
            Ok(_) => {}
            Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => break,
            Err(timeout) => {
                let _ = sim.kill();
                panic!("the simulator ran past its --duration: {timeout}");
            }
        }
    }
    assert_eq!(said.len(), 1, "{said:#?}");
    assert!(
        said[0].contains(&format!(
            "{MAV} -> 0000000000000000: not delivered while 0000000000000000's link is down"
        )),
        "{said:#?}"
    );
    assert!(sim.wait().unwrap().success());
}

#[test]
fn send_confirm_asks_the_mav_and_fails_unless_its_report_shows_the_command_taken() {
    let sim = Sim::start("tcp-listen:127.0.0.1:0");
    let confirm = |command: &[&str], format: &str| {
        let args = [
            &["send", "--to", MAV, "--confirm", "--format", format],
            command,
        ]
        .concat();
        sim.gs(&args)
    };
    // The MAV takes the command: the report says so.
    let out = confirm(&["controller", "mpc"], "text");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    let lines: Vec<&str> = stdout.lines().collect();
    assert!(
        lines[0].starts_with(&format!("delivered to {MAV}/")),
        "{stdout}"
    );
    assert_eq!(
        lines[1..],
        ["confirmed: report controllers mpc"],
        "{stdout}"
    );
    // In JSON: one object, the delivery, `confirmed` and the report.
    let out = confirm(&["landing", "on"], "json");
    assert_eq!(out.status.code(), Some(0));
    let object: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (
            &object["result"],
            &object["confirmed"],
            &object["reported"]["type"],
            &object["reported"]["state_name"]
        ),
        (
            &"delivered".into(),
            &true.into(),
            &"landing".into(),
            &"landing".into()
        ),
        "{object}"
    );
    // A trajectory with --confirm: confirmed by a status request too, said as the others.
    let out = confirm(&["trajectory", "--waypoint", "1800000000,0.5,0,1"], "json");
    assert_eq!(out.status.code(), Some(0));
    let object: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (&object["confirmed"], &object["reported"]["type"]),
        (&true.into(), &"trajectory_set".into()),
        "{object}"
    );
    // A controller the MAV does not have: delivered, not taken (exit 1), and the report
    // says which is active.
    let out = confirm(&["controller", "9"], "json");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("the MAV did not take the command: it reports controllers mpc"),
        "{stderr}"
    );
    let object: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (
            &object["result"],
            &object["confirmed"],
            &object["reported"]["controller_name"]
        ),
        (&"delivered".into(), &false.into(), &"mpc".into()),
        "{object}"
    );
    // What cannot be confirmed is refused before anything is sent (exit 2).
    for (command, said) in [
        (
            &["position-set", "0.5", "0.5"][..],
            "a position_set command cannot be confirmed",
        ),
        (
            &["status", "landing"][..],
            "a status request is not confirmed",
        ),
        (
            &["message", "hello"][..],
            "a message or another packet cannot be confirmed",
        ),
    ] {
        let out = confirm(command, "text");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{command:?}: {stderr}");
        assert!(stderr.contains(said), "{command:?}: {stderr}");
        assert_eq!(String::from_utf8_lossy(&out.stdout), "", "{command:?}");
    }
    let args = [
        "send",
        "--to",
        "000000000000ffff",
        "--confirm",
        "landing",
        "on",
    ];
    let out = sim.gs(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("send the command to each MAV's address"),
        "{stderr}"
    );
    // Fire and forget cannot be confirmed: a usage error.
    let args = [
        "send",
        "--to",
        MAV,
        "--confirm",
        "--no-status",
        "landing",
        "on",
    ];
    let out = sim.gs(&args);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot be used with"));
}
