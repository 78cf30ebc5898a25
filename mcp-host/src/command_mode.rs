//! The radio's AT command mode (`+++`): how a radio in transparent mode (`AP=0`, as
//! XBee modules leave the factory) is put into API mode, which everything else in this
//! crate speaks, without Digi's XCTU.
//!
//! In command mode the radio takes text commands, `AT` and two letters and an optional
//! hex value, each ended by a carriage return, and answers each with a line: the value
//! read (hex, without leading zeros), `OK` or `ERROR`. It is entered by `+++` alone on
//! the line between two guard times of silence (`GT`, one second by default), and left
//! by `ATCN` (or after `CT`, ten seconds by default, with no command).
//!
//! The radio's answers come back as text that is safe to print: printable ASCII as it
//! came, a backslash doubled, any other byte as `\xNN` (a node identifier `café` reads
//! `caf\xc3\xa9`; noise or a hostile bridge on the line cannot send a terminal its
//! control sequences).
//!
//! ```no_run
//! use std::time::Duration;
//! use mcp_host::command_mode::CommandMode;
//! use mcp_host::{Connector, Link, LinkOptions};
//!
//! # async fn run() -> Result<(), Box<dyn std::error::Error>> {
//! let link: Link = "serial:/dev/ttyUSB0:9600".parse()?;
//! let mut connector = Connector::new(&link, &LinkOptions::default()).await?;
//! let port = connector.open().await?;
//! let timeout = Duration::from_secs(3);
//! let mut radio = CommandMode::enter(port, CommandMode::<()>::GUARD_TIME, timeout).await?;
//! if radio.read(*b"AP").await? == "0" {
//!     radio.set(*b"AP", "1").await?; // API mode 1
//!     radio.set(*b"WR", "").await?; // kept across power cycles
//! }
//! radio.exit().await?; // ATCN: the new mode takes effect
//! # Ok(())
//! # }
//! ```

use std::fmt::Write as _;
use std::io;
use std::time::Duration;

use tokio::io::{AsyncRead, AsyncReadExt, AsyncWrite, AsyncWriteExt};

/// The baud rates the radio's UART runs at for each value of `BD`, 0 to 8.
pub const BAUD_RATES: [u32; 9] = [
    1200, 2400, 4800, 9600, 19_200, 38_400, 57_600, 115_200, 230_400,
];

/// Longest answer line kept; a radio's answers are a few characters.
const LINE_MAX: usize = 64;

/// Why a command mode exchange failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CommandModeError {
    /// Reading from or writing to the link failed.
    #[error("command mode: {0}")]
    Io(io::Error),
    /// The link closed.
    #[error("command mode: the link closed")]
    Closed,
    /// No answer line came in time: to `+++`, a radio in API mode, at another baud rate
    /// or with a longer guard time (`GT`).
    #[error(
        "command mode: no answer to {sent} within {secs}",
        secs = crate::render::Seconds(*.timeout)
    )]
    #[non_exhaustive]
    NoAnswer {
        /// What was sent, as text (`+++`, `ATAP`).
        sent: String,
        /// How long the answer was waited for.
        timeout: Duration,
    },
    /// The radio answered something else than `OK`: `ERROR` for a command it does not
    /// know or a value it refuses.
    #[error("command mode: the radio answered {sent} with \"{answer}\"")]
    #[non_exhaustive]
    Refused {
        /// What was sent, as text.
        sent: String,
        /// The radio's answer line, as [safe text](self).
        answer: String,
    },
    /// A value holding a comma or a line end, which the radio would read as the end of
    /// the command (the rest as another command): nothing was sent.
    #[error("command mode: {sent:?} was not sent: a value cannot hold a comma or a line end")]
    #[non_exhaustive]
    InvalidValue {
        /// What would have been sent, as text.
        sent: String,
    },
}

/// The message says what the system said: no [`source`](std::error::Error::source), so
/// that a chain of errors says it once.
impl From<io::Error> for CommandModeError {
    fn from(error: io::Error) -> Self {
        CommandModeError::Io(error)
    }
}

/// A radio in AT command mode, over `io` (a [`Transport`](crate::Transport), or any
/// byte stream to the radio's UART).
#[derive(Debug)]
pub struct CommandMode<T> {
    io: T,
    timeout: Duration,
    /// Bytes read after the last answer line.
    pending: Vec<u8>,
}

impl<T> CommandMode<T> {
    /// The radio's guard time by default (`GT` = 0x3E8 ms): the silence it needs before
    /// and after `+++`.
    pub const GUARD_TIME: Duration = Duration::from_secs(1);
}

impl<T: AsyncRead + AsyncWrite + Unpin> CommandMode<T> {
    /// Enters command mode: `guard_time` of silence (what the radio sends meanwhile is
    /// dropped), `+++`, and the radio's `OK`, waited for `guard_time` and `timeout` more.
    /// Bytes the radio hands over from the air before its `OK` (in transparent mode it
    /// passes on what it receives) are passed over.
    ///
    /// The silence is counted from this call: bytes written to `io` just before may
    /// still be on their way to the radio at a low baud rate, and cut it short.
    pub async fn enter(
        mut io: T,
        guard_time: Duration,
        timeout: Duration,
    ) -> Result<Self, CommandModeError> {
        let mut scratch = [0u8; 256];
        let silence = async {
            loop {
                match io.read(&mut scratch).await {
                    Ok(0) => return Err::<(), _>(CommandModeError::Closed),
                    Ok(_) => {}
                    Err(e) => return Err(CommandModeError::from(e)),
                }
            }
        };
        if let Ok(Err(error)) = tokio::time::timeout(guard_time, silence).await {
            return Err(error);
        }
        io.write_all(b"+++").await?;
        io.flush().await?;
        let mut radio = CommandMode {
            io,
            timeout,
            pending: Vec::new(),
        };
        let wait = guard_time + timeout;
        let ok = async {
            loop {
                // Data from the air may come before the answer, on its line.
                if radio.line().await?.ends_with("OK") {
                    return Ok(());
                }
            }
        };
        match tokio::time::timeout(wait, ok).await {
            Ok(result) => result.map(|()| radio),
            Err(_) => Err(CommandModeError::NoAnswer {
                sent: "+++".to_owned(),
                timeout: wait,
            }),
        }
    }

    /// Reads a parameter (`AT` `command`): the radio's answer, its value in hex as the
    /// radio writes it (`AP` in transparent mode: `0`), as [safe text](self). `ERROR`,
    /// a command the radio does not know, is [`CommandModeError::Refused`], not a value
    /// (so a text parameter that reads `ERROR`, a node identifier set so, cannot be told
    /// from it here: read it in an API frame).
    pub async fn read(&mut self, command: [u8; 2]) -> Result<String, CommandModeError> {
        let answer = self.send(command, "").await?;
        if answer == "ERROR" {
            return Err(CommandModeError::Refused {
                sent: text(command, ""),
                answer,
            });
        }
        Ok(answer)
    }

    /// Sets a parameter, or runs a command that takes no value with `value` empty
    /// (`WR`, `AC`): `AT` `command` `value`, which the radio must answer `OK`.
    pub async fn set(&mut self, command: [u8; 2], value: &str) -> Result<(), CommandModeError> {
        let sent = text(command, value);
        let answer = self.send(command, value).await?;
        if answer == "OK" {
            Ok(())
        } else {
            Err(CommandModeError::Refused { sent, answer })
        }
    }

    /// Leaves command mode (`ATCN`): changes made take effect (a new `AP` or `BD` from
    /// here on). Hands the link back.
    pub async fn exit(mut self) -> Result<T, CommandModeError> {
        self.set(*b"CN", "").await?;
        Ok(self.io)
    }

    /// Sends `AT` `command` `value` and a carriage return; the answer line. Lines read
    /// before (a late answer to a command that timed out) are no answer to it.
    async fn send(&mut self, command: [u8; 2], value: &str) -> Result<String, CommandModeError> {
        let sent = text(command, value);
        if value.contains([',', '\r', '\n']) {
            return Err(CommandModeError::InvalidValue { sent });
        }
        self.pending.clear();
        self.io.write_all(format!("{sent}\r").as_bytes()).await?;
        self.io.flush().await?;
        match tokio::time::timeout(self.timeout, self.line()).await {
            Ok(line) => line,
            Err(_) => Err(CommandModeError::NoAnswer {
                sent,
                timeout: self.timeout,
            }),
        }
    }

    /// The next line the radio writes, without its carriage return (or line feed), safe
    /// to print ([`printable`]); empty lines are passed over, and a line longer than
    /// [`LINE_MAX`] keeps its end.
    async fn line(&mut self) -> Result<String, CommandModeError> {
        loop {
            if let Some(end) = self.pending.iter().position(|&b| b == b'\r' || b == b'\n') {
                let line: Vec<u8> = self.pending.drain(..=end).collect();
                let line = printable(line.get(..end).unwrap_or_default().trim_ascii());
                if !line.is_empty() {
                    return Ok(line);
                }
                continue;
            }
            if self.pending.len() > LINE_MAX {
                let cut = self.pending.len() - LINE_MAX;
                self.pending.drain(..cut);
            }
            let mut buf = [0u8; 64];
            match self.io.read(&mut buf).await? {
                0 => return Err(CommandModeError::Closed),
                n => self
                    .pending
                    .extend_from_slice(buf.get(..n).unwrap_or_default()),
            }
        }
    }
}

/// `AT` `command` `value`, as sent (without the carriage return).
fn text(command: [u8; 2], value: &str) -> String {
    format!("AT{}{value}", String::from_utf8_lossy(&command))
}

/// A line from the radio as text that is safe to print: printable ASCII as it is, a
/// backslash doubled, any other byte as `\xNN`. A radio answers in printable ASCII;
/// whatever else is on the line (a bridge, noise) must not reach a terminal as its
/// control sequences, nor pass for an escape.
fn printable(line: &[u8]) -> String {
    let mut text = String::with_capacity(line.len());
    for &b in line {
        if b == b'\\' {
            text.push_str("\\\\");
        } else if b == b' ' || b.is_ascii_graphic() {
            text.push(char::from(b));
        } else {
            let _ = write!(text, "\\x{b:02x}");
        }
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A radio in command mode played over an in-memory pipe: answers `+++` with `OK`
    /// after data from the air, `ATAP` with `0`, `ATAP1` with `OK`, anything else with
    /// `ERROR`.
    async fn radio(mut io: tokio::io::DuplexStream) {
        let mut seen = Vec::new();
        let mut buf = [0u8; 64];
        loop {
            let n = match io.read(&mut buf).await {
                Ok(0) | Err(_) => return,
                Ok(n) => n,
            };
            seen.extend_from_slice(&buf[..n]);
            if seen == b"+++" {
                io.write_all(b"air data\rmore airOK\r").await.unwrap();
                seen.clear();
            }
            while let Some(end) = seen.iter().position(|&b| b == b'\r') {
                let line: Vec<u8> = seen.drain(..=end).collect();
                let answer: &[u8] = match &line[..end] {
                    b"ATAP" => b"0\r",
                    // What noise or a hostile bridge may write: a terminal's escape
                    // sequences (set the window title, clear the screen).
                    b"ATNI" => b"\x1b]0;owned\x07\x1b[2J MAV \xc3\xa9 \\x1b\r",
                    b"ATAP1" | b"ATCN" => b"OK\r\n",
                    _ => b"ERROR\r",
                };
                io.write_all(answer).await.unwrap();
            }
        }
    }

    #[tokio::test]
    async fn reads_sets_refuses_and_leaves() {
        let (host, radio_side) = tokio::io::duplex(256);
        tokio::spawn(radio(radio_side));
        let guard = Duration::from_millis(10);
        let mut mode = CommandMode::enter(host, guard, Duration::from_secs(5))
            .await
            .unwrap();
        assert_eq!(mode.read(*b"AP").await.unwrap(), "0");
        mode.set(*b"AP", "1").await.unwrap();
        let refused = mode.set(*b"BD", "9").await.unwrap_err();
        assert_eq!(
            refused.to_string(),
            "command mode: the radio answered ATBD9 with \"ERROR\""
        );
        // A value that would end the command early is not sent: the radio would run
        // what follows the comma as a command of its own.
        for value in ["MAV,WR", "MAV\rATWR"] {
            assert!(matches!(
                mode.set(*b"NI", value).await,
                Err(CommandModeError::InvalidValue { .. })
            ));
        }
        // The exchange goes on as before.
        assert_eq!(mode.read(*b"AP").await.unwrap(), "0");
        // A parameter the radio does not know: refused, not a value of "ERROR".
        let unknown = mode.read(*b"ZZ").await.unwrap_err();
        assert_eq!(
            unknown.to_string(),
            "command mode: the radio answered ATZZ with \"ERROR\""
        );
        // An answer is safe to print, whatever bytes came.
        assert_eq!(
            mode.read(*b"NI").await.unwrap(),
            r"\x1b]0;owned\x07\x1b[2J MAV \xc3\xa9 \\x1b"
        );
        mode.exit().await.unwrap();
    }

    #[tokio::test(start_paused = true)]
    async fn a_radio_that_does_not_answer_plus_plus_plus_says_so() {
        let (host, _silent) = tokio::io::duplex(256);
        let error = CommandMode::enter(host, Duration::from_secs(1), Duration::from_secs(2))
            .await
            .unwrap_err();
        assert_eq!(
            error.to_string(),
            "command mode: no answer to +++ within 3 s"
        );
    }
}
