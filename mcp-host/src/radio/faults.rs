//! Faults injected on the way to a link: loss, latency, jitter, duplication, reordering
//! and corruption, drawn from a seeded ChaCha generator so that a run replays.

use std::time::Duration;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use xbee_api::Address64;

/// Faults applied to the frames the network writes to a link.
///
/// Probabilities are in `0.0..=1.0` (values outside are clamped). Every frame written
/// to the link after its connection's modem status is subject to them: receive packets,
/// transmit statuses and AT command responses alike.
///
/// ```
/// use mcp_host::radio::Faults;
/// let faults = Faults { loss: 0.1, ..Faults::default() };
/// assert!(!faults.is_none());
/// assert!(Faults::default().is_none());
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Faults {
    /// Probability that a frame is dropped.
    pub loss: f64,
    /// Fixed delay before a frame is written.
    pub latency: Duration,
    /// Extra delay, uniform in `0..=jitter`, added to the latency. Frames to one link
    /// stay in order (a UART does not reorder); see `reorder` for that.
    pub jitter: Duration,
    /// Probability that a frame is written twice.
    pub duplicate: f64,
    /// Probability that a frame is held back and written after the next frame to the
    /// same link (or after `reorder_window` if none comes).
    pub reorder: f64,
    /// How long a held-back frame waits for a next frame to overtake it
    /// ([`REORDER_WINDOW`] by default).
    pub reorder_window: Duration,
    /// Probability that one byte of the frame data is changed while the checksum is
    /// kept, so that the receiver's decoder reports a bad checksum.
    pub corrupt: f64,
}

/// How long a frame held back by [`Faults::reorder`] waits by default for a next frame
/// to overtake it.
pub const REORDER_WINDOW: Duration = Duration::from_millis(250);

impl Default for Faults {
    /// No faults.
    fn default() -> Self {
        Faults {
            loss: 0.0,
            latency: Duration::ZERO,
            jitter: Duration::ZERO,
            duplicate: 0.0,
            reorder: 0.0,
            reorder_window: REORDER_WINDOW,
            corrupt: 0.0,
        }
    }
}

impl Faults {
    /// `true` when no fault is configured.
    pub fn is_none(&self) -> bool {
        Faults {
            reorder_window: REORDER_WINDOW,
            ..*self
        } == Faults::default()
    }
}

/// What the faults decided for one frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Fate {
    /// Dropped.
    pub(crate) lost: bool,
    /// Delay before writing.
    pub(crate) delay: Duration,
    /// Written twice.
    pub(crate) duplicate: bool,
    /// Held back behind the next frame.
    pub(crate) reorder: bool,
    /// `Some((index, mask))`: XOR byte `index % len` of the frame data with `mask`.
    pub(crate) corrupt: Option<(usize, u8)>,
}

/// The per-link random source: seeded from the network seed and the link's address, so
/// that each link's faults replay whatever the other links do.
#[derive(Debug, Clone)]
pub(crate) struct FaultRng {
    rng: ChaCha8Rng,
}

impl FaultRng {
    pub(crate) fn new(seed: u64, address: Address64) -> Self {
        // SplitMix-style mixing so that neighbouring addresses get unrelated streams.
        let mut z = seed ^ address.0.wrapping_mul(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        FaultRng {
            rng: ChaCha8Rng::seed_from_u64(z),
        }
    }

    /// Decides the fate of one frame. Draws the same number of values whatever the
    /// faults, so a given seed gives the same decisions for the same traffic.
    pub(crate) fn decide(&mut self, faults: &Faults) -> Fate {
        let loss: f64 = self.rng.random();
        let jitter: f64 = self.rng.random();
        let duplicate: f64 = self.rng.random();
        let reorder: f64 = self.rng.random();
        let corrupt: f64 = self.rng.random();
        let index: usize = self.rng.random_range(0..usize::from(u16::MAX));
        let mask: u8 = self.rng.random_range(1..=u8::MAX);
        let jitter = faults.jitter.mul_f64(jitter);
        Fate {
            lost: hit(loss, faults.loss),
            delay: faults.latency.saturating_add(jitter),
            duplicate: hit(duplicate, faults.duplicate),
            reorder: hit(reorder, faults.reorder),
            corrupt: hit(corrupt, faults.corrupt).then_some((index, mask)),
        }
    }
}

/// `true` with probability `p` given a uniform draw in `0..1`: never for `p <= 0`,
/// always for `p >= 1`.
fn hit(draw: f64, p: f64) -> bool {
    draw < p.clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn certain_and_impossible_faults() {
        let mut rng = FaultRng::new(7, Address64(1));
        let all = Faults {
            loss: 1.0,
            duplicate: 1.0,
            reorder: 1.0,
            corrupt: 1.0,
            ..Faults::default()
        };
        for _ in 0..1000 {
            let fate = rng.decide(&all);
            assert!(fate.lost && fate.duplicate && fate.reorder);
            assert!(fate.corrupt.is_some_and(|(_, mask)| mask != 0));
            let none = rng.decide(&Faults::default());
            assert!(!none.lost && !none.duplicate && !none.reorder);
            assert_eq!(none.corrupt, None);
            assert_eq!(none.delay, Duration::ZERO);
        }
    }

    #[test]
    fn same_seed_same_decisions() {
        let faults = Faults {
            loss: 0.5,
            jitter: Duration::from_millis(10),
            corrupt: 0.3,
            ..Faults::default()
        };
        let run = |seed| {
            let mut rng = FaultRng::new(seed, Address64(0x0013_A200_40B5_99B9));
            (0..100).map(|_| rng.decide(&faults)).collect::<Vec<_>>()
        };
        assert_eq!(run(42), run(42));
        assert_ne!(run(42), run(43));
    }

    #[test]
    fn jitter_stays_within_bounds() {
        let faults = Faults {
            latency: Duration::from_millis(5),
            jitter: Duration::from_millis(10),
            ..Faults::default()
        };
        let mut rng = FaultRng::new(1, Address64(2));
        for _ in 0..1000 {
            let d = rng.decide(&faults).delay;
            assert!(d >= Duration::from_millis(5) && d <= Duration::from_millis(15));
        }
    }
}
