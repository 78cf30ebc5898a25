//! The baseline of `rx_path`: the same start-up, UART0 interrupt and idle loop, but the
//! received bytes are only counted, with no decoder and no parser.
#![no_std]
#![no_main]

use core::sync::atomic::{AtomicU32, Ordering};

use cortex_m_rt::entry;
use lm3s6965::interrupt;
use mav_firmware::{app, hw};
use panic_halt as _;

static BYTES: AtomicU32 = AtomicU32::new(0);

#[entry]
fn main() -> ! {
    hw::init_clock();
    hw::init_uart0();
    let mut seen = 0;
    loop {
        seen = core::hint::black_box(BYTES.load(Ordering::Relaxed).max(seen));
        app::wait_for(|_| BYTES.load(Ordering::Relaxed) == seen);
    }
}

#[interrupt]
fn UART0() {
    critical_section::with(|_| {
        while let Some(byte) = hw::uart0_read() {
            if byte.is_ok() {
                BYTES.fetch_add(1, Ordering::Relaxed);
            }
        }
    });
}
