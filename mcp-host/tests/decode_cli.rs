//! `mcp-gs decode` of damaged input: lines of hex text that are not hex, recordings cut
//! off, and the messages that name the file.

use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Output, Stdio};

use serde_json::Value;

mod common;

/// A modem status frame, "coordinator started", as hex text.
const FRAME: &str = "7E 00 02 8A 06 6F";

fn gs() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
}

/// `mcp-gs decode` with `args`, `input` on its standard input.
fn decode_stdin(args: &[&str], input: &str) -> Output {
    let mut child = gs()
        .arg("decode")
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("mcp-gs runs");
    let mut stdin = child.stdin.take().expect("stdin");
    stdin.write_all(input.as_bytes()).unwrap();
    drop(stdin);
    child.wait_with_output().unwrap()
}

/// `mcp-gs decode` with `args`.
fn decode(args: &[&str]) -> Output {
    gs().arg("decode").args(args).output().expect("mcp-gs runs")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8(bytes.to_vec()).expect("utf-8 output")
}

/// A file of this test's own in a temporary directory, removed when dropped.
struct TempFile {
    /// Held for its removal when dropped.
    _dir: tempfile::TempDir,
    path: PathBuf,
}

impl TempFile {
    fn new(name: &str, bytes: &[u8]) -> Self {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        TempFile { _dir: dir, path }
    }

    fn path(&self) -> &str {
        self.path.to_str().unwrap()
    }
}

#[test]
fn a_line_that_is_not_hex_is_said_and_skipped_and_decoding_goes_on() {
    let input = format!("{FRAME}\nxx\n{FRAME}\n");
    let output = decode_stdin(&["--hex"], &input);
    let (out, err) = (text(&output.stdout), text(&output.stderr));
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 3, "{out}");
    assert!(lines[0].contains("coordinator_started"), "{out}");
    assert_eq!(
        lines[1],
        "error, found at input line 2: `xx` is not a hex byte (line skipped)"
    );
    assert!(lines[2].contains("coordinator_started"), "{out}");
    // Bad input all the same, said on standard error: from standard input, no file named.
    assert_eq!(output.status.code(), Some(2), "{err}");
    assert!(
        err.starts_with("mcp-gs: line 2: `xx` is not a hex byte (line skipped); the other lines"),
        "{err}"
    );

    // In JSON, an error object with the line, as a dropped frame's with its offset.
    let output = decode_stdin(&["--hex", "--format", "json"], &input);
    assert_eq!(output.status.code(), Some(2));
    let values: Vec<Value> = text(&output.stdout)
        .lines()
        .map(|line| serde_json::from_str(line).unwrap())
        .collect();
    assert_eq!(values.len(), 3, "{values:?}");
    assert_eq!(values[0]["frame"], "modem_status");
    assert_eq!(values[1]["error"], "hex");
    assert_eq!(values[1]["line"], 2);
    assert_eq!(
        values[1]["message"],
        "`xx` is not a hex byte (line skipped)"
    );
    assert_eq!(values[2]["frame"], "modem_status");
}

#[test]
fn a_frame_split_around_a_bad_line_is_read_without_it() {
    // The good bytes of a bad line go with it: the decoder reads on as if the line was
    // not there, and the frame's two halves make it whole.
    let output = decode_stdin(&["--hex"], "7E 00 02\n8A zz 06\n8A 06 6F\n");
    let out = text(&output.stdout);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 2, "{out}");
    assert!(
        lines[0].starts_with("error, found at input line 2: "),
        "{out}"
    );
    assert!(lines[1].contains("coordinator_started"), "{out}");
    assert_eq!(output.status.code(), Some(2));
}

#[test]
fn the_summary_counts_bad_lines_among_errors() {
    let input = format!("{FRAME}\nxx\n{FRAME} 0\n{FRAME}\n");
    let output = decode_stdin(&["--hex", "--summary", "--format", "json"], &input);
    assert_eq!(output.status.code(), Some(2));
    let summary: Value = serde_json::from_str(text(&output.stdout).trim()).unwrap();
    assert_eq!(summary["frames"], 2, "{summary}");
    assert_eq!(summary["errors"]["bad_hex_line"], 2, "{summary}");
    let err = text(&output.stderr);
    assert!(
        err.starts_with("mcp-gs: 2 lines that are not hex were skipped (the first, line 2: "),
        "{err}"
    );
    let output = decode_stdin(&["--hex", "--summary"], &input);
    let out = text(&output.stdout);
    assert!(out.contains("\nerrors:\n"), "{out}");
    assert!(out.contains("\n  bad_hex_line: 2\n"), "{out}");
    // A frame type xbee-api reads is named as JSON names its frames.
    assert!(out.contains("\n  type 0x8a (modem_status): 2\n"), "{out}");
    // Good hex counts none, and exits 0.
    let output = decode_stdin(&["--hex", "--summary"], &format!("{FRAME}\n"));
    assert_eq!(output.status.code(), Some(0));
    assert!(text(&output.stdout).contains("\n  bad_hex_line: 0\n"));
}

#[test]
fn hex_errors_in_a_file_name_the_file() {
    let dump = TempFile::new("typo.hex", format!("{FRAME}\n{FRAME}\n7E 0G\n").as_bytes());
    let output = decode(&["--hex", dump.path()]);
    let (out, err) = (text(&output.stdout), text(&output.stderr));
    assert_eq!(output.status.code(), Some(2), "{err}");
    assert_eq!(out.lines().count(), 3, "{out}");
    assert!(
        err.starts_with(&format!(
            "mcp-gs: {}: line 3: `0G` is not a hex byte",
            dump.path()
        )),
        "{err}"
    );
    // A raw capture given as hex still stops at once, and names the file too.
    let raw = TempFile::new("raw.bin", &[0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F]);
    let output = decode(&["--hex", raw.path()]);
    let err = text(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{err}");
    assert_eq!(
        err.trim_end(),
        format!(
            "mcp-gs: {}: line 1: not text (a raw capture needs no --hex)",
            raw.path()
        )
    );
}

#[test]
fn a_recording_cut_off_names_the_file_and_the_frames_decoded_before_it() {
    let mut bytes = common::modem_status_recording(3);
    bytes.truncate(bytes.len() - 1);
    let cut = TempFile::new("cut.mcprec", &bytes);
    let output = decode(&[cut.path()]);
    let (out, err) = (text(&output.stdout), text(&output.stderr));
    // Bad input: a script learns the file is damaged, with every frame before it shown.
    assert_eq!(output.status.code(), Some(2), "{err}");
    let frames = out.lines().filter(|l| !l.starts_with("-- ")).count();
    assert_eq!(frames, 2, "{out}");
    let offset = 8 + 2 * mcp_host::record::record_len(2);
    assert_eq!(
        err.trim_end(),
        format!(
            "mcp-gs: {}: recording cut off part way through the record at offset \
             {offset}: 5 of its 6 bytes of frame and CRC are there; the 2 frames before it \
             were decoded",
            cut.path()
        )
    );
    // In JSON, the stream ends with the error, for a program reading it.
    let output = decode(&["--format", "json", cut.path()]);
    assert_eq!(output.status.code(), Some(2));
    let lines: Vec<serde_json::Value> = text(&output.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 3);
    assert_eq!(
        lines[2],
        serde_json::json!({
            "error": "recording",
            "offset": offset,
            "message": format!(
                "recording cut off part way through the record at offset {offset}: 5 of its \
                 6 bytes of frame and CRC are there"
            ),
        })
    );
    // From standard input, no file is named.
    let file = std::fs::File::open(cut.path()).unwrap();
    let output = gs().arg("decode").stdin(file).output().unwrap();
    let err = text(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{err}");
    assert!(
        err.starts_with("mcp-gs: recording cut off part way through the record"),
        "{err}"
    );
    // Cut off in a record's header, before any frame: the summary counts it among the
    // errors too.
    let header = TempFile::new("head.mcprec", &common::modem_status_recording(1)[..12]);
    let output = decode(&["--summary", header.path()]);
    let err = text(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{err}");
    assert!(
        text(&output.stdout).contains("\n  damaged_record: 1\n"),
        "{output:?}"
    );
    assert_eq!(
        err.trim_end(),
        format!(
            "mcp-gs: {}: recording cut off part way through the header of the record at \
             offset 8: 4 of its 11 bytes are there; no frame came before it",
            header.path()
        )
    );
}

#[test]
fn a_noisy_capture_in_the_right_mode_is_not_told_to_try_the_other() {
    // Receive Packets in API mode 1 whose data holds bytes mode 2 escapes (0x11, 0x13,
    // 0x7D), one in four with its checksum damaged on the line.
    let frame = |i: u8| {
        let data = [
            0x90, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0x7D, 0x33, 0x01, b'm', 0x11, i,
        ];
        let sum = data.iter().fold(0u8, |s, b| s.wrapping_add(*b));
        let mut bytes = vec![0x7E, 0x00, u8::try_from(data.len()).unwrap()];
        bytes.extend_from_slice(&data);
        bytes.push(if i.is_multiple_of(4) {
            (0xFF - sum) ^ 0x01
        } else {
            0xFF - sum
        });
        bytes
    };
    let capture: Vec<u8> = (0..100).flat_map(frame).collect();
    let file = TempFile::new("noisy.bin", &capture);
    let output = decode(&["--summary", file.path()]);
    let err = text(&output.stderr);
    assert!(text(&output.stdout).contains("frames: 75\n"), "{output:?}");
    assert!(!err.contains("--api-mode 2"), "{err}");
    // The same frames read in the wrong mode: told, since mode 1 finds more.
    let output = decode(&["--summary", "--api-mode", "2", file.path()]);
    let err = text(&output.stderr);
    assert!(err.contains("decode it with --api-mode 1"), "{err}");
}

#[test]
fn frames_too_long_for_mode_1_alone_are_no_sign_of_mode_2() {
    // Receive Packets of 509 to 512 bytes of frame data, with no byte mode 2 escapes:
    // too long for the decoder in mode 1 (508), not in mode 2 (512), and no more a
    // mode 2 capture for that. Between them, short ones.
    let frame = |len: usize| {
        let mut data = vec![
            0x90, 0, 0x13, 0xA2, 0, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0x01,
        ];
        data.resize(len, b'a');
        let sum = data.iter().fold(0u8, |s, b| s.wrapping_add(*b));
        let len = u16::try_from(len).unwrap().to_be_bytes();
        [&[0x7E, len[0], len[1]][..], &data, &[0xFF - sum]].concat()
    };
    let capture: Vec<u8> = (0..12)
        .flat_map(|i| [frame(509 + i % 4), frame(20)].concat())
        .collect();
    let file = TempFile::new("long.bin", &capture);
    let output = decode(&["--summary", file.path()]);
    let err = text(&output.stderr);
    let out = text(&output.stdout);
    assert!(out.contains("frames: 12\n"), "{out}");
    assert!(out.contains("oversize: 12\n"), "{out}");
    assert!(!err.contains("--api-mode 2"), "{err}");
}

#[test]
fn recordings_joined_one_after_the_other_decode_whole() {
    let one = common::modem_status_recording(3);
    let joined = TempFile::new("joined.mcprec", &[&one[..], &one].concat());
    let output = decode(&["--summary", "--format", "json", joined.path()]);
    assert_eq!(output.status.code(), Some(0), "{}", text(&output.stderr));
    let summary: Value = serde_json::from_str(text(&output.stdout).trim()).unwrap();
    assert_eq!(summary["frames"], 6, "{summary}");
    assert_eq!(summary["errors"]["damaged_record"], 0, "{summary}");
}

#[test]
fn a_first_line_that_is_not_hex_is_said_as_soon_as_it_ends() {
    // Typed on a terminal: the error comes before the next line, not with it.
    let mut child = gs()
        .args(["decode", "--hex"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("mcp-gs runs");
    let mut stdin = child.stdin.take().expect("stdin");
    stdin.write_all(b"zz\n").unwrap();
    stdin.flush().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    let stdout = child.stdout.take().expect("stdout");
    std::thread::spawn(move || {
        let mut line = String::new();
        let _ = std::io::BufRead::read_line(&mut std::io::BufReader::new(stdout), &mut line);
        let _ = tx.send(line);
    });
    // Failure guard only: the line comes at once.
    let line = rx.recv_timeout(std::time::Duration::from_secs(20));
    drop(stdin);
    let _ = child.kill();
    let _ = child.wait();
    let line = line.expect("the error line while the input is still open");
    assert!(
        line.contains("input line 1: `zz` is not a hex byte"),
        "{line}"
    );
}

#[test]
fn input_with_no_hex_line_says_so() {
    let out = decode_stdin(&["--hex"], "zz\n");
    assert_eq!(out.status.code(), Some(2));
    let stderr = text(&out.stderr);
    assert!(
        stderr.contains("; no line was hex: correct that line"),
        "{stderr}"
    );
}

#[test]
fn a_hex_dump_of_a_recording_under_a_title_line_is_read_as_the_recording() {
    // A dump pasted under a line of its own that is not hex: the line is said and
    // skipped, and the recording is found after it (its frames carry their times).
    let hex: String = common::modem_status_recording(2)
        .iter()
        .map(|b| format!("{b:02x} "))
        .collect();
    let input = format!("Flight 3, from the hub\n\n{hex}\n");
    let output = decode_stdin(&["--hex"], &input);
    let (out, err) = (text(&output.stdout), text(&output.stderr));
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(
        lines[0], "error, found at input line 1: `Fl` is not a hex byte (line skipped)",
        "{out}"
    );
    let frames: Vec<&&str> = lines[1..]
        .iter()
        .filter(|l| !l.starts_with("-- "))
        .collect();
    assert_eq!(frames.len(), 2, "{out}");
    assert!(
        frames
            .iter()
            .all(|l| l.contains(" rx modem status coordinator_started")),
        "{out}"
    );
    assert_eq!(output.status.code(), Some(2), "{err}");
    assert!(
        err.starts_with("mcp-gs: line 1: `Fl` is not a hex byte (line skipped); the other lines"),
        "{err}"
    );

    let output = decode_stdin(&["--hex", "--summary", "--format", "json"], &input);
    assert_eq!(output.status.code(), Some(2));
    let summary: Value = serde_json::from_str(text(&output.stdout).trim()).unwrap();
    assert_eq!(summary["frames"], 2, "{summary}");
    assert_eq!(summary["errors"]["bad_hex_line"], 1, "{summary}");
}
