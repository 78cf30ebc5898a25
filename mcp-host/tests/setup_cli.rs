//! `mcp-gs setup` as a process against a fake radio on a real pseudo-terminal: a radio
//! in transparent mode (AP=0), as XBee modules leave the factory, is put into API mode
//! through its AT command mode (`+++`, `ATAP`, `ATAPn`, `ATWR`, `ATCN`) and then answers
//! API frames; one that does not answer `+++` (here an older radio in API mode, which
//! takes `+++` in transparent mode only) is asked in API frames instead, and found set
//! up already or the operator told how to set it. And the simulator's own radio, started
//! as from the factory, is set up, then reaches its MAV, and is found set up the next
//! time.

mod common;

use std::process::Output;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use mcp_host::{Connector, Link, LinkOptions, Transport};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use xbee_api::{ApiMode, AtCommandRepr, AtCommandResponseRepr, AtStatus, Decoder, EncodeFrame};

/// Failure guard only.
const GUARD: Duration = Duration::from_secs(30);
/// `mcp-gs` with `args`, to its end.
async fn mcp_gs(args: &[&str]) -> Output {
    let run = tokio::process::Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(args)
        .env_remove("MCP_LOG")
        .kill_on_drop(true)
        .output();
    tokio::time::timeout(GUARD, run)
        .await
        .expect("mcp-gs ends")
        .unwrap()
}

/// What the fake radio holds and what it was told.
#[derive(Debug, Default)]
struct Radio {
    /// Its API mode setting: 0 transparent, 1 or 2.
    ap: u8,
    /// An `AP` set in command mode, applied when command mode is left.
    pending: Option<u8>,
    /// Its baud rate setting (`BD`: 3 is 9600 baud, 7 is 115200).
    bd: u8,
    /// A `BD` set in command mode, applied when command mode is left.
    pending_bd: Option<u8>,
    /// `WR` was given.
    saved: bool,
    /// The command mode lines it got, in order.
    commands: Vec<String>,
    /// The AT commands it got in API frames, in order: `AP` for a read, `AP=[1]` for a
    /// value.
    api: Vec<String>,
    /// `WR` in an API frame is refused (a radio that cannot save).
    refuse_wr: bool,
    /// `ATAP` in command mode is answered `ERROR` (a firmware without API mode, or no
    /// XBee at all).
    refuse_ap: bool,
}

/// Plays the radio on the pseudo-terminal of `connector`, for each device that opens
/// its far end in turn.
async fn play(mut connector: Connector, radio: Arc<Mutex<Radio>>) {
    while let Ok(port) = connector.open().await {
        serve(port, &radio).await;
    }
}

/// One device's session: transparent mode and its command mode while `AP` is 0, API
/// frames (an `AT AP` answered) otherwise.
async fn serve(mut port: Transport, radio: &Mutex<Radio>) {
    // What a radio in transparent mode passes on from the air, unasked.
    if radio.lock().unwrap().ap == 0 && port.write_all(b"HELLO FROM THE AIR\r").await.is_err() {
        return;
    }
    let mut command_mode = false;
    let mut line = Vec::new();
    let mut decoder: Option<(ApiMode, Decoder)> = None;
    let mut buf = [0u8; 256];
    loop {
        let n = match port.read(&mut buf).await {
            Ok(0) | Err(_) => return,
            Ok(n) => n,
        };
        let bytes = &buf[..n];
        let ap = radio.lock().unwrap().ap;
        let mut out = Vec::new();
        if ap == 0 {
            if !command_mode {
                // `+++` alone after silence (what else comes goes over the air).
                if bytes == b"+++" {
                    command_mode = true;
                    out.extend_from_slice(b"OK\r");
                }
            } else {
                line.extend_from_slice(bytes);
                while let Some(end) = line.iter().position(|&b| b == b'\r') {
                    let text: Vec<u8> = line.drain(..=end).collect();
                    let text = String::from_utf8_lossy(&text[..end]).into_owned();
                    let mut radio = radio.lock().unwrap();
                    radio.commands.push(text.clone());
                    let answer = match text.as_str() {
                        "ATAP" if radio.refuse_ap => "ERROR".to_owned(),
                        "ATAP" => format!("{:X}", radio.ap),
                        "ATAP0" | "ATAP1" | "ATAP2" => {
                            radio.pending = text[4..].parse().ok();
                            "OK".to_owned()
                        }
                        "ATBD" => format!("{:X}", radio.bd),
                        "ATBD3" | "ATBD7" => {
                            radio.pending_bd = text[4..].parse().ok();
                            "OK".to_owned()
                        }
                        "ATWR" => {
                            radio.saved = true;
                            "OK".to_owned()
                        }
                        "ATCN" => {
                            command_mode = false;
                            if let Some(ap) = radio.pending.take() {
                                radio.ap = ap;
                            }
                            if let Some(bd) = radio.pending_bd.take() {
                                radio.bd = bd;
                            }
                            "OK".to_owned()
                        }
                        _ => "ERROR".to_owned(),
                    };
                    out.extend_from_slice(format!("{answer}\r").as_bytes());
                }
            }
        } else {
            let mode = if ap == 1 {
                ApiMode::Unescaped
            } else {
                ApiMode::Escaped
            };
            let (_, reading) = decoder.get_or_insert_with(|| (mode, Decoder::new(mode)));
            let mut requests = Vec::new();
            reading.decode_each(bytes, |event| {
                if let Ok(frame) = event {
                    if let Ok(at) = AtCommandRepr::parse_bytes(frame.data()) {
                        requests.push((at.frame_id, at.command, at.parameter.to_vec()));
                    }
                }
            });
            // Taken in API frames as an XBee does, each applied once answered: AP
            // (then answered and read in the new mode), BD and WR.
            let mut new_ap = None;
            for (frame_id, command, parameter) in requests {
                let mut radio = radio.lock().unwrap();
                let mut text = String::from_utf8_lossy(&command).into_owned();
                if !parameter.is_empty() {
                    text += &format!("={parameter:X?}");
                }
                radio.api.push(text);
                let value = match (&command, &parameter[..]) {
                    (b"AP", []) => Some(vec![ap]),
                    (b"BD", []) => Some(vec![radio.bd]),
                    (b"AP", [1 | 2]) => {
                        new_ap = Some(parameter[0]);
                        Some(vec![])
                    }
                    (b"BD", [bd]) => {
                        radio.bd = *bd;
                        Some(vec![])
                    }
                    (b"WR", []) if !radio.refuse_wr => {
                        radio.saved = true;
                        Some(vec![])
                    }
                    _ => None,
                };
                let response = AtCommandResponseRepr {
                    frame_id,
                    command,
                    status: if value.is_some() {
                        AtStatus::Ok
                    } else {
                        AtStatus::InvalidCommand
                    },
                    data: value.as_deref().unwrap_or_default(),
                };
                let mut frame = vec![0u8; response.encoded_len(mode)];
                let n = response.encode(mode, &mut frame).unwrap();
                out.extend_from_slice(&frame[..n]);
            }
            if let Some(new_ap) = new_ap {
                radio.lock().unwrap().ap = new_ap;
                decoder = None;
            }
        }
        if !out.is_empty() && port.write_all(&out).await.is_err() {
            return;
        }
    }
}

/// A fake radio with `AP` = `ap` on a pseudo-terminal: its state, and the far end's
/// path, for `mcp-gs` to open as `serial:PATH`.
async fn fake_radio(ap: u8) -> (Arc<Mutex<Radio>>, String) {
    let connector = Connector::new(&Link::Pty, &LinkOptions::default())
        .await
        .unwrap();
    let path = connector.pty_path().unwrap().display().to_string();
    let radio = Arc::new(Mutex::new(Radio {
        ap,
        bd: 3,
        ..Radio::default()
    }));
    tokio::spawn(play(connector, radio.clone()));
    (radio, path)
}

/// `mcp-gs setup --link LINK ARGS...`, with a short guard time.
async fn setup(link: &str, args: &[&str]) -> Output {
    let mut all = vec!["setup", "--link", link, "--guard-time", "50"];
    all.extend_from_slice(args);
    mcp_gs(&all).await
}

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[tokio::test]
async fn a_radio_in_transparent_mode_is_put_into_api_mode_and_answers_in_it() {
    for (mode, meaning, flag) in [
        ("1", "API mode 1", ""),
        ("2", "API mode 2, escaped", " with --api-mode 2"),
    ] {
        let (radio, path) = fake_radio(0).await;
        let out = setup(&format!("serial:{path}"), &["--api-mode", mode]).await;
        assert!(out.status.success(), "{out:?}");
        assert_eq!(
            stdout(&out),
            format!(
                "AP = 0 (transparent mode) -> {mode} ({meaning}), saved\n\
                 checked: the radio answers API frames in mode {mode} \
                 (use --link serial:{path}:115200{flag})\n"
            ),
            "{out:?}"
        );
        let radio = radio.lock().unwrap();
        assert_eq!(
            radio.commands,
            [
                "ATAP".to_owned(),
                format!("ATAP{mode}"),
                "ATWR".into(),
                "ATCN".into()
            ]
        );
        assert_eq!(radio.ap.to_string(), mode);
        assert!(radio.saved);
    }
}

#[tokio::test]
async fn the_baud_rate_is_set_with_the_mode_and_the_check_runs_at_it() {
    // A radio fresh from the factory: transparent mode, 9600 baud.
    let (radio, path) = fake_radio(0).await;
    let out = setup(&format!("serial:{path}:9600"), &["--baud", "115200"]).await;
    assert!(out.status.success(), "{out:?}");
    assert_eq!(
        stdout(&out),
        format!(
            "AP = 0 (transparent mode) -> 1 (API mode 1), saved\n\
             BD = 3 (9600 baud) -> 7 (115200 baud), saved\n\
             checked: the radio answers API frames in mode 1 (use --link serial:{path}:115200)\n"
        ),
        "{out:?}"
    );
    let radio = radio.lock().unwrap();
    assert_eq!(
        radio.commands,
        ["ATAP", "ATAP1", "ATBD", "ATBD7", "ATWR", "ATCN"]
    );
    assert_eq!((radio.ap, radio.bd), (1, 7));
}

#[tokio::test]
async fn a_change_made_before_command_mode_fails_is_said_and_applied_at_once() {
    // A radio that takes AP but not BD 8 (230400 baud: an older one tops out lower).
    let (radio, path) = fake_radio(0).await;
    let out = setup(&format!("serial:{path}:9600"), &["--baud", "230400"]).await;
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("the radio answered ATBD8 with \"ERROR\""),
        "{err}"
    );
    assert!(
        err.contains(
            "made already, in effect but not saved: AP = 0 (transparent mode) -> 1 (API mode \
             1) (powering the radio off and on undoes it"
        ),
        "{err}"
    );
    // Command mode left, so that the change applies now, not when it times out.
    let radio = radio.lock().unwrap();
    assert_eq!(
        radio.commands.last().map(String::as_str),
        Some("ATCN"),
        "{:?}",
        radio.commands
    );
    assert_eq!((radio.ap, radio.saved), (1, false));
}

#[tokio::test]
async fn a_baud_rate_the_radio_does_not_take_is_refused() {
    let out = setup("serial:/dev/null", &["--baud", "100000"]).await;
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    assert!(
        stderr(&out).contains("a baud rate the radio takes: 1200, 2400"),
        "{out:?}"
    );
}

#[tokio::test]
async fn transparent_mode_is_no_api_mode_to_set() {
    let out = setup("serial:/dev/null", &["--api-mode", "0"]).await;
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    assert!(
        stderr(&out).contains("API mode must be 1 or 2, got `0`"),
        "{out:?}"
    );
}

#[tokio::test]
async fn a_radio_set_up_already_is_checked_and_left_as_it_is() {
    // An older radio in API mode does not take +++: it is asked in API frames instead.
    let (radio, path) = fake_radio(1).await;
    let out = setup(&format!("serial:{path}"), &["--timeout", "1"]).await;
    assert!(out.status.success(), "{out:?}");
    assert_eq!(
        stdout(&out),
        format!(
            "AP = 1 (API mode 1) already\n\
             checked: the radio answers API frames in mode 1 (use --link serial:{path}:115200)\n"
        ),
        "{out:?}"
    );
    let slow = format!("serial:{path}:9600");
    let out = setup(&slow, &["--timeout", "1", "--baud", "9600"]).await;
    assert!(out.status.success(), "{out:?}");
    assert_eq!(
        stdout(&out),
        format!(
            "AP = 1 (API mode 1) already\n\
             BD = 3 (9600 baud) already\n\
             checked: the radio answers API frames in mode 1 (use --link {slow})\n"
        ),
        "{out:?}"
    );
    let radio = radio.lock().unwrap();
    assert!(radio.commands.is_empty(), "{:?}", radio.commands);
    // Read, and read again for the check: nothing set.
    assert_eq!(radio.api, ["AP", "AP", "AP", "BD", "AP"]);
    assert!(!radio.saved);
}

#[tokio::test]
async fn a_radio_in_api_mode_set_otherwise_is_set_up_in_api_frames() {
    let (radio, path) = fake_radio(2).await;
    let link = format!("serial:{path}:9600");
    let out = setup(&link, &["--timeout", "1", "--baud", "115200"]).await;
    assert!(out.status.success(), "{out:?}");
    assert!(
        stderr(&out).contains("answers API frames in mode 2: setting it up in API frames"),
        "{out:?}"
    );
    assert_eq!(
        stdout(&out),
        format!(
            "AP = 2 (API mode 2, escaped) -> 1 (API mode 1), saved\n\
             BD = 3 (9600 baud) -> 7 (115200 baud), saved\n\
             checked: the radio answers API frames in mode 1 (use --link serial:{path}:115200)\n"
        ),
        "{out:?}"
    );
    let radio = radio.lock().unwrap();
    assert!(radio.commands.is_empty(), "{:?}", radio.commands);
    // Read in mode 2; AP set in mode 2, the rest in mode 1; then checked.
    assert_eq!(radio.api, ["AP", "BD", "AP=[1]", "BD=[7]", "WR", "AP"]);
    assert_eq!((radio.ap, radio.bd, radio.saved), (1, 7, true));
}

#[tokio::test]
async fn a_change_in_api_frames_that_cannot_be_saved_is_said_to_be_in_effect() {
    let (radio, path) = fake_radio(2).await;
    radio.lock().unwrap().refuse_wr = true;
    let out = setup(&format!("serial:{path}"), &["--timeout", "1"]).await;
    assert_eq!(out.status.code(), Some(1), "{out:?}");
    let err = stderr(&out);
    assert!(err.contains("the radio refused WR"), "{err}");
    assert!(
        err.contains(
            "made already, in effect but not saved: AP = 2 (API mode 2, escaped) -> 1 (API mode 1)"
        ),
        "{err}"
    );
    assert_eq!(radio.lock().unwrap().ap, 1);
}

#[cfg(unix)]
#[tokio::test]
async fn a_radio_that_answers_neither_plus_plus_plus_nor_api_frames_sends_the_operator_to_probe() {
    // A pseudo-terminal nobody serves.
    let silent = Connector::new(&Link::Pty, &LinkOptions::default())
        .await
        .unwrap();
    let path = silent.pty_path().unwrap().display().to_string();
    let out = setup(&format!("serial:{path}"), &["--timeout", "0.2"]).await;
    assert_eq!(out.status.code(), Some(4), "{out:?}");
    assert!(out.stdout.is_empty(), "{out:?}");
    let err = stderr(&out);
    assert!(
        err.contains("no answer to +++") && err.contains("nor to an API frame"),
        "{err}"
    );
    let probe = format!("`mcp-gs probe --link serial:{path}` tries every rate");
    assert!(err.contains(&probe), "{err}");
    assert!(err.contains(&format!("serial:{path}:9600;")), "{err}");
    // At 9600 baud already, the factory's rate is not suggested again.
    let out = setup(&format!("serial:{path}:9600"), &["--timeout", "0.2"]).await;
    let err = stderr(&out);
    assert!(err.contains(&probe), "{err}");
    assert!(!err.contains("leave the factory at 9600"), "{err}");
}

#[tokio::test]
async fn a_link_to_no_radio_is_refused() {
    let out = setup("pty", &[]).await;
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    assert!(
        stderr(&out).contains("setup needs a link to a radio that is there"),
        "{out:?}"
    );
}

#[tokio::test]
async fn the_simulators_factory_radio_is_set_up_and_then_reaches_the_mav() {
    let (_sim, link) = factory_sim();

    // At another rate than the factory's 9600 baud, the radio does not understand +++.
    let out = mcp_gs(&["setup", "--link", &link, "--timeout", "1"]).await;
    assert_eq!(out.status.code(), Some(4), "{out:?}");
    assert!(stderr(&out).contains("no answer to +++"), "{out:?}");
    // In transparent mode it answers no API frame: the operator is sent to probe.
    let factory = format!("{link}:9600");
    let out = mcp_gs(&["at", "--link", &factory, "--timeout", "1", "AP"]).await;
    assert_eq!(out.status.code(), Some(4), "{out:?}");
    // Pointed at the port without a rate: probe tries the factory's first, then the
    // others.
    let probe = format!("`mcp-gs probe --link {link}` finds what it is set to");
    assert!(stderr(&out).contains(&probe), "{out:?}");

    // The emulated radio's guard time is Digi's default, setup's too.
    let out = mcp_gs(&[
        "setup",
        "--link",
        &factory,
        "--api-mode",
        "2",
        "--baud",
        "115200",
    ])
    .await;
    assert!(out.status.success(), "{out:?}");
    assert_eq!(
        stdout(&out),
        format!(
            "AP = 0 (transparent mode) -> 2 (API mode 2, escaped), saved\n\
             BD = 3 (9600 baud) -> 7 (115200 baud), saved\n\
             checked: the radio answers API frames in mode 2 (use --link {link}:115200 with \
             --api-mode 2)\n"
        ),
        "{out:?}"
    );

    // Its UART runs at 115200 baud now: a ground station at 9600 gets no answer.
    let slow = mcp_gs(&[
        "status",
        "--link",
        &factory,
        "--api-mode",
        "2",
        "--to",
        "0013A20040B599B9",
        "--timeout",
        "1",
        "landing",
    ])
    .await;
    assert_eq!(slow.status.code(), Some(4), "{slow:?}");
    let link = format!("{link}:115200");
    let out = mcp_gs(&[
        "status",
        "--link",
        &link,
        "--api-mode",
        "2",
        "--to",
        "0013A20040B599B9",
        "landing",
    ])
    .await;
    assert!(out.status.success(), "{out:?}");
    assert!(stdout(&out).contains("landing"), "{out:?}");

    // Set up again, it is found as asked (in API mode, it takes no +++) and left so.
    let out = mcp_gs(&[
        "setup",
        "--link",
        &link,
        "--api-mode",
        "2",
        "--baud",
        "115200",
        "--timeout",
        "1",
    ])
    .await;
    assert!(out.status.success(), "{out:?}");
    assert_eq!(
        stdout(&out),
        format!(
            "AP = 2 (API mode 2, escaped) already\n\
             BD = 7 (115200 baud) already\n\
             checked: the radio answers API frames in mode 2 (use --link {link} with \
             --api-mode 2)\n"
        ),
        "{out:?}"
    );

    // Asked for mode 1, it is set up in API frames, and found so the next time.
    let to_one = ["setup", "--link", &link, "--timeout", "1"];
    let out = mcp_gs(&to_one).await;
    assert!(out.status.success(), "{out:?}");
    assert_eq!(
        stdout(&out),
        format!(
            "AP = 2 (API mode 2, escaped) -> 1 (API mode 1), saved\n\
             checked: the radio answers API frames in mode 1 (use --link {link})\n"
        ),
        "{out:?}"
    );
    let out = mcp_gs(&to_one).await;
    assert!(out.status.success(), "{out:?}");
    assert_eq!(
        stdout(&out),
        format!(
            "AP = 1 (API mode 1) already\n\
             checked: the radio answers API frames in mode 1 (use --link {link})\n"
        ),
        "{out:?}"
    );

    // A BD set in an API frame applies once answered: its UART is back at 9600 baud.
    let out = mcp_gs(&["at", "--link", &link, "BD", "3"]).await;
    assert!(out.status.success(), "{out:?}");
    let out = mcp_gs(&["at", "--link", &factory, "--timeout", "1", "AP"]).await;
    assert!(out.status.success(), "{out:?}");
    let out = mcp_gs(&["at", "--link", &link, "--timeout", "1", "AP"]).await;
    assert_eq!(out.status.code(), Some(4), "{out:?}");
}

/// A simulator whose ground station radio is as from the factory (transparent mode, its
/// UART at 9600 baud), and the `serial:` link to its pseudo-terminal without the rate.
fn factory_sim() -> (common::Running, String) {
    let args = [
        "sim",
        "--link",
        "pty",
        "--api-mode",
        "0",
        "--duration",
        "60",
    ];
    let (child, lines) = common::spawn_lines(&args);
    let link = sim_link(&lines);
    let path = link
        .strip_suffix(":9600")
        .unwrap_or_else(|| panic!("announced at 9600 baud: {link}"));
    (common::Running(child), path.to_owned())
}

/// The `serial:` link of a simulator's ground station radio, from its announcement.
fn sim_link(lines: &std::sync::mpsc::Receiver<String>) -> String {
    let announced = loop {
        let line = lines.recv_timeout(GUARD).expect("sim prints its link");
        if line.starts_with("ground station link") {
            break line;
        }
    };
    announced
        .split("(open it as ")
        .nth(1)
        .and_then(|rest| rest.split(')').next())
        .expect("the pty's link")
        .to_owned()
}

#[tokio::test]
async fn probe_finds_a_factory_radio_and_one_in_api_mode_2() {
    let (_sim, link) = factory_sim();
    let out = mcp_gs(&["probe", "--link", &link]).await;
    assert!(out.status.success(), "{out:?}");
    assert_eq!(
        stdout(&out),
        format!(
            "{link}:9600: transparent mode (AP=0): `mcp-gs setup --link {link}:9600` puts it \
             into API mode\n"
        )
    );
    // Set up for 115200 baud, it is found there, after 9600 is tried in vain.
    let factory = format!("{link}:9600");
    let out = mcp_gs(&["setup", "--link", &factory, "--baud", "115200"]).await;
    assert!(out.status.success(), "{out:?}");
    let out = mcp_gs(&["probe", "--link", &link]).await;
    assert!(out.status.success(), "{out:?}");
    assert_eq!(
        stdout(&out),
        format!("{link}:115200: API mode 1 (use --link {link}:115200)\n")
    );
    assert!(stderr(&out).contains("mcp-gs: 9600 baud..."), "{out:?}");

    let (radio, path) = fake_radio(2).await;
    let out = mcp_gs(&[
        "probe",
        "--link",
        &format!("serial:{path}"),
        "--guard-time",
        "50",
    ])
    .await;
    assert!(out.status.success(), "{out:?}");
    assert_eq!(
        stdout(&out),
        format!("serial:{path}:9600: API mode 2 (use --link serial:{path}:9600 --api-mode 2)\n")
    );
    // Asked in an API frame only: no command mode.
    assert!(radio.lock().unwrap().commands.is_empty());
}

#[cfg(unix)]
#[tokio::test]
async fn a_simulated_radio_in_api_mode_is_found_at_115200_baud_only() {
    // Its UART runs at its BD, 7: at 9600 baud (tried first) it is not understood.
    let (child, lines) = common::spawn_lines(&["sim", "--link", "pty", "--duration", "60"]);
    let _sim = common::Running(child);
    // Printed as `serial:PATH`: 115200 is the links' default rate.
    let path = sim_link(&lines);
    let found = format!("{path}:115200: API mode 1 (use --link {path}:115200)\n");
    let out = mcp_gs(&["probe", "--link", &path, "--timeout", "0.3"]).await;
    assert!(out.status.success(), "{out:?}");
    assert_eq!(stdout(&out), found, "{out:?}");
    assert!(stderr(&out).contains("mcp-gs: 9600 baud..."), "{out:?}");
    // With the rate in the link, that rate is tried first: found at once.
    let link = format!("{path}:115200");
    let out = mcp_gs(&["probe", "--link", &link, "--timeout", "0.3"]).await;
    assert!(out.status.success(), "{out:?}");
    assert_eq!(stdout(&out), found, "{out:?}");
    assert_eq!(stderr(&out), "mcp-gs: 115200 baud...\n", "{out:?}");
}

#[tokio::test]
async fn probe_and_setup_say_when_plus_plus_plus_is_answered_but_atap_is_not() {
    let (radio, path) = fake_radio(0).await;
    radio.lock().unwrap().refuse_ap = true;
    let link = format!("serial:{path}");
    let out = mcp_gs(&["probe", "--link", &link, "--guard-time", "50"]).await;
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(out.stdout.is_empty(), "{out:?}");
    // Found at the first rate: no other tried.
    assert!(!err.contains("115200 baud"), "{err}");
    assert!(
        err.contains(&format!(
            "{link}:9600: something answered +++ with OK, but not ATAP (command mode: the \
             radio answered ATAP with \"ERROR\"): a radio slow to answer (give a longer \
             --timeout), an XBee whose firmware has no API mode, or no XBee"
        )),
        "{err}"
    );
    // Setup says the same refusal, and sets nothing.
    let out = setup(&format!("{link}:9600"), &[]).await;
    let err = stderr(&out);
    assert_ne!(out.status.code(), Some(0), "{err}");
    assert!(
        err.contains("the radio answered ATAP with \"ERROR\""),
        "{err}"
    );
    assert!(!err.contains("AP = ERROR"), "{err}");
    let commands = radio.lock().unwrap().commands.clone();
    assert!(
        !commands
            .iter()
            .any(|c| c.starts_with("ATAP") && c.len() > 4),
        "{commands:?}"
    );
}

#[cfg(unix)]
#[tokio::test]
async fn probe_says_when_nothing_answers_at_any_rate() {
    // A pseudo-terminal nobody serves.
    let silent = Connector::new(&Link::Pty, &LinkOptions::default())
        .await
        .unwrap();
    let path = silent.pty_path().unwrap().display().to_string();
    let out = mcp_gs(&[
        "probe",
        "--link",
        &format!("serial:{path}"),
        "--timeout",
        "0.1",
        "--guard-time",
        "20",
    ])
    .await;
    assert_eq!(out.status.code(), Some(4), "{out:?}");
    assert!(out.stdout.is_empty(), "{out:?}");
    let err = stderr(&out);
    for baud in ["9600", "115200", "230400", "1200"] {
        assert!(err.contains(&format!("mcp-gs: {baud} baud...")), "{err}");
    }
    assert!(
        err.contains(&format!(
            "no radio answered on serial:{path} at any baud rate"
        )),
        "{err}"
    );

    let out = mcp_gs(&["probe", "--link", "tcp:127.0.0.1:9"]).await;
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    assert!(stderr(&out).contains("give serial:PATH"), "{out:?}");

    // A port that is not there is named at the first rate probe would try, not at the
    // links' default rate.
    for (link, named) in [
        (
            "serial:/dev/mcp-gs-no-such-port",
            "serial:/dev/mcp-gs-no-such-port:9600",
        ),
        (
            "serial:/dev/mcp-gs-no-such-port:57600",
            "serial:/dev/mcp-gs-no-such-port:57600",
        ),
    ] {
        let out = mcp_gs(&["probe", "--link", link]).await;
        assert_eq!(out.status.code(), Some(3), "{out:?}");
        assert!(
            stderr(&out).starts_with(&format!("mcp-gs: cannot open {named}: no such device")),
            "{out:?}"
        );
    }
}
