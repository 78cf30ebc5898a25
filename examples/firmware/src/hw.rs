//! Register access to the LM3S6965: system clock, UART0, SysTick and the NVIC.
//!
//! The one module with `unsafe`: volatile reads and writes of memory-mapped registers
//! at their datasheet addresses, and unmasking the UART0 interrupt. Everything else in
//! the firmware goes through the safe functions here.
#![allow(unsafe_code)]

use cortex_m::peripheral::{NVIC, SYST, syst::SystClkSource};
use lm3s6965::Interrupt;

/// System clock after [`init_clock`]: 50 MHz (PLL 200 MHz / 4).
pub const SYSCLK_HZ: u32 = 50_000_000;

/// UART0 baud rate: the XBee's 115200 8N1.
pub const BAUD: u32 = 115_200;

/// A 32-bit memory-mapped register.
#[derive(Debug, Clone, Copy)]
struct Reg(usize);

impl Reg {
    fn read(self) -> u32 {
        // SAFETY: every `Reg` below is a documented, aligned LM3S6965 register
        // address, always mapped; volatile access is how registers are read.
        unsafe { core::ptr::read_volatile(self.0 as *const u32) }
    }

    fn write(self, value: u32) {
        // SAFETY: as in `read`; these registers have no memory-safety side effects.
        unsafe { core::ptr::write_volatile(self.0 as *mut u32, value) }
    }

    fn modify(self, f: impl FnOnce(u32) -> u32) {
        self.write(f(self.read()));
    }
}

/// System control (datasheet section 6).
mod sysctl {
    use super::Reg;
    const BASE: usize = 0x400F_E000;
    /// Raw interrupt status.
    pub(super) const RIS: Reg = Reg(BASE + 0x050);
    /// Masked interrupt status and clear.
    pub(super) const MISC: Reg = Reg(BASE + 0x058);
    /// Run-mode clock configuration.
    pub(super) const RCC: Reg = Reg(BASE + 0x060);
    /// Run-mode clock gating 1 (UART0 is bit 0).
    pub(super) const RCGC1: Reg = Reg(BASE + 0x104);
    /// Run-mode clock gating 2 (GPIO port A is bit 0).
    pub(super) const RCGC2: Reg = Reg(BASE + 0x108);

    /// RIS/MISC: PLL lock.
    pub(super) const PLLL: u32 = 1 << 6;
    /// RCC fields.
    pub(super) const MOSCDIS: u32 = 1 << 0;
    pub(super) const OSCSRC_MASK: u32 = 0b11 << 4;
    pub(super) const XTAL_MASK: u32 = 0xF << 6;
    /// The evaluation board's 8 MHz crystal.
    pub(super) const XTAL_8MHZ: u32 = 0xE << 6;
    pub(super) const BYPASS: u32 = 1 << 11;
    pub(super) const OE: u32 = 1 << 12;
    pub(super) const PWRDN: u32 = 1 << 13;
    pub(super) const USESYSDIV: u32 = 1 << 22;
    pub(super) const SYSDIV_MASK: u32 = 0xF << 23;
    /// Divide the 200 MHz PLL output by 4: 50 MHz.
    pub(super) const SYSDIV_4: u32 = 3 << 23;
}

/// GPIO port A: PA0/PA1 are U0Rx/U0Tx.
mod gpioa {
    use super::Reg;
    const BASE: usize = 0x4000_4000;
    pub(super) const AFSEL: Reg = Reg(BASE + 0x420);
    pub(super) const DEN: Reg = Reg(BASE + 0x51C);
    pub(super) const UART_PINS: u32 = 0b11;
}

/// UART0, an ARM PL011.
mod uart0 {
    use super::Reg;
    const BASE: usize = 0x4000_C000;
    pub(super) const DR: Reg = Reg(BASE);
    pub(super) const FR: Reg = Reg(BASE + 0x018);
    pub(super) const IBRD: Reg = Reg(BASE + 0x024);
    pub(super) const FBRD: Reg = Reg(BASE + 0x028);
    pub(super) const LCRH: Reg = Reg(BASE + 0x02C);
    pub(super) const CTL: Reg = Reg(BASE + 0x030);
    pub(super) const IFLS: Reg = Reg(BASE + 0x034);
    pub(super) const IM: Reg = Reg(BASE + 0x038);
    pub(super) const ICR: Reg = Reg(BASE + 0x044);

    /// FR: receive FIFO empty.
    pub(super) const RXFE: u32 = 1 << 4;
    /// FR: transmit FIFO full.
    pub(super) const TXFF: u32 = 1 << 5;
    /// DR: framing, parity, break and overrun error bits.
    pub(super) const DR_ERRORS: u32 = 0xF << 8;
    /// LCRH: 8 data bits, FIFOs on (1 stop bit, no parity).
    pub(super) const LCRH_8N1_FIFO: u32 = (0b11 << 5) | (1 << 4);
    /// CTL: UART, transmitter and receiver enable.
    pub(super) const CTL_ENABLE: u32 = (1 << 0) | (1 << 8) | (1 << 9);
    /// IFLS: interrupt at RX FIFO 1/2 full (QEMU interrupts on any byte).
    pub(super) const IFLS_RX_HALF: u32 = 0b010 << 3;
    /// IM/ICR: receive and receive-timeout interrupts.
    pub(super) const RX_INTERRUPTS: u32 = (1 << 4) | (1 << 6);
}

/// Runs the system clock from the PLL at [`SYSCLK_HZ`], the evaluation board's
/// 8 MHz crystal as reference (what StellarisWare's `SysCtlClockSet` does).
pub fn init_clock() {
    use sysctl::*;
    // Run from the raw oscillator while changing the PLL.
    let mut rcc = RCC.read();
    rcc = (rcc | BYPASS) & !USESYSDIV;
    RCC.write(rcc);
    // Main oscillator, 8 MHz crystal, PLL powered with its output enabled.
    rcc &= !(MOSCDIS | OSCSRC_MASK | XTAL_MASK | PWRDN | OE);
    rcc |= XTAL_8MHZ;
    MISC.write(PLLL);
    RCC.write(rcc);
    rcc = (rcc & !SYSDIV_MASK) | SYSDIV_4 | USESYSDIV;
    RCC.write(rcc);
    // Wait for the lock, bounded: the datasheet gives at most 0.5 ms.
    let mut spins = 0u32;
    while RIS.read() & PLLL == 0 && spins < 100_000 {
        spins += 1;
    }
    RCC.write(rcc & !BYPASS);
}

/// Sets UART0 up for the XBee: 115200 8N1 with FIFOs, receive interrupts on, and
/// unmasks its interrupt in the NVIC. The `UART0` handler must be defined.
pub fn init_uart0() {
    sysctl::RCGC1.modify(|v| v | 1);
    sysctl::RCGC2.modify(|v| v | 1);
    gpioa::AFSEL.modify(|v| v | gpioa::UART_PINS);
    gpioa::DEN.modify(|v| v | gpioa::UART_PINS);

    use uart0::*;
    CTL.write(0);
    // Divisor = SYSCLK / (16 * BAUD), as 16.6 fixed point, rounded.
    let div64 = (SYSCLK_HZ * 4 + BAUD / 2) / BAUD;
    IBRD.write(div64 / 64);
    FBRD.write(div64 % 64);
    LCRH.write(LCRH_8N1_FIFO);
    IFLS.write(IFLS_RX_HALF);
    ICR.write(0x7FF);
    IM.write(RX_INTERRUPTS);
    CTL.write(CTL_ENABLE);
    // SAFETY: the UART0 handler only takes bytes through `uart0_read` and shares
    // state with the main loop through critical sections.
    unsafe { NVIC::unmask(Interrupt::UART0) };
}

/// A byte received with a framing, parity, break or overrun error.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RxError;

/// Takes the next received byte from the RX FIFO; `None` when it is empty.
///
/// The receive interrupts clear themselves as the FIFO is read (receive: below the
/// trigger level; receive timeout: empty), so an interrupt handler that stops before
/// the FIFO is empty leaves its interrupt pending, as it should. (Clearing it through
/// `UARTICR` then would lose the bytes left: no new edge comes while they wait.)
pub fn uart0_read() -> Option<Result<u8, RxError>> {
    if uart0::FR.read() & uart0::RXFE != 0 {
        return None;
    }
    let dr = uart0::DR.read();
    Some(if dr & uart0::DR_ERRORS != 0 {
        Err(RxError)
    } else {
        Ok(dr as u8)
    })
}

/// Turns the UART0 receive interrupts on or off. While they are off, received bytes
/// wait in the RX FIFO; turning them on with bytes waiting raises the interrupt.
pub fn uart0_rx_interrupts(on: bool) {
    uart0::IM.write(if on { uart0::RX_INTERRUPTS } else { 0 });
}

/// Raises the UART0 interrupt without a new byte (for work left to its handler).
pub fn uart0_pend() {
    NVIC::pend(Interrupt::UART0);
}

/// Writes a byte to UART0, waiting for room in the TX FIFO.
pub fn uart0_write_byte(b: u8) {
    while uart0::FR.read() & uart0::TXFF != 0 {}
    uart0::DR.write(u32::from(b));
}

/// Starts SysTick from the system clock, interrupting `hz` times a second.
pub fn init_systick(syst: &mut SYST, hz: u32) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(SYSCLK_HZ / hz - 1);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}
