//! The receive path alone, to measure its footprint against `baseline`: the same
//! start-up and UART0 interrupt, plus the XBee decoder (with the tick that gives up a
//! stale frame), the Receive Packet view and the MCP parser. Parsed packets are only
//! counted.
#![no_std]
#![no_main]

use core::hint::black_box;

use cortex_m_rt::entry;
use lm3s6965::interrupt;
use mav_firmware::{app, hw, rx};
use panic_halt as _;

#[entry]
fn main() -> ! {
    hw::init_clock();
    hw::init_uart0();
    let mut counts = [0u32; 2];
    loop {
        while let Some(payload) = rx::take() {
            let valid = mcp_core::parse(payload.data()).is_ok();
            counts[usize::from(valid)] += 1;
            black_box(&counts);
        }
        // What a tick does on the receive path: give up a frame the line left stale.
        rx::on_tick();
        app::wait_for(|cs| !rx::is_pending(cs));
    }
}

#[interrupt]
fn UART0() {
    rx::on_uart0_interrupt();
}
