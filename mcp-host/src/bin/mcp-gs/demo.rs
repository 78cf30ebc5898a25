//! `mcp-gs demo`: a ground station and a simulated MAV in one process, over a
//! pseudo-terminal, showing every command, delivery status, report and some telemetry.

use std::fmt;
use std::num::NonZeroU64;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::{Duration, SystemTime};

use clap::Args;
use futures::StreamExt;
use mcp_core::{
    Address, Command, Controller, LandingState, Packet, Report, Slot, StatusRequest, TelemetryId,
    TrajectoryBuilder, Waypoint,
};
use mcp_host::render::text::{self, DateLines};
use mcp_host::sim::{Simulator, posix_now};
use mcp_host::{
    CommandSender, DeliveryReport, Event, Link, LinkEvent, LinkOptions, PacketStream, RequestError,
    SendError,
};
use tokio::sync::watch;
use tokio::time::Instant;
use xbee_api::{Address64, ApiMode, Frame};

use crate::Failure;
use crate::interrupt::Interrupt;

/// Arguments of `demo`.
#[derive(Debug, Args)]
pub(crate) struct DemoArgs {
    /// How long the demo runs, seconds; 0 runs until Ctrl-C.
    #[arg(long, default_value = "10", value_name = "SECONDS", value_parser = crate::radio::parse_duration)]
    duration: Duration,
    /// Show every Nth telemetry packet (they arrive at 20 Hz); at least 1.
    #[arg(long, default_value = "10", value_name = "N", value_parser = parse_every)]
    telemetry_every: NonZeroU64,
    /// How the ground station reaches the simulated coordinator radio: a
    /// pseudo-terminal, as a radio on a serial port is reached (Unix), or TCP on
    /// 127.0.0.1 (a free port). Default: pty on Unix, tcp elsewhere.
    #[arg(long, value_enum, default_value_t = Over::default())]
    over: Over,
}

/// [`DemoArgs::over`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Over {
    /// A pseudo-terminal.
    Pty,
    /// TCP.
    Tcp,
}

impl Default for Over {
    fn default() -> Self {
        match cfg!(unix) {
            true => Over::Pty,
            false => Over::Tcp,
        }
    }
}

fn parse_every(s: &str) -> Result<NonZeroU64, String> {
    s.parse()
        .map_err(|_| format!("expected a whole number of packets, 1 or more, got `{s}`"))
}

/// The simulated MAV.
const MAV: Address64 = Address64(0x0013_A200_40B5_99B9);
/// How long to wait for the simulator's radio to come up.
const STARTUP: Duration = Duration::from_secs(5);

/// What the ground station saw, for the summary.
#[derive(Debug, Default)]
struct Seen {
    telemetry: u64,
    shown: u64,
    reports: u64,
    other: u64,
    decode_errors: u64,
}

/// The date lines of the demo's output.
static DATES: Mutex<DateLines> = Mutex::new(DateLines::new());

/// Prints a line that starts with `time`'s time of day (UTC), after a line with its date
/// if it is the first line stamped or on another day than the one before, as `monitor`
/// prints its lines.
fn stamped_line(time: SystemTime, rest: fmt::Arguments<'_>) {
    // Held while both print, so that a line from another task cannot come between.
    let mut dates = DATES.lock().unwrap_or_else(PoisonError::into_inner);
    if let Some(date) = dates.before(time) {
        out!("{date}");
    }
    out!("{} {rest}", text::time(time));
}

/// `stamped!(time, "...", args)`: a line stamped with `time` ([`stamped_line`]).
macro_rules! stamped {
    ($time:expr, $($arg:tt)*) => {
        stamped_line($time, format_args!($($arg)*))
    };
}

/// `say!("...", args)`: a line stamped with the time now ([`stamped_line`]).
macro_rules! say {
    ($($arg:tt)*) => {
        stamped_line(SystemTime::now(), format_args!($($arg)*))
    };
}

/// Prints what arrives on the ground station's link.
async fn print_events(
    mut stream: PacketStream,
    seen: Arc<Mutex<Seen>>,
    every: u64,
    landing: watch::Sender<Option<LandingState>>,
    radio_up: watch::Sender<bool>,
    reports_printed: watch::Sender<u64>,
) {
    while let Some(event) = stream.next().await {
        let mut seen = seen.lock().unwrap_or_else(|p| p.into_inner());
        match event {
            Event::Packet(rx) => {
                let from = rx.origin.src64;
                match &rx.packet {
                    Packet::Telemetry(_) => {
                        seen.telemetry += 1;
                        if (seen.telemetry - 1).is_multiple_of(every) {
                            seen.shown += 1;
                            stamped!(
                                rx.origin.received_at,
                                "{from} {} (#{})",
                                rx.packet,
                                seen.telemetry
                            );
                        }
                    }
                    Packet::Report(report) => {
                        seen.reports += 1;
                        stamped!(rx.origin.received_at, "{from} <- {}", rx.packet);
                        reports_printed.send_replace(seen.reports);
                        if let Report::Landing(state) = report {
                            landing.send_replace(Some(*state));
                        }
                    }
                    _ => {
                        seen.other += 1;
                        stamped!(rx.origin.received_at, "{from} {}", rx.packet);
                    }
                }
            }
            Event::Frame(frame) => match frame.parse() {
                Ok(f) => {
                    say!("radio: {}", text::frame(&f));
                    if matches!(f, Frame::ModemStatus(_)) {
                        radio_up.send_replace(true);
                    }
                }
                Err(e) => say!("radio: malformed frame: {e}"),
            },
            Event::InvalidPacket(bad) => {
                seen.other += 1;
                say!("{} invalid packet: {}", bad.origin.src64, bad.error);
            }
            Event::DecodeError(e) => {
                seen.decode_errors += 1;
                say!("link: frame dropped: {e}");
            }
            Event::Link(LinkEvent::Closed { reason, .. }) => {
                say!("link closed: {reason}");
                return;
            }
            Event::Link(
                LinkEvent::Connected { peer, .. } | LinkEvent::Reconnected { peer, .. },
            ) => {
                say!("link: connected ({peer})");
            }
            Event::Link(LinkEvent::Disconnected { reason, .. }) => {
                say!("link: disconnected: {reason}");
            }
            other => say!("{other:?}"),
        }
    }
}

/// Pause after each step, so that a reader can follow and the answers and
/// unsolicited reports print before the next step; skipped once the time is up.
const STEP_PAUSE: Duration = Duration::from_millis(150);

/// How long a request waits for its answer to be printed, after the sender has it.
const PRINT_WAIT: Duration = Duration::from_secs(1);

/// Sends the commands and tallies the outcomes.
struct Script {
    sender: CommandSender,
    /// How many reports the printer has printed.
    reports_printed: watch::Receiver<u64>,
    deadline: Option<Instant>,
    delivered: u64,
    answered: u64,
    failures: Vec<Failure>,
}

impl Script {
    async fn pause(&self) {
        if self
            .deadline
            .is_none_or(|d| Instant::now() + STEP_PAUSE < d)
        {
            tokio::time::sleep(STEP_PAUSE).await;
        }
    }

    async fn send(&mut self, what: &str, command: &Command<&[u8]>) {
        say!("{MAV} -> {command}   ({what})");
        match self.sender.send(MAV, command).await {
            Ok(DeliveryReport::Delivered {
                frame_id,
                dst16,
                retries,
                ..
            }) => {
                self.delivered += 1;
                say!(
                    "                 delivered (transmit status id {frame_id}: success, to {dst16}, {retries} retries)"
                );
            }
            // Written, no status asked (not the demo's way), or a report newer than it.
            Ok(_) => self.delivered += 1,
            Err(e) => {
                say!("                 NOT delivered: {e}");
                self.failures.push(send_failure(&e));
            }
        }
        self.pause().await;
    }

    async fn request(&mut self, request: StatusRequest) {
        let command: Command<&[u8]> = Command::StatusRequest(request);
        say!("{MAV} -> {command}");
        let printed_before = *self.reports_printed.borrow_and_update();
        match self.sender.request(MAV, request).await {
            Ok(_) => {
                self.answered += 1;
                // The sender has the answer; the printer prints it from the stream.
                // Wait for that, so that it shows under this step's heading.
                let printed = self.reports_printed.wait_for(|n| *n > printed_before);
                let _ = tokio::time::timeout(PRINT_WAIT, printed).await;
            }
            Err(RequestError::Send(e)) => {
                say!("                 NOT delivered: {e}");
                self.failures.push(send_failure(&e));
            }
            Err(e) => {
                say!("                 no answer: {e}");
                self.failures
                    .push(Failure::new(Failure::TIMEOUT, e.to_string()));
            }
        }
        self.pause().await;
    }
}

fn send_failure(e: &SendError) -> Failure {
    match e {
        SendError::Delivery { .. } => Failure::new(Failure::DELIVERY, e.to_string()),
        e if e.is_timeout() => Failure::new(Failure::TIMEOUT, e.to_string()),
        SendError::Disconnected { .. } | SendError::Closed => Failure::link(e.to_string()),
        _ => Failure::new(Failure::OTHER, e.to_string()),
    }
}

fn heading(text: &str) {
    out!("\n== {text}");
}

/// The simulator and the ground station's link to it over a pseudo-terminal, as if
/// its XBee were on a serial port; and what is between them, said.
async fn over_pty(
    options: LinkOptions,
) -> Result<(Simulator, PacketStream, CommandSender, String), Failure> {
    let (stream, sender) = mcp_host::connect(&Link::Pty, options)
        .await
        .map_err(|e| Failure::link(format!("{e} (`--over tcp` runs the demo over TCP)")))?;
    let path = stream
        .info()
        .pty_path
        .clone()
        .ok_or_else(|| Failure::link("the pseudo-terminal has no path"))?;
    // The simulator's end: a virtual XBee coordinator on the pty's far end, the MAV
    // behind it.
    let sim_link: Link = format!("serial:{}", path.display())
        .parse()
        .map_err(|e: mcp_host::LinkParseError| Failure::link(e.to_string()))?;
    let sim = Simulator::start(
        &sim_link,
        ApiMode::Unescaped,
        &[MAV],
        Simulator::network_config(),
    )
    .await
    .map_err(|e| Failure::link(e.to_string()))?;
    let between = format!("pseudo-terminal {}", path.display());
    Ok((sim, stream, sender, between))
}

/// The simulator, listening on a free TCP port of 127.0.0.1, and the ground station's
/// link to it; and what is between them, said.
async fn over_tcp(
    options: LinkOptions,
) -> Result<(Simulator, PacketStream, CommandSender, String), Failure> {
    let sim = Simulator::start(
        &Link::tcp_listen("127.0.0.1", 0),
        ApiMode::Unescaped,
        &[MAV],
        Simulator::network_config(),
    )
    .await
    .map_err(|e| Failure::link(e.to_string()))?;
    let link = sim
        .ground_station_link()
        .ok_or_else(|| Failure::link("the simulator's TCP port is not known"))?;
    let (stream, sender) = mcp_host::connect(&link, options)
        .await
        .map_err(|e| Failure::link(e.to_string()))?;
    let between = format!("TCP {link}");
    Ok((sim, stream, sender, between))
}

/// Runs `demo`.
pub(crate) async fn run(args: DemoArgs) -> Result<(), Failure> {
    let started = Instant::now();
    let deadline = (!args.duration.is_zero()).then(|| started + args.duration);
    // Set when the time is up, or at Ctrl-C (which then no longer ends the process
    // at once: the demo stops where it is and prints the summary).
    let mut stop = stop_signal(deadline, crate::interrupt::ctrl_c());

    out!("MCP demo: a ground station talking to a simulated MAV. No hardware needed.");
    let options = LinkOptions {
        api_mode: ApiMode::Unescaped,
        send_timeout: Duration::from_secs(5),
        ..LinkOptions::default()
    };
    let (sim, stream, sender, between) = match args.over {
        Over::Pty => over_pty(options).await?,
        Over::Tcp => over_tcp(options).await?,
    };
    out!(
        "  ground station <-> {between} <-> virtual XBee coordinator <-> radio <-> MAV {MAV} (XBee API mode 1)"
    );
    out!(
        "  Lines: time (UTC), MAV address, what happened. `->` is a command sent, `<-` a report received."
    );
    out!(
        "  Telemetry arrives at 20 Hz: {} is shown (#n counts them all).",
        every_nth(args.telemetry_every.get())
    );
    match deadline {
        Some(_) => out!(
            "  Runs for {}, then prints a summary.",
            mcp_host::render::Seconds(args.duration)
        ),
        None => out!("  Runs until Ctrl-C, then prints a summary."),
    }

    let seen = Arc::new(Mutex::new(Seen::default()));
    let (landing_tx, mut landing) = watch::channel(None);
    let (radio_tx, mut radio_up) = watch::channel(false);
    let (printed_tx, reports_printed) = watch::channel(0);
    let printer = tokio::spawn(print_events(
        stream,
        seen.clone(),
        args.telemetry_every.get(),
        landing_tx,
        radio_tx,
        printed_tx,
    ));

    let mut script = Script {
        sender,
        reports_printed,
        deadline,
        delivered: 0,
        answered: 0,
        failures: Vec::new(),
    };
    // Ctrl-C stops the script where it is; the time being up lets it finish.
    let mut interrupt = stop.clone();
    let finished = tokio::select! {
        result = steps(&mut script, &mut radio_up, &mut landing, stop.clone()) => {
            result?;
            true
        }
        _ = interrupt.wait_for(|stop| matches!(stop, Stop::Interrupted(_))) => false,
    };
    if finished {
        heading(match deadline {
            Some(_) => "Watching telemetry until the time is up",
            None => "Watching telemetry until Ctrl-C",
        });
        let _ = stop.wait_for(|stop| *stop != Stop::Running).await;
    }

    sim.shutdown();
    printer.abort();
    let seen = seen.lock().unwrap_or_else(|p| p.into_inner());
    heading("Summary");
    if let Stop::Interrupted(by) = *stop.borrow() {
        out!("  stopped by {by}");
    }
    out!(
        "  {:.1} s, MAV {MAV}: {} commands delivered, {} status requests answered, {} failures",
        started.elapsed().as_secs_f64(),
        script.delivered,
        script.answered,
        script.failures.len()
    );
    out!(
        "  received {} telemetry packets ({} shown), {} reports, {} other packets, {} frames dropped",
        seen.telemetry,
        seen.shown,
        seen.reports,
        seen.other,
        seen.decode_errors
    );
    match args.over {
        Over::Pty => out!(
            "  Next: `mcp-gs sim --link pty` runs the simulated MAV alone for your own ground station."
        ),
        Over::Tcp => out!(
            "  Next: `mcp-gs sim --link tcp-listen:127.0.0.1:9750` runs the simulated MAV alone for \
             your own ground station, on --link tcp:127.0.0.1:9750."
        ),
    }
    match script.failures.into_iter().next() {
        Some(failure) => Err(failure),
        None => Ok(()),
    }
}

/// Tells why the demo stops: [`Stop::TimeUp`] at `deadline` (if any), then
/// [`Stop::Interrupted`] when `interrupt` (Ctrl-C) completes, before or after the time
/// is up. The sender lives until then, so that a receiver waiting for Ctrl-C is not
/// woken by its end.
fn stop_signal(
    deadline: Option<Instant>,
    interrupt: impl Future<Output = Interrupt> + Send + 'static,
) -> watch::Receiver<Stop> {
    let (stop_tx, stop) = watch::channel(Stop::Running);
    tokio::spawn(async move {
        let time_up = async {
            match deadline {
                Some(d) => tokio::time::sleep_until(d).await,
                None => std::future::pending().await,
            }
        };
        let mut interrupt = std::pin::pin!(interrupt);
        tokio::select! {
            () = time_up => {
                stop_tx.send_replace(Stop::TimeUp);
                let by = interrupt.await;
                stop_tx.send_replace(Stop::Interrupted(by));
            }
            by = &mut interrupt => {
                stop_tx.send_replace(Stop::Interrupted(by));
            }
        }
    });
    stop
}

/// Why the demo stops.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Stop {
    /// It does not yet.
    Running,
    /// `--duration` is over: the script finishes its steps.
    TimeUp,
    /// Ctrl-C or a signal to stop: everything stops at once.
    Interrupted(Interrupt),
}

/// The scripted steps, one after the other.
async fn steps(
    script: &mut Script,
    radio_up: &mut watch::Receiver<bool>,
    landing: &mut watch::Receiver<Option<LandingState>>,
    mut stop: watch::Receiver<Stop>,
) -> Result<(), Failure> {
    heading("Starting the radio");
    let _ = tokio::time::timeout(STARTUP, radio_up.wait_for(|up| *up)).await;

    heading("Clock: set the MAV time, then ask for it");
    script.send("time set", &Command::Time(posix_now())).await;
    script.request(StatusRequest::Time).await;

    heading("Telemetry: turn on four ids; the MAV sends them in one packet, ascending ids");
    for id in [
        TelemetryId::Altitude,
        TelemetryId::EstimatedAltitude,
        TelemetryId::AltitudeSetpoint,
        TelemetryId::PitchAngle,
    ] {
        let on = Command::TelemetryToCoordinator { on: true, id };
        script.send("telemetry on", &on).await;
    }
    script
        .request(StatusRequest::TelemetryToCoordinator(TelemetryId::Altitude))
        .await;

    heading("Controller: switch to MPC (the MAV reports the change by itself)");
    script
        .send("controller", &Command::Controllers(Controller::Mpc))
        .await;
    script.request(StatusRequest::Controllers).await;

    // Two: the most a frame the deployed MAV takes (60 bytes) holds.
    heading("Trajectory: two waypoints, answered at once by a trajectory report");
    let t0 = posix_now();
    let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
    let mut builder = TrajectoryBuilder::command(&mut buf)
        .map_err(|e| Failure::new(Failure::OTHER, e.to_string()))?;
    for (i, (elevator, aileron, altitude)) in
        [(0.5, 0.0, 1.2), (0.5, 0.5, 1.4)].into_iter().enumerate()
    {
        let waypoint = Waypoint {
            time: t0 + 1 + i as u32,
            elevator,
            aileron,
            altitude,
        };
        builder
            .push(waypoint)
            .map_err(|e| Failure::new(Failure::OTHER, e.to_string()))?;
    }
    let len = builder.finish();
    match mcp_core::parse(&buf[..len]) {
        Ok(Packet::Command(command)) => script.send("trajectory set", &command).await,
        _ => {
            return Err(Failure::new(
                Failure::OTHER,
                "trajectory command did not encode",
            ));
        }
    }
    script.request(StatusRequest::TrajectorySet).await;

    heading("Position: move the coordinate system, name a slave MAV");
    let position = Command::PositionSet {
        elevator: 0.25,
        aileron: -0.25,
    };
    script.send("position set", &position).await;
    let slave = Command::PositionSlaveSet {
        slot: Slot::new(1),
        address: Address(0x0013_A200_40B5_99BF_u64.to_be_bytes()),
    };
    script.send("position slave set", &slave).await;
    script.request(StatusRequest::PositionSlaveSet).await;

    heading("Landing: turn autonomous landing on and watch the state change");
    script
        .send("landing on", &Command::Landing { on: true })
        .await;
    script.request(StatusRequest::Landing).await;

    let landed = tokio::select! {
        r = landing.wait_for(|s| *s == Some(LandingState::OnGround)) => r.is_ok(),
        _ = stop.wait_for(|stop| *stop != Stop::Running) => false,
    };
    if landed {
        heading("Take-off: landing off on the ground");
        script
            .send("landing off", &Command::Landing { on: false })
            .await;
        let _ = tokio::select! {
            r = landing.wait_for(|s| *s == Some(LandingState::Flight)) => r.is_ok(),
            _ = stop.wait_for(|stop| *stop != Stop::Running) => false,
        };
        script.request(StatusRequest::Landing).await;
    }
    Ok(())
}

/// Which packets of a series are shown: `every packet`, `every 2nd packet`, `every 3rd
/// packet`, `every 11th packet`...
fn every_nth(n: u64) -> String {
    let suffix = match (n % 10, n % 100) {
        (_, 11..=13) => "th",
        (1, _) => "st",
        (2, _) => "nd",
        (3, _) => "rd",
        _ => "th",
    };
    match n {
        0 | 1 => "every packet".to_owned(),
        n => format!("every {n}{suffix} packet"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_nth_packet_reads_as_english() {
        let said: Vec<String> = [1, 2, 3, 4, 11, 12, 13, 21, 22, 23, 101, 111]
            .into_iter()
            .map(every_nth)
            .collect();
        assert_eq!(
            said,
            [
                "every packet",
                "every 2nd packet",
                "every 3rd packet",
                "every 4th packet",
                "every 11th packet",
                "every 12th packet",
                "every 13th packet",
                "every 21st packet",
                "every 22nd packet",
                "every 23rd packet",
                "every 101st packet",
                "every 111th packet",
            ]
        );
    }

    #[tokio::test]
    async fn ctrl_c_after_the_time_is_up_still_interrupts() {
        let (ctrl_c, pressed) = tokio::sync::oneshot::channel::<()>();
        let mut stop = stop_signal(Some(Instant::now()), async {
            let _ = pressed.await;
            Interrupt::CtrlC
        });
        stop.wait_for(|s| *s == Stop::TimeUp).await.unwrap();
        ctrl_c.send(()).unwrap();
        stop.wait_for(|s| *s == Stop::Interrupted(Interrupt::CtrlC))
            .await
            .unwrap();
    }

    #[tokio::test]
    async fn ctrl_c_before_the_time_is_up_interrupts() {
        let (signal, sent) = tokio::sync::oneshot::channel::<()>();
        let mut stop = stop_signal(None, async {
            let _ = sent.await;
            Interrupt::Terminate
        });
        assert_eq!(*stop.borrow(), Stop::Running);
        signal.send(()).unwrap();
        stop.wait_for(|s| *s == Stop::Interrupted(Interrupt::Terminate))
            .await
            .unwrap();
    }
}
