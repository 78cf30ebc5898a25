//! `mcp-gs demo` runs on its own, with no hardware, and exits 0.

use std::process::Command;

#[test]
fn demo_runs_for_two_seconds_and_exits_0() {
    let output = Command::new(env!("CARGO_BIN_EXE_mcp-gs"))
        .args(["demo", "--duration", "2"])
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
        stdout.contains("<- report trajectory_set 3 waypoints"),
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
