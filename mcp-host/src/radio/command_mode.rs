//! The AT command mode of an emulated radio in transparent mode: `+++` alone between two
//! guard times of silence enters it, each `AT` line is answered, and `ATCN` (or `CT`
//! with no command) leaves it, applying a new `AP`.

use std::time::Duration;

use tokio::time::Instant;

use super::router::{COMMAND_TIMEOUT, GUARD_TIME_MS, hex_value};

/// `CN`: leave command mode.
const CN: [u8; 2] = *b"CN";
/// `AP`: the API mode setting.
const AP: [u8; 2] = *b"AP";
/// `AT` alone, as [`parse`] gives it.
const LISTEN: [u8; 2] = *b"\0\0";

/// The longest command line kept; longer lines keep their start and are refused.
const LINE_MAX: usize = 64;

/// What the device's bytes or a passing deadline made the radio do.
#[derive(Debug, PartialEq, Eq)]
pub(crate) enum Step {
    /// Command mode is entered: write `OK` and a carriage return to the device.
    Enter,
    /// Write these bytes to the device (an answer line).
    Answer(Vec<u8>),
    /// Command mode is over, with `ap` the API mode setting; `rest` are the bytes the
    /// device wrote after the command that ended it.
    Leave { ap: u8, rest: Vec<u8> },
}

/// The state of one device's session with a radio in transparent mode.
#[derive(Debug)]
pub(crate) struct CommandMode {
    guard: Duration,
    timeout: Duration,
    /// When the device last wrote; `None`: not in this session (a radio has been silent
    /// long before its device opens the link).
    last: Option<Instant>,
    /// `+` written after a guard time of silence, up to 3.
    plus: u8,
    /// In command mode: the line so far, `AP` as set, and when it times out.
    command: Option<Command>,
}

#[derive(Debug)]
struct Command {
    line: Vec<u8>,
    ap: u8,
    deadline: Instant,
}

impl CommandMode {
    /// A session in transparent mode, with Digi's default guard time (`GT`) and command
    /// mode timeout (`CT`).
    pub(crate) fn new() -> Self {
        CommandMode {
            guard: Duration::from_millis(u64::from(GUARD_TIME_MS)),
            timeout: Duration::from_millis(u64::from(COMMAND_TIMEOUT) * 100),
            last: None,
            plus: 0,
            command: None,
        }
    }

    /// When [`on_deadline`](Self::on_deadline) is due: the end of the guard time after
    /// `+++`, or the command mode timeout.
    pub(crate) fn deadline(&self) -> Option<Instant> {
        match &self.command {
            Some(command) => Some(command.deadline),
            None => self
                .last
                .filter(|_| self.plus == 3)
                .map(|last| last + self.guard),
        }
    }

    /// The deadline passed: command mode is entered or left.
    pub(crate) fn on_deadline(&mut self, now: Instant) -> Option<Step> {
        match &self.command {
            Some(command) if now >= command.deadline => {
                let ap = command.ap;
                self.command = None;
                Some(Step::Leave {
                    ap,
                    rest: Vec::new(),
                })
            }
            None if self.plus == 3 && self.last.is_some_and(|last| now >= last + self.guard) => {
                self.plus = 0;
                self.command = Some(Command {
                    line: Vec::new(),
                    ap: 0,
                    deadline: now + self.timeout,
                });
                Some(Step::Enter)
            }
            _ => None,
        }
    }

    /// The device wrote `bytes` at `now`. Outside command mode they are data (which go
    /// nowhere here) or part of `+++`; in command mode, command lines, each answered by
    /// `execute` (given the command and its value as typed) but `AP` and `CN`, which
    /// are handled here.
    pub(crate) fn on_bytes(
        &mut self,
        now: Instant,
        bytes: &[u8],
        mut execute: impl FnMut([u8; 2], &str) -> String,
    ) -> Vec<Step> {
        let mut steps = Vec::new();
        let Some(command) = &mut self.command else {
            for &b in bytes {
                let after_silence = self.plus > 0
                    || self
                        .last
                        .is_none_or(|last| now.duration_since(last) >= self.guard);
                self.plus = if b == b'+' && after_silence && self.plus < 3 {
                    self.plus + 1
                } else {
                    0
                };
                self.last = Some(now);
            }
            return steps;
        };
        let mut rest = bytes;
        while let Some(end) = rest.iter().position(|&b| b == b'\r') {
            let (head, tail) = rest.split_at(end);
            rest = tail.get(1..).unwrap_or_default();
            if command.line.len() < LINE_MAX {
                let room = LINE_MAX - command.line.len();
                command
                    .line
                    .extend_from_slice(head.get(..room.min(head.len())).unwrap_or_default());
            }
            let line = String::from_utf8_lossy(&std::mem::take(&mut command.line)).into_owned();
            // Each line is a command, good or not: `CT` counts from the last one.
            command.deadline = now + self.timeout;
            // A line feed after the carriage return (a terminal's CRLF) and spaces around
            // the command are no part of it. Commands chained with commas are answered
            // one by one, as if each had its own line.
            for parsed in parse(line.trim()) {
                match parsed {
                    Some((CN, "")) => {
                        steps.push(Step::Answer(b"OK\r".to_vec()));
                        steps.push(Step::Leave {
                            ap: command.ap,
                            rest: rest.to_vec(),
                        });
                        self.command = None;
                        self.last = Some(now);
                        return steps;
                    }
                    Some((AP, "")) => steps.push(answer(&format!("{:X}", command.ap))),
                    Some((AP, value)) => match hex_u8(value) {
                        Some(ap @ 0..=2) => {
                            command.ap = ap;
                            steps.push(answer("OK"));
                        }
                        _ => steps.push(answer("ERROR")),
                    },
                    // `AT` alone: the radio is listening.
                    Some((LISTEN, _)) => steps.push(answer("OK")),
                    Some((name, value)) => steps.push(answer(&execute(name, value))),
                    None => steps.push(answer("ERROR")),
                }
            }
        }
        let room = LINE_MAX.saturating_sub(command.line.len());
        command
            .line
            .extend_from_slice(rest.get(..room.min(rest.len())).unwrap_or_default());
        steps
    }
}

/// An answer line.
fn answer(text: &str) -> Step {
    Step::Answer(format!("{text}\r").into_bytes())
}

/// The commands of a line: `AT`, a command (two characters, either case) and its value,
/// then any further commands after commas, without `AT` (`ATAP1,WR,CN`); a comma always
/// ends a command, so no value holds one. `AT` alone is command `\0\0`. `None` for a
/// line that is no AT command, or for a part of one that is no command.
fn parse(line: &str) -> Vec<Option<([u8; 2], &str)>> {
    let Some(body) = line.strip_prefix("AT").or_else(|| line.strip_prefix("at")) else {
        return vec![None];
    };
    if body.trim().is_empty() {
        return vec![Some((LISTEN, ""))];
    }
    body.split(',').map(|part| command(part.trim())).collect()
}

/// One command: two characters, either case, then its value as typed.
fn command(text: &str) -> Option<([u8; 2], &str)> {
    let name = text.get(..2)?;
    let value = text.get(2..)?;
    let mut command = [0u8; 2];
    for (slot, c) in command.iter_mut().zip(name.bytes()) {
        if !c.is_ascii_alphanumeric() && c != b'%' && c != b'?' {
            return None;
        }
        *slot = c.to_ascii_uppercase();
    }
    Some((command, value))
}

/// A one-byte value, read as every number typed in command mode is ([`hex_value`]).
fn hex_u8(value: &str) -> Option<u8> {
    match hex_value(value)?.as_slice() {
        &[byte] => Some(byte),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A session at `start` that entered command mode.
    fn in_command_mode(start: Instant) -> (CommandMode, Instant) {
        let mut mode = CommandMode::new();
        let typed = start;
        assert!(
            mode.on_bytes(typed, b"+++", |_, _| unreachable!())
                .is_empty()
        );
        assert_eq!(mode.deadline(), Some(typed + Duration::from_secs(1)));
        let entered = typed + Duration::from_secs(1);
        assert_eq!(mode.on_deadline(entered), Some(Step::Enter));
        (mode, entered)
    }

    fn lines(steps: &[Step]) -> Vec<String> {
        steps
            .iter()
            .filter_map(|s| match s {
                Step::Answer(bytes) => Some(String::from_utf8_lossy(bytes).into_owned()),
                Step::Enter | Step::Leave { .. } => None,
            })
            .collect()
    }

    #[test]
    fn plus_plus_plus_needs_silence_before_and_after() {
        let start = Instant::now();
        let second = Duration::from_secs(1);
        // Too soon after other data.
        let mut mode = CommandMode::new();
        mode.on_bytes(start + second, b"data", |_, _| unreachable!());
        mode.on_bytes(start + second * 3 / 2, b"+++", |_, _| unreachable!());
        assert_eq!(mode.deadline(), None);
        let mut mode = CommandMode::new();
        mode.on_bytes(start + second, b"data+++", |_, _| unreachable!());
        assert_eq!(mode.deadline(), None);
        // Followed by data within the guard time.
        let mut mode = CommandMode::new();
        mode.on_bytes(start + second, b"+++", |_, _| unreachable!());
        mode.on_bytes(start + second * 3 / 2, b"x", |_, _| unreachable!());
        assert_eq!(mode.deadline(), None);
        assert_eq!(mode.on_deadline(start + second * 3), None);
        // Four of them are data.
        let mut mode = CommandMode::new();
        mode.on_bytes(start + second, b"++++", |_, _| unreachable!());
        assert_eq!(mode.deadline(), None);
        // Typed one at a time.
        let mut mode = CommandMode::new();
        for i in 0..3 {
            mode.on_bytes(
                start + second + Duration::from_millis(i * 10),
                b"+",
                |_, _| unreachable!(),
            );
        }
        assert!(mode.deadline().is_some());
    }

    #[test]
    fn commands_are_answered_and_cn_leaves_with_the_mode_set() {
        let (mut mode, at) = in_command_mode(Instant::now());
        let mut asked = Vec::new();
        let steps = mode.on_bytes(
            at,
            b"ATAP\rATAP2\rATAP\rATAP3\rAT\rhello\rATNI MAV\r",
            |c, v| {
                asked.push((c, v.to_owned()));
                "OK".to_owned()
            },
        );
        assert_eq!(
            lines(&steps),
            ["0\r", "OK\r", "2\r", "ERROR\r", "OK\r", "ERROR\r", "OK\r"]
        );
        assert_eq!(asked, [(*b"NI", " MAV".to_owned())]);
        // A line in two writes, then CN and the first bytes of an API frame.
        assert!(mode.on_bytes(at, b"ATw", |_, _| unreachable!()).is_empty());
        let steps = mode.on_bytes(at, b"r\rATCN\r\x7E\x00", |c, _| {
            assert_eq!(c, *b"WR");
            "OK".to_owned()
        });
        assert_eq!(
            steps,
            [
                Step::Answer(b"OK\r".to_vec()),
                Step::Answer(b"OK\r".to_vec()),
                Step::Leave {
                    ap: 2,
                    rest: vec![0x7E, 0x00]
                }
            ]
        );
        assert_eq!(mode.deadline(), None);
    }

    #[test]
    fn commands_chained_with_commas_are_answered_one_by_one() {
        // Digi's own example, then the usual way to set a factory radio up in one line.
        let (mut mode, at) = in_command_mode(Instant::now());
        let mut asked = Vec::new();
        let steps = mode.on_bytes(
            at,
            b"ATNIMy XBee,AC\rATAP0x2,XX?,WR,CN,NIlost\rrest",
            |c, v| {
                asked.push((c, v.to_owned()));
                if c == *b"XX" { "ERROR" } else { "OK" }.to_owned()
            },
        );
        assert_eq!(
            asked,
            [
                (*b"NI", "My XBee".to_owned()),
                (*b"AC", String::new()),
                (*b"XX", "?".to_owned()),
                (*b"WR", String::new()),
            ]
        );
        assert_eq!(
            steps,
            [
                Step::Answer(b"OK\r".to_vec()),
                Step::Answer(b"OK\r".to_vec()),
                Step::Answer(b"OK\r".to_vec()),
                // A command that fails is answered so; the next ones still run.
                Step::Answer(b"ERROR\r".to_vec()),
                Step::Answer(b"OK\r".to_vec()),
                Step::Answer(b"OK\r".to_vec()),
                // CN leaves at once: what follows it on its line is not run.
                Step::Leave {
                    ap: 2,
                    rest: b"rest".to_vec()
                }
            ]
        );
        // The line must start with AT; the commands after a comma do without it.
        let (mut mode, at) = in_command_mode(Instant::now());
        let steps = mode.on_bytes(at, b"AP1,WR\rATAP1,\r", |_, _| unreachable!());
        assert_eq!(lines(&steps), ["ERROR\r", "OK\r", "ERROR\r"]);
    }

    #[test]
    fn a_terminals_line_feeds_and_spaces_are_no_part_of_a_command() {
        let (mut mode, at) = in_command_mode(Instant::now());
        let steps = mode.on_bytes(at, b"ATAP\r\nATAP1 \r\n ATCN \r", |_, _| unreachable!());
        assert_eq!(
            steps,
            [
                Step::Answer(b"0\r".to_vec()),
                Step::Answer(b"OK\r".to_vec()),
                Step::Answer(b"OK\r".to_vec()),
                Step::Leave {
                    ap: 1,
                    rest: Vec::new()
                }
            ]
        );
    }

    #[test]
    fn command_mode_times_out_ct_after_the_last_command() {
        let (mut mode, at) = in_command_mode(Instant::now());
        let later = at + Duration::from_secs(5);
        mode.on_bytes(later, b"ATAP1\r", |_, _| unreachable!());
        // Bytes of no whole command do not hold command mode open.
        mode.on_bytes(later + Duration::from_secs(5), b"AT", |_, _| unreachable!());
        let timeout = later + Duration::from_secs(10);
        assert_eq!(mode.deadline(), Some(timeout));
        assert_eq!(mode.on_deadline(timeout - Duration::from_millis(1)), None);
        assert_eq!(
            mode.on_deadline(timeout),
            Some(Step::Leave {
                ap: 1,
                rest: Vec::new()
            })
        );
    }

    #[test]
    fn an_endless_line_is_cut_and_refused() {
        let (mut mode, at) = in_command_mode(Instant::now());
        let long = vec![b'A'; 10_000];
        assert!(mode.on_bytes(at, &long, |_, _| unreachable!()).is_empty());
        let steps = mode.on_bytes(at, b"\r", |_, _| unreachable!());
        assert_eq!(lines(&steps), ["ERROR\r"]);
    }
}
