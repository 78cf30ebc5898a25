//! A duration shown as an operator writes it.

use std::fmt;
use std::time::Duration;

/// Shows a duration in seconds, exactly and without float noise: `3 s`, `0.25 s`,
/// `1.14 s`, `0.000001 s`; as an operator gives durations on a command line, where
/// Rust's `Debug` gives `3s`, `250ms` or `1µs`. Every error message of this crate shows
/// its durations so.
///
/// ```
/// use std::time::Duration;
/// use mcp_host::render::Seconds;
///
/// assert_eq!(Seconds(Duration::from_secs(3)).to_string(), "3 s");
/// assert_eq!(Seconds(Duration::from_millis(250)).to_string(), "0.25 s");
/// assert_eq!(Seconds(Duration::from_millis(1140)).to_string(), "1.14 s");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Seconds(pub Duration);

impl Seconds {
    /// A duration measured on a clock, shown to the millisecond (`7.105 s`, not
    /// `7.105894811 s`): finer is noise.
    pub(crate) fn measured(duration: Duration) -> Self {
        let millis = u64::try_from(duration.as_millis()).unwrap_or(u64::MAX);
        Seconds(Duration::from_millis(millis))
    }
}

impl fmt::Display for Seconds {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // From the whole seconds and the nanoseconds, not a float: 1.14 s, not
        // 1.1400000000000001 s.
        let (whole, nanos) = (self.0.as_secs(), self.0.subsec_nanos());
        let text = if nanos == 0 {
            format!("{whole} s")
        } else {
            let fraction = format!("{nanos:09}");
            format!("{whole}.{} s", fraction.trim_end_matches('0'))
        };
        // Width and alignment as for any text: `{:>8}`.
        f.pad(&text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_measured_duration_is_shown_to_the_millisecond() {
        let gap = Duration::from_nanos(7_105_894_811);
        assert_eq!(Seconds::measured(gap).to_string(), "7.105 s");
        assert_eq!(
            Seconds::measured(Duration::from_micros(999)).to_string(),
            "0 s"
        );
    }

    #[test]
    fn whole_fractional_and_tiny_durations_print_exactly() {
        for (duration, text) in [
            (Duration::ZERO, "0 s"),
            (Duration::from_secs(100), "100 s"),
            (Duration::from_millis(100_100), "100.1 s"),
            (Duration::from_micros(100_100), "0.1001 s"),
            (Duration::from_millis(1118), "1.118 s"),
            (Duration::from_nanos(1), "0.000000001 s"),
            (Duration::from_micros(1), "0.000001 s"),
            (Duration::from_secs_f64(0.1001), "0.1001 s"),
            (Duration::MAX, "18446744073709551615.999999999 s"),
        ] {
            assert_eq!(Seconds(duration).to_string(), text);
        }
        assert_eq!(
            format!("[{:>7}]", Seconds(Duration::from_secs(3))),
            "[    3 s]"
        );
    }
}
