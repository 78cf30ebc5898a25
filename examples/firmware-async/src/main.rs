//! The async MAV firmware on the LM3S6965 (QEMU `lm3s6965evb`), API mode 1 on UART0.
//!
//! No HAL and no executor: UART0 behind `embedded_io_async` by polling its FIFOs (a
//! future that is pending while the FIFO is empty), SysTick's wrap flag as the 20 Hz
//! ticker, and `embassy_futures::block_on`, which polls the task in a loop. Its
//! futures wake themselves at once when they are pending: a busy loop, which a chip
//! with nothing else to do and no interrupt set up can afford; an Embassy driver
//! instead wakes its task from its interrupt, and the executor sleeps meanwhile. An
//! Embassy firmware swaps in its `BufferedUart` halves, `embassy_time::Ticker` and a
//! spawned task; the task itself ([`mav_firmware_async::run`]) is the same.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod target {
    use core::convert::Infallible;
    use core::future::poll_fn;
    use core::task::Poll;

    use cortex_m::peripheral::{SYST, syst::SystClkSource};
    use cortex_m_rt::entry;
    use embedded_io_async::{ErrorKind, ErrorType, Read, Write};
    use mav_firmware_async::model::{FlightModel, TICK_HZ};
    use mav_firmware_async::{MavCore, Reader, Ticker, run};
    use panic_halt as _;
    use xbee_api::Mode1;

    /// QEMU's system clock at reset (12 MHz internal oscillator / 1, as QEMU models it).
    const SYSCLK_HZ: u32 = 12_500_000;

    struct Reg(usize);
    impl Reg {
        fn read(&self) -> u32 {
            // SAFETY: a documented, aligned LM3S6965 register, always mapped.
            unsafe { core::ptr::read_volatile(self.0 as *const u32) }
        }
        fn write(&self, value: u32) {
            // SAFETY: as in `read`.
            unsafe { core::ptr::write_volatile(self.0 as *mut u32, value) }
        }
    }

    const UART0: usize = 0x4000_C000;
    const DR: Reg = Reg(UART0);
    const FR: Reg = Reg(UART0 + 0x018);
    const LCRH: Reg = Reg(UART0 + 0x02C);
    const CTL: Reg = Reg(UART0 + 0x030);
    const RCGC1: Reg = Reg(0x400F_E104);
    const FR_RXFE: u32 = 1 << 4;
    const FR_TXFF: u32 = 1 << 5;
    const FR_BUSY: u32 = 1 << 3;
    const DR_ERRORS: u32 = 0xF << 8;

    /// UART0's receive half; a byte received with an error flag (overrun, framing...)
    /// after others in the same read is reported at the next read, so that those
    /// before it are handed over.
    struct Rx {
        error: bool,
    }
    /// UART0's transmit half.
    struct Tx;

    impl ErrorType for Rx {
        type Error = ErrorKind;
    }
    impl ErrorType for Tx {
        type Error = Infallible;
    }

    impl Read for Rx {
        async fn read(&mut self, buf: &mut [u8]) -> Result<usize, ErrorKind> {
            poll_fn(|cx| {
                if core::mem::take(&mut self.error) {
                    return Poll::Ready(Err(ErrorKind::Other));
                }
                let mut n = 0;
                for slot in buf.iter_mut() {
                    if FR.read() & FR_RXFE != 0 {
                        break;
                    }
                    let dr = DR.read();
                    if dr & DR_ERRORS != 0 {
                        if n == 0 {
                            return Poll::Ready(Err(ErrorKind::Other));
                        }
                        self.error = true;
                        break;
                    }
                    *slot = dr as u8;
                    n += 1;
                }
                if n == 0 && !buf.is_empty() {
                    cx.waker().wake_by_ref();
                    Poll::Pending
                } else {
                    Poll::Ready(Ok(n))
                }
            })
            .await
        }
    }

    impl Write for Tx {
        async fn write(&mut self, buf: &[u8]) -> Result<usize, Infallible> {
            poll_fn(|cx| {
                let mut n = 0;
                for byte in buf {
                    if FR.read() & FR_TXFF != 0 {
                        break;
                    }
                    DR.write(u32::from(*byte));
                    n += 1;
                }
                if n == 0 && !buf.is_empty() {
                    cx.waker().wake_by_ref();
                    Poll::Pending
                } else {
                    Poll::Ready(Ok(n))
                }
            })
            .await
        }

        async fn flush(&mut self) -> Result<(), Infallible> {
            poll_fn(|cx| {
                if FR.read() & FR_BUSY != 0 {
                    cx.waker().wake_by_ref();
                    Poll::Pending
                } else {
                    Poll::Ready(Ok(()))
                }
            })
            .await
        }
    }

    /// SysTick at `TICK_HZ`, its wrap flag polled.
    struct SysTicker(SYST);

    impl Ticker for SysTicker {
        async fn next(&mut self) {
            poll_fn(|cx| {
                if self.0.has_wrapped() {
                    Poll::Ready(())
                } else {
                    cx.waker().wake_by_ref();
                    Poll::Pending
                }
            })
            .await
        }
    }

    #[entry]
    fn main() -> ! {
        let Some(core) = cortex_m::Peripherals::take() else {
            loop {
                cortex_m::asm::wfi();
            }
        };
        let mut syst = core.SYST;
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(SYSCLK_HZ / TICK_HZ - 1);
        syst.clear_current();
        syst.enable_counter();
        RCGC1.write(RCGC1.read() | 1);
        CTL.write(0);
        LCRH.write((0b11 << 5) | (1 << 4));
        CTL.write((1 << 0) | (1 << 8) | (1 << 9));

        let mut reader: Reader<Rx, Mode1> = Reader::fixed(Rx { error: false });
        let mut tx = Tx;
        let mut ticker = SysTicker(syst);
        let mut mav: MavCore<FlightModel, Mode1> = MavCore::new(FlightModel::new());
        embassy_futures::block_on(run(&mut reader, &mut tx, &mut ticker, &mut mav));
        loop {
            cortex_m::asm::wfi();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    println!(
        "mav-firmware-async runs on thumbv7m-none-eabi; `cargo test --target <host>` tests its core"
    );
}
