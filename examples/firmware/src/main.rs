//! The MAV firmware: see the library docs.
#![no_std]
#![no_main]

use cortex_m_rt::{entry, exception};
use lm3s6965::interrupt;
use panic_halt as _;

#[entry]
fn main() -> ! {
    mav_firmware::app::run()
}

#[interrupt]
fn UART0() {
    mav_firmware::rx::on_uart0_interrupt();
}

#[exception]
fn SysTick() {
    mav_firmware::clock::on_systick();
    // Here, not in the main loop: ticks the main loop catches up on come back to back,
    // and would give up a frame whose next byte is on its way.
    mav_firmware::rx::on_tick();
}
