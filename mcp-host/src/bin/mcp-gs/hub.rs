//! `mcp-gs hub`: one radio shared by several `mcp-gs` commands (or other programs)
//! through a TCP port.

use std::path::PathBuf;
use std::time::Duration;

use clap::Args;
use futures::StreamExt;

use futures::stream::FusedStream;
use mcp_host::hub::{Hub, HubError};
use mcp_host::record::Record;
use mcp_host::{Diagnoser, Subscription};

use crate::Failure;
use crate::hints::{Role, connect_failure_as, hint};
use crate::link_args::{ApiModeChoice, LinkArgs};
use crate::recording::{self, Recording, RecordingFile};

/// Arguments of `hub`.
#[derive(Debug, Args)]
#[command(mut_arg("timeout", |arg| arg.help(
    "Seconds to wait for the radio's link to connect (tcp:) [default: 12]; with \
--wait, or on pty or tcp-listen:, the hub waits for its radio as long as it \
runs"
)))]
pub(crate) struct HubArgs {
    #[command(flatten)]
    link: LinkArgs,
    /// Where to serve the radio: other commands then take `--link tcp:ADDR:PORT`. The
    /// hub has no authentication: every client may send the radio any frame, AT
    /// commands that change or reset it included, so an address other programs of this
    /// machine alone reach (127.0.0.1) is the default, and another is warned about.
    #[arg(long, value_name = "ADDR:PORT", default_value = "127.0.0.1:9750", value_parser = parse_listen)]
    listen: String,
    /// Wait for a radio that is not there yet (not plugged in, a simulator not
    /// started) instead of failing at once, refusing clients meanwhile: for a hub
    /// started at boot.
    #[arg(long)]
    wait: bool,
    /// Record every frame between the hub and the radio to FILE, both ways: what the
    /// radio said, and what every client said to it through the hub (see `decode` and
    /// `replay`). An existing FILE is kept unless `--force` is given.
    #[arg(long, value_name = "FILE")]
    record: Option<PathBuf>,
    /// Overwrite the `--record` file if it exists.
    #[arg(long, requires = "record")]
    force: bool,
}

/// `--listen`: an address and a port (`127.0.0.1:9750`, `localhost:9750`, `[::1]:9750`,
/// `0.0.0.0:9750`), checked before anything is opened.
fn parse_listen(s: &str) -> Result<String, String> {
    let valid = s
        .rsplit_once(':')
        .is_some_and(|(host, port)| !host.is_empty() && port.parse::<u16>().is_ok());
    if valid {
        Ok(s.to_owned())
    } else {
        Err(format!(
            "expected ADDR:PORT, e.g. 127.0.0.1:9750, got `{s}`"
        ))
    }
}

/// The failure of a `--listen` address that cannot be listened on, with what to do about
/// the common causes.
fn listen_failure(addr: &str, error: &std::io::Error) -> Failure {
    let hint = match error.kind() {
        std::io::ErrorKind::AddrInUse => Some(
            "another hub serves there or holds the port while its radio is away, or another \
             program serves there: give this one another --listen ADDR:PORT",
        ),
        _ => crate::hints::listen_hint(error),
    };
    let hint = hint.map(|h| format!(" ({h})")).unwrap_or_default();
    Failure::link(format!("cannot listen on {addr}: {error}{hint}"))
}

/// Runs `hub` until Ctrl-C, or until the link to the radio ends.
pub(crate) async fn run(mut args: HubArgs) -> Result<(), Failure> {
    // A burst from the radio (as it comes while the hub asks the radio for its mode,
    // before it reads the link's events) is held rather than lost.
    args.link.event_capacity = Some(crate::link_args::EVENTS_HELD);
    args.link.check_wait(args.wait)?;
    // Refused before the radio's link is opened; made once a frame is there to record.
    let record = args
        .record
        .as_deref()
        .map(|path| RecordingFile::check(path, args.force))
        .transpose()?;
    // Heard from here on: Ctrl-C while the radio is asked for its mode (`--api-mode
    // auto`, and the hub's own check) stops the hub.
    let ctrl_c = crate::interrupt::ctrl_c();
    tokio::pin!(ctrl_c);
    let radio = &args.link.link;
    let start = async {
        let options = mcp_host::LinkOptions {
            wait_for_link: args.wait,
            // Its clients may be anyone who reaches its port: no frame longer than a
            // request is (every frame of the radio's fits too).
            max_frame_len: mcp_host::codec::MAX_REQUEST_DATA,
            ..args.link.options(true, Role::Hub).await?
        };
        // With a recording, the frames from the link's very first: the radio's first
        // ones and the hub's own AT AP too.
        let started = match record {
            Some(_) => Hub::start_tapped(radio, options, &args.listen)
                .await
                .map(|(hub, tap)| (hub, Some(tap))),
            None => Hub::start(radio, options, &args.listen)
                .await
                .map(|hub| (hub, None)),
        };
        started.map_err(|e| match e {
            HubError::Connect(e) => connect_failure_as(radio, e, Role::Hub),
            HubError::Listen { addr, error, .. } => listen_failure(&addr, &error),
            other => Failure::link(other.to_string()),
        })
    };
    let (hub, tap) = tokio::select! {
        started = start => started?,
        interrupt = &mut ctrl_c => {
            out!("stopped: {interrupt} before the hub served");
            return Ok(());
        }
    };
    let mut recorder = record.zip(tap).map(|(file, tap)| Recorder::new(file, tap));
    crate::hints::announce_radio_side(hub.radio_link());
    let addr = hub.local_addr();
    let mode = u8::from(hub.api_mode());
    if !addr.ip().is_loopback() {
        err!(
            "mcp-gs: warning: serving on {addr}, reached from other machines: the hub has \
             no authentication, and every host that reaches it can send the radio any \
             frame, AT commands that change or reset it included (listen on 127.0.0.1, or \
             on a network whose every host you trust)"
        );
    }
    if hub.stats().listening {
        out!(
            "serving {radio} on {addr}: give other commands --link tcp:{addr} --api-mode \
             {mode} (Ctrl-C stops)"
        );
    } else {
        out!(
            "will serve {radio} on {addr} once a radio is there: then give other commands \
             --link tcp:{addr} --api-mode {mode} (Ctrl-C stops)"
        );
        // A status line like the hub's own "radio there" that follows it, with the time.
        tracing::info!(
            target: mcp_host::hub::STATUS_TARGET,
            "hub: no radio on {radio} yet: clients are refused until one is there"
        );
    }
    // What is wrong with the radio's settings, said from its link's counters (a radio
    // in another API mode, at another baud rate, in transparent mode): the hub drops
    // what it cannot read, and its clients hear nothing. Once for each time the radio
    // is there; not with `--api-mode auto`, which asked the radio.
    let fixed = match args.link.api_mode {
        ApiModeChoice::Fixed(mode) => Some(mode),
        ApiModeChoice::Auto => None,
    };
    let mut last = hub.stats().radio;
    // From the radio link's first byte on: what came before this line counts too.
    let mut diagnoser = fixed.map(|mode| Diagnoser::new(mode, mcp_host::Stats::default()));
    let mut hinted = false;
    let mut look = tokio::time::interval(Duration::from_secs(1));
    loop {
        tokio::select! {
            _ = &mut ctrl_c => break,
            () = hub.finished() => {
                hub.stop().await;
                let closed = Failure::link(format!("the link to {radio} closed"));
                // The link's end is what the exit status says; a failure of the
                // recording's as the hub stopped is said here (one before, as it came).
                let said = recorder.as_ref().is_some_and(|r| r.failure.is_some());
                if let (Err(failure), false) = (Recorder::end(recorder).await, said) {
                    err!("mcp-gs: warning: {}", failure.message);
                }
                return Err(closed);
            }
            step = recorder_step(&mut recorder) => {
                if let Some(recorder) = &mut recorder {
                    match step {
                        Ok(frame) => recorder.take(&frame),
                        Err(failure) => recorder.stop(failure),
                    }
                }
            }
            _ = look.tick(), if fixed.is_some() => {
                let now = hub.stats().radio;
                if now.reconnects > last.reconnects {
                    // Another radio, maybe: counted afresh.
                    diagnoser = fixed.map(|mode| Diagnoser::new(mode, now));
                    hinted = false;
                }
                last = now;
                let hint = diagnoser
                    .as_mut()
                    .and_then(|d| d.look(now))
                    .map(|found| hint(found, &args.link.link));
                if let (Some(hint), false) = (hint, hinted) {
                    hinted = true;
                    let reason = hint.strip_prefix("hint: ").unwrap_or(&hint);
                    // A warning like the hub's own, with the time of day.
                    tracing::warn!(
                        "hub: the radio's frames cannot be read and are dropped: its \
                         clients get none of them: {reason} (stop the hub, and start it \
                         again with that fixed)"
                    );
                }
            }
        }
    }
    let stats = hub.stats();
    hub.stop().await;
    out!(
        "stopped: {}, {} from the radio, {} from clients, {} dropped for slow clients, {} \
         from clients refused",
        crate::counted(stats.clients, "client"),
        crate::counted(stats.frames_from_radio, "frame"),
        stats.frames_from_clients,
        stats.frames_dropped,
        crate::counted(stats.frames_refused, "frame")
    );
    let turned_away = (stats.clients_turned_away > 0).then(|| {
        format!(
            "{} turned away ({} connected)",
            crate::counted(stats.clients_turned_away, "client"),
            mcp_host::hub::MAX_CLIENTS
        )
    });
    let held = (stats.requests_held > 0).then(|| {
        format!(
            "{} waited for a frame id",
            crate::counted(stats.requests_held, "request")
        )
    });
    let skipped = (stats.bytes_skipped > 0).then(|| {
        format!(
            "{} that began no frame skipped",
            crate::counted(stats.bytes_skipped, "byte")
        )
    });
    let clients: Vec<String> = turned_away.into_iter().chain(held).chain(skipped).collect();
    if !clients.is_empty() {
        out!("clients: {}", clients.join(", "));
    }
    let radio = stats.radio;
    if radio.events_dropped > 0 || radio.decode_errors() > 0 {
        out!(
            "from the radio: {} lost while the hub fell behind, {} dropped \
             (bad checksum, cut off, ...)",
            crate::counted(radio.events_dropped, "event"),
            crate::counted(radio.decode_errors(), "frame")
        );
    }
    Recorder::end(recorder).await
}

/// What the recording has next, while it goes on: a frame to take, or the failure of a
/// write to its file as it fails; never, without one.
async fn recorder_step(recorder: &mut Option<Recorder>) -> Result<Record, Failure> {
    let Some(recorder) = recorder.as_mut().filter(|r| r.going()) else {
        return std::future::pending().await;
    };
    tokio::select! {
        Some(frame) = recorder.frames.next() => Ok(frame),
        failure = recording::write_failed(&mut recorder.recording) => Err(failure),
    }
}

/// `--record`: the frames between the hub and its radio, to a file made at the first of
/// them (not before a radio is there: a hub started with `--wait` and `--force` keeps the
/// file it would overwrite until then).
struct Recorder {
    frames: Subscription<Record>,
    /// The file, until it is made.
    file: Option<RecordingFile>,
    recording: Option<Recording>,
    /// Why the recording stopped, if it did: the hub goes on serving (a full disk does
    /// not cut the ground station off its MAV), and says it at the end.
    failure: Option<Failure>,
    /// Whether the hub has stopped: a failure is then the end's alone, not said as one
    /// the hub serves on after.
    ending: bool,
}

impl Recorder {
    fn new(file: RecordingFile, frames: Subscription<Record>) -> Self {
        Recorder {
            frames,
            file: Some(file),
            recording: None,
            failure: None,
            ending: false,
        }
    }

    /// Whether frames are still to be recorded (the tap has not ended, nor the file
    /// failed).
    fn going(&self) -> bool {
        self.failure.is_none() && !self.frames.is_terminated()
    }

    /// Records `frame` (making the file for the first), or stops recording if the file
    /// cannot take it.
    fn take(&mut self, frame: &Record) {
        if let Some(file) = self.file.take() {
            match file.create() {
                Ok(recording) => self.recording = Some(recording),
                Err(failure) => return self.stop(failure),
            }
        }
        let Some(file) = &mut self.recording else {
            return;
        };
        if let Err(failure) = file.write(frame.time, frame.direction, &frame.frame) {
            self.stop(failure);
        }
    }

    fn stop(&mut self, failure: Failure) {
        if !self.ending {
            err!(
                "mcp-gs: warning: {}: the recording stops here, the hub goes on serving",
                failure.message
            );
        }
        self.failure = Some(failure);
    }

    /// Once the hub has stopped (which ends the tap): records the frames still held
    /// for it, says what was recorded, and fails if the recording did.
    async fn end(recorder: Option<Self>) -> Result<(), Failure> {
        let Some(mut recorder) = recorder else {
            return Ok(());
        };
        recorder.ending = true;
        // Bounded all the same: the link ended with the hub.
        let drained = tokio::time::timeout(Duration::from_secs(5), async {
            while recorder.going() {
                match recorder.frames.next().await {
                    Some(frame) => recorder.take(&frame),
                    None => break,
                }
            }
        });
        let _ = drained.await;
        if let Some(recording) = recorder.recording.take() {
            let recorded = recording.end().await;
            // Frames the hub's loop did not take from the link in time (the machine
            // busy), and frames the file did not take in time.
            let behind = recorder.frames.missed();
            let lost: Vec<String> = [
                (behind, "while the recording fell behind the link"),
                (recorded.missed, "while writing the file fell behind"),
            ]
            .into_iter()
            .filter(|(n, _)| *n > 0)
            .map(|(n, why)| format!("{} lost {why}", crate::counted(n, "frame")))
            .collect();
            let lost = match lost.is_empty() {
                true => String::new(),
                false => format!(" ({})", lost.join(", ")),
            };
            out!(
                "recorded {} to {}{lost}",
                crate::counted(recorded.frames, "frame"),
                recorded.path.display()
            );
            // A write that failed as the hub stopped: the exit status says it.
            if recorder.failure.is_none() {
                recorder.failure = recorded.failure;
            }
        } else if recorder.failure.is_none() {
            out!("recorded nothing: no frame came (the file was not made)");
        }
        recorder.failure.map_or(Ok(()), Err)
    }
}
