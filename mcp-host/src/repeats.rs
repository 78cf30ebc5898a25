//! A warning a peer can make repeat without end (a client turned away, a frame dropped
//! for a device that reads nothing): said the first time, then counted and said at most
//! once every [`QUIET`], so that a flood of them makes a line a second, not thousands.

use std::time::Duration;

use tokio::time::Instant;

/// How often a repeated warning is said at most.
pub(crate) const QUIET: Duration = Duration::from_secs(1);

/// The times a warning came, and when it was last said.
#[derive(Debug, Default)]
pub(crate) struct Repeats {
    /// When it was last said.
    said: Option<Instant>,
    /// Times it came since, not said.
    unsaid: u64,
}

impl Repeats {
    /// Counts one at `now`: `Some(n)` to say it now, with the `n` not said before it,
    /// or `None` to stay quiet (it is counted, to be said later).
    pub(crate) fn count(&mut self, now: Instant) -> Option<u64> {
        match self.said {
            Some(said) if now.duration_since(said) < QUIET => {
                self.unsaid += 1;
                None
            }
            _ => {
                self.said = Some(now);
                Some(std::mem::take(&mut self.unsaid))
            }
        }
    }

    /// When those not said are due ([`QUIET`] after the last one said), if any are.
    pub(crate) fn due_at(&self) -> Option<Instant> {
        if self.unsaid == 0 {
            return None;
        }
        self.said.map(|said| said + QUIET)
    }

    /// Those not said, taken to be said, if they are due at `now` (they stopped
    /// coming: [`count`](Self::count) says the rest with the next one).
    pub(crate) fn take_due(&mut self, now: Instant) -> Option<u64> {
        if self.due_at()? > now {
            return None;
        }
        self.said = Some(now);
        Some(std::mem::take(&mut self.unsaid))
    }

    /// Those not said, taken to be said whatever the time (at the end), if any.
    pub(crate) fn take_rest(&mut self) -> Option<u64> {
        if self.unsaid == 0 {
            return None;
        }
        self.said = Some(Instant::now());
        Some(std::mem::take(&mut self.unsaid))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[tokio::test(start_paused = true)]
    async fn the_first_is_said_at_once_then_a_count_a_second() {
        let mut repeats = Repeats::default();
        assert_eq!(repeats.count(Instant::now()), Some(0));
        for _ in 0..1000 {
            assert_eq!(repeats.count(Instant::now()), None);
        }
        assert_eq!(repeats.take_due(Instant::now()), None);
        tokio::time::advance(QUIET).await;
        assert_eq!(repeats.count(Instant::now()), Some(1000));
        assert_eq!(repeats.count(Instant::now()), None);
        // They stop coming: the last ones are due a second after the last line.
        assert_eq!(repeats.due_at(), Some(Instant::now() + QUIET));
        tokio::time::advance(QUIET).await;
        assert_eq!(repeats.take_due(Instant::now()), Some(1));
        assert_eq!(repeats.take_rest(), None);
        repeats.count(Instant::now());
        assert_eq!(repeats.take_rest(), Some(1));
    }
}
