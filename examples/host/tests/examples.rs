//! Each example program run against a simulated MAV (in this test's process, its
//! coordinator's link on a TCP port), as a user runs them against `mcp-gs sim`.

use std::process::{Command, Output};

use mcp_host::sim::{Simulator, fleet_addresses};
use mcp_host::xbee_api::ApiMode;

/// A simulated MAV behind a coordinator listening on a free port: the simulator (held
/// for as long as the test runs) and the link its ground station takes.
async fn simulator() -> (Simulator, String) {
    let link = "tcp-listen:127.0.0.1:0".parse().unwrap();
    let sim = Simulator::start(
        &link,
        ApiMode::Unescaped,
        &fleet_addresses(1),
        Simulator::network_config(),
    )
    .await
    .expect("the simulator starts");
    let addr = sim.coordinator().local_addr.expect("a bound port");
    (sim, format!("tcp:{addr}"))
}

/// Runs the example `bin` with `args`, off the runtime's threads (the simulator runs
/// on them meanwhile).
async fn run(bin: &'static str, args: &[&str]) -> Output {
    let args: Vec<String> = args.iter().map(|a| (*a).to_owned()).collect();
    tokio::task::spawn_blocking(move || {
        let path = match bin {
            "telemetry" => env!("CARGO_BIN_EXE_telemetry"),
            "land" => env!("CARGO_BIN_EXE_land"),
            "record" => env!("CARGO_BIN_EXE_record"),
            "read_recording" => env!("CARGO_BIN_EXE_read_recording"),
            _ => unreachable!("no example {bin}"),
        };
        Command::new(path)
            .args(&args)
            .output()
            .expect("the example runs")
    })
    .await
    .unwrap()
}

/// Standard output of a run that succeeded.
fn stdout(output: &Output) -> String {
    assert!(output.status.success(), "{output:?}");
    String::from_utf8(output.stdout.clone()).unwrap()
}

const MAV: &str = "0013A20040B599B9";

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn telemetry_prints_the_altitude_the_mav_sends() {
    let (_sim, link) = simulator().await;
    let out = stdout(&run("telemetry", &[&link, MAV, "2"]).await);
    let altitudes = out.lines().filter(|l| l.starts_with("altitude = ")).count();
    // 20 a second.
    assert!(altitudes >= 5, "{out}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn land_gets_the_command_delivered_and_the_mav_says_it_lands() {
    let (_sim, link) = simulator().await;
    let out = stdout(&run("land", &[&link, MAV, "on"]).await);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines.len(), 2, "{out}");
    assert!(lines[0].starts_with("delivered after "), "{out}");
    assert!(lines[1].starts_with("landing "), "{out}");
    let output = run("land", &[&link, MAV, "sideways"]).await;
    assert!(!output.status.success());
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_recording_holds_both_ways_and_reads_back() {
    let (_sim, link) = simulator().await;
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("flight.mcprec");
    let path = file.to_str().unwrap();
    let out = stdout(&run("record", &[&link, path, "1"]).await);
    assert!(out.contains(" frames recorded to "), "{out}");

    let out = stdout(&run("read_recording", &[path]).await);
    // The status request as it went, and the MAV's report.
    assert!(
        out.lines()
            .any(|l| l.contains(" tx 0013a20040b599b9: command landing status request")),
        "{out}"
    );
    assert!(
        out.lines()
            .any(|l| l.contains(" rx 0013a20040b599b9: report landing ")),
        "{out}"
    );
}
