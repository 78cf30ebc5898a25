//! The receive path with the slice decoder, to measure its footprint against
//! `baseline` and `rx_path`: the UART0 interrupt drains the RX FIFO into a chunk and
//! hands the chunk to `Decoder::decode_each`, which views each Receive Packet and
//! parses its MCP payload in place. Parsed packets are only counted.
#![no_std]
#![no_main]

use core::cell::RefCell;
use core::hint::black_box;

use cortex_m_rt::entry;
use critical_section::Mutex;
use lm3s6965::interrupt;
use mav_firmware::rx::XbeeDecoder;
use mav_firmware::{app, hw};
use panic_halt as _;
use xbee_api::{Decoder, ReceivePacket};

/// The RX FIFO's depth on the LM3S6965: the most one interrupt finds.
const CHUNK: usize = 16;

static DECODER: Mutex<RefCell<XbeeDecoder>> = Mutex::new(RefCell::new(Decoder::fixed()));

/// Packets that parsed, and those that did not.
static COUNTS: Mutex<RefCell<[u32; 2]>> = Mutex::new(RefCell::new([0; 2]));

#[entry]
fn main() -> ! {
    hw::init_clock();
    hw::init_uart0();
    loop {
        app::wait_for(|_| true);
    }
}

#[interrupt]
fn UART0() {
    critical_section::with(|cs| {
        let mut chunk = [0u8; CHUNK];
        let mut len = 0;
        while len < CHUNK {
            match hw::uart0_read() {
                Some(Ok(byte)) => {
                    chunk[len] = byte;
                    len += 1;
                }
                Some(Err(_)) => {}
                None => break,
            }
        }
        // `try_borrow_mut` and `get`: `borrow_mut` and `&chunk[..len]` would keep a panic
        // path.
        let Ok(mut counts) = COUNTS.borrow(cs).try_borrow_mut() else {
            return;
        };
        let (Ok(mut decoder), Some(input)) =
            (DECODER.borrow(cs).try_borrow_mut(), chunk.get(..len))
        else {
            return;
        };
        decoder.decode_each(input, |event| {
            if let Ok(frame) = event {
                if let Ok(packet) = ReceivePacket::new_checked(frame.data()) {
                    let valid = mcp_core::parse(packet.data()).is_ok();
                    counts[usize::from(valid)] += 1;
                }
            }
        });
        black_box(&*counts);
    });
}
