//! `mcp-gs replay`: play a recording back onto a link.

use std::collections::{BTreeMap, BTreeSet};
use std::fs::File;
use std::io::{self, BufReader, Read};
use std::path::{Path, PathBuf};
use std::time::Duration;

use clap::{Args, ValueEnum};
use mcp_host::mcp_core::{Command, Packet};
use mcp_host::record::{Direction, Record, RecordError, RecordReader};
use mcp_host::xbee_api::Address64;
use mcp_host::{CommandSender, Link, SendError};

use crate::Failure;
use crate::hints::send_failure;
use crate::link_args::LinkArgs;
use mcp_host::render::Seconds;

/// Which recorded frames to play.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub(crate) enum Which {
    /// Frames received from the radio (what a ground station saw): the default.
    Rx,
    /// Frames sent to the radio (`hub --record` records them beside the received
    /// ones, `monitor --record` received frames only).
    Tx,
    /// Both.
    Both,
}

/// Arguments of `replay`.
#[derive(Debug, Args)]
#[command(mut_arg("timeout", |arg| arg.help(
    "Seconds to wait to connect (on tcp-listen:, for the ground station to connect) \
and for the link to take each frame [default: 12]"
)))]
#[command(mut_arg("link", |arg| arg.help(
    "Where to play the frames: to a ground station (received frames, the default), \
     tcp-listen:ADDR:PORT for it to connect to, or serial:PATH on a serial cable to it; \
     to a radio (--frames tx), serial:PATH[:BAUD][:rtscts] or tcp:HOST:PORT"
)))]
pub(crate) struct ReplayArgs {
    /// A recording made by `monitor --record` or `hub --record` (or by a program with
    /// `mcp_host::record::RecordWriter`); `-` reads standard input. A file is read
    /// through before anything is played: a damaged or cut-off one plays nothing.
    /// Standard input (or a FIFO) is read once, as it plays: it plays up to the
    /// damage. `mcp-gs decode FILE` shows what it holds.
    file: PathBuf,
    #[command(flatten)]
    link: LinkArgs,
    /// Playback speed: 1 is real time, 2 twice as fast, 0 as fast as possible.
    #[arg(long, default_value = "1", value_parser = parse_speed)]
    speed: Speed,
    /// Which frames to play. Sent frames (tx) carry the recorded commands: played to a
    /// radio, they act on the MAVs again as they did then (a landing, a trajectory, a
    /// time command that sets a MAV's clock to the recorded time); what they are is said
    /// before the first is played, and at the end how many the radio delivered, by its
    /// transmit statuses (waited for --timeout).
    #[arg(long, value_enum, default_value_t = Which::Rx)]
    frames: Which,
    /// Also play the AT commands sent to radios (0x08, 0x09 to the local radio, 0x17
    /// to a remote one), left out by default: they set the radios' parameters (network,
    /// API mode, node identifier, ...) again as they were set when recorded.
    #[arg(long)]
    with_at: bool,
    /// The longest a replay waits between two frames, in the recording's seconds (before
    /// --speed): a recording quiet for an hour then plays on after this long.
    #[arg(long, value_name = "SECONDS", value_parser = parse_max_gap)]
    max_gap: Option<Duration>,
}

/// `--max-gap`: a finite number of seconds, 0 or more.
fn parse_max_gap(s: &str) -> Result<Duration, String> {
    s.parse::<f64>()
        .ok()
        .and_then(|x| Duration::try_from_secs_f64(x).ok())
        .ok_or_else(|| format!("expected a number of seconds, 0 or more, got `{s}`"))
}

/// A `--speed`, and the text it was given as, for the messages that name it (as typed:
/// `1e-300` rather than its 302 characters in full, `0.1234567890123` rather than
/// `1.234567890123e-1`).
#[derive(Debug, Clone)]
struct Speed {
    value: f64,
    text: String,
}

/// `--speed`: a finite number, 0 or more.
fn parse_speed(s: &str) -> Result<Speed, String> {
    s.parse::<f64>()
        .ok()
        .filter(|x| x.is_finite() && *x >= 0.0)
        .map(|value| Speed {
            value,
            text: s.to_owned(),
        })
        .ok_or_else(|| {
            format!(
                "expected a speed of 0 (as fast as possible) or more (1 is real time), got `{s}`"
            )
        })
}

/// Runs `replay`.
pub(crate) async fn run(args: ReplayArgs) -> Result<(), Failure> {
    let stdin = args.file.as_os_str() == "-";
    let input: Box<dyn Read + Send> = if stdin {
        Box::new(io::stdin())
    } else {
        Box::new(
            File::open(&args.file)
                .map_err(|e| Failure::input(format!("cannot open {}: {e}", args.file.display())))?,
        )
    };
    let mut reader = RecordReader::new(BufReader::new(input)).map_err(|e| {
        let hint = match e {
            RecordError::NoHeader | RecordError::TooShort => {
                " (replay plays recordings, made with --record; `mcp-gs decode` reads a raw \
                 capture too)"
            }
            _ => "",
        };
        Failure::input(format!("{}: {e}{hint}", args.file.display()))
    })?;
    // A file is read through first: nothing of a damaged one is played, and the
    // commands it would play are said. Standard input, a pipe or a FIFO is read once.
    let survey = match stdin {
        false if is_regular_file(&args.file) => Some(survey(&args)?),
        _ => None,
    };
    let (first, mut at_left_out) = first_wanted(&args, &mut reader)?;
    if let Some(warning) = radio_side_warning(&args.link.link, args.frames) {
        err!("mcp-gs: warning: {warning}");
    }
    if let Some(warning) = commands_warning(args.frames, survey.as_ref()) {
        err!("mcp-gs: warning: {warning}");
    }
    let (stream, sender) = args.link.open(false).await?;
    if let Some(path) = &stream.info().pty_path {
        err!("mcp-gs: pseudo-terminal: {}", path.display());
    }
    // Sent frames that ask for a transmit status get one from the radio: counted, to
    // say whether they were delivered. (Otherwise the stream is dropped: its queue,
    // full of what nobody read, would hold up the last event of the link.)
    let statuses = (args.frames != Which::Rx).then(|| gather_statuses(stream));
    let start = tokio::time::Instant::now();
    let mut played = Played::default();
    let records = std::iter::once(Ok(first)).chain(reader);
    let result = play(
        &args,
        records,
        &sender,
        start,
        &mut played,
        &mut at_left_out,
    )
    .await;
    let statuses = match (statuses, &result) {
        (Some(mut statuses), Ok(())) => {
            let wait = args.link.timeout();
            let awaited = played.awaiting_status;
            let answered = statuses.wait_for(|got| got.count() >= awaited);
            let _ = tokio::time::timeout(wait, answered).await;
            let got = statuses.borrow().clone();
            Some((got, awaited, wait))
        }
        _ => None,
    };
    // What was written goes out before the process ends, also after an error.
    sender.close();
    sender.closed().await;
    if at_left_out > 0 {
        err!("mcp-gs: {}", at_left_out_note(at_left_out));
    }
    result?;
    let delivery = match statuses {
        Some((got, awaited, wait)) if awaited > 0 => format!("; {}", got.said(awaited, wait)),
        _ => String::new(),
    };
    err!(
        "mcp-gs: replayed {}{delivery}",
        crate::counted(played.frames, "frame")
    );
    Ok(())
}

/// The frames a replay wrote, and those of them that ask for a transmit status (a
/// Transmit Request or Explicit Addressing Command with a frame id).
#[derive(Debug, Default)]
struct Played {
    frames: u64,
    awaiting_status: u64,
}

/// The transmit statuses the radio sent back while a replay ran.
#[derive(Debug, Clone, Default)]
struct Statuses {
    delivered: u64,
    /// Those not delivered, by their delivery status's name.
    failed: BTreeMap<String, u64>,
}

impl Statuses {
    fn count(&self) -> u64 {
        self.delivered + self.failed.values().sum::<u64>()
    }

    /// What to say of them, `awaited` having asked for one, waited for `wait` at most.
    fn said(&self, awaited: u64, wait: Duration) -> String {
        let mut parts = vec![format!("{} delivered", self.delivered)];
        if !self.failed.is_empty() {
            let failed: Vec<String> = self
                .failed
                .iter()
                .map(|(name, n)| format!("{name} {n}"))
                .collect();
            parts.push(format!(
                "{} not delivered ({})",
                self.failed.values().sum::<u64>(),
                failed.join(", ")
            ));
        }
        let missing = awaited.saturating_sub(self.count());
        if missing > 0 {
            parts.push(format!(
                "{missing} without a transmit status in {}",
                Seconds(wait)
            ));
        }
        format!(
            "of the {} that asked for a transmit status: {}",
            awaited,
            parts.join(", ")
        )
    }
}

/// Counts the transmit statuses among the link's events, as they come, until the link
/// ends.
fn gather_statuses(mut stream: mcp_host::PacketStream) -> tokio::sync::watch::Receiver<Statuses> {
    let (tell, told) = tokio::sync::watch::channel(Statuses::default());
    tokio::spawn(async move {
        let mut got = Statuses::default();
        while let Some(event) = futures::StreamExt::next(&mut stream).await {
            let mcp_host::Event::Frame(frame) = event else {
                continue;
            };
            let Ok(mcp_host::xbee_api::Frame::TransmitStatus(status)) = frame.parse() else {
                continue;
            };
            if status.delivery.is_success() {
                got.delivered += 1;
            } else {
                // Its name, as xbee-api says a status (`unknown(0xNN)` for a code it
                // does not name).
                *got.failed.entry(status.delivery.to_string()).or_default() += 1;
            }
            tell.send_replace(got.clone());
        }
    });
    told
}

/// Whether a recorded frame is an AT command to a radio: a local one (AT Command 0x08,
/// Queue Parameter Value 0x09) or a remote one (0x17), which sets a radio's parameters
/// when it has a value.
fn is_at_command(record: &Record) -> bool {
    record.direction == Direction::Sent && matches!(record.frame.first(), Some(0x08 | 0x09 | 0x17))
}

/// What to say of the AT commands not replayed.
fn at_left_out_note(count: u64) -> String {
    format!(
        "{} to radios in the recording not replayed: they would set the radios' \
         parameters again (--with-at plays them)",
        crate::counted(count, "AT command")
    )
}

/// What to say when the received frames (what a radio said, for a ground station) go
/// onto a `tcp:` link: most often a radio's side (a hub, a serial bridge, `mcp-gs sim`),
/// which takes requests only, so that the replay would seem to succeed while every frame
/// is dropped. Only a warning: a ground station listening on `tcp-listen:` takes them.
fn radio_side_warning(link: &Link, frames: Which) -> Option<String> {
    let (Link::Tcp { .. }, Which::Rx | Which::Both) = (link, frames) else {
        return None;
    };
    let which = match frames {
        Which::Both => "--frames both",
        _ => "--frames rx, the default,",
    };
    Some(format!(
        "{which} plays what a radio said, for a ground station; {link} is most often a \
         radio's side (a hub, a serial bridge, `mcp-gs sim`), which drops such frames (a \
         hub refuses them): --frames tx plays what was said to the radio (ignore this if a \
         ground station listens there)"
    ))
}

/// The longest a replay waits for a record, from the start (about 31 years, as the
/// longest `--duration`): a later one is a damaged or hostile time stamp.
const MAX_WAIT: Duration = Duration::from_secs(1_000_000_000);

/// Whether `direction` is one of the frames `which` plays.
fn wanted(which: Which, direction: Direction) -> bool {
    matches!(
        (which, direction),
        (Which::Both, _) | (Which::Rx, Direction::Received) | (Which::Tx, Direction::Sent)
    )
}

/// `duration` to the second (to the millisecond below one, as it is below a
/// millisecond), as said to an operator.
fn rounded(duration: Duration) -> Duration {
    match duration.as_secs() {
        // Below a millisecond, as it is.
        0 if duration.as_millis() == 0 => duration,
        0 => Duration::from_millis(duration.as_millis().try_into().unwrap_or(0)),
        _ => Duration::from_secs_f64(duration.as_secs_f64().round()),
    }
}

/// Whether the replay plays `record`: of the direction `--frames` plays, and no AT
/// command to a radio unless `--with-at`.
fn plays(args: &ReplayArgs, record: &Record) -> bool {
    wanted(args.frames, record.direction) && (args.with_at || !is_at_command(record))
}

/// A wait between two frames this long or longer is said as it begins: the replay
/// seems stuck otherwise.
const LONG_QUIET: Duration = Duration::from_secs(10);

/// Reads the recording up to its first frame the replay plays, before the link is
/// opened, and returns it (the records before it are not played) with the number of AT
/// commands left out before it: one that holds no
/// such frame is an input error (a recording made by `monitor` holds received frames
/// only), and so is one damaged before it. The recording is read once, so that a pipe
/// or a FIFO plays as a file does.
fn first_wanted(
    args: &ReplayArgs,
    reader: &mut RecordReader<impl Read>,
) -> Result<(Record, u64), Failure> {
    let (mut received, mut sent, mut at) = (0u64, 0u64, 0u64);
    for record in reader {
        let record = record.map_err(|e| {
            Failure::input(format!(
                "{}: {e} (no frame to replay before it)",
                args.file.display()
            ))
        })?;
        match record.direction {
            Direction::Received => received += 1,
            Direction::Sent => sent += 1,
        }
        if plays(args, &record) {
            return Ok((record, at));
        }
        if wanted(args.frames, record.direction) {
            at += 1;
        }
    }
    let file = args.file.display();
    Err(Failure::input(match args.frames {
        _ if received + sent == 0 => format!("{file} holds no frames: nothing to replay"),
        // Every frame it would play was an AT command.
        Which::Tx | Which::Both if at > 0 => {
            format!("{file}: nothing to replay: {}", at_left_out_note(at))
        }
        Which::Tx => format!(
            "{file} holds no sent frames (--frames tx), only {received} received ones \
             (`monitor --record` records received frames only, `hub --record` both): \
             replay those with --frames rx, the default"
        ),
        _ => format!(
            "{file} holds no received frames (--frames rx), only {sent} sent ones: \
             replay those with --frames tx"
        ),
    }))
}

/// Whether `path` is a regular file (not a FIFO, a device or a directory), which can be
/// read through twice.
fn is_regular_file(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|meta| meta.is_file())
}

/// The commands among the frames a replay plays, found by reading the whole recording
/// before anything is played.
#[derive(Debug, Default)]
struct Survey {
    /// Commands that act on a MAV, by their type's name.
    commands: BTreeMap<String, u64>,
    /// Status requests, which only ask.
    requests: u64,
    /// The MAVs the commands and requests go to.
    mavs: BTreeSet<Address64>,
}

/// Reads the whole recording `args` names (a regular file) and finds the commands among
/// the frames the replay plays. A damaged or cut-off record is a failure, so that
/// nothing of such a recording is played (the replay would stop there, part way
/// through what was recorded; and a record whose length was damaged reads as one cut
/// off, with whole records after it).
fn survey(args: &ReplayArgs) -> Result<Survey, Failure> {
    let name = args.file.display();
    let file =
        File::open(&args.file).map_err(|e| Failure::input(format!("cannot open {name}: {e}")))?;
    let reader = RecordReader::new(BufReader::new(file))
        .map_err(|e| Failure::input(format!("{name}: {e}")))?;
    let mut survey = Survey::default();
    for (whole, record) in (0u64..).zip(reader) {
        let record = match record {
            Ok(record) => record,
            // Cut off too: a record whose length was damaged reaches past the end as
            // one cut off does, with whole records after it.
            Err(e) => {
                let keep = match e.offset() {
                    Some(offset) => format!(
                        "; the {} before it are whole (`head -c {offset} {}` keeps them)",
                        crate::counted(whole, "record"),
                        shlex::try_quote(&name.to_string())
                            .unwrap_or_else(|_| name.to_string().into())
                    ),
                    None => String::new(),
                };
                return Err(Failure::input(format!(
                    "{name}: {e}: nothing replayed, as a damaged or cut-off recording is \
                     not played in part{keep}"
                )));
            }
        };
        if record.direction != Direction::Sent || !plays(args, &record) {
            continue;
        }
        if let Some((to, Ok(Packet::Command(command)))) = record.mcp() {
            match command {
                Command::StatusRequest(_) => survey.requests += 1,
                command => {
                    *survey
                        .commands
                        .entry(command.command_type().to_string())
                        .or_default() += 1;
                }
            }
            survey.mavs.insert(to);
        }
    }
    Ok(survey)
}

/// What to say before sent frames are played: the commands in them act on the MAVs
/// again. `survey` is `None` where the recording could not be read through first
/// (standard input, a pipe).
fn commands_warning(frames: Which, survey: Option<&Survey>) -> Option<String> {
    if frames == Which::Rx {
        return None;
    }
    let Some(survey) = survey else {
        return Some(
            "the recorded commands among the sent frames act on the MAVs again as they \
             did then (a time command sets a MAV's clock to the recorded time); `mcp-gs \
             decode FILE` shows them"
                .to_owned(),
        );
    };
    if survey.commands.is_empty() {
        return None;
    }
    let kinds: Vec<String> = survey
        .commands
        .iter()
        .map(|(kind, n)| format!("{kind} {n}"))
        .collect();
    let mavs: Vec<String> = survey.mavs.iter().map(Address64::to_string).collect();
    let requests = match survey.requests {
        0 => String::new(),
        n => format!(" (and {})", crate::counted(n, "status request")),
    };
    let time = match survey.commands.contains_key("time") {
        true => "; a time command sets the MAV's clock to the recorded time",
        false => "",
    };
    Some(format!(
        "the sent frames hold commands that act on MAVs, {}{requests}, to {} ({}): \
         played, they act again as they did when recorded{time}",
        kinds.join(", "),
        crate::counted(u64::try_from(mavs.len()).unwrap_or(u64::MAX), "MAV"),
        mavs.join(", ")
    ))
}

/// The failure of a frame that could not be written, after `played` were.
fn lost(error: SendError, played: u64) -> Failure {
    let failure = send_failure(error);
    let message = format!(
        "{} (replayed {} before it)",
        failure.message,
        crate::counted(played, "frame")
    );
    Failure::new(failure.code(), message)
}

/// Writes the records of `records` the replay plays at their pace, each the time after
/// the one before that the recording says (none when its clock went back, at most
/// `--max-gap`); counts them in `played`, and the AT commands it leaves out in
/// `at_left_out`.
async fn play(
    args: &ReplayArgs,
    records: impl Iterator<Item = Result<Record, RecordError>>,
    sender: &CommandSender,
    start: tokio::time::Instant,
    played: &mut Played,
    at_left_out: &mut u64,
) -> Result<(), Failure> {
    let mut previous = None;
    let mut at = start;
    let mut went_back = false;
    for record in records {
        let record = record.map_err(|e| {
            Failure::input(format!(
                "{}: {e} (replayed {} before it)",
                args.file.display(),
                crate::counted(played.frames, "frame")
            ))
        })?;
        if !plays(args, &record) {
            if wanted(args.frames, record.direction) {
                *at_left_out += 1;
            }
            continue;
        }
        let recorded_gap = match previous.replace(record.time) {
            None => Duration::ZERO,
            Some(previous) => record.time.duration_since(previous).unwrap_or_else(|back| {
                // The recording machine's clock was set back (a time server's
                // correction, a clock set at boot, recordings joined out of order): the
                // frames after it keep their pace from there. Said where there is a
                // pace to keep.
                if args.speed.value > 0.0 && !std::mem::replace(&mut went_back, true) {
                    err!(
                        "mcp-gs: warning: the recording's clock goes back {} before its \
                         frame {}: played at once, and the frames after it at their pace \
                         from there",
                        Seconds(rounded(back.duration())),
                        played.frames + 1
                    );
                }
                Duration::ZERO
            }),
        };
        let gap = args
            .max_gap
            .map_or(recorded_gap, |max| recorded_gap.min(max));
        if args.speed.value > 0.0 {
            // A hostile or damaged recording may stamp a record beyond any time a clock
            // can wait for (at a slow speed, all the more).
            let wait = Duration::try_from_secs_f64(gap.as_secs_f64() / args.speed.value)
                .ok()
                .filter(|wait| *wait <= MAX_WAIT);
            at = wait.and_then(|wait| at.checked_add(wait)).ok_or_else(|| {
                Failure::input(format!(
                    "{}: a record stamped {} s after the one before it is too far ahead to \
                     wait for at --speed {} (replayed {} before it; --speed 0 plays every \
                     frame at once, --max-gap shortens the waits)",
                    args.file.display(),
                    gap.as_secs(),
                    args.speed.text,
                    crate::counted(played.frames, "frame")
                ))
            })?;
            if let Some(wait) = wait.filter(|wait| *wait >= LONG_QUIET) {
                let shorten = match args.max_gap {
                    Some(_) => "",
                    None => " (--max-gap shortens such waits)",
                };
                err!(
                    "mcp-gs: waiting {}: the recording is quiet for {} after its frame \
                     {}{shorten}",
                    Seconds(rounded(wait)),
                    Seconds(rounded(recorded_gap)),
                    played.frames
                );
            }
            // A link that ends while the replay waits for a record's time is said at
            // once, not at the record.
            tokio::select! {
                () = tokio::time::sleep_until(at) => {}
                () = sender.closed() => return Err(lost(SendError::Closed, played.frames)),
            }
        }
        sender
            .write_frame(&record.frame)
            .await
            .map_err(|e| lost(e, played.frames))?;
        played.frames += 1;
        if matches!(record.frame[..], [0x10 | 0x11, id, ..] if id != 0) {
            played.awaiting_status += 1;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn received_frames_onto_a_tcp_link_are_warned_of() {
        let tcp: Link = "tcp:127.0.0.1:9750".parse().unwrap();
        let listen: Link = "tcp-listen:127.0.0.1:9750".parse().unwrap();
        assert!(radio_side_warning(&tcp, Which::Rx).is_some());
        assert!(radio_side_warning(&tcp, Which::Both).is_some());
        assert_eq!(radio_side_warning(&tcp, Which::Tx), None);
        assert_eq!(radio_side_warning(&listen, Which::Rx), None);
    }
}
