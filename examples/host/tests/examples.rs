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

/// The lines a running example prints: those read so far, and the rest to come.
struct Lines {
    seen: Vec<String>,
    rest: tokio::io::Lines<tokio::io::BufReader<tokio::process::ChildStdout>>,
}

impl Lines {
    fn new(out: tokio::process::ChildStdout) -> Self {
        use tokio::io::AsyncBufReadExt;
        Lines {
            seen: Vec::new(),
            rest: tokio::io::BufReader::new(out).lines(),
        }
    }

    fn len(&self) -> usize {
        self.seen.len()
    }

    /// The first line from index `from` on that satisfies `f`, read as it comes (for
    /// `within` at most): the index after it.
    async fn wait_for(
        &mut self,
        from: usize,
        within: std::time::Duration,
        what: &str,
        f: impl Fn(&str) -> bool,
    ) -> usize {
        if let Some(at) = self.seen.iter().skip(from).position(|l| f(l)) {
            return from + at + 1;
        }
        let deadline = tokio::time::Instant::now() + within;
        loop {
            let line = tokio::time::timeout_at(deadline, self.rest.next_line()).await;
            match line {
                Ok(Ok(Some(line))) => {
                    let matched = f(&line);
                    self.seen.push(line);
                    if matched && self.seen.len() > from {
                        return self.seen.len();
                    }
                }
                other => panic!(
                    "no line {what} within {within:?} ({other:?}); the watchdog printed:\n{}",
                    self.seen.join("\n")
                ),
            }
        }
    }
}

/// Whether `line` says `mav` is well: its altitude telemetry comes.
fn ok_with_telemetry(line: &str, mav: &str) -> bool {
    line.starts_with(mav) && line.contains(" ok altitude 1.") && !line.contains(" 0 packets/s")
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn watchdog_finds_the_fleet_reports_a_lost_mav_and_survives_the_link_dropping() {
    use std::time::Duration;

    let mavs: Vec<String> = fleet_addresses(3).iter().map(|a| a.to_string()).collect();
    let link = "tcp-listen:127.0.0.1:0".parse().unwrap();
    let config = Simulator::network_config();
    let sim = Simulator::start(
        &link,
        ApiMode::Unescaped,
        &fleet_addresses(2),
        config.clone(),
    )
    .await
    .expect("the simulator starts");
    let addr = sim.coordinator().local_addr.expect("a bound port");

    let mut child = tokio::process::Command::new(env!("CARGO_BIN_EXE_watchdog"))
        .args([format!("tcp:{addr}"), "90".to_owned(), "1".to_owned()])
        .stdout(std::process::Stdio::piped())
        .kill_on_drop(true)
        .spawn()
        .expect("the watchdog runs");
    let mut lines = Lines::new(child.stdout.take().unwrap());
    let long = Duration::from_secs(15);

    // Both MAVs found, and their telemetry turned on.
    for mav in &mavs[..2] {
        lines
            .wait_for(0, long, &format!("discovering {mav}"), |l| {
                l.starts_with("discovered ") && l.contains(mav.as_str())
            })
            .await;
        lines
            .wait_for(0, long, &format!("with {mav}'s telemetry"), |l| {
                ok_with_telemetry(l, mav)
            })
            .await;
    }

    // The second goes out of range: asked after 2 s of silence, it cannot answer.
    let mav2 = fleet_addresses(2)[1];
    let from = lines.len();
    assert!(sim.network().cut(mav2));
    lines
        .wait_for(from, long, "asking the cut MAV", |l| {
            l.starts_with(&mavs[1]) && l.contains("asking its landing state")
        })
        .await;
    let lost = lines
        .wait_for(from, long, "saying the cut MAV is lost", |l| {
            l.starts_with(&mavs[1]) && l.contains(" lost: ")
        })
        .await;
    // The first goes on meanwhile.
    lines
        .wait_for(lost, long, "with the first MAV well", |l| {
            ok_with_telemetry(l, &mavs[0])
        })
        .await;
    assert!(sim.network().restore(mav2));
    let back = lines
        .wait_for(lost, long, "saying the MAV is back", |l| {
            l == format!("{} back", mavs[1])
        })
        .await;
    lines
        .wait_for(back, long, "with the MAV back well", |l| {
            ok_with_telemetry(l, &mavs[1])
        })
        .await;

    // The radio goes away, and comes back with a third MAV; every MAV behind it has
    // forgotten its telemetry.
    let from = lines.len();
    sim.stop().await;
    lines
        .wait_for(from, long, "saying the link is down", |l| {
            l.starts_with("link disconnected")
        })
        .await;
    let relink = format!("tcp-listen:{addr}").parse().unwrap();
    let sim = Simulator::start(&relink, ApiMode::Unescaped, &fleet_addresses(3), config)
        .await
        .expect("the simulator starts again on the same port");
    let reconnected = lines
        .wait_for(from, long, "saying the link is back", |l| {
            l.starts_with("link reconnected")
        })
        .await;
    lines
        .wait_for(reconnected, long, "discovering the new MAV", |l| {
            l.starts_with("discovered ") && l.contains(mavs[2].as_str())
        })
        .await;
    for mav in &mavs {
        lines
            .wait_for(
                reconnected,
                long,
                &format!("with {mav}'s telemetry again"),
                |l| ok_with_telemetry(l, mav),
            )
            .await;
    }

    child.kill().await.unwrap();
    sim.stop().await;
}
