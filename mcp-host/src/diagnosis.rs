//! What a link's counters say may be wrong with the radio's settings: [`Stats::diagnose`].
//!
//! A radio in the other API mode, at another baud rate or in transparent mode sends
//! bytes that fail to decode in ways of their own, and nothing else tells: frames
//! are dropped, answers never come. The link logs a warning (target
//! `mcp_host::diagnosis`) once a connection when its counters show the signs (looked
//! at when a frame fails to decode and when a request times out), and a program can
//! ask at any time.

use std::fmt;

use xbee_api::ApiMode;

use crate::stats::Stats;

/// The failed frames it takes for [`Stats::diagnose_running`].
const RUNNING_FAILURES: u64 = 5;

/// The bytes that begin no frame it takes for [`Stats::diagnose`], when no frame came.
const SHORT_BYTES: u64 = 2;

/// The bytes that begin no frame it takes for [`Stats::diagnose_running`], when no
/// frame came: a few are noise on a line, a port opened in the middle of a frame.
const RUNNING_BYTES: u64 = 80;

/// What a link's counters say may be wrong with the radio's settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Diagnosis {
    /// Frames failed their checksum (or, in API mode 2, held a bad escape): the radio
    /// may be in the other API mode. A frame with no byte to escape reads the same in
    /// both, so some may pass.
    #[non_exhaustive]
    OtherApiMode {
        /// Frames that failed.
        failed: u64,
        /// Frames that passed.
        passed: u64,
        /// The mode the radio may be in.
        radio: ApiMode,
    },
    /// Bytes came and none began a frame: the radio may be in transparent mode
    /// (`AP=0`), or at another baud rate.
    #[non_exhaustive]
    NoFrames {
        /// Bytes skipped.
        bytes: u64,
    },
    /// Only frames of impossible lengths (too long, empty, cut off) and bytes that were
    /// no frames: the link's baud rate may differ from the radio's, or the radio may be
    /// in transparent mode.
    #[non_exhaustive]
    ImpossibleFrames {
        /// Frames dropped for their length.
        frames: u64,
        /// Bytes skipped.
        bytes: u64,
    },
    /// Most frames that came were of the types this side writes (requests, which a
    /// radio never sends, [`Stats::echoed`]): the port hands back what is written to it
    /// (a loopback, a cable or adapter with its data lines joined, a terminal's echo),
    /// and no radio answers there.
    #[non_exhaustive]
    Echo {
        /// Frames of request types that came.
        frames: u64,
    },
}

impl Stats {
    /// What these counters say may be wrong with the settings of a radio read in
    /// `mode`, if anything, taking any sign as one (two bytes that begin no frame, with
    /// no frame at all, among them): for the counters of a short
    /// exchange that went unanswered ([`since`](Stats::since) gives those).
    ///
    /// The counters see only what comes from the radio. A radio in the other API mode
    /// that says nothing meanwhile leaves no sign here, although it drops the frames
    /// sent to it that have a byte to escape: then the sign is a request it never
    /// answered itself, [`SendError::Timeout`](crate::SendError::Timeout) (no transmit
    /// status or response) or [`RequestError::Timeout`](crate::RequestError::Timeout)
    /// with `delivered` false, which `mcp-gs` turns into its hint to check the mode.
    ///
    /// ```
    /// use mcp_host::{Diagnosis, Stats};
    /// use mcp_host::xbee_api::ApiMode;
    ///
    /// // What came while a request waited for its answer, which never came.
    /// let stats = Stats { frames: 3, bad_checksum: 1, ..Stats::default() };
    /// assert!(matches!(
    ///     stats.diagnose(ApiMode::Unescaped),
    ///     Some(Diagnosis::OtherApiMode { failed: 1, passed: 3, radio: ApiMode::Escaped, .. })
    /// ));
    /// ```
    pub fn diagnose(&self, mode: ApiMode) -> Option<Diagnosis> {
        // In a short exchange a radio at another baud rate sends few bytes (an AT
        // answer at 9600 read at 115200: six), and a request went unanswered where the
        // local radio always answers: a few bytes and no frame are a sign (one alone
        // may be a glitch as the port opened).
        self.diagnose_with(mode, 1, SHORT_BYTES, false)
    }

    /// What these counters say may be wrong, for the counters of a link over a long
    /// time: it takes 5 failed frames, and more failed than good ones (a frame with no
    /// byte to escape passes in either mode, and a line may corrupt a few), or 80
    /// skipped bytes and no frame. The link's own warning reads its counters so.
    ///
    /// ```
    /// use mcp_host::{Diagnosis, Stats};
    /// use mcp_host::xbee_api::ApiMode;
    ///
    /// let stats = Stats { frames: 2, bad_checksum: 6, ..Stats::default() };
    /// assert!(matches!(
    ///     stats.diagnose_running(ApiMode::Unescaped),
    ///     Some(Diagnosis::OtherApiMode { failed: 6, passed: 2, radio: ApiMode::Escaped, .. })
    /// ));
    /// // Most frames pass: a few failures are noise on the line.
    /// let stats = Stats { frames: 100, bad_checksum: 6, ..Stats::default() };
    /// assert_eq!(stats.diagnose_running(ApiMode::Unescaped), None);
    /// ```
    pub fn diagnose_running(&self, mode: ApiMode) -> Option<Diagnosis> {
        self.diagnose_with(mode, RUNNING_FAILURES, RUNNING_BYTES, true)
    }

    /// [`diagnose`](Self::diagnose) with `min_failed` failed frames (or `min_bytes`
    /// skipped bytes and no frame), and with `majority` more failed frames than good
    /// ones.
    fn diagnose_with(
        &self,
        mode: ApiMode,
        min_failed: u64,
        min_bytes: u64,
        majority: bool,
    ) -> Option<Diagnosis> {
        // Echoes pass their checksum: looked at first.
        if self.echoed >= min_failed && self.echoed.saturating_mul(2) > self.frames {
            return Some(Diagnosis::Echo {
                frames: self.echoed,
            });
        }
        let failed = self.bad_checksum + self.bad_escape;
        if failed >= min_failed && (!majority || failed > self.frames) {
            return Some(Diagnosis::OtherApiMode {
                failed,
                passed: self.frames,
                radio: mode.other(),
            });
        }
        let impossible = self.oversize + self.empty + self.truncated;
        if self.frames == 0
            && impossible == 0
            && failed == 0
            && self.bytes_skipped >= min_bytes.max(1)
        {
            return Some(Diagnosis::NoFrames {
                bytes: self.bytes_skipped,
            });
        }
        if impossible >= min_failed && self.frames == 0 {
            return Some(Diagnosis::ImpossibleFrames {
                frames: impossible,
                bytes: self.bytes_skipped,
            });
        }
        None
    }
}

/// Good frames after which [`Diagnoser::look`] forgets what it counted before: a radio
/// whose settings change while the link is up is then not outvoted by the frames that
/// passed before.
const WINDOW_FRAMES: u64 = 64;

/// Reads a link's counters as they grow ([`Stats::diagnose_running`] on what was
/// counted since it started, or since its last 64 good frames), so that a radio whose
/// settings change while the link is up (`AP` set through a hub, say) is told too: the
/// frames that passed before do not outvote the ones failing now.
///
/// ```
/// use mcp_host::{Diagnoser, Diagnosis, Stats};
/// use mcp_host::xbee_api::ApiMode;
///
/// let start = Stats { frames: 10_000, ..Stats::default() };
/// let mut diagnoser = Diagnoser::new(ApiMode::Unescaped, start);
/// // Someone sets the radio to API mode 2: the first frame fails.
/// let now = Stats { frames: 10_100, bad_checksum: 1, ..Stats::default() };
/// assert_eq!(diagnoser.look(now), None);
/// // Most frames fail from then on.
/// let now = Stats { frames: 10_102, bad_checksum: 7, ..Stats::default() };
/// assert!(matches!(diagnoser.look(now), Some(Diagnosis::OtherApiMode { .. })));
/// // Read over the whole run, the good frames before outvote them.
/// assert_eq!(now.diagnose_running(ApiMode::Unescaped), None);
/// ```
#[derive(Debug, Clone)]
pub struct Diagnoser {
    mode: ApiMode,
    since: Stats,
}

impl Diagnoser {
    /// Reads the counters of a link in `mode` from `now` on.
    pub fn new(mode: ApiMode, now: Stats) -> Self {
        Diagnoser { mode, since: now }
    }

    /// What the counters counted since the start, or since the last window of good
    /// frames, say may be wrong; `now`: the link's counters now.
    pub fn look(&mut self, now: Stats) -> Option<Diagnosis> {
        let counted = now.since(&self.since);
        let found = counted.diagnose_running(self.mode);
        if found.is_none() && counted.frames >= WINDOW_FRAMES {
            self.since = now;
        }
        found
    }
}

/// `n noun`, with an `s` unless `n` is 1.
pub(crate) fn counted(n: u64, noun: &str) -> String {
    match n {
        1 => format!("1 {noun}"),
        n => format!("{n} {noun}s"),
    }
}

/// One sentence, for a log line or an error's hint.
///
/// ```
/// use mcp_host::Stats;
/// use mcp_host::xbee_api::ApiMode;
///
/// let stats = Stats { frames: 2, bad_checksum: 6, ..Stats::default() };
/// let diagnosis = stats.diagnose(ApiMode::Unescaped).unwrap();
/// assert_eq!(
///     diagnosis.to_string(),
///     "6 frames failed the checksum and 2 passed: the radio may be in API mode 2 (AP=2)"
/// );
/// // No more failed than passed: a line that corrupts a frame now and then reads so too.
/// let stats = Stats { frames: 1, bad_checksum: 1, ..Stats::default() };
/// assert_eq!(
///     stats.diagnose(ApiMode::Unescaped).unwrap().to_string(),
///     "1 frame failed the checksum and 1 passed: the radio may be in API mode 2 (AP=2), \
///      or the line corrupted it"
/// );
/// // Read in API mode 2, frames of mode 1 fail on escapes too.
/// let stats = Stats { frames: 2, bad_escape: 100, ..Stats::default() };
/// assert_eq!(
///     stats.diagnose(ApiMode::Escaped).unwrap().to_string(),
///     "100 frames failed their checksum or escapes and 2 passed: the radio may be in API \
///      mode 1 (AP=1)"
/// );
/// ```
impl fmt::Display for Diagnosis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Diagnosis::OtherApiMode {
                failed,
                passed,
                radio,
            } => {
                // Read in mode 2 (the radio in mode 1), a frame fails on an escape too.
                let failed_on = match radio {
                    ApiMode::Unescaped => "their checksum or escapes",
                    ApiMode::Escaped => "the checksum",
                };
                let radio = u8::from(radio);
                write!(
                    f,
                    "{} failed {failed_on} and {passed} passed: the radio may be in API \
                     mode {radio} (AP={radio})",
                    counted(failed, "frame")
                )?;
                // As many good frames as bad: noise on the line reads the same.
                match failed {
                    _ if failed > passed => Ok(()),
                    1 => f.write_str(", or the line corrupted it"),
                    _ => f.write_str(", or the line corrupted them"),
                }
            }
            Diagnosis::NoFrames { bytes } => write!(
                f,
                "{} came from the radio and none began a frame: the radio may be in \
                 transparent mode (AP=0), or the link's baud rate may differ from the \
                 radio's",
                counted(bytes, "byte")
            ),
            Diagnosis::ImpossibleFrames { frames, bytes } => write!(
                f,
                "{} of impossible length, {} that were no frames, and no good frame: the \
                 link's baud rate may differ from the radio's, or the radio may be in \
                 transparent mode (AP=0)",
                counted(frames, "frame"),
                counted(bytes, "byte")
            ),
            Diagnosis::Echo { frames } => write!(
                f,
                "{} came back of the types written to the radio (requests, which no radio \
                 sends): the port hands back what is written to it (a loopback, an adapter \
                 with its data lines joined, a terminal's echo), and no radio answers there",
                counted(frames, "frame")
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_of_the_types_written_coming_back_are_an_echo() {
        let mode = ApiMode::Unescaped;
        // The request sent, handed back: one is a sign in a short exchange.
        let echo = Stats {
            frames: 1,
            echoed: 1,
            ..Stats::default()
        };
        assert_eq!(echo.diagnose(mode), Some(Diagnosis::Echo { frames: 1 }));
        assert_eq!(echo.diagnose_running(mode), None);
        assert_eq!(
            Diagnosis::Echo { frames: 1 }.to_string(),
            "1 frame came back of the types written to the radio (requests, which no radio \
             sends): the port hands back what is written to it (a loopback, an adapter with \
             its data lines joined, a terminal's echo), and no radio answers there"
        );
        // Over a long time, 5 and most frames.
        let running = Stats {
            frames: 9,
            echoed: 5,
            ..Stats::default()
        };
        assert_eq!(
            running.diagnose_running(mode),
            Some(Diagnosis::Echo { frames: 5 })
        );
        // A radio's own frames outnumber them: not an echo.
        let radio = Stats {
            frames: 10,
            echoed: 5,
            ..Stats::default()
        };
        assert_eq!(radio.diagnose_running(mode), None);
    }

    #[test]
    fn each_sign_is_read_as_its_cause() {
        let mode = ApiMode::Escaped;
        let checksums = Stats {
            bad_checksum: 1,
            ..Stats::default()
        };
        assert_eq!(
            checksums.diagnose(mode),
            Some(Diagnosis::OtherApiMode {
                failed: 1,
                passed: 0,
                radio: ApiMode::Unescaped
            })
        );
        // Over a long time it takes 5 of them, and most frames failing.
        assert_eq!(checksums.diagnose_running(mode), None);
        let skipped = Stats {
            bytes_skipped: 80,
            ..Stats::default()
        };
        assert_eq!(
            skipped.diagnose_running(mode),
            Some(Diagnosis::NoFrames { bytes: 80 })
        );
        let fewer = Stats {
            bytes_skipped: 79,
            ..skipped
        };
        assert_eq!(fewer.diagnose_running(mode), None);
        assert!(fewer.diagnose(mode).is_some());
        // In a short exchange two bytes and no frame are a sign; one may be a glitch.
        let two = Stats {
            bytes_skipped: 2,
            ..Stats::default()
        };
        assert_eq!(two.diagnose(mode), Some(Diagnosis::NoFrames { bytes: 2 }));
        assert_eq!(two.diagnose_running(mode), None);
        let one = Stats {
            bytes_skipped: 1,
            ..two
        };
        assert_eq!(one.diagnose(mode), None);
        let lengths = Stats {
            oversize: 3,
            truncated: 2,
            bytes_skipped: 7,
            ..Stats::default()
        };
        assert_eq!(
            lengths.diagnose_running(mode),
            Some(Diagnosis::ImpossibleFrames {
                frames: 5,
                bytes: 7
            })
        );
        // A good frame says the rate and mode are right.
        let good = Stats {
            frames: 1,
            ..lengths
        };
        assert_eq!(good.diagnose(mode), None);
        assert_eq!(Stats::default().diagnose(mode), None);
    }
}
