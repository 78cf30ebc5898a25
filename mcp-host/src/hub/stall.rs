//! The hub's own stalls: times it could read nothing (the process stopped, by `SIGSTOP`,
//! Ctrl-Z or a debugger; its runtime starved), during which clients' requests may have
//! come and waited unread. They are seen on the monotonic clock, which a system clock
//! set (a time server's step) does not move; a machine suspended stops it too (on
//! Linux), and the clients on that machine with it. A request's [`REQUEST_WAIT`](super::REQUEST_WAIT)
//! counts from when the hub could first have read it; after a stall that is any time
//! since the stall began, as far as the hub can tell, so a request read just after one
//! counts from its beginning. Without this, the commands of clients that gave up
//! during a stall (their `send` timed out and exited) reached the MAVs once the hub
//! went on, after newer commands of other clients.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use tokio::time::Instant;
use tokio_util::sync::CancellationToken;

use crate::mutex::lock;

/// How often the hub notes that it runs.
const BEAT: Duration = Duration::from_millis(250);

/// A time without a beat that is a stall: far longer than [`BEAT`], so that a busy
/// runtime's late beat is not one.
const STALL: Duration = Duration::from_secs(2);

/// How long after a stall was seen the requests read count from its beginning: those
/// the hub reads as it goes on, which may have waited unread through it.
const AFTER_STALL: Duration = Duration::from_secs(1);

/// When the hub last ran, and its last stall.
#[derive(Debug)]
pub(super) struct Stalls {
    state: Mutex<State>,
}

#[derive(Debug)]
struct State {
    /// The last beat.
    beat: Instant,
    /// The last stall: when it began, and when it was seen to end.
    last: Option<(Instant, Instant)>,
}

impl Stalls {
    pub(super) fn new() -> Self {
        Stalls {
            state: Mutex::new(State {
                beat: Instant::now(),
                last: None,
            }),
        }
    }

    /// Notes that the hub runs now, and returns since when a request it reads now may
    /// have waited unread: the beginning of a stall seen [`AFTER_STALL`] ago at most,
    /// else `None`. Called by the hub's beat, every [`BEAT`], and for each request read,
    /// as the task reading it may run before the beat after a stall.
    pub(super) fn beat(&self) -> Option<Instant> {
        let now = Instant::now();
        let mut state = lock(&self.state);
        let then = state.beat;
        let gap = now.saturating_duration_since(then);
        if gap > STALL {
            tracing::warn!(
                "hub: it could read nothing for {}: requests read as it goes on count from \
                 the start of that, and those that waited too long are refused",
                crate::render::Seconds::measured(gap)
            );
            state.last = Some((then, now));
        }
        state.beat = now;
        let (began, seen) = state.last?;
        (now.saturating_duration_since(seen) <= AFTER_STALL).then_some(began)
    }
}

/// Notes every [`BEAT`] that the hub runs, so that its stalls are seen (see
/// [`Stalls`]), until the hub stops.
pub(super) async fn beat(stalls: Arc<Stalls>, stop: CancellationToken) {
    let mut beat = tokio::time::interval(BEAT);
    beat.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    loop {
        tokio::select! {
            () = stop.cancelled() => return,
            _ = beat.tick() => {
                stalls.beat();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test(start_paused = true)]
    async fn a_stall_counts_for_the_requests_read_just_after_it() {
        let stalls = Stalls::new();
        let start = Instant::now();
        tokio::time::advance(BEAT).await;
        assert_eq!(stalls.beat(), None, "a beat on time");
        tokio::time::advance(STALL + BEAT).await;
        // Seen by the first to look, and by those that look just after it.
        assert_eq!(stalls.beat(), Some(start + BEAT));
        tokio::time::advance(AFTER_STALL / 2).await;
        assert_eq!(stalls.beat(), Some(start + BEAT));
        tokio::time::advance(AFTER_STALL).await;
        assert_eq!(stalls.beat(), None, "long after it");
    }
}
