//! The seeded generator behind every stream.

/// xorshift64*: a small seeded generator, so that every run measures the same bytes.
///
/// ```
/// let mut a = perf::Rng::new(7);
/// let mut b = perf::Rng::new(7);
/// assert_eq!(a.next_u64(), b.next_u64());
/// ```
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// The seed the streams use.
    pub const SEED: u64 = 0x005E_ED0F_CAFE;

    /// A generator from `seed` (0 is replaced by [`Rng::SEED`]: xorshift needs a
    /// non-zero state).
    pub const fn new(seed: u64) -> Self {
        Self(if seed == 0 { Self::SEED } else { seed })
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// A telemetry-like value from 64 random bits: within ±32768, 16 fractional bits.
    pub fn value(bits: u64) -> f32 {
        ((bits >> 16) as i32 as f32) / 65536.0
    }
}
