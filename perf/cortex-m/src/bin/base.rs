//! Start-up and exit alone, to take off the other cases.
#![no_std]
#![no_main]

use lm3s6965 as _;
use panic_halt as _;

#[perf_cortex_m::cortex_m_rt::entry]
fn main() -> ! {
    let mode = xbee_api::ApiMode::Escaped;
    let (_, (frames, _)) = perf_cortex_m::stream(mode);
    let nothing = perf::Totals {
        frames,
        ..Default::default()
    };
    perf_cortex_m::finish(mode, nothing)
}
