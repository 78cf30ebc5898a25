//! `mcp-gs at` and `mcp-gs nodes` as processes against `mcp-gs sim` (its emulated
//! radios) over TCP: how values and radios print, what the radio's refusals say and
//! which exit codes they give.

use std::process::{Child, Command, Output};
use std::time::Duration;

mod common;

const MAV: &str = "0013a20040b599b9";
/// An address no node of the simulated network has.
const NOBODY: &str = "0013a200deadbeef";
/// Failure guard only.
const GUARD: Duration = Duration::from_secs(30);

/// `mcp-gs sim` listening on TCP, killed when dropped.
struct Sim {
    child: Child,
    link: String,
}

impl Sim {
    fn start() -> Self {
        Self::start_with(&[])
    }

    /// `sim` with more arguments.
    fn start_with(args: &[&str]) -> Self {
        let mut all = vec![
            "sim",
            "--link",
            "tcp-listen:127.0.0.1:0",
            "--duration",
            "300",
        ];
        all.extend_from_slice(args);
        let (child, rx) = common::spawn_lines(&all);
        let link = announced_link(&rx);
        Sim { child, link }
    }

    /// `mcp-gs at --link LINK ARGS...`.
    fn at(&self, args: &[&str]) -> Output {
        Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
            .args(["at", "--link", &self.link, "--timeout", "10"])
            .args(args)
            .output()
            .expect("run mcp-gs at")
    }

    /// The standard output of a successful `at`.
    fn ok(&self, args: &[&str]) -> String {
        let out = self.at(args);
        assert!(
            out.status.success(),
            "at {args:?}: {}\n{}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8(out.stdout).unwrap()
    }
}

impl Drop for Sim {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// A virtual network of a coordinator alone, on TCP: the process and its link.
fn lone_coordinator() -> (common::Running, String) {
    let (child, rx) = common::spawn_lines(&["radio", "--coordinator", "tcp-listen:127.0.0.1:0"]);
    (common::Running(child), announced_link(&rx))
}

/// The link a `sim` or `radio` process says to connect with, from its output lines.
fn announced_link(lines: &std::sync::mpsc::Receiver<String>) -> String {
    loop {
        let line = lines
            .recv_timeout(GUARD)
            .expect("the process prints its link");
        if let Some(rest) = line.split("(connect with ").nth(1) {
            return rest.split(')').next().unwrap().to_string();
        }
    }
}

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn text_parameters_print_as_text_and_numbers_as_numbers() {
    let sim = Sim::start();
    // NI is text: one space by default, quoted, not the number 0x20.
    assert_eq!(sim.ok(&["NI"]), "NI = \" \"\n");
    assert_eq!(sim.ok(&["--to", MAV, "NI"]), "NI = \" \"\n");
    // HV and VR are numbers.
    assert_eq!(sim.ok(&["HV"]), "HV = 2E00 (0x2e00, 11776)\n");
    assert_eq!(sim.ok(&["VR"]), "VR = 4060 (0x4060, 16480)\n");
}

#[test]
fn a_remote_command_that_is_not_delivered_exits_5() {
    let sim = Sim::start();
    let out = sim.at(&["--to", NOBODY, "NI"]);
    assert_eq!(out.status.code(), Some(5), "{out:?}");
    let message = stderr(&out);
    assert_eq!(message.lines().count(), 1, "{message}");
    assert!(
        message.contains("not delivered to") && message.contains("tx_failure (0x04)"),
        "{message}"
    );
    assert!(out.stdout.is_empty());
}

#[test]
fn an_at_command_without_answer_exits_4() {
    // A peer that reads everything and never answers, for two ground stations in turn.
    let (link, peer) = common::silent_peer(2);
    for to in [None, Some(MAV)] {
        let mut args = vec!["at", "--link", &link, "--timeout", "0.5"];
        if let Some(to) = to {
            args.extend(["--to", to]);
        }
        args.push("NI");
        let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
            .args(&args)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(4), "{args:?}: {out:?}");
        assert!(stderr(&out).contains("within 0.5 s"), "{out:?}");
    }
    peer.join().unwrap();
    // Without --timeout a local command is waited for 3 s: the radio answers at once.
    let (link, peer) = common::silent_peer(1);
    let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["at", "--link", &link, "AP"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(4), "{out:?}");
    assert!(stderr(&out).contains("within 3 s"), "{out:?}");
    peer.join().unwrap();
}

#[test]
fn refusals_say_what_the_radio_answered() {
    let sim = Sim::start();
    // A command or value the radio does not take is bad input: exit code 2.
    let out = sim.at(&["HV", "1"]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let message = stderr(&out);
    assert!(
        message.contains("invalid_parameter (0x03)") && message.contains("refused the value"),
        "{message}"
    );
    let out = sim.at(&["ZZ"]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let message = stderr(&out);
    assert!(
        message.contains("invalid_command (0x02)") && message.contains("does not know"),
        "{message}"
    );
    // A remote radio's refusal names it.
    let out = sim.at(&["--to", MAV, "HV", "1"]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let message = stderr(&out);
    assert!(
        message.starts_with(&format!("mcp-gs: HV on {}: ", MAV.to_lowercase()))
            && message.contains("invalid_parameter (0x03)"),
        "{message}"
    );
}

#[test]
fn options_for_a_value_without_one_are_usage_errors() {
    // Nothing to take as text or to queue: a read, not silently a read.
    for option in ["--text", "--no-apply"] {
        let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
            .args(["at", "--link", "tcp:127.0.0.1:9", option, "NI"])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{out:?}");
        assert!(stderr(&out).contains("<VALUE>"), "{out:?}");
    }
}

#[test]
fn network_parameters_read_and_the_node_identifier_is_set_as_text() {
    let sim = Sim::start();
    assert_eq!(
        sim.ok(&["ID"]),
        "ID = 0000000000000000 (0x0000000000000000, 0)\n"
    );
    assert!(sim.ok(&["OP"]).starts_with("OP = "));
    let ch = sim.ok(&["CH"]);
    assert!(
        ch.starts_with("CH = ") && ch.len() == "CH = 17 (0x17, 23)\n".len(),
        "{ch}"
    );
    // NI takes text without --text, locally and remotely.
    assert_eq!(sim.ok(&["NI", "Ground 1"]), "NI: ok\n");
    assert_eq!(sim.ok(&["NI"]), "NI = \"Ground 1\"\n");
    assert_eq!(sim.ok(&["--to", MAV, "NI", "Left wing"]), "NI: ok\n");
    assert_eq!(sim.ok(&["--to", MAV, "NI"]), "NI = \"Left wing\"\n");
    // Too long: the radio refuses it.
    let out = sim.at(&["NI", "twenty-one characters"]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    assert!(stderr(&out).contains("refused the value"), "{out:?}");
}

#[test]
fn json_prints_each_answer_as_its_frame_with_the_value_read() {
    let sim = Sim::start();
    let json = |args: &[&str], code: i32| {
        let out = sim.at(&[&["--format", "json"], args].concat());
        assert_eq!(out.status.code(), Some(code), "{out:?}");
        serde_json::from_str::<serde_json::Value>(&stdout(&out)).unwrap()
    };
    // A number, locally.
    let ch = json(&["CH"], 0);
    assert_eq!(
        (
            &ch["result"],
            &ch["frame"],
            &ch["command"],
            &ch["status_name"]
        ),
        (
            &"answered".into(),
            &"at_response".into(),
            &"CH".into(),
            &"ok".into()
        ),
        "{ch}"
    );
    let data = u64::from_str_radix(ch["data"].as_str().unwrap(), 16).unwrap();
    assert_eq!(ch["value"], data, "{ch}");
    // Text, remotely, with where it came from.
    assert_eq!(
        json(&["--to", MAV, "NI", "Left wing"], 0).get("value"),
        None
    );
    let ni = json(&["--to", MAV, "NI"], 0);
    assert_eq!(
        (&ni["frame"], &ni["src64"], &ni["value"]),
        (
            &"remote_at_response".into(),
            &MAV.into(),
            &"Left wing".into()
        ),
        "{ni}"
    );
    // A value longer than 6 bytes is in `data` alone: no JSON number holds every one.
    let op = json(&["OP"], 0);
    assert_eq!(
        (op["data"].as_str().map(str::len), op.get("value")),
        (Some(16), None)
    );
    // A refusal prints its answer too, and fails as in text.
    let refused = json(&["NI", "twenty-one characters"], 2);
    assert_eq!(
        (&refused["result"], &refused["status_name"]),
        (&"answered".into(), &"invalid_parameter".into()),
        "{refused}"
    );
    // Every answer to a broadcast.
    let all = json(&["--to", "000000000000ffff", "--window", "1", "NI"], 0);
    assert_eq!(
        (&all["src64"], &all["value"]),
        (&MAV.into(), &"Left wing".into())
    );
}

#[test]
fn a_queued_change_is_applied_with_ac_and_saved_with_wr() {
    let sim = Sim::start();
    // As --no-apply's help says: queue, then AC; WR writes the settings to flash.
    for to in [&[][..], &["--to", MAV][..]] {
        let run = |args: &[&str]| sim.ok(&[to, args].concat());
        assert_eq!(run(&["--no-apply", "NI", "Queued"]), "NI: ok\n");
        assert_eq!(run(&["AC"]), "AC: ok\n");
        assert_eq!(run(&["WR"]), "WR: ok\n");
        assert_eq!(run(&["NI"]), "NI = \"Queued\"\n");
    }
    // The commissioning button, pressed remotely: an action too.
    assert_eq!(sim.ok(&["--to", MAV, "CB", "1"]), "CB: ok\n");
    // AC and WR take no value.
    let out = sim.at(&["AC", "1"]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    assert!(stderr(&out).contains("invalid_parameter (0x03)"), "{out:?}");
}

#[test]
fn api_mode_auto_waits_for_a_slow_radio_as_long_as_the_timeout_given() {
    // Every frame to the link 3.5 s late: longer than auto's own 3 s.
    let sim = Sim::start_with(&["--latency", "3500"]);
    let out = sim.ok(&["--api-mode", "auto", "AP"]);
    assert_eq!(out.trim(), "AP = 01 (0x01, 1)", "{out}");
}

#[test]
fn reading_ap_in_another_api_mode_warns() {
    let sim = Sim::start();
    // The simulated radio is in mode 1; its AP answer reads the same in mode 2.
    let out = sim.at(&["--api-mode", "2", "AP"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("the radio is in API mode 1 (AP=1) but --api-mode is 2"),
        "{}",
        stderr(&out)
    );
    // Over TCP, which may be a hub: the hub must speak the radio's mode too.
    assert!(
        stderr(&out).contains("through a hub, the hub itself must be started with --api-mode 1"),
        "{}",
        stderr(&out)
    );
    // In its own mode, no warning.
    let out = sim.at(&["AP"]);
    assert_eq!(stderr(&out), "");
}

/// `mcp-gs nodes --link LINK ARGS...` against `sim`.
fn nodes(link: &str, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["nodes", "--link", link, "--timeout", "10"])
        .args(args)
        .output()
        .expect("run mcp-gs nodes")
}

#[test]
fn nodes_lists_the_radios_that_answer_node_discovery() {
    let sim = Sim::start();
    sim.ok(&["--to", MAV, "NI", "MAV 1"]);
    let out = nodes(&sim.link, &["--window", "2"]);
    assert!(out.status.success(), "{out:?}");
    let text = String::from_utf8(out.stdout.clone()).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 1, "{text}");
    assert!(
        lines[0].starts_with("0013a20040b599b9 (") && lines[0].ends_with(") router \"MAV 1\""),
        "{text}"
    );
    assert!(stderr(&out).contains("answers for 2 s"), "{out:?}");

    let out = nodes(&sim.link, &["--window", "2", "--format", "json"]);
    let node: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(node["addr64"], MAV);
    // As a node identification frame's fields: the role a number with its name, no
    // RSSI field where the radio gives none.
    assert_eq!(node["identifier"], "MAV 1");
    assert_eq!(node["device_type"], 1);
    assert_eq!(node["device_type_name"], "router");
    assert_eq!(node.get("rssi_dbm"), None);

    // Text from the radio is written as message text (a backslash doubled, bytes
    // outside printable ASCII as \xNN), the same by `at` and `nodes`. (A radio takes
    // printable ASCII alone in its NI.) It is given as it is printed, too.
    sim.ok(&["--to", MAV, "NI", r#"M\\1 "x""#]);
    let out = sim.at(&["--format", "json", "--to", MAV, "NI"]);
    let at: serde_json::Value = serde_json::from_str(&stdout(&out)).unwrap();
    assert_eq!(at["value"], r#"M\\1 "x""#, "{at}");
    let out = sim.at(&["--to", MAV, "NI"]);
    assert!(stdout(&out).contains(r##"NI = "M\\1 \"x\"""##), "{out:?}");
    let out = nodes(&sim.link, &["--window", "2", "--format", "json"]);
    let node: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(node["identifier"], at["value"], "{node}");
    sim.ok(&["--to", MAV, "NI", "MAV 1"]);

    // Without --window: as long as the radio's NT says, and a second.
    sim.ok(&["NT", "20"]);
    let out = nodes(&sim.link, &[]);
    assert!(out.status.success(), "{out:?}");
    assert!(stderr(&out).contains("answers for 4.2 s"), "{out:?}");
    assert_eq!(String::from_utf8(out.stdout).unwrap(), text);

    // `at ND` shows the first answer, and says where the others are.
    let out = sim.at(&["ND"]);
    assert!(out.status.success(), "{out:?}");
    assert!(stdout(&out).starts_with("ND = "), "{out:?}");
    assert!(
        stderr(&out).contains("this is the first answer; `mcp-gs nodes` lists them all"),
        "{out:?}"
    );
}

#[test]
fn nodes_says_when_no_radio_answers() {
    let (_radio, link) = lone_coordinator();
    let out = nodes(&link, &["--window", "1"]);
    assert_eq!(out.status.code(), Some(4), "{out:?}");
    assert!(out.stdout.is_empty(), "{out:?}");
    assert!(stderr(&out).contains("no radio answered"), "{out:?}");
    assert!(!stderr(&out).contains("hint"), "{out:?}");
}

#[test]
fn nodes_in_the_wrong_api_mode_points_at_the_mode() {
    // The local radio answers N? in either mode (no byte of it is escaped), but every
    // node's answer holds its 64-bit address, 0013A2..., whose 0x13 a radio in mode 2
    // escapes: read in mode 1, the answer fails its checksum.
    let sim = Sim::start_with(&["--api-mode", "2"]);
    let out = nodes(&sim.link, &["--window", "1", "--api-mode", "1"]);
    assert_eq!(out.status.code(), Some(4), "{out:?}");
    // Not that no radio answered: their answers could not be read.
    assert!(
        stderr(&out).contains("no answer could be read: ")
            && stderr(&out).contains(" from the radio failed to decode"),
        "{out:?}"
    );
    assert!(!stderr(&out).contains("no radio answered"), "{out:?}");
    assert!(
        stderr(&out).contains("the radio may be in API mode 2 (AP=2)"),
        "{out:?}"
    );
}

#[test]
fn a_command_sent_in_the_wrong_api_mode_times_out_pointing_at_the_mode() {
    // The radio's modem status passes in either mode, but the Transmit Request holds the
    // MAV's address, 0013A2..., whose 0x13 is escaped in mode 2: a radio in mode 1
    // fails its checksum and never answers.
    let sim = Sim::start();
    let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["send", "--link", &sim.link, "--api-mode", "2", "--to", MAV])
        .args(["--timeout", "2", "landing", "on"])
        .output()
        .expect("run mcp-gs send");
    assert_eq!(out.status.code(), Some(4), "{out:?}");
    let err = stderr(&out);
    assert!(err.contains("may still have gone out"), "{err}");
    assert!(
        err.contains("other frames came from the radio, but no answer to this one"),
        "{err}"
    );
    let read_mode = format!("mcp-gs at --link {} --api-mode auto AP", sim.link);
    assert!(err.contains(&read_mode), "{err}");
}

#[test]
fn a_mav_that_does_not_answer_is_no_api_mode_problem() {
    // The radio delivers the request (its Transmit Status proves the mode right), but
    // every frame to the MAV is lost: no report, and no hint at the API mode.
    let sim = Sim::start_with(&["--faults", "0013A20040B599B9=loss=1"]);
    let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["status", "--link", &sim.link, "--to", MAV])
        .args(["--timeout", "1", "landing"])
        .output()
        .expect("run mcp-gs status");
    assert_eq!(out.status.code(), Some(4), "{out:?}");
    let err = stderr(&out);
    assert!(err.contains("the radio delivered the request"), "{err}");
    assert!(!err.contains("hint"), "{err}");
}

#[test]
fn a_broadcast_remote_command_is_carried_out_by_every_radio_and_answered_once() {
    let sim = Sim::start_with(&["--mavs", "2"]);
    let broadcast = |args: &[&str]| {
        let mut all = vec!["--to", "000000000000ffff", "--window", "2"];
        all.extend_from_slice(args);
        sim.at(&all)
    };
    // Every MAV's radio takes the name; the Zigbee radio hands over one answer.
    let out = broadcast(&["NI", "MAV"]);
    assert!(out.status.success(), "{out:?}");
    assert_eq!(stdout(&out), "0013a20040b599b9: NI: ok\n", "{out:?}");
    for mav in [MAV, "0013a20040b599bf"] {
        assert_eq!(sim.ok(&["--to", mav, "NI"]), "NI = \"MAV\"\n");
    }
    let out = broadcast(&["NI"]);
    assert!(out.status.success(), "{out:?}");
    assert_eq!(stdout(&out), "0013a20040b599b9: NI = \"MAV\"\n");
    assert!(
        stderr(&out).contains("a Zigbee radio hands over a single answer to a broadcast"),
        "{out:?}"
    );
    // Digi's commands with a sign are commands too: N? reaches the radio, which, as a
    // Zigbee radio, does not know it.
    let out = sim.at(&["N?"]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    assert!(
        stderr(&out).contains("N?: the radio answered invalid_command"),
        "{out:?}"
    );
    // A refusal: its line, and the exit code a refusal gives (2: an invalid value).
    let out = broadcast(&["HV", "1"]);
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    assert!(
        stdout(&out).starts_with("0013a20040b599b9: HV: the radio answered invalid_parameter"),
        "{out:?}"
    );
    assert!(
        stderr(&out).contains("HV: the radio that answered refused the command"),
        "{out:?}"
    );
}

#[test]
fn a_broadcast_nobody_answers_exits_4() {
    let (_radio, link) = lone_coordinator();
    let out = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args([
            "at",
            "--link",
            &link,
            "--to",
            "000000000000ffff",
            "--window",
            "1",
            "VR",
        ])
        .output()
        .expect("run mcp-gs at");
    assert_eq!(out.status.code(), Some(4), "{out:?}");
    assert!(out.stdout.is_empty(), "{out:?}");
    assert!(
        stderr(&out).contains("VR: no radio answered the broadcast within 1 s"),
        "{out:?}"
    );
}

#[test]
fn a_local_mode_or_rate_changed_says_what_later_commands_need() {
    let sim = Sim::start();
    // BD reads as its baud rate, as `setup` prints it.
    assert_eq!(sim.ok(&["BD"]), "BD = 7 (115200 baud)\n");
    let out = sim.at(&["BD", "3"]);
    assert!(out.status.success(), "{out:?}");
    assert_eq!(stdout(&out), "BD: ok\n");
    assert!(
        stderr(&out).contains("note: the radio's UART now runs at 9600 baud"),
        "{}",
        stderr(&out)
    );
    // The same mode as --api-mode needs nothing; another does.
    let out = sim.at(&["AP", "1"]);
    assert_eq!(stderr(&out), "", "{out:?}");
    let out = sim.at(&["AP", "2"]);
    assert!(out.status.success(), "{out:?}");
    assert!(
        stderr(&out).contains("note: the radio now speaks API mode 2: give --api-mode 2"),
        "{}",
        stderr(&out)
    );
    // A remote radio's settings are not the link's.
    let out = sim.at(&["--api-mode", "2", "--to", MAV, "AP", "1"]);
    assert!(out.status.success(), "{out:?}");
    assert!(!stderr(&out).contains("note:"), "{}", stderr(&out));
}
