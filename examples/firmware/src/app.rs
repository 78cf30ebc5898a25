//! The firmware's main loop: received payloads through the MCP state machine, the
//! 20 Hz model step and telemetry, unsolicited reports, sleep until the next interrupt.

use mcp_core::Command;
use mcp_core::mav::Mav;

use crate::model::FlightModel;
use crate::rx::{self, MAX_PAYLOAD};
use crate::{clock, hw, tx};

/// Counters of the application layer.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct AppStats {
    /// Payloads that were no valid MCP command (telemetry, reports and text included:
    /// a MAV acts on commands alone), ignored.
    pub invalid: u32,
    /// Answers that did not fit a payload, not sent.
    pub unsent: u32,
}

/// The MAV: the protocol state machine, the flight model and a reply buffer.
#[derive(Debug)]
pub struct App {
    mav: Mav,
    model: FlightModel,
    buf: [u8; MAX_PAYLOAD],
    stats: AppStats,
}

impl Default for App {
    fn default() -> Self {
        Self::new()
    }
}

impl App {
    /// A MAV in its start-up state.
    pub fn new() -> Self {
        let model = FlightModel::new();
        App {
            mav: Mav::new(&model),
            model,
            buf: [0; MAX_PAYLOAD],
            stats: AppStats::default(),
        }
    }

    /// Handles one received MCP payload: commands are carried out and answered,
    /// other packets and invalid ones ignored. `send` transmits each answer.
    pub fn on_payload(&mut self, payload: &[u8], send: &mut impl FnMut(&[u8])) {
        // Commands alone: the parsers of the other categories are not linked.
        let Ok(command) = Command::parse(payload) else {
            self.stats.invalid = self.stats.invalid.wrapping_add(1);
            return;
        };
        match self.mav.handle(&mut self.model, &command, &mut self.buf) {
            Ok(Some(len)) => self.send(len, send),
            Ok(None) => {}
            Err(_) => self.stats.unsent = self.stats.unsent.wrapping_add(1),
        }
        self.report_changes(send);
    }

    /// One SysTick tick: steps the model, reports state changes, sends telemetry.
    pub fn on_tick(&mut self, send: &mut impl FnMut(&[u8])) {
        self.model.step();
        self.report_changes(send);
        match self.mav.telemetry(&self.model, &mut self.buf) {
            Ok(Some(len)) => self.send(len, send),
            Ok(None) => {}
            Err(_) => self.stats.unsent = self.stats.unsent.wrapping_add(1),
        }
    }

    /// Sends the unsolicited landing and controller reports.
    fn report_changes(&mut self, send: &mut impl FnMut(&[u8])) {
        while let Ok(Some(len)) = self.mav.poll_changes(&self.model, &mut self.buf) {
            self.send(len, send);
        }
    }

    fn send(&self, len: usize, send: &mut impl FnMut(&[u8])) {
        send(self.buf.get(..len).unwrap_or_default());
    }

    /// The flight model.
    pub fn model(&self) -> &FlightModel {
        &self.model
    }

    /// The protocol state machine.
    pub fn mav(&self) -> &Mav {
        &self.mav
    }

    /// The application counters.
    pub fn stats(&self) -> AppStats {
        self.stats
    }
}

/// The message packet sent once the UART is up: it tells the ground station (and the
/// tests) that the MAV listens from now on. Bytes sent before it are lost.
pub const STARTUP_MESSAGE: &[u8] = b"mMAV started";

/// Starts the hardware and runs the MAV forever.
pub fn run() -> ! {
    let Some(mut core) = cortex_m::Peripherals::take() else {
        halt()
    };
    hw::init_clock();
    let mut app = App::new();
    hw::init_uart0();
    hw::init_systick(&mut core.SYST, clock::TICK_HZ);

    let mut send = |payload: &[u8]| {
        tx::send_to_coordinator(payload);
    };
    send(STARTUP_MESSAGE);
    let mut seen = clock::ticks();
    loop {
        while let Some(payload) = rx::take() {
            app.on_payload(payload.data(), &mut send);
        }
        while seen != clock::ticks() {
            seen = seen.wrapping_add(1);
            app.on_tick(&mut send);
        }
        wait_for(|cs| !rx::is_pending(cs) && clock::ticks() == seen);
    }
}

/// Sleeps until an interrupt if `idle` holds. `idle` is checked with interrupts
/// masked, so an interrupt arriving after the check still wakes the core (WFI wakes on
/// a pending interrupt even when masked; it runs when the critical section ends).
pub fn wait_for(idle: impl FnOnce(critical_section::CriticalSection<'_>) -> bool) {
    critical_section::with(|cs| {
        if idle(cs) {
            cortex_m::asm::wfi();
        }
    });
}

/// Stops for good, sleeping.
pub fn halt() -> ! {
    loop {
        cortex_m::asm::wfi();
    }
}
