//! `mcp-gs replay`: play a recording back onto a link.

use std::fs::File;
use std::io::BufReader;
use std::path::PathBuf;
use std::time::Duration;

use clap::{Args, ValueEnum};
use mcp_host::record::{Direction, Record, RecordReader};
use mcp_host::{CommandSender, Link, SendError};

use crate::Failure;
use crate::link_args::{LinkArgs, send_failure};

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
    /// `mcp_host::record::RecordWriter`).
    file: PathBuf,
    #[command(flatten)]
    link: LinkArgs,
    /// Playback speed: 1 is real time, 2 twice as fast, 0 as fast as possible.
    #[arg(long, default_value_t = 1.0, value_parser = parse_speed)]
    speed: f64,
    /// Which frames to play.
    #[arg(long, value_enum, default_value_t = Which::Rx)]
    frames: Which,
}

/// `--speed`: a finite number, 0 or more.
fn parse_speed(s: &str) -> Result<f64, String> {
    s.parse::<f64>()
        .ok()
        .filter(|x| x.is_finite() && *x >= 0.0)
        .ok_or_else(|| {
            format!(
                "expected a speed of 0 (as fast as possible) or more (1 is real time), got `{s}`"
            )
        })
}

/// Runs `replay`.
pub(crate) async fn run(args: ReplayArgs) -> Result<(), Failure> {
    let file = File::open(&args.file)
        .map_err(|e| Failure::input(format!("cannot open {}: {e}", args.file.display())))?;
    let mut reader = RecordReader::new(BufReader::new(file))
        .map_err(|e| Failure::input(format!("{}: {e}", args.file.display())))?;
    let first = first_wanted(&args, &mut reader)?;
    if let Some(warning) = radio_side_warning(&args.link.link, args.frames) {
        err!("mcp-gs: warning: {warning}");
    }
    let (stream, sender) = args.link.open(false).await?;
    if let Some(path) = &stream.info().pty_path {
        err!("mcp-gs: pseudo-terminal: {}", path.display());
    }
    let start = tokio::time::Instant::now();
    let mut played = 0u64;
    let records = std::iter::once(Ok(first)).chain(reader);
    let result = play(&args, records, &sender, start, &mut played).await;
    // What was written goes out before the process ends, also after an error. (The
    // stream is dropped first: its queue, full of what nobody read, would hold up the
    // last event of the link.)
    drop(stream);
    sender.close();
    sender.closed().await;
    result?;
    err!("mcp-gs: replayed {}", crate::counted(played, "frame"));
    Ok(())
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

/// Reads the recording up to its first frame `--frames` plays, before the link is
/// opened, and returns it (the records before it are not played): one that holds no
/// such frame is an input error (a recording made by `monitor` holds received frames
/// only), and so is one damaged before it. The recording is read once, so that a pipe
/// or a FIFO plays as a file does.
fn first_wanted(
    args: &ReplayArgs,
    reader: &mut RecordReader<BufReader<File>>,
) -> Result<Record, Failure> {
    let (mut received, mut sent) = (0u64, 0u64);
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
        if wanted(args.frames, record.direction) {
            return Ok(record);
        }
    }
    let file = args.file.display();
    Err(Failure::input(match args.frames {
        _ if received + sent == 0 => format!("{file} holds no frames: nothing to replay"),
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

/// Writes the wanted records of `records` at their pace; counts them in `played`.
async fn play(
    args: &ReplayArgs,
    records: impl Iterator<Item = std::io::Result<Record>>,
    sender: &CommandSender,
    start: tokio::time::Instant,
    played: &mut u64,
) -> Result<(), Failure> {
    let mut first = None;
    for record in records {
        let record = record.map_err(|e| {
            Failure::input(format!(
                "{}: {e} (replayed {} before it)",
                args.file.display(),
                crate::counted(*played, "frame")
            ))
        })?;
        if !wanted(args.frames, record.direction) {
            continue;
        }
        let first = *first.get_or_insert(record.time);
        if args.speed > 0.0 {
            let offset = record.time.duration_since(first).unwrap_or_default();
            // A hostile or damaged recording may stamp a record beyond any time a clock
            // can wait for (at a slow speed, all the more).
            let at = Duration::try_from_secs_f64(offset.as_secs_f64() / args.speed)
                .ok()
                .filter(|wait| *wait <= MAX_WAIT)
                .and_then(|wait| start.checked_add(wait))
                .ok_or_else(|| {
                    Failure::input(format!(
                        "{}: a record stamped {} s after the first is too far ahead to wait \
                         for at --speed {} (replayed {} before it; --speed 0 plays every \
                         frame at once)",
                        args.file.display(),
                        offset.as_secs(),
                        args.speed,
                        crate::counted(*played, "frame")
                    ))
                })?;
            // A link that ends while the replay waits for a record's time is said at
            // once, not at the record.
            tokio::select! {
                () = tokio::time::sleep_until(at) => {}
                () = sender.closed() => return Err(lost(SendError::Closed, *played)),
            }
        }
        sender
            .write_frame(&record.frame)
            .await
            .map_err(|e| lost(e, *played))?;
        *played += 1;
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
