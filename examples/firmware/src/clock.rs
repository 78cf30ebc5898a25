//! The SysTick time base: ticks at [`TICK_HZ`], counted by the SysTick exception.

use core::sync::atomic::{AtomicU32, Ordering};

/// SysTick rate: the 20 Hz telemetry and flight model step.
pub const TICK_HZ: u32 = 20;

static TICKS: AtomicU32 = AtomicU32::new(0);

/// The SysTick exception: one more tick.
pub fn on_systick() {
    TICKS.fetch_add(1, Ordering::Relaxed);
}

/// Ticks since start-up (wrapping).
pub fn ticks() -> u32 {
    TICKS.load(Ordering::Relaxed)
}
