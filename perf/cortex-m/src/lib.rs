//! The host benchmarks' measured loops (`perf::run`) on a Cortex-M3: QEMU's model of
//! the LM3S6965 runs one binary a case and counts the instructions it executes
//! (`count.sh`). Each binary decodes its stream (the host benchmarks' seeded stream, a
//! smaller piece of it, in flash), checks what it found against what the generator put
//! in, and ends QEMU through semihosting: with status 0 if the totals match.
//! `base` does nothing but start and stop, so a case less `base` is the measured loop.
#![no_std]

use perf::Totals;
use xbee_api::ApiMode;

pub use cortex_m_rt;
pub use perf::run;

include!(concat!(env!("OUT_DIR"), "/totals.rs"));

/// The API mode 1 stream.
pub static STREAM1: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/stream1.bin"));
/// The API mode 2 stream.
pub static STREAM2: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/stream2.bin"));

/// Chunks of the `fifo` cases: a UART FIFO's worth.
pub const CHUNK: usize = 16;

/// The stream of `mode` and the frames and values in it.
pub fn stream(mode: ApiMode) -> (&'static [u8], (usize, usize)) {
    match mode {
        ApiMode::Unescaped => (STREAM1, TOTALS1),
        ApiMode::Escaped => (STREAM2, TOTALS2),
    }
}

/// Ends the run: QEMU exits with 0 if `found` has the frames of `mode`'s stream.
pub fn finish(mode: ApiMode, found: Totals) -> ! {
    let (_, (frames, _)) = stream(mode);
    let status = if found.frames == frames {
        cortex_m_semihosting::debug::EXIT_SUCCESS
    } else {
        cortex_m_semihosting::debug::EXIT_FAILURE
    };
    cortex_m_semihosting::debug::exit(status);
    // Only reached where semihosting is off.
    loop {
        cortex_m::asm::wfi();
    }
}

/// The `main` of a case binary: `case!(run_push, Escaped)` runs
/// `perf::run::run_push` over the mode 2 stream (extra arguments follow the mode).
#[macro_export]
macro_rules! case {
    ($run:ident, $mode:ident $(, $arg:expr)*) => {
        use lm3s6965 as _;
        use panic_halt as _;

        #[$crate::cortex_m_rt::entry]
        fn main() -> ! {
            let mode = xbee_api::ApiMode::$mode;
            let (bytes, _) = $crate::stream(mode);
            $crate::finish(mode, $crate::run::$run(bytes, mode $(, $arg)*))
        }
    };
}
