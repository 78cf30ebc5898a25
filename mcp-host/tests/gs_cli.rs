//! The `mcp-gs` binary: decode, encode, argument errors and exit codes.

use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};

use serde_json::Value;

mod common;

fn gs() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
}

fn testdata(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../testdata")
        .join(name)
}

fn run(args: &[&str]) -> Output {
    gs().args(args).output().expect("mcp-gs runs")
}

fn stdout(output: &Output) -> String {
    assert!(
        output.status.success(),
        "mcp-gs failed: {}\n{}",
        output.status,
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8(output.stdout.clone()).expect("utf-8 output")
}

/// `expected` is contained in `got`: same values for its keys (floats the same as f32,
/// or within 1e-6 relative), extra keys in `got` allowed.
fn assert_subset(got: &Value, expected: &Value, path: &str) {
    match (got, expected) {
        (Value::Object(g), Value::Object(e)) => {
            for (key, value) in e {
                let Some(got) = g.get(key) else {
                    panic!("{path}.{key} missing in {got:?}")
                };
                assert_subset(got, value, &format!("{path}.{key}"));
            }
        }
        (Value::Array(g), Value::Array(e)) => {
            assert_eq!(g.len(), e.len(), "{path}: array lengths");
            for (i, (g, e)) in g.iter().zip(e).enumerate() {
                assert_subset(g, e, &format!("{path}[{i}]"));
            }
        }
        (Value::Number(g), Value::Number(e)) if e.is_f64() => {
            let (g, e) = (g.as_f64().unwrap(), e.as_f64().unwrap());
            // The vectors' rule: within 1e-6, relative.
            assert!((g - e).abs() <= 1e-6 * e.abs(), "{path}: {g} != {e}");
        }
        _ => assert_eq!(got, expected, "{path}"),
    }
}

fn check_decode_json(stream: &str, expected: &str, mode: &str) {
    let out = stdout(&run(&[
        "decode",
        testdata(stream).to_str().unwrap(),
        "--api-mode",
        mode,
        "--format",
        "json",
    ]));
    let got = json_lines(&out);
    let expected = json_lines(&std::fs::read_to_string(testdata(expected)).unwrap());
    assert_eq!(got.len(), expected.len(), "number of frames");
    for (i, (g, e)) in got.iter().zip(&expected).enumerate() {
        assert_subset(g, e, &format!("frame {i}"));
    }
}

#[test]
fn decode_json_of_mode_1_stream_matches_expected() {
    check_decode_json("ap1.bin", "ap1.expected.jsonl", "1");
}

#[test]
fn decode_json_of_mode_2_stream_matches_expected() {
    check_decode_json("ap2.bin", "ap2.expected.jsonl", "2");
}

#[test]
fn decode_names_ids_and_escapes_text() {
    // Receive Packet holding a telemetry record (altitude = 1.5) and one holding a
    // message with a byte >= 0x80.
    let hex = "7E 00 12 90 00 13 A2 00 40 52 2B AA 7D 84 01 74 01 00 00 C0 3F DD\n\
               7E 00 0F 90 00 13 A2 00 40 52 2B AA 7D 84 01 6D 68 E9 93\n";
    let out = decode_hex(hex, "json");
    let lines = json_lines(&out);
    assert_eq!(lines.len(), 2, "{out}");
    assert_eq!(
        lines[0]["mcp"],
        serde_json::json!({"category": "telemetry", "values": [{"id": 1, "name": "altitude", "value": 1.5}]})
    );
    assert_eq!(lines[1]["mcp"]["text"], "h\\xe9");
}

/// Each line of `out` as JSON.
fn json_lines(out: &str) -> Vec<Value> {
    out.lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// `mcp-gs decode --hex` of `hex` in `format`.
fn decode_hex(hex: &str, format: &str) -> String {
    let mut child = gs()
        .args(["decode", "--hex", "--format", format])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(hex.as_bytes())
        .unwrap();
    stdout(&child.wait_with_output().unwrap())
}

#[test]
fn decode_tells_queued_at_commands_apart() {
    // Digi's manual: BD = 7 queued (0x09), then NJ queried (0x08).
    let hex = "7E 00 05 09 01 42 44 07 68 7E 00 04 08 52 4E 4A 0D";
    assert_eq!(
        decode_hex(hex, "text"),
        "at queued id 1 BD 07\nat id 82 NJ\n"
    );
    let json = json_lines(&decode_hex(hex, "json"));
    assert_eq!(json.len(), 2);
    assert_eq!(json[0]["queued"], true);
    assert_eq!(json[0]["command"], "BD");
    assert_eq!(json[1].get("queued"), None);
}

#[test]
fn decode_reads_a_node_identification() {
    // Digi's manual: router 0013A20040522BAA, NI " ", announces itself (its
    // commissioning button was pressed).
    let hex = "7E 00 20 95 00 13 A2 00 40 52 2B AA 7D 84 02 7D 84 00 13 A2 00 40 52 2B AA \
               20 00 FF FE 01 01 C1 05 10 1E 1B";
    assert_eq!(
        decode_hex(hex, "text"),
        "node identification 0013a20040522baa/7d84 router \" \" parent fffe: pushbutton \
         (0x01), from 0013a20040522baa/7d84 opt 02\n"
    );
    let json = json_lines(&decode_hex(hex, "json"));
    assert_eq!(
        json,
        [serde_json::json!({
            "frame": "node_identification",
            "src64": "0013a20040522baa", "src16": "7d84", "options": 2,
            "addr64": "0013a20040522baa", "addr16": "7d84", "identifier": " ",
            "parent": "fffe", "device_type": 1, "device_type_name": "router",
            "event": 1, "event_name": "pushbutton",
            "profile": 0xC105, "manufacturer": 0x101E,
        })]
    );
    // An identifier byte that is no printable ASCII is kept, as `\xNN`, as in a message.
    let hex = "7E 00 20 95 00 13 A2 00 40 52 2B AA 7D 84 02 7D 84 00 13 A2 00 40 52 2B AA \
               E9 00 FF FE 01 01 C1 05 10 1E 52";
    assert!(decode_hex(hex, "text").contains(r#"router "\xe9" parent"#));
    assert_eq!(
        json_lines(&decode_hex(hex, "json"))[0]["identifier"],
        r"\xe9"
    );
}

#[test]
fn decode_reports_bad_frames_and_goes_on() {
    // A frame with a wrong checksum between two good modem status frames.
    let stream = [
        0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F, // good
        0x7E, 0x00, 0x02, 0x8A, 0x06, 0x00, // bad checksum
        0x7E, 0x00, 0x02, 0x8A, 0x02, 0x73, // good
    ];
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.bin");
    std::fs::write(&path, stream).unwrap();
    let out = stdout(&run(&[
        "decode",
        path.to_str().unwrap(),
        "--format",
        "json",
    ]));
    let lines = json_lines(&out);
    assert_eq!(lines.len(), 3, "{out}");
    assert_eq!(
        lines[0],
        serde_json::json!({"frame": "modem_status", "status": 6, "status_name": "coordinator_started"})
    );
    assert_eq!(lines[1]["error"], "checksum");
    assert_eq!(lines[1]["offset"], 12);
    assert_eq!(
        lines[2],
        serde_json::json!({"frame": "modem_status", "status": 2, "status_name": "joined_network"})
    );

    let text = stdout(&run(&["decode", path.to_str().unwrap()]));
    assert_eq!(text.lines().count(), 3, "{text}");
    assert!(
        text.lines()
            .nth(1)
            .unwrap()
            .starts_with("error, found at input offset 12: bad checksum"),
        "{text}"
    );
}

#[test]
fn decode_summary_counts() {
    let out = stdout(&run(&[
        "decode",
        testdata("ap2.bin").to_str().unwrap(),
        "--api-mode",
        "2",
        "--summary",
        "--format",
        "json",
    ]));
    let summary: Value = serde_json::from_str(out.trim()).unwrap();
    let expected = std::fs::read_to_string(testdata("ap2.expected.jsonl")).unwrap();
    let frames = expected.lines().count() as u64;
    let telemetry = expected
        .lines()
        .filter(|l| l.contains(r#""category": "telemetry""#))
        .count() as u64;
    assert_eq!(summary["frames"], frames);
    assert_eq!(summary["mcp"]["telemetry"], telemetry);
    assert_eq!(summary["errors"]["checksum"], 0);
}

/// Digi's manual: Transmit Request of "TxData0A" to 0013A200400A0127, frame id 1.
#[test]
fn encode_gives_digi_manual_bytes() {
    let lines: Vec<String> = std::fs::read_to_string(testdata("digi-manual.txt"))
        .unwrap()
        .lines()
        .filter(|l| l.starts_with("10 "))
        .map(|l| l[5..].trim().to_string())
        .collect();
    assert_eq!(lines.len(), 2);
    for (mode, expected) in ["1", "2"].iter().zip(&lines) {
        let out = stdout(&run(&[
            "encode",
            "--to",
            "0013A200400A0127",
            "--frame-id",
            "1",
            "--api-mode",
            mode,
            "raw",
            "5478446174613041",
        ]));
        assert_eq!(out.trim(), expected, "mode {mode}");
    }
}

#[test]
fn encode_every_command() {
    let to = "0013A20040B599B9";
    let cases: &[(&[&str], &str)] = &[
        (&["telemetry", "on", "altitude"], "63 01 01 01"),
        (&["telemetry", "off", "0x11"], "63 01 00 11"),
        (&["landing", "on"], "63 02 01"),
        (&["controller", "mpc"], "63 03 03"),
        (&["controller", "2"], "63 03 02"),
        (
            &["trajectory", "--waypoint", "1700000000,1.5,-2.25,3"],
            "63 04 01 00 F1 53 65 00 00 C0 3F 00 00 10 C0 00 00 40 40",
        ),
        (
            &["slave-set", "0013A20040B599BF"],
            "63 05 00 13 A2 00 40 B5 99 BF",
        ),
        (
            &["slave-set", "0013A20040B599BF", "--slot", "2"],
            "63 05 02 00 13 A2 00 40 B5 99 BF",
        ),
        (&["time", "1763683200"], "63 06 80 AB 1F 69"),
        (
            &["position-set", "-1.5", "2"],
            "63 07 00 00 C0 BF 00 00 00 40",
        ),
        (&["status", "landing"], "63 02 FF"),
        (
            &["status", "telemetry_to_coordinator", "pitch_angle"],
            "63 01 FF 19",
        ),
        (&["message", "Hi"], "6D 48 69"),
        // The words of `send`'s commands name status requests too; on/off in any case.
        (&["status", "controller"], "63 03 FF"),
        (&["status", "trajectory"], "63 04 FF"),
        (&["status", "slave-set"], "63 05 FF"),
        (&["status", "telemetry", "altitude"], "63 01 FF 01"),
        (&["landing", "ON"], "63 02 01"),
    ];
    for (args, payload) in cases {
        let mut argv = vec!["encode", "--to", to, "--frame-id", "0"];
        argv.extend_from_slice(args);
        let out = stdout(&run(&argv));
        let bytes: Vec<&str> = out.split_whitespace().collect();
        // 7E, length (2), 10, id, 8 + 2 address bytes, radius, options, payload, checksum.
        let got = bytes[17..bytes.len() - 1].join(" ");
        assert_eq!(got, *payload, "{args:?}");
        let len = usize::from_str_radix(&(bytes[1].to_string() + bytes[2]), 16).unwrap();
        assert_eq!(len, bytes.len() - 4, "{args:?}: length field");
    }
    // An address as XCTU shows it, SH and SL apart, is the same address.
    let xctu = stdout(&run(&[
        "encode",
        "--to",
        "0013A200 40B599B9",
        "landing",
        "on",
    ]));
    assert_eq!(xctu, stdout(&run(&["encode", "--to", to, "landing", "on"])));
    // Frame id, options and radius take 0x-hex as every byte on the command line does.
    let out = stdout(&run(&[
        "encode",
        "--to",
        to,
        "--frame-id",
        "0x11",
        "--options",
        "0x01",
        "--radius",
        "0x02",
        "landing",
        "on",
    ]));
    let bytes: Vec<&str> = out.split_whitespace().collect();
    assert_eq!(bytes[4], "11", "{out}");
    assert_eq!(bytes[15..17], ["02", "01"], "{out}");
}

#[test]
fn bad_arguments_exit_2_with_one_line() {
    for args in [
        &["encode", "--to", "xyz", "landing", "on"][..],
        // A 64-bit address is all 16 digits: one left out is not another address.
        &["encode", "--to", "0013a20040b599", "landing", "on"],
        &["encode", "--to", "ffff", "landing", "on"],
        &[
            "encode",
            "--to",
            "0013a20040b599b9",
            "slave-set",
            "0013a200",
        ],
        &["encode", "--to", "0013a20040b599b9", "controller", "fast"],
        &[
            "encode",
            "--to",
            "0013a20040b599b9",
            "trajectory",
            "--waypoint",
            "1,2,3",
        ],
        &[
            "encode",
            "--to",
            "0013a20040b599b9",
            "status",
            "position_set",
        ],
        &[
            "encode",
            "--to",
            "0013a20040b599b9",
            "status",
            "telemetry_to_coordinator",
        ],
        &["decode", "/nonexistent/capture.bin"],
        &["monitor", "--link", "tcp:127.0.0.1:9", "--record", "/"],
        // `status` prints one MAV's report: a broadcast would print the first of many.
        &[
            "status",
            "--link",
            "tcp:127.0.0.1:9",
            "--to",
            "000000000000ffff",
            "landing",
        ],
        // A one-shot subcommand on a new pseudo-terminal would wait for nobody.
        &[
            "send",
            "--link",
            "pty",
            "--to",
            "0013a20040b599b9",
            "landing",
            "on",
        ],
        &["decode", "--api-mode", "3", "-"],
        // A window gathers a broadcast's answers: one radio's would be ignored.
        &["at", "--link", "tcp:127.0.0.1:9", "--window", "5", "NI"],
        // Past what a clock can add (it used to panic).
        &["demo", "--duration", "1e300"],
        // No position a MAV can fly to (`raw` sends any bytes).
        &[
            "encode",
            "--to",
            "0013a20040b599b9",
            "position-set",
            "nan",
            "0",
        ],
        &[
            "encode",
            "--to",
            "0013a20040b599b9",
            "position-set",
            "0",
            "inf",
        ],
        &[
            "encode",
            "--to",
            "0013a20040b599b9",
            "trajectory",
            "--waypoint",
            "1,0,-inf,2",
        ],
        &[
            "encode",
            "--to",
            "0013a20040b599b9",
            "--frame-id",
            "0x100",
            "landing",
            "on",
        ],
        &["monitor", "--link", "tcp:127.0.0.1:9", "--count", "0"],
        &[
            "status",
            "--link",
            "tcp:127.0.0.1:9",
            "--to",
            "0013a20040b599b9",
            "position_set",
        ],
        &[
            "send",
            "--link",
            "bogus:thing",
            "--to",
            "0013a20040b599b9",
            "landing",
            "on",
        ],
    ] {
        let output = run(args);
        assert_eq!(output.status.code(), Some(2), "{args:?}");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(!stderr.trim().is_empty(), "{args:?}: no message");
        assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    }
}

#[test]
fn a_bad_16_bit_address_says_what_one_looks_like() {
    let encode = |to16: &str| {
        run(&[
            "encode",
            "--to",
            "0013a20040b599b9",
            "--to16",
            to16,
            "landing",
            "on",
        ])
    };
    for (to16, why) in [
        ("zz", "invalid hex digit at byte 0"),
        ("12345", "5 hex digits"),
        ("", "empty"),
    ] {
        let output = encode(to16);
        assert_eq!(output.status.code(), Some(2), "{to16:?}");
        let stderr = String::from_utf8_lossy(&output.stderr);
        let first = stderr.lines().next().unwrap_or_default();
        assert!(
            first.contains(&format!(
                "bad 16-bit address `{to16}` (1 to 4 hex digits, e.g. fffe"
            )) && first.contains(why),
            "{first}"
        );
    }
    // Any case, with or without `0x`.
    for to16 in ["0x0000", "FFFE", "1a2"] {
        let output = encode(to16);
        assert_eq!(output.status.code(), Some(0), "{to16:?}: {output:?}");
    }
}

#[cfg(unix)]
#[test]
fn missing_device_exits_3() {
    let send = |link: &str| {
        run(&[
            "send",
            "--link",
            link,
            "--to",
            "0013A20040B599B9",
            "landing",
            "on",
        ])
    };
    let output = send("serial:/dev/mcp-gs-test-no-such-device");
    assert_eq!(output.status.code(), Some(3));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("/dev/mcp-gs-test-no-such-device"),
        "{stderr}"
    );
    assert!(stderr.contains("`mcp-gs ports` lists"), "{stderr}");
    // A baud rate that is not digits is part of the path: the hint says so when the path
    // without it exists (a pseudo-terminal's far end here).
    let (_terminal, far) = serialport::TTYPort::pair().expect("pseudo-terminal");
    let device = serialport::SerialPort::name(&far).expect("far end's path");
    let output = send(&format!("serial:{device}:9600baud"));
    assert_eq!(output.status.code(), Some(3));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains(&format!(
            "`9600baud` was read as part of the path: a baud rate is digits alone, as in \
             serial:{device}:9600"
        )),
        "{stderr}"
    );
    // Nothing listening on a TCP port: said so.
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", listener.local_addr().unwrap());
    drop(listener);
    let output = send(&link);
    assert_eq!(output.status.code(), Some(3));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("nothing listens there"), "{stderr}");
    // The address once, as the error says it.
    let addr = link.trim_start_matches("tcp:");
    assert!(
        stderr.starts_with(&format!("mcp-gs: cannot connect to {addr}: ")),
        "{stderr}"
    );
}

#[test]
fn status_timeout_exits_4() {
    // A peer that reads every request but never answers.
    let (link, peer) = common::silent_peer(1);
    let output = run(&[
        "status",
        "--link",
        &link,
        "--to",
        "0013A20040B599B9",
        "--timeout",
        "0.5",
        "landing",
    ]);
    assert_eq!(output.status.code(), Some(4));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("no ") && stderr.contains("within"),
        "{stderr}"
    );
    // Nothing at all came back: what keeps a radio silent.
    assert!(
        stderr.contains("nothing at all came from the radio"),
        "{stderr}"
    );
    // Over TCP, the peer may be serving another connection.
    assert!(stderr.contains("serves another connection"), "{stderr}");
    peer.join().unwrap();
}

#[test]
fn send_status_and_at_in_json_print_a_timeout_object() {
    // A peer that reads every request but never answers: no transmit status, no report.
    let (link, peer) = common::silent_peer(4);
    let json = |sub: &str, args: &[&str]| {
        let options = ["--link", &link, "--timeout", "0.5", "--format", "json"];
        let output = run(&[&[sub][..], &options, args].concat());
        assert_eq!(output.status.code(), Some(4), "{sub} {args:?}: {output:?}");
        serde_json::from_slice::<Value>(&output.stdout).expect("one JSON object")
    };
    let sent = json("send", &["--to", "0013A20040B599B9", "landing", "on"]);
    assert_eq!(
        sent,
        serde_json::json!({
            "result": "timeout",
            "dst64": "0013a20040b599b9",
            "id": 1,
            "delivered": false,
            "mcp": {"category": "command", "type": "landing", "on": true},
        })
    );
    let asked = json("status", &["--to", "0013A20040B599B9", "landing"]);
    assert_eq!(
        asked,
        serde_json::json!({
            "result": "timeout",
            "dst64": "0013a20040b599b9",
            "delivered": false,
            "mcp": {"category": "command", "type": "landing", "status_request": true},
        })
    );
    let local = json("at", &["NI"]);
    assert_eq!(
        local,
        serde_json::json!({"result": "timeout", "command": "NI", "id": 1})
    );
    let remote = json("at", &["--to", "0013A20040B599B9", "NI"]);
    assert_eq!(
        remote,
        serde_json::json!({
            "result": "timeout",
            "command": "NI",
            "dst64": "0013a20040b599b9",
            "id": 1,
        })
    );
    peer.join().unwrap();
}

/// `mcp-gs SUB --link LINK --format json ARGS...` that fails on its link (exit 3),
/// printing one object of `result` with a `reason`: the object, and standard error.
fn json_link_failure(link: &str, result: &str, sub: &str, args: &[&str]) -> (Value, String) {
    let options = ["--link", link, "--format", "json"];
    let output = run(&[&[sub][..], &options, args].concat());
    assert_eq!(output.status.code(), Some(3), "{sub} {args:?}: {output:?}");
    let json: Value = serde_json::from_slice(&output.stdout).expect("one JSON object");
    assert_eq!(json["result"], result, "{json}");
    assert!(json["reason"].is_string(), "{json}");
    (json, String::from_utf8_lossy(&output.stderr).into_owned())
}

/// That `send` and `status` name their request in their JSON failure (`json` runs one).
fn send_and_status_name_their_request(json: impl Fn(&str, &[&str]) -> Value) {
    let sent = json("send", &["--to", "0013A20040B599B9", "landing", "on"]);
    assert_eq!(sent["dst64"], "0013a20040b599b9");
    assert_eq!(sent["mcp"]["type"], "landing");
    let asked = json("status", &["--to", "0013A20040B599B9", "landing"]);
    assert_eq!(asked["mcp"]["status_request"], true);
}

#[test]
fn send_status_and_at_in_json_print_a_link_lost_meanwhile() {
    // A peer that takes each request and hangs up before it answers.
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", listener.local_addr().unwrap());
    let peer = std::thread::spawn(move || {
        for stream in listener.incoming().take(5) {
            let mut stream = stream.unwrap();
            let mut byte = [0u8];
            std::io::Read::read_exact(&mut stream, &mut byte).unwrap();
        }
    });
    let json = |sub: &str, args: &[&str]| json_link_failure(&link, "disconnected", sub, args).0;
    send_and_status_name_their_request(json);
    let at = json("at", &["NI"]);
    assert_eq!(at["command"], "NI");
    let all = json("at", &["--to", "000000000000ffff", "NI"]);
    assert_eq!(all["dst64"], "000000000000ffff");
    let nodes = json("nodes", &[]);
    assert_eq!(nodes["command"], "ND");
    peer.join().unwrap();
}

#[test]
fn send_status_and_at_in_json_print_a_request_never_sent_when_the_link_does_not_open() {
    // A port nothing listens on: the link is refused before anything is sent.
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", listener.local_addr().unwrap());
    drop(listener);
    let json = |sub: &str, args: &[&str]| {
        let (json, stderr) = json_link_failure(&link, "not_sent", sub, args);
        // The reason, as standard error's first line says it, without its hints.
        let reason = json["reason"].as_str().expect("a reason");
        assert!(reason.starts_with("cannot connect to "), "{json}");
        assert!(
            stderr.contains(reason) && !reason.contains('\n'),
            "{stderr}"
        );
        json
    };
    send_and_status_name_their_request(json);
    let at = json("at", &["NI"]);
    assert_eq!(at["command"], "NI");
    assert!(at.get("dst64").is_none(), "{at}");
    let remote = json("at", &["--to", "0013A20040B599B9", "NI"]);
    assert_eq!(remote["dst64"], "0013a20040b599b9");
    let nodes = json("nodes", &[]);
    assert_eq!(nodes["command"], "ND");
}

#[test]
fn a_broadcast_nobody_answers_says_so_and_what_keeps_the_radio_silent() {
    // A peer that reads every request but never answers, as a radio in the other API
    // mode would not.
    let (link, peer) = common::silent_peer(2);
    let options = ["--link", &link, "--window", "0.5"];
    let output = run(&[&["at"][..], &options, &["--to", "000000000000ffff", "NI"]].concat());
    assert_eq!(output.status.code(), Some(4), "{output:?}");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("no radio answered the broadcast"),
        "{stderr}"
    );
    assert!(
        stderr.contains("nothing at all came from the local radio either"),
        "{stderr}"
    );
    // Node discovery given a window, which asks the radio nothing first; in JSON, one
    // object that says so.
    let output = run(&[&["nodes"][..], &options, &["--format", "json"]].concat());
    assert_eq!(output.status.code(), Some(4), "{output:?}");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("no radio answered"), "{stderr}");
    assert!(
        stderr.contains("nothing at all came from the local radio either"),
        "{stderr}"
    );
    let json: Value = serde_json::from_slice(&output.stdout).expect("one JSON object");
    assert_eq!(
        json,
        serde_json::json!({"result": "timeout", "command": "ND"})
    );
    peer.join().unwrap();
}

/// The first line `monitor --link LINK` writes to its standard error (it runs until
/// then, and is stopped after).
fn first_monitor_hint(link: &str) -> String {
    let mut monitor = common::Running(
        gs().args(["monitor", "--link", link])
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap(),
    );
    let lines = common::stderr_lines(&mut monitor.0);
    lines.recv_timeout(common::GUARD).expect("monitor hints")
}

#[test]
fn monitor_on_a_radio_that_says_nothing_says_what_keeps_it_silent() {
    // As a simulator serving another client lets this one wait, saying nothing.
    let (link, peer) = common::silent_peer(1);
    let hint = first_monitor_hint(&link);
    assert!(
        hint.contains("did not answer AT AP within 3 s, and nothing at all came from it"),
        "{hint}"
    );
    assert!(
        hint.contains("whether the peer serves another connection"),
        "{hint}"
    );
    peer.join().unwrap();
}

#[test]
fn a_peer_that_closes_at_once_is_said_to_turn_us_away() {
    let (link, peer) = common::closing_peer(1);
    let output = run(&[
        "send",
        "--link",
        &link,
        "--to",
        "0013A20040B599B9",
        "landing",
        "on",
    ]);
    assert_eq!(output.status.code(), Some(3), "{output:?}");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("the peer closed the connection before anything came"),
        "{stderr}"
    );
    assert!(stderr.contains("use mcp-gs hub"), "{stderr}");
    // Through a hub, its radio gone: the hub did it, not a peer serving another.
    assert!(
        stderr.contains("a hub closes its clients' connections when it loses its radio"),
        "{stderr}"
    );
    peer.join().unwrap();

    // monitor reconnects, and says it once the peer has done it three times.
    let (link, peer) = common::closing_peer(3);
    let hint = first_monitor_hint(&link);
    assert!(
        hint.contains("the peer closed the connection before anything came"),
        "{hint}"
    );
    peer.join().unwrap();
}

#[test]
fn a_broadcast_at_nobody_answers_prints_a_timeout_object() {
    let (link, peer) = common::silent_peer(1);
    let output = run(&[
        "at",
        "--link",
        &link,
        "--window",
        "0.5",
        "--format",
        "json",
        "--to",
        "000000000000ffff",
        "NI",
    ]);
    assert_eq!(output.status.code(), Some(4), "{output:?}");
    let json: Value = serde_json::from_slice(&output.stdout).expect("one JSON object");
    assert_eq!(
        json,
        serde_json::json!({"result": "timeout", "command": "NI", "dst64": "000000000000ffff"})
    );
    peer.join().unwrap();
}

#[test]
fn every_subcommand_has_help() {
    for sub in [
        "monitor", "send", "status", "decode", "encode", "replay", "at", "ports", "radio", "sim",
        "demo", "hub",
    ] {
        let out = stdout(&run(&[sub, "--help"]));
        assert!(out.contains("Usage: mcp-gs"), "{sub}: {out}");
    }
    // The subcommands that need a radio that is there do not offer pty.
    for sub in ["send", "status", "at", "nodes"] {
        let out = stdout(&run(&[sub, "--help"]));
        assert!(
            out.contains("tcp:HOST:PORT or tcp-listen:ADDR:PORT. Not pty, which makes a new"),
            "{sub}: {out}"
        );
    }
    // Where a telemetry id is given, its help lists them all, with their numbers.
    for args in [
        &["send", "telemetry", "--help"][..],
        &["encode", "telemetry", "--help"],
        &["status", "--help"],
    ] {
        let out = stdout(&run(args));
        assert!(
            out.contains("estimated_altitude (0), altitude (1),")
                && out.contains("aileron_acceleration_error (32)"),
            "{args:?}: {out}"
        );
    }
}

#[test]
fn closed_standard_output_ends_quietly() {
    // As `mcp-gs demo | head -1`: the reader goes away after one line.
    let mut child = gs()
        .args(["demo", "--duration", "5"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdout = std::io::BufReader::new(child.stdout.take().unwrap());
    let mut first = String::new();
    std::io::BufRead::read_line(&mut stdout, &mut first).unwrap();
    assert!(first.starts_with("MCP demo"), "{first}");
    drop(stdout);
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(output.status.code(), Some(0), "{stderr}");
}

/// `/dev/full`, opened for writing: every write fails with "no space left on device".
#[cfg(target_os = "linux")]
fn dev_full() -> std::fs::File {
    std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap()
}

#[cfg(target_os = "linux")]
#[test]
fn standard_output_that_cannot_be_written_is_a_failure() {
    // A full disk, unlike a reader that went away, loses what was to be printed: a
    // script must not read it as success.
    let mut decode = gs()
        .args(["decode", "--hex"])
        .stdin(Stdio::piped())
        .stdout(dev_full())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    decode
        .stdin
        .take()
        .unwrap()
        .write_all(b"7E 00 02 8A 06 6F\n")
        .unwrap();
    let encode = gs()
        .args(["encode", "--to", "0013a20040b599b9", "landing", "on"])
        .stdout(dev_full())
        .output()
        .unwrap();
    // The help asked for, too.
    let help = gs().arg("--help").stdout(dev_full()).output().unwrap();
    for output in [decode.wait_with_output().unwrap(), encode, help] {
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(1), "{stderr}");
        assert!(
            stderr.starts_with("mcp-gs: cannot write to standard output: "),
            "{stderr}"
        );
    }
}

#[cfg(target_os = "linux")]
#[test]
fn standard_error_that_cannot_be_written_keeps_the_exit_status() {
    // A logger that went away, or a full disk: the message is lost, the status is not
    // (a panic would exit 101).
    let missing = gs()
        .args(["decode", "/nonexistent/recording.mcprec"])
        .stderr(dev_full())
        .output()
        .unwrap();
    assert_eq!(missing.status.code(), Some(2));
    // A warning on standard error, then the frame on standard output: success.
    let encode = gs()
        .args(["encode", "--to", "0013a20040b599b9", "trajectory"])
        .args(["--waypoint", "1,0,0,1"])
        .stderr(dev_full())
        .output()
        .unwrap();
    assert_eq!(encode.status.code(), Some(0));
    assert!(encode.stdout.starts_with(b"7E"), "{:?}", encode.stdout);
}

#[test]
fn a_recording_on_a_pipe_is_decoded_as_it_comes() {
    // As `monitor --record /dev/stdout | decode` or a recording sent over a network:
    // each record is shown while the writer is still at work.
    let mut child = gs()
        .args(["decode"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let recording = common::modem_status_recording(2);
    // The header and the first record, then nothing more until a line has come out.
    let header = mcp_host::record::HEADER_LEN;
    let first = header + (recording.len() - header) / 2;
    stdin.write_all(&recording[..first]).unwrap();
    stdin.flush().unwrap();
    let stdout = child.stdout.take().unwrap();
    let (first_line, lines) = std::sync::mpsc::channel();
    let reader = std::thread::spawn(move || {
        let mut lines = std::io::BufRead::lines(std::io::BufReader::new(stdout))
            .map(Result::unwrap)
            .filter(|line| line.contains("modem status"));
        first_line.send(lines.next()).unwrap();
        lines.count()
    });
    // Failing, decode would hold the line until the end of its input.
    let line = lines
        .recv_timeout(std::time::Duration::from_secs(30))
        .expect("the first record is shown before the input ends")
        .unwrap();
    assert!(line.contains("coordinator_started"), "{line}");
    stdin.write_all(&recording[first..]).unwrap();
    drop(stdin);
    assert_eq!(reader.join().unwrap(), 1);
    assert!(child.wait().unwrap().success());
}

#[cfg(unix)]
#[test]
fn log_lines_into_a_pipe_carry_no_colour_codes() {
    let output = gs()
        .args(["sim", "--link", "pty", "--duration", "0.1"])
        .env("MCP_LOG", "debug")
        .output()
        .expect("mcp-gs runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    assert!(stderr.contains("DEBUG"), "{stderr}");
    assert!(!stderr.contains('\u{1b}'), "{stderr:?}");
}

#[test]
fn sim_and_radio_on_a_port_in_use_say_what_to_do_and_nothing_else() {
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp-listen:{}", taken.local_addr().unwrap());
    for args in [
        &["sim", "--link", &link, "--duration", "1"][..],
        &["radio", "--coordinator", &link, "--duration", "1"],
    ] {
        let output = run(args);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(3), "{args:?}: {stderr}");
        assert!(
            stderr.contains("perhaps another mcp-gs, listens there: give another port"),
            "{args:?}: {stderr}"
        );
        // No banner of a network that did not start.
        assert_eq!(String::from_utf8_lossy(&output.stdout), "", "{args:?}");
    }
}

#[test]
fn a_time_before_2000_is_warned_about_once() {
    let output = run(&[
        "encode",
        "--to",
        "0013a20040b599b9",
        "trajectory",
        "--waypoint",
        "1,0,0,1",
        "--waypoint",
        "2,0,0,1",
        "--waypoint",
        "3,0,0,1",
    ]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    assert_eq!(stderr.matches("s after 1970").count(), 1, "{stderr}");
    assert!(
        stderr.contains("waypoint time 1 is 1 s after 1970"),
        "{stderr}"
    );
}

#[cfg(unix)]
#[test]
fn a_log_filter_that_cannot_be_read_is_said_so() {
    let output = gs()
        .args(["sim", "--link", "pty", "--duration", "0.1"])
        .env("MCP_LOG", "mcp_host=nonsense")
        .output()
        .expect("mcp-gs runs");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains("mcp-gs: warning: MCP_LOG=mcp_host=nonsense is no log filter"),
        "{stderr}"
    );
}

#[test]
fn decoding_in_the_wrong_api_mode_hints_at_the_other() {
    // A mode 2 capture read in mode 1 fails checksums; a mode 1 capture read in mode 2
    // loses bytes to what look like escapes, but most of its frames still pass.
    for (file, right, wrong) in [("ap2.bin", "2", "1"), ("ap1.bin", "1", "2")] {
        let capture = testdata(file);
        let capture = capture.to_str().unwrap();
        for summary in [false, true] {
            let mut args = vec!["decode", capture, "--api-mode", wrong];
            args.extend(summary.then_some("--summary"));
            let output = run(&args);
            let stderr = String::from_utf8_lossy(&output.stderr);
            assert_eq!(output.status.code(), Some(0), "{stderr}");
            let hint = format!("decode it with --api-mode {right}");
            assert!(stderr.contains(&hint), "{file}: {stderr}");
        }
        // In the right mode, no hint.
        let output = run(&["decode", capture, "--api-mode", right]);
        assert_eq!(output.status.code(), Some(0));
        assert_eq!(String::from_utf8_lossy(&output.stderr), "");
    }
}

#[test]
fn a_cut_off_recording_is_summed_up_to_the_cut_then_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cut.mcprec");
    let mut bytes = common::modem_status_recording(3);
    bytes.truncate(bytes.len() - 1);
    std::fs::write(&path, &bytes).unwrap();
    let file = path.to_str().unwrap();

    let output = run(&["decode", file, "--summary", "--format", "json"]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(!stderr.trim().is_empty());
    let summary: Value = serde_json::from_str(stdout.trim()).unwrap();
    assert_eq!(summary["frames"], 2, "{stdout}");
    // Without --summary, the frames before the cut as well.
    let output = run(&["decode", file]);
    assert_eq!(output.status.code(), Some(2));
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    let frames = stdout.lines().filter(|l| !l.starts_with("-- ")).count();
    assert_eq!(frames, 2, "{stdout}");

    // Replayed: nothing, before the link is opened (nothing listens there), with how
    // to keep the records before the cut.
    let output = run(&["replay", file, "--link", "tcp:127.0.0.1:9", "--speed", "0"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("nothing replayed") && stderr.contains("the 2 records before it are whole"),
        "{stderr}"
    );
}

#[cfg(unix)]
#[test]
fn a_recording_piped_in_is_replayed_whole() {
    // Read once, as a pipe (or a FIFO) can be: from its first record on.
    let bytes = common::modem_status_recording(3);
    let (link, reader) = common::recording_peer();
    let mut child = gs()
        .args(["replay", "/dev/stdin", "--link", &link, "--speed", "0"])
        .stdin(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::io::Write::write_all(&mut child.stdin.take().unwrap(), &bytes).unwrap();
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    assert!(stderr.contains("replayed 3 frames"), "{stderr}");
    let modem_status = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];
    assert_eq!(reader.join().unwrap(), modem_status.repeat(3));
}

/// Waits until the recording at `path` holds `bytes` (its records are flushed as they
/// come), polled until the guard's deadline; `what` says what was waited for.
#[cfg(unix)]
fn recorded(path: &std::path::Path, bytes: u64, what: &str) {
    let deadline = std::time::Instant::now() + common::GUARD;
    while std::fs::metadata(path).map_or(0, |m| m.len()) < bytes {
        assert!(std::time::Instant::now() < deadline, "{what}: not recorded");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}

/// A link that goes away: monitor says it is reconnecting, as nothing is printed until
/// it is back.
#[cfg(unix)]
#[test]
fn monitor_says_it_reconnects_when_the_link_goes_away() {
    let radio = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", radio.local_addr().unwrap());
    let mut child = common::Running(
        gs().args(["monitor", "--link", &link])
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let lines = common::stdout_lines(&mut child.0);
    let (socket, _) = radio.accept().unwrap();
    drop(socket);
    let said = loop {
        let line = lines.recv_timeout(common::GUARD).expect("monitor goes on");
        if line.contains("link disconnected") {
            break line;
        }
    };
    assert!(said.ends_with("; reconnecting (Ctrl-C stops)"), "{said}");
    // And it does (looked for until the guard's deadline, not waited on for ever).
    radio.set_nonblocking(true).unwrap();
    let deadline = std::time::Instant::now() + common::GUARD;
    let _socket = loop {
        match radio.accept() {
            Ok((socket, _)) => break socket,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                assert!(
                    std::time::Instant::now() < deadline,
                    "monitor never came back"
                );
                std::thread::sleep(std::time::Duration::from_millis(10));
            }
            Err(e) => panic!("{e}"),
        }
    };
    let back = lines.recv_timeout(common::GUARD).expect("monitor goes on");
    assert!(back.contains("link reconnected"), "{back}");
}

/// A pager paused: monitor's output is not read at all. The link's frames are still
/// taken as they come, and recorded, every one; the lines of those beyond what waits
/// for the reader are dropped, and said.
#[cfg(unix)]
#[test]
fn monitor_records_every_frame_while_its_output_is_not_read() {
    let radio = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", radio.local_addr().unwrap());
    let dir = tempfile::tempdir().unwrap();
    let record = dir.path().join("paused.mcprec");
    let monitor = gs()
        .args(["monitor", "--link", &link, "--record"])
        .arg(&record)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut child = common::Running(monitor);
    // Held, never read.
    let stdout = child.0.stdout.take().unwrap();
    let errors = common::stderr_lines(&mut child.0);
    let (mut socket, _) = radio.accept().unwrap();
    let modem_status = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];
    // 20 000 lines, far more than the pipe (64 KiB), the output thread's queue and
    // monitor's own hold; in batches smaller than the link's queue of events (1024),
    // each once the last is recorded (a record is written, and flushed, as it comes).
    let (batch, batches) = (500, 40);
    for n in 1..=batches {
        socket.write_all(&modem_status.repeat(batch)).unwrap();
        let all =
            (mcp_host::record::HEADER_LEN + n * batch * mcp_host::record::record_len(2)) as u64;
        recorded(
            &record,
            all,
            &format!("batch {n} while the output was not read"),
        );
    }
    // Lines are dropped once one has waited a while: for the frames that come then.
    let (said, more) =
        common::write_until_said(&mut socket, &modem_status, &errors, " not shown: ");
    let frames = batch * batches + more;
    let all = (mcp_host::record::HEADER_LEN + frames * mcp_host::record::record_len(2)) as u64;
    recorded(&record, all, "the frames after the batches");
    assert!(
        said.starts_with("mcp-gs: warning: ")
            && said.contains(
                " received frames not shown: standard output is not read as fast as they \
                 come (a pager paused?) (the recording has them)"
            ),
        "{said}"
    );
    let pid = i32::try_from(child.0.id()).unwrap();
    // SAFETY: kill(2) with the pid of a child of this process and a valid signal.
    assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
    assert_eq!(common::exit_code(&mut child.0), Some(0));
    // The lines still waiting then, which the reader never took, are said too.
    let unwritten = loop {
        let line = errors
            .recv_timeout(common::GUARD)
            .expect("monitor says what it did not write");
        if line.contains(" not written: ") {
            break line;
        }
    };
    assert!(
        unwritten.starts_with("mcp-gs: warning: ")
            && unwritten
                .ends_with(" lines not written: standard output took nothing more after Ctrl-C"),
        "{unwritten}"
    );
    drop(stdout);
    let output = run(&["decode", "--summary", record.to_str().unwrap()]);
    let summary = String::from_utf8_lossy(&output.stdout);
    assert!(
        summary.contains(&format!("frames: {frames}\n")),
        "{summary}"
    );
}

/// `monitor --record FILE 2>&1 | less`, the pager paused: its warnings (lines not shown)
/// wait with its output for a reader that takes nothing, and the recording still takes
/// every frame, where a warning written on the command's own thread held it up.
#[cfg(unix)]
#[test]
fn monitor_records_every_frame_while_its_warnings_are_not_read() {
    let radio = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", radio.local_addr().unwrap());
    let dir = tempfile::tempdir().unwrap();
    let record = dir.path().join("paused.mcprec");
    // Standard output and error on one pipe, held and not read until the end.
    let (mut pipe, into_pipe) = std::io::pipe().unwrap();
    let mut monitor = gs();
    monitor
        .args(["monitor", "--link", &link, "--record"])
        .arg(&record)
        .stdout(into_pipe.try_clone().unwrap())
        .stderr(into_pipe);
    let mut child = common::Running(monitor.spawn().unwrap());
    drop(monitor);
    let (mut socket, _) = radio.accept().unwrap();
    let modem_status = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];
    // Batches, each once the last is recorded, for long enough that lines not shown
    // are said (once a line has waited 2 s for the reader) and more come after.
    let start = std::time::Instant::now();
    let batch = 200;
    let mut frames = 0;
    while frames < 20_000 || start.elapsed() < std::time::Duration::from_secs(4) {
        socket.write_all(&modem_status.repeat(batch)).unwrap();
        frames += batch;
        let all = mcp_host::record::HEADER_LEN + frames * mcp_host::record::record_len(2);
        recorded(
            &record,
            all as u64,
            &format!("frame {frames}, {:?} in", start.elapsed()),
        );
    }
    // The reader comes back, then Ctrl-C: what waited for it, the warnings among it,
    // is read.
    let reader = std::thread::spawn(move || {
        let mut said = String::new();
        std::io::Read::read_to_string(&mut pipe, &mut said).unwrap();
        said
    });
    let pid = i32::try_from(child.0.id()).unwrap();
    // SAFETY: kill(2) with the pid of a child of this process and a valid signal.
    assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
    assert_eq!(common::exit_code(&mut child.0), Some(0));
    let said = reader.join().unwrap();
    assert!(
        said.contains(
            " received frames not shown: standard output is not read as fast as they come"
        ),
        "{}",
        &said[said.len().saturating_sub(2000)..]
    );
    let output = run(&["decode", "--summary", record.to_str().unwrap()]);
    let summary = String::from_utf8_lossy(&output.stdout);
    assert!(
        summary.contains(&format!("frames: {frames}\n")),
        "{summary}"
    );
}

/// A reader that paused (a program busy elsewhere, a pager): where monitor dropped
/// lines for it, a line says how many, in the JSON stream itself, before the next line
/// kept; with every frame accounted for.
#[cfg(unix)]
#[test]
fn monitor_marks_the_lines_it_dropped_for_a_paused_reader_in_its_output() {
    let radio = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", radio.local_addr().unwrap());
    let dir = tempfile::tempdir().unwrap();
    let record = dir.path().join("paused.mcprec");
    let monitor = gs()
        .args(["monitor", "--format", "json", "--link", &link, "--record"])
        .arg(&record)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut child = common::Running(monitor);
    let stdout = child.0.stdout.take().unwrap();
    let errors = common::stderr_lines(&mut child.0);
    let (mut socket, _) = radio.accept().unwrap();
    let modem_status = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];
    // Far more lines than the pipe, the output thread and monitor hold, none read; in
    // batches smaller than the link's queue of events, each once the last is recorded.
    let (batch, batches) = (500, 10);
    for n in 1..=batches {
        socket.write_all(&modem_status.repeat(batch)).unwrap();
        let all = mcp_host::record::HEADER_LEN + n * batch * mcp_host::record::record_len(2);
        recorded(&record, all as u64, &format!("batch {n}"));
    }
    // Lines are dropped once one has waited a while: for the frames that come then.
    let (_, more) = common::write_until_said(&mut socket, &modem_status, &errors, " not shown: ");
    // The reader back: the lines held come, then those of frames after the gap (sent
    // until one is shown, as the first may come while the lines held fill monitor's
    // queue still).
    let (lines, got_lines) = std::sync::mpsc::channel();
    let reader = std::thread::spawn(move || {
        for line in std::io::BufRead::lines(std::io::BufReader::new(stdout)) {
            let Ok(line) = line else { break };
            let value: Value = serde_json::from_str(&line).unwrap();
            let _ = lines.send(value);
        }
    });
    let realigned = [0x7E, 0x00, 0x02, 0x8A, 0x0B, 0x6A];
    let is_realigned = |l: &Value| l["frame"] == "modem_status" && l["status"] == 0x0B;
    let deadline = std::time::Instant::now() + common::GUARD;
    let mut got: Vec<Value> = Vec::new();
    let mut sent = batch * batches + more;
    while !got.iter().any(is_realigned) {
        assert!(
            std::time::Instant::now() < deadline,
            "no frame shown after the gap"
        );
        socket.write_all(&realigned).unwrap();
        sent += 1;
        while let Ok(line) = got_lines.recv_timeout(std::time::Duration::from_millis(100)) {
            got.push(line);
        }
    }
    // Every frame taken by monitor (recorded as it is taken) before it ends: each is then
    // shown, or counted in a gap.
    let all = mcp_host::record::HEADER_LEN + sent * mcp_host::record::record_len(2);
    recorded(&record, all as u64, "every frame");
    let pid = i32::try_from(child.0.id()).unwrap();
    // SAFETY: kill(2) with the pid of a child of this process and a valid signal.
    assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
    assert_eq!(common::exit_code(&mut child.0), Some(0));
    reader.join().unwrap();
    got.extend(got_lines.try_iter());
    let frames = got.iter().filter(|l| l["frame"] == "modem_status").count();
    let gaps: Vec<&Value> = got.iter().filter(|l| l.get("gap").is_some()).collect();
    assert!(!gaps.is_empty());
    assert!(
        gaps.iter()
            .all(|gap| gap["gap"] == "output" && gap["time"].is_f64()),
        "{gaps:?}"
    );
    let dropped: u64 = gaps.iter().map(|gap| gap["frames"].as_u64().unwrap()).sum();
    // Every frame is shown or counted in a gap.
    assert_eq!(frames as u64 + dropped, sent as u64, "{gaps:?}");
    // The gap stands where the lines were dropped: before the first line kept after
    // them, the first of a frame sent after the reader paused.
    let first_after = got.iter().position(is_realigned).unwrap();
    assert!(
        got[first_after - 1].get("gap").is_some(),
        "{:?}",
        &got[first_after - 1]
    );
}

/// Monitor stopped a while (Ctrl-Z, SIGSTOP) while frames come: once it goes on, the
/// burst that waited in the connection is recorded whole, not dropped for monitor being
/// behind, and shown whole to a reader that takes it as it comes. (Linux: the
/// connection's buffers hold the burst while monitor is stopped.)
#[cfg(target_os = "linux")]
#[test]
fn monitor_records_the_burst_that_waited_while_it_was_stopped() {
    let radio = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", radio.local_addr().unwrap());
    let dir = tempfile::tempdir().unwrap();
    let record = dir.path().join("stopped.mcprec");
    // JSON lines of telemetry, read: each frame takes monitor longer than the link.
    let monitor = gs()
        .args(["monitor", "--format", "json", "--link", &link, "--record"])
        .arg(&record)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut child = common::Running(monitor);
    let errors = common::stderr_lines(&mut child.0);
    let lines = common::stdout_lines(&mut child.0);
    let (mut socket, _) = radio.accept().unwrap();
    // A Receive Packet from a MAV holding 8 telemetry values, as a MAV sends 20 a second.
    let mut data = vec![
        0x90, 0x00, 0x13, 0xA2, 0x00, 0x40, 0xB5, 0x99, 0xB9, 0x7D, 0x84, 0x01,
    ];
    data.push(b't');
    for id in 1..=8u8 {
        data.push(id);
        data.extend_from_slice(&(f32::from(id) * 0.5).to_le_bytes());
    }
    let sum = data.iter().fold(0u8, |sum, b| sum.wrapping_add(*b));
    let length = u8::try_from(data.len()).unwrap();
    let frame = [&[0x7E, 0x00, length][..], &data, &[0xFF - sum]].concat();
    let record_len = mcp_host::record::record_len(data.len()) as u64;
    socket.write_all(&frame).unwrap();
    let header = mcp_host::record::HEADER_LEN as u64;
    recorded(&record, header + record_len, "the first frame");
    let pid = i32::try_from(child.0.id()).unwrap();
    // SAFETY: kill(2) with the pid of a child of this process and a valid signal.
    assert_eq!(unsafe { libc::kill(pid, libc::SIGSTOP) }, 0);
    // Far more than the link's default queue of events, all in the connection's buffers.
    // (233 KB: the sender's buffer grows to hold it, on Linux up to 4 MB.)
    let burst = 4096;
    socket.set_write_timeout(Some(common::GUARD)).unwrap();
    socket.write_all(&frame.repeat(burst)).unwrap();
    // SAFETY: as above.
    assert_eq!(unsafe { libc::kill(pid, libc::SIGCONT) }, 0);
    let all = header + (burst as u64 + 1) * record_len;
    recorded(&record, all, "the burst");
    // And shown whole, to a reader that takes it: a line per frame, none dropped.
    let mut shown = 0;
    while shown < burst + 1 {
        let line = lines.recv_timeout(common::GUARD).expect("the burst shown");
        assert!(!line.contains("\"gap\""), "{line}");
        if line.contains("\"category\":\"telemetry\"") {
            shown += 1;
        }
    }
    // SAFETY: as above.
    assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
    assert_eq!(common::exit_code(&mut child.0), Some(0));
    let said: Vec<String> = errors.try_iter().collect();
    assert!(
        !said
            .iter()
            .any(|l| l.contains(" lost: ") || l.contains(" not shown: ")),
        "{said:?}"
    );
    drop(lines);
}

/// A reader that took part of monitor's output and no more (a pager paused), the link
/// quiet since: Ctrl-C still ends monitor, whether it was still taking frames or had
/// taken its `--count` and was writing its last lines.
#[cfg(target_os = "linux")]
#[test]
fn monitor_ends_on_ctrl_c_with_its_last_lines_not_read() {
    use std::os::fd::AsRawFd;
    for count in [None, Some("100")] {
        let radio = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
        let link = format!("tcp:{}", radio.local_addr().unwrap());
        let dir = tempfile::tempdir().unwrap();
        let record = dir.path().join("taken.mcprec");
        let mut args = vec!["monitor", "--link", &link, "--record"];
        args.push(record.to_str().unwrap());
        args.extend(count.iter().flat_map(|n| ["--count", n]));
        let mut monitor = gs()
            .args(&args)
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        // A pipe of 4 KiB: 100 lines of modem status (50 bytes each) fill it (it holds
        // 2.5 to 4 KiB of them), and the rest wait in monitor, fewer than it queues.
        let stdout = monitor.stdout.take().unwrap();
        let fd = stdout.as_raw_fd();
        // SAFETY: fcntl(2) and ioctl(2) on the pipe's read end, which `stdout` owns.
        assert_eq!(unsafe { libc::fcntl(fd, libc::F_SETPIPE_SZ, 4096) }, 4096);
        let (mut socket, _) = radio.accept().unwrap();
        let modem_status = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];
        socket.write_all(&modem_status.repeat(100)).unwrap();
        // Monitor has taken every frame once its recording holds them all (a record
        // is written, and flushed, before its line): their lines fill the pipe, the
        // rest wait, and the link says nothing more.
        let all = (8 + 100 * mcp_host::record::record_len(2)) as u64;
        recorded(&record, all, &format!("{args:?}"));
        let pid = i32::try_from(monitor.id()).unwrap();
        // SAFETY: kill(2) with the pid of a child of this process and a valid signal.
        assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
        let (done, ended) = std::sync::mpsc::channel();
        std::thread::spawn(move || done.send(monitor.wait()));
        let status = ended
            .recv_timeout(common::GUARD)
            .unwrap_or_else(|_| panic!("{args:?}: monitor did not end"))
            .unwrap();
        assert_eq!(status.code(), Some(0), "{args:?}");
        drop(stdout);
    }
}

/// A recording into a pipe whose reader stopped taking: the file falls behind, never
/// monitor, which takes Ctrl-C and ends, saying how many frames the recording misses.
#[cfg(target_os = "linux")]
#[test]
fn monitor_ends_on_ctrl_c_with_its_recording_stuck() {
    let dir = tempfile::tempdir().unwrap();
    let (fifo, reader) = common::stuck_fifo(dir.path());
    let radio = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", radio.local_addr().unwrap());
    let mut monitor = common::Running(
        gs().args(["monitor", "--link", &link, "--record"])
            .arg(&fifo)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap(),
    );
    let errors = common::stderr_lines(&mut monitor.0);
    let (mut socket, _) = radio.accept().unwrap();
    common::fill_the_pipe(&mut socket, &reader);
    let pid = i32::try_from(monitor.0.id()).unwrap();
    // SAFETY: kill(2) with the pid of a child of this process and a valid signal.
    assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
    let missing = loop {
        let line = errors
            .recv_timeout(common::GUARD)
            .expect("monitor says what the recording is missing");
        if line.contains(" missing from the recording ") {
            break line;
        }
    };
    let n: u64 = missing
        .strip_prefix("mcp-gs: warning: ")
        .and_then(|l| l.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("{missing}"));
    assert!(
        n >= 1
            && missing.ends_with(&format!(
                " missing from the recording {}: writing the file fell behind",
                fifo.display()
            )),
        "{missing}"
    );
    assert_eq!(common::exit_code(&mut monitor.0), Some(0));
    drop(reader);
}

#[cfg(unix)]
#[test]
fn monitor_ends_on_ctrl_c_while_its_output_is_not_read() {
    let radio = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", radio.local_addr().unwrap());
    let mut monitor = gs()
        .args(["monitor", "--link", &link])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let errors = common::stderr_lines(&mut monitor);
    let (mut socket, _) = radio.accept().unwrap();
    let modem_status = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];
    socket.write_all(&modem_status.repeat(50_000)).unwrap();
    // Stuck on its output (said as frames not shown), it still takes Ctrl-C, and ends.
    common::write_until_said(&mut socket, &modem_status, &errors, " not shown: ");
    let pid = i32::try_from(monitor.id()).unwrap();
    // SAFETY: kill(2) with the pid of a child of this process and a valid signal.
    assert_eq!(unsafe { libc::kill(pid, libc::SIGINT) }, 0);
    let (done, ended) = std::sync::mpsc::channel();
    let stdout = monitor.stdout.take();
    std::thread::spawn(move || done.send(monitor.wait()));
    let status = ended
        .recv_timeout(common::GUARD)
        .expect("monitor ends")
        .unwrap();
    assert_eq!(status.code(), Some(0));
    drop(stdout);
}

#[test]
fn monitor_keeps_an_existing_recording() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("flight.mcprec");
    std::fs::write(&file, b"yesterday's flight").unwrap();
    let path = file.to_str().unwrap();
    let missing = "serial:/dev/mcp-gs-test-no-such-device";
    // Without --force: refused before the link is opened.
    let output = run(&["monitor", "--link", missing, "--record", path]);
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(
        stderr.contains("exists") && stderr.contains("--force"),
        "{stderr}"
    );
    // With --force, a link that cannot be opened still leaves the file alone.
    let output = run(&["monitor", "--link", missing, "--record", path, "--force"]);
    assert_eq!(output.status.code(), Some(3));
    assert_eq!(std::fs::read(&file).unwrap(), b"yesterday's flight");
    // Nothing could be recorded: refused before the link is opened, for the hub too,
    // which would otherwise serve a whole session unrecorded.
    let nowhere = dir.path().join("no-such-dir").join("flight.mcprec");
    let nowhere = nowhere.to_str().unwrap();
    for command in ["monitor", "hub"] {
        let output = run(&[command, "--link", missing, "--record", nowhere]);
        assert_eq!(output.status.code(), Some(2), "{command}: {output:?}");
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(
            stderr.contains(&format!(
                "cannot record to {nowhere}: no file can be made in"
            )),
            "{stderr}"
        );
    }
    // The check leaves nothing behind.
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
    assert_eq!(left.len(), 1, "{left:?}");
}

#[cfg(unix)]
#[test]
fn monitor_records_into_a_pipe_that_is_read_and_refuses_one_that_is_not() {
    use std::os::unix::fs::OpenOptionsExt;
    let dir = tempfile::tempdir().unwrap();
    let fifo = common::fifo(dir.path(), "flight.fifo");
    let path = fifo.to_str().unwrap();
    // Nothing reads it: refused once a frame is to be recorded, where the open would
    // wait for a reader, deaf to Ctrl-C.
    let modem_status = vec![0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];
    let (link, peer) = common::talking_peer(modem_status.clone());
    let output = run(&["monitor", "--link", &link, "--record", path]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains(&format!(
            "cannot create {path}: it is a FIFO that nothing reads: start its reader first"
        )),
        "{stderr}"
    );
    peer.join().unwrap();
    // Read (as `--record >(gzip > f.gz)` is): the recording goes through it. The read
    // end opened first, without waiting for a writer; what comes stays in the pipe.
    let mut reader = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK)
        .open(&fifo)
        .unwrap();
    let (link, peer) = common::talking_peer(modem_status);
    let output = run(&["monitor", "--link", &link, "--count", "1", "--record", path]);
    peer.join().unwrap();
    assert_eq!(output.status.code(), Some(0), "{output:?}");
    // The writer gone: what it wrote, then the end.
    let mut recorded = Vec::new();
    std::io::Read::read_to_end(&mut reader, &mut recorded).unwrap();
    assert!(recorded.starts_with(b"MCPREC\x02\x00"), "{recorded:02x?}");
    // The last record's length, frame and CRC.
    assert!(
        recorded[..recorded.len() - 4].ends_with(&[2, 0, 0x8A, 0x06]),
        "{recorded:02x?}"
    );
}

#[test]
fn monitor_counts_the_frames_that_fail_after_its_hint_rather_than_showing_each() {
    // A radio in API mode 2 read in mode 1: every Receive Packet from 0013A2... has a
    // byte escaped, and fails the checksum. After the hint, the failures are counted.
    let frame = xbee_api::ReceivePacketRepr {
        src64: "0013A20040B599B9".parse().unwrap(),
        src16: xbee_api::Address16(0x7B1F),
        options: 0x01,
        data: b"t\x01\x00\x00\x80\x3F",
    };
    let mut one = [0u8; 64];
    let n = xbee_api::EncodeFrame::encode(&frame, xbee_api::ApiMode::Escaped, &mut one).unwrap();
    let (link, peer) = common::talking_peer(one[..n].repeat(40));
    let output = run(&["monitor", "--link", &link, "--count", "40"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    let stdout = String::from_utf8_lossy(&output.stdout);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    assert!(stderr.contains("hint: "), "{stderr}");
    let shown = stdout
        .lines()
        .filter(|l| l.contains("error: bad checksum"))
        .count();
    // Those before the hint: it may come before any (the counters are read too).
    assert!(shown < 10, "{stdout}");
    // The rest, said in one line at the end, with the hint again.
    let count = format!(
        "error: {} more frames failed to decode, not shown",
        40 - shown
    );
    let told = stdout.lines().last().unwrap_or_default();
    assert!(told.contains(&count), "{stdout}");
    assert!(told.contains("try --api-mode 2"), "{stdout}");
    peer.join().unwrap();
}

#[test]
fn monitor_shows_each_failure_again_once_frames_pass_again() {
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", listener.local_addr().unwrap());
    let mut monitor = common::Running(
        gs().args(["monitor", "--link", &link, "--count", "301"])
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap(),
    );
    let stdout = common::stdout_lines(&mut monitor.0);
    let stderr = common::stderr_lines(&mut monitor.0);
    let (mut radio, _) = listener.accept().unwrap();
    // Two hundred frames that fail as from a radio in API mode 2 (an escaped byte
    // each): more than the good ones after them. The monitor says so.
    let escaped = [0x7E, 0x00, 0x03, 0x8A, 0x7D, 0x33, 0x00, 0x62];
    radio.write_all(&escaped.repeat(200)).unwrap();
    while !stderr
        .recv_timeout(common::GUARD)
        .expect("the hint")
        .contains("hint: ")
    {}
    // The radio set right: a hundred good frames, then one the line corrupted.
    let good = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];
    radio.write_all(&good.repeat(100)).unwrap();
    radio
        .write_all(&[0x7E, 0x00, 0x02, 0x8A, 0x06, 0x70])
        .unwrap();
    let mut lines = Vec::new();
    while let Ok(line) = stdout.recv_timeout(common::GUARD) {
        lines.push(line);
    }
    let last = lines.last().cloned().unwrap_or_default();
    assert!(last.contains("error: bad checksum"), "{lines:#?}");
    // The hidden ones were counted before the good frames' lines.
    assert!(
        lines
            .iter()
            .any(|l| l.contains("failed to decode, not shown")),
        "{lines:#?}"
    );
    // The hint, once.
    let mut hints = Vec::new();
    while let Ok(line) = stderr.recv_timeout(common::GUARD) {
        hints.extend(line.contains("hint: ").then_some(line));
    }
    assert!(hints.is_empty(), "{hints:#?}");
}

#[test]
fn a_port_that_hands_back_what_is_written_is_said_to_be_no_radio() {
    // A loopback: every byte written comes back.
    let listener = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let link = format!("tcp:{}", listener.local_addr().unwrap());
    let peer = std::thread::spawn(move || {
        let (mut socket, _) = listener.accept().unwrap();
        let mut back = socket.try_clone().unwrap();
        let _ = std::io::copy(&mut socket, &mut back);
    });
    let output = run(&["at", "--link", &link, "--timeout", "1", "AP"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(4), "{stderr}");
    assert!(
        stderr.contains(
            "hint: 1 frame came back of the types written to the radio (requests, which no \
             radio sends): the port hands back what is written to it"
        ),
        "{stderr}"
    );
    assert!(!stderr.contains("API mode 2"), "{stderr}");
    peer.join().unwrap();
}

#[cfg(target_os = "linux")]
#[test]
fn a_recording_that_cannot_be_written_is_named() {
    // A modem status, recorded to a full disk.
    let (link, peer) = common::talking_peer(vec![0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F]);
    let output = run(&[
        "monitor",
        "--link",
        &link,
        "--record",
        "/dev/full",
        "--force",
    ]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.starts_with("mcp-gs: cannot write to /dev/full: "),
        "{stderr}"
    );
    peer.join().unwrap();
}

/// A disk that fills part way through a record (here a file size limit, RLIMIT_FSIZE):
/// the recording is cut back to its last whole record, which reads to its end.
#[cfg(target_os = "linux")]
#[test]
fn a_recording_that_fills_its_disk_ends_at_its_last_whole_record() {
    use std::os::unix::process::CommandExt;
    let modem_status = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];
    // Room for the header and 58.6 records of 17 bytes; for 5 bytes of the header.
    for (limit, whole) in [(1000u64, 58usize), (5, 0)] {
        let (link, peer) = common::talking_peer(modem_status.repeat(300));
        let dir = tempfile::tempdir().unwrap();
        let record = dir.path().join("full.mcprec");
        let mut monitor = gs();
        monitor
            .args(["monitor", "--link", &link, "--record"])
            .arg(&record);
        // SAFETY: between fork and exec, setrlimit(2) and signal(2) only, which are
        // async-signal-safe; a write past the limit then fails with EFBIG, not SIGXFSZ.
        unsafe {
            monitor.pre_exec(move || {
                let size = libc::rlimit {
                    rlim_cur: limit,
                    rlim_max: limit,
                };
                if libc::setrlimit(libc::RLIMIT_FSIZE, &size) != 0 {
                    return Err(std::io::Error::last_os_error());
                }
                libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
                Ok(())
            });
        }
        let output = monitor.output().unwrap();
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(1), "{stderr}");
        assert!(stderr.contains("cannot write to "), "{stderr}");
        let bytes = std::fs::read(&record).unwrap();
        if whole == 0 {
            assert!(
                bytes.is_empty(),
                "a header cut off is cut back: {bytes:02x?}"
            );
        } else {
            let records = mcp_host::record::RecordReader::new(&bytes[..])
                .unwrap()
                .collect::<Result<Vec<_>, _>>()
                .unwrap_or_else(|e| panic!("{} bytes: {e}", bytes.len()));
            assert_eq!(
                bytes.len(),
                8 + records.len() * mcp_host::record::record_len(2)
            );
            assert_eq!(records.len(), whole, "every whole record that fits is kept");
        }
        peer.join().unwrap();
    }
}

#[test]
fn monitor_hints_at_the_baud_rate_when_nothing_makes_sense() {
    // What a radio at another baud rate looks like: start delimiters with impossible
    // lengths, and no good frame.
    let noise: Vec<u8> = (0..10).flat_map(|_| [0x7E, 0xFF, 0xF0, 0x00]).collect();
    let (link, peer) = common::talking_peer(noise);
    let output = run(&["monitor", "--link", &link, "--count", "8"]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    assert!(stderr.contains("baud rate may differ"), "{stderr}");
    // The text lines carry the time of day, after a line with the date.
    let stdout = String::from_utf8_lossy(&output.stdout);
    let first = stdout.lines().next().unwrap_or_default();
    let date = first
        .strip_prefix("-- ")
        .and_then(|l| l.strip_suffix(" (UTC) --"))
        .unwrap_or_else(|| panic!("{stdout}"));
    assert!(
        date.len() == 10 && date.chars().filter(|c| *c == '-').count() == 2,
        "{stdout}"
    );
    peer.join().unwrap();
}

#[test]
fn a_few_bytes_that_make_no_frame_point_a_request_to_the_baud_rate() {
    // A radio at 9600 baud read at 115200: its answer is a few bytes of nothing.
    let (link, peer) = common::talking_peer(vec![0x56, 0xA5, 0xB5, 0xF1, 0x95, 0xDE]);
    let stderr = unanswered_status(&link);
    assert!(
        stderr.contains("hint: 6 bytes came from the radio and none began a frame")
            && stderr.contains("baud rate may differ"),
        "{stderr}"
    );
    peer.join().unwrap();
}

/// The standard error of a landing status request on `link` that no answer comes to
/// within a second (exit code 4).
fn unanswered_status(link: &str) -> String {
    let output = run(&[
        "status",
        "--link",
        link,
        "--to",
        "0013A20040B599B9",
        "--timeout",
        "1",
        "landing",
    ]);
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(output.status.code(), Some(4), "{stderr}");
    stderr
}

#[test]
fn a_radio_in_transparent_mode_is_named_by_status_and_monitor() {
    // A radio in transparent mode (AP=0) passes on what it hears as it is: text from a
    // MAV's console, with no frame in it.
    let text = b"MAV booting... IMU ok, GPS waiting for fix\r\n".repeat(4);
    let (link, peer) = common::talking_peer(text.clone());
    let stderr = unanswered_status(&link);
    assert!(
        stderr.contains("hint: 176 bytes came from the radio and none began a frame")
            && stderr.contains("the radio may be in transparent mode (AP=0)")
            && stderr.contains("`mcp-gs setup` puts a radio in transparent mode into API mode"),
        "{stderr}"
    );
    peer.join().unwrap();

    // monitor has no event to show for it, and says it all the same.
    let (link, peer) = common::talking_peer(text);
    let hint = first_monitor_hint(&link);
    assert!(
        hint.contains("none began a frame") && hint.contains("transparent mode"),
        "{hint}"
    );
    peer.join().unwrap();
}

#[test]
fn decode_says_what_input_it_cannot_read() {
    let dir = tempfile::tempdir().unwrap();
    // A recording given as hex text.
    let recording = dir.path().join("flight.mcprec");
    let mut bytes = Vec::new();
    mcp_host::record::RecordWriter::new(&mut bytes).unwrap();
    std::fs::write(&recording, &bytes).unwrap();
    let output = run(&["decode", "--hex", recording.to_str().unwrap()]);
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("decode it without --hex"), "{stderr}");
    // A hex dump of a recording is read as the recording.
    let bytes = common::modem_status_recording(1);
    let dump = dir.path().join("flight.hex");
    let hex: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
    std::fs::write(&dump, hex).unwrap();
    let out = stdout(&run(&["decode", "--hex", dump.to_str().unwrap()]));
    assert!(out.contains("rx modem status coordinator_started"), "{out}");
    // Bytes with no frame in them: said so, and an input error.
    let noise = dir.path().join("noise.bin");
    std::fs::write(&noise, b"hello, this is no capture\n").unwrap();
    let output = run(&["decode", noise.to_str().unwrap()]);
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("no XBee frame in 26 bytes"), "{stderr}");
}

#[test]
fn options_may_follow_the_command_word() {
    let to = "0013A20040B599B9";
    let canonical = stdout(&run(&[
        "encode",
        "--to",
        to,
        "--frame-id",
        "5",
        "--api-mode",
        "2",
        "landing",
        "on",
    ]));
    for args in [
        &[
            "encode",
            "landing",
            "on",
            "--to",
            to,
            "--frame-id",
            "5",
            "--api-mode",
            "2",
        ][..],
        &[
            "encode",
            "--api-mode",
            "2",
            "landing",
            "--frame-id=5",
            "on",
            "--to",
            to,
        ],
    ] {
        assert_eq!(stdout(&run(args)), canonical, "{args:?}");
    }
    // The command's own options stay with it.
    let trajectory = &["trajectory", "--waypoint", "1,2,3,4"];
    let mut first = vec!["encode", "--to", to];
    first.extend_from_slice(trajectory);
    let mut last = vec!["encode"];
    last.extend_from_slice(trajectory);
    last.extend(["--to", to]);
    assert_eq!(stdout(&run(&last)), stdout(&run(&first)));
    // After `--`, a word that looks like an option is text.
    let out = stdout(&run(&["encode", "--to", to, "message", "--", "--to"]));
    assert!(out.contains("6D 2D 2D 74 6F"), "{out}");
}

#[test]
fn a_one_shot_command_on_tcp_listen_waits_for_its_peer() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("one.mcprec");
    std::fs::write(&file, common::modem_status_recording(1)).unwrap();
    // A port held free: replay listens there, the peer connects once it does.
    let reserved = common::ReservedPort::new();
    let port = reserved.port;
    let peer = std::thread::spawn(move || {
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(20);
        let mut socket = loop {
            match std::net::TcpStream::connect(("127.0.0.1", port)) {
                Ok(socket) => break socket,
                Err(_) if std::time::Instant::now() < deadline => std::thread::yield_now(),
                Err(e) => panic!("replay never listened: {e}"),
            }
        };
        let mut bytes = Vec::new();
        std::io::Read::read_to_end(&mut socket, &mut bytes).unwrap();
        bytes
    });
    let link = format!("tcp-listen:127.0.0.1:{port}");
    let output = run(&[
        "replay",
        file.to_str().unwrap(),
        "--link",
        &link,
        "--speed",
        "0",
    ]);
    assert_eq!(
        output.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    assert_eq!(peer.join().unwrap(), [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F]);
    // Nobody comes: no link, as for a `tcp:` link that cannot connect, whichever
    // command waited.
    let file = file.to_str().unwrap();
    for command in [
        &["send", "--to", "0013A20040B599B9", "landing", "on"][..],
        &["status", "--to", "0013A20040B599B9", "landing"],
        &["at", "AP"],
        &["replay", file],
    ] {
        let (sub, rest) = command.split_first().unwrap();
        let mut args = vec![*sub, "--link", "tcp-listen:127.0.0.1:0", "--timeout", "0.3"];
        args.extend_from_slice(rest);
        let output = run(&args);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(3), "{command:?}: {stderr}");
        assert!(
            stderr.contains("mcp-gs: no peer connected to 127.0.0.1:")
                && stderr.contains(" within 0.3 s"),
            "{command:?}: {stderr}"
        );
    }
}

#[test]
fn decode_of_a_recording_dates_its_lines_at_each_new_day() {
    // 2026-11-22 23:59:59.5, then 00:00:00.25 and 00:00:01 the next day (UTC).
    let midnight = std::time::UNIX_EPOCH + std::time::Duration::from_secs(1_795_392_000);
    let times = [
        midnight - std::time::Duration::from_millis(500),
        midnight + std::time::Duration::from_millis(250),
        midnight + std::time::Duration::from_secs(1),
    ];
    let mut bytes = Vec::new();
    {
        let mut writer = mcp_host::record::RecordWriter::new(&mut bytes).unwrap();
        for time in times {
            writer
                .write(time, mcp_host::record::Direction::Received, &[0x8A, 0x06])
                .unwrap();
        }
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("days.mcprec");
    std::fs::write(&path, &bytes).unwrap();
    let file = path.to_str().unwrap();

    let output = run(&["decode", file]);
    assert_eq!(output.status.code(), Some(0));
    let stdout = String::from_utf8_lossy(&output.stdout);
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), 5, "{stdout}");
    assert_eq!(lines[0], "-- 2026-11-22 (UTC) --");
    assert!(lines[1].starts_with("23:59:59.500 rx "), "{stdout}");
    assert_eq!(lines[2], "-- 2026-11-23 (UTC) --");
    assert!(lines[3].starts_with("00:00:00.250 rx "), "{stdout}");
    assert!(lines[4].starts_with("00:00:01.000 rx "), "{stdout}");

    // JSON carries the whole time in each object: no date lines.
    let output = run(&["decode", file, "--format", "json"]);
    let stdout = String::from_utf8_lossy(&output.stdout);
    let times: Vec<f64> = stdout
        .lines()
        .map(|l| {
            serde_json::from_str::<Value>(l).unwrap()["time"]
                .as_f64()
                .unwrap()
        })
        .collect();
    assert_eq!(times, [1_795_391_999.5, 1_795_392_000.25, 1_795_392_001.0]);
}

#[test]
fn a_recorded_frame_that_cannot_be_read_keeps_its_time() {
    let noon = std::time::UNIX_EPOCH + std::time::Duration::from_secs(1_795_435_200);
    let mut bytes = Vec::new();
    {
        let mut writer = mcp_host::record::RecordWriter::new(&mut bytes).unwrap();
        // A Receive Packet too short for its addresses.
        writer
            .write(noon, mcp_host::record::Direction::Received, &[0x90, 0x01])
            .unwrap();
    }
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.mcprec");
    std::fs::write(&path, &bytes).unwrap();
    let file = path.to_str().unwrap();
    let text = stdout(&run(&["decode", file]));
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "-- 2026-11-23 (UTC) --", "{text}");
    assert!(lines[1].starts_with("12:00:00.000 rx error: "), "{text}");
    assert!(lines[1].ends_with(": 9001"), "{text}");
    let json = stdout(&run(&["decode", file, "--format", "json"]));
    let value: Value = serde_json::from_str(json.trim()).unwrap();
    assert_eq!(value["error"], "frame");
    assert_eq!(value["time"], 1_795_435_200.0);
    assert_eq!(value["direction"], "rx");
}

#[test]
fn a_negative_number_gets_the_options_own_message() {
    for (args, expected) in [
        (
            &["demo", "--duration", "-1"][..],
            "expected a number of seconds from 0",
        ),
        (
            &["monitor", "--link", "pty", "--count", "-5"][..],
            "expected a number of received items, 1 or more, got `-5`",
        ),
        (
            &["sim", "--link", "pty", "--loss", "-0.1"][..],
            "expected a probability from 0 to 1",
        ),
        // A command word's own argument.
        (
            &["encode", "--to", "0013A20040B599B9", "time", "-5"][..],
            "expected `now`, `+N` (N seconds from now) or seconds since 1970",
        ),
    ] {
        let output = run(args);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
    }
}

#[test]
fn monitor_waits_for_a_link_that_is_not_there_yet() {
    use std::io::Read;
    let reserved = common::ReservedPort::new();
    let port = reserved.port;
    let link = format!("tcp:127.0.0.1:{port}");
    // Without --wait: nothing listens, exit 3 at once.
    assert_eq!(
        run(&["monitor", "--link", &link, "--count", "1"])
            .status
            .code(),
        Some(3)
    );
    // --wait cannot ask the radio its mode first, and a path that is no device never
    // becomes one.
    let output = run(&["monitor", "--link", &link, "--wait", "--api-mode", "auto"]);
    assert_eq!(output.status.code(), Some(2));
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("not-a-tty");
    std::fs::write(&file, b"").unwrap();
    let serial = format!("serial:{}", file.display());
    let output = run(&["monitor", "--link", &serial, "--wait"]);
    assert_eq!(output.status.code(), Some(3));
    assert!(
        String::from_utf8_lossy(&output.stderr).contains("is not a serial device"),
        "{output:?}"
    );

    let record = dir.path().join("flight.mcprec");
    let mut child = gs()
        .args(["monitor", "--link", &link, "--count", "1", "--wait"])
        .args(["--record", record.to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let errors = common::stderr_lines(&mut child);
    // It says why it waits, once.
    let waiting = format!(
        "mcp-gs: warning: link not there yet: waiting for it: cannot connect to 127.0.0.1:{port}: "
    );
    while !errors
        .recv_timeout(std::time::Duration::from_secs(30))
        .expect("the waiting line")
        .starts_with(&waiting)
    {}
    // The recording is made once the link is up, not before.
    assert!(!record.exists());
    // The radio comes. Asked its mode, it says 2 (monitor reads mode 1): a warning.
    let listener = reserved.listen();
    let (mut radio, _) = listener.accept().unwrap();
    let mut asked = [0u8; 8];
    radio.read_exact(&mut asked).unwrap();
    assert_eq!(
        (&asked[..4], &asked[5..7]),
        (&[0x7E, 0x00, 0x04, 0x08][..], &b"AP"[..])
    );
    let answer = [0x88, asked[4], b'A', b'P', 0x00, 0x02];
    let sum = answer.iter().fold(0u8, |s, b| s.wrapping_add(*b));
    radio.write_all(&[0x7E, 0x00, 0x06]).unwrap();
    radio.write_all(&answer).unwrap();
    radio.write_all(&[0xFF - sum]).unwrap();
    while !errors
        .recv_timeout(std::time::Duration::from_secs(30))
        .expect("the mode warning")
        .contains("the radio is in API mode 2 (AP=2) but --api-mode is 1")
    {}
    // Its modem status is the one item counted.
    radio
        .write_all(&[0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F])
        .unwrap();
    let output = child.wait_with_output().unwrap();
    assert_eq!(output.status.code(), Some(0));
    let out = stdout(&output);
    assert!(
        out.contains("link connected") && out.contains("modem status coordinator_started"),
        "{out}"
    );
    assert!(record.exists());
}

#[test]
fn a_missing_on_or_off_is_named_so() {
    for args in [
        &["encode", "--to", "0013a20040b599b9", "landing"][..],
        &["encode", "--to", "0013a20040b599b9", "telemetry"][..],
    ] {
        let output = run(args);
        assert_eq!(output.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&output.stderr);
        assert!(err.contains("<on|off>"), "{args:?}: {err}");
    }
}

#[test]
fn a_radio_or_hub_without_room_says_to_try_again_shortly() {
    let (link, radio) = common::refusing_radio(0x32);
    let output = run(&[
        "send",
        "--link",
        &link,
        "--to",
        "0013a20040b599b9",
        "landing",
        "on",
    ]);
    radio.join().unwrap();
    assert_eq!(output.status.code(), Some(5), "{output:?}");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("resource_error"), "{stderr}");
    assert!(
        stderr.contains("hint: the radio had no room for the frame")
            && stderr.contains("a hub between had no frame id free for it in time")
            && stderr.contains("try again shortly"),
        "{stderr}"
    );
}
