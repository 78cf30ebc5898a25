//! `mcp-gs demo` runs on its own, with no hardware, and exits 0.

use std::process::Command;

#[test]
fn demo_runs_for_two_seconds_and_exits_0() {
    let stdout = demo_runs(&[]);
    // On Unix, over a pseudo-terminal, as a radio on a serial port.
    if cfg!(unix) {
        assert!(
            stdout.contains("ground station <-> pseudo-terminal /dev/"),
            "{stdout}"
        );
        assert!(stdout.contains("`mcp-gs sim --link pty`"), "{stdout}");
    }
}

/// Where there is no pseudo-terminal (Windows), the demo runs over TCP.
#[test]
fn demo_runs_over_tcp_too() {
    let stdout = demo_runs(&["--over", "tcp"]);
    assert!(
        stdout.contains("ground station <-> TCP tcp:127.0.0.1:"),
        "{stdout}"
    );
    assert!(
        stdout.contains("`mcp-gs sim --link tcp-listen:127.0.0.1:9750`"),
        "{stdout}"
    );
}

/// Runs the demo for two seconds with `more` arguments: its output, checked for every
/// command delivered and every request answered.
fn demo_runs(more: &[&str]) -> String {
    let output = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["demo", "--duration", "2"])
        .args(more)
        .output()
        .expect("run mcp-gs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stdout}\n{stderr}");
    // Every command was delivered and every request answered.
    assert!(
        stdout.contains("delivered (transmit status id 1: success"),
        "{stdout}"
    );
    assert!(stdout.contains("<- report time "), "{stdout}");
    assert!(stdout.contains("<- report controllers mpc"), "{stdout}");
    assert!(
        stdout.contains("<- report trajectory_set 2 waypoints"),
        "{stdout}"
    );
    assert!(stdout.contains("<- report landing landing"), "{stdout}");
    assert!(stdout.contains("telemetry estimated_altitude="), "{stdout}");
    assert!(
        stdout.contains("status requests answered, 0 failures"),
        "{stdout}"
    );
    assert!(!stdout.contains("NOT delivered"), "{stdout}");
    answers_print_under_their_requests_heading(&stdout);
    dated_before_the_first_time_of_day(&stdout);
    stdout.into_owned()
}

/// The lines carry the time of day: a line with the UTC date comes before the first,
/// as in `monitor`'s text output.
fn dated_before_the_first_time_of_day(stdout: &str) {
    let is_time = |line: &str| {
        let b = line.as_bytes();
        b.len() > 12 && b[2] == b':' && b[5] == b':' && b[8] == b'.' && b[12] == b' '
    };
    let first = stdout.lines().position(is_time).expect("a stamped line");
    let dates: Vec<&str> = stdout
        .lines()
        .take(first)
        .filter(|line| line.starts_with("-- ") && line.ends_with(" (UTC) --"))
        .collect();
    assert_eq!(dates.len(), 1, "{stdout}");
    let date = dates[0]
        .strip_prefix("-- ")
        .and_then(|d| d.strip_suffix(" (UTC) --"))
        .unwrap_or_default();
    let shape: String = date
        .chars()
        .map(|c| if c.is_ascii_digit() { '9' } else { c })
        .collect();
    assert_eq!(shape, "9999-99-99", "{date}");
}

/// A status request's answer prints before the next step's heading.
fn answers_print_under_their_requests_heading(stdout: &str) {
    let mut waiting = None;
    for line in stdout.lines() {
        if line.contains(" -> ") && line.contains("status request") {
            waiting = Some(line);
        } else if line.contains(" <- report ") {
            waiting = None;
        } else if line.starts_with("== ") {
            assert_eq!(waiting, None, "unanswered before {line:?}:\n{stdout}");
        }
    }
}

#[test]
fn demo_rejects_a_negative_duration() {
    let output = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["demo", "--duration", "-1"])
        .output()
        .expect("run mcp-gs");
    assert_eq!(output.status.code(), Some(2));
}
