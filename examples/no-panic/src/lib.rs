//! Every path a MAV firmware takes through `xbee-api` and `mcp-core`, as `extern "C"`
//! entry points of a static library, with a panic handler that calls a function no one
//! defines. Once optimised (release: `opt-level = "s"`, LTO, as the firmware is built),
//! the library refers to that function only if some panic is still reachable: a bounds
//! check, an `unwrap` or an overflow the compiler could not prove away. `check.sh`
//! builds it and fails if the reference is there.
//!
//! The entry points take the decoder and MAV state by pointer, as an interrupt handler
//! and a main loop sharing them would, and hand what they produce to `sink`, which is
//! left undefined too, so that nothing is optimised away.
#![no_std]

use mcp_core::mav::{Mav, Vehicle};
use mcp_core::{
    Command, Controller, LandingState, Packet, Report, StatusRequest, TelemetryBuilder,
    TelemetryId, Text, Waypoint, Waypoints, parse,
};
use xbee_api::io::{self, FrameReader};
use xbee_api::{
    Address16, Address64, AnyMode, ApiMode, DecodeEvent, Decoder, EncodeFrame, Frame, InPlaceFrame,
    Inbox, Mode1, Mode2, ReceivePacket, TransmitRequestRepr,
};

unsafe extern "C" {
    /// Called by the panic handler; defined nowhere, so that a reachable panic shows
    /// up as a reference to it.
    fn no_panic_path_may_remain() -> !;
    /// Where the entry points put what they produce.
    fn sink(bytes: *const u8, len: usize);
    /// A UART: reads up to `len` bytes into `buf`, returns how many it read.
    fn uart_read(buf: *mut u8, len: usize) -> usize;
    /// A UART: writes up to `len` bytes of `buf`, returns how many it took (0 when full).
    fn uart_write(buf: *const u8, len: usize) -> usize;
}

/// The UART of [`mav_uart`], an `embedded-io` reader and writer, blocking and async.
struct Uart;

impl embedded_io::ErrorType for Uart {
    type Error = core::convert::Infallible;
}

impl embedded_io::Read for Uart {
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        // SAFETY: `uart_read` writes at most `len` bytes to `buf`, which has that room.
        Ok(unsafe { uart_read(buf.as_mut_ptr(), buf.len()) }.min(buf.len()))
    }
}

impl embedded_io::Write for Uart {
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        // SAFETY: `uart_write` reads at most `len` bytes of `buf`.
        Ok(unsafe { uart_write(buf.as_ptr(), buf.len()) }.min(buf.len()))
    }
    fn flush(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

impl embedded_io_async::Read for Uart {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        embedded_io::Read::read(self, buf)
    }
}

impl embedded_io_async::Write for Uart {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        embedded_io::Write::write(self, buf)
    }
    async fn flush(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

/// Polls `future` once, as an executor would on a wake-up.
fn poll_once<F: core::future::Future>(future: F) -> Option<F::Output> {
    let mut future = core::pin::pin!(future);
    let mut cx = core::task::Context::from_waker(core::task::Waker::noop());
    match future.as_mut().poll(&mut cx) {
        core::task::Poll::Ready(output) => Some(output),
        core::task::Poll::Pending => None,
    }
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
    // SAFETY: never defined; the check is that nothing calls this.
    unsafe { no_panic_path_may_remain() }
}

fn out(bytes: &[u8]) {
    // SAFETY: `sink` reads `len` bytes from `bytes`, which are valid for that long.
    unsafe { sink(bytes.as_ptr(), bytes.len()) }
}

/// A vehicle that answers every query.
struct Craft {
    time: u32,
    landing: LandingState,
    controller: Controller,
    position: [f32; 2],
    trajectory: [Option<Waypoint>; 4],
}

impl Vehicle for Craft {
    fn landing_state(&self) -> LandingState {
        self.landing
    }
    fn set_landing(&mut self, on: bool) {
        self.landing = if on {
            LandingState::Landing
        } else {
            LandingState::TakeOff
        };
    }
    fn controller(&self) -> Controller {
        self.controller
    }
    fn set_controller(&mut self, controller: Controller) {
        self.controller = controller;
    }
    fn time(&self) -> u32 {
        self.time
    }
    fn set_time(&mut self, time: u32) {
        self.time = time;
    }
    fn set_position(&mut self, elevator: f32, aileron: f32) {
        self.position = [elevator, aileron];
    }
    fn telemetry(&self, id: TelemetryId) -> f32 {
        f32::from(u8::from(id)) + self.position[0]
    }
    fn set_trajectory(&mut self, waypoints: Waypoints<&[u8]>) {
        self.trajectory = [None; 4];
        for (slot, waypoint) in self.trajectory.iter_mut().zip(waypoints.iter()) {
            *slot = Some(waypoint);
        }
    }
    fn waypoint(&self, index: usize) -> Option<Waypoint> {
        self.trajectory.get(index).copied().flatten()
    }
}

/// What a firmware keeps: the decoder, and what answers the commands.
pub struct State {
    decoder: Decoder<100>,
    mav: MavSide,
}

/// The MAV and its vehicle, and buffers for the answers.
struct MavSide {
    mav: Mav,
    craft: Craft,
    payload: [u8; 84],
    frame: [u8; 200],
}

/// Sends `payload` to the coordinator in a Transmit Request, in `mode`.
fn transmit(mode: ApiMode, payload: &[u8], frame: &mut [u8]) {
    let request = TransmitRequestRepr {
        frame_id: 0,
        dst64: Address64::COORDINATOR,
        dst16: Address16::UNKNOWN,
        radius: 0,
        options: 0,
        data: payload,
    };
    if let Ok(n) = request.encode(mode, frame) {
        out(frame.get(..n).unwrap_or_default());
    }
}

impl MavSide {
    /// Handles one decoded frame: a command in a Receive Packet is carried out and
    /// answered.
    fn receive(&mut self, event: DecodeEvent<'_>, mode: ApiMode) {
        let Ok(raw) = event else { return };
        let Ok(rx) = ReceivePacket::new_checked(raw.data()) else {
            return;
        };
        let Ok(packet) = parse(rx.data()) else { return };
        if let Ok(Some(n)) = self
            .mav
            .handle_packet(&mut self.craft, &packet, &mut self.payload)
        {
            transmit(
                mode,
                self.payload.get(..n).unwrap_or_default(),
                &mut self.frame,
            );
        }
    }

    /// Unsolicited reports, then the telemetry packet.
    fn tick(&mut self, mode: ApiMode) {
        while let Ok(Some(n)) = self.mav.poll_changes(&self.craft, &mut self.payload) {
            transmit(
                mode,
                self.payload.get(..n).unwrap_or_default(),
                &mut self.frame,
            );
        }
        if let Ok(Some(n)) = self.mav.telemetry(&self.craft, &mut self.payload) {
            transmit(
                mode,
                self.payload.get(..n).unwrap_or_default(),
                &mut self.frame,
            );
        }
    }
}

/// Creates the state in `mode` (1 or 2) at `state`.
#[unsafe(no_mangle)]
pub extern "C" fn mav_init(state: &mut core::mem::MaybeUninit<State>, mode: u8) {
    let craft = Craft {
        time: 0,
        landing: LandingState::OnGround,
        controller: Controller::Manual,
        position: [0.0; 2],
        trajectory: [None; 4],
    };
    state.write(State {
        decoder: Decoder::new(ApiMode::try_from(mode).unwrap_or(ApiMode::Unescaped)),
        mav: MavSide {
            mav: Mav::new(&craft),
            craft,
            payload: [0; 84],
            frame: [0; 200],
        },
    });
}

/// A UART receive interrupt: one byte, then every event it completes.
#[unsafe(no_mangle)]
pub extern "C" fn mav_rx_byte(state: &mut State, byte: u8) {
    let State { decoder, mav } = state;
    let mode = decoder.mode();
    let mut event = decoder.push(byte);
    while let Some(e) = event {
        mav.receive(e, mode);
        event = decoder.poll();
    }
}

/// A UART FIFO or DMA buffer drained at once.
///
/// # Safety
///
/// `bytes` points to `len` readable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mav_rx_chunk(state: &mut State, bytes: *const u8, len: usize) {
    // SAFETY: the caller passes `len` readable bytes.
    let input = unsafe { core::slice::from_raw_parts(bytes, len) };
    let State { decoder, mav } = state;
    let mode = decoder.mode();
    decoder.decode_each(input, |e| mav.receive(e, mode));
}

/// The same with one `decode` call a frame, and every frame typed.
///
/// # Safety
///
/// `bytes` points to `len` readable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn mav_rx_frames(state: &mut State, bytes: *const u8, len: usize) {
    // SAFETY: the caller passes `len` readable bytes.
    let mut input = unsafe { core::slice::from_raw_parts(bytes, len) };
    while !input.is_empty() {
        let (used, event) = state.decoder.decode(input);
        if let Some(Ok(raw)) = event {
            if let Ok(Frame::ReceivePacket(rx)) = Frame::parse(raw) {
                out(rx.data);
            }
        }
        input = input.get(used..).unwrap_or_default();
        if used == 0 {
            break;
        }
    }
}

/// The receive path of a firmware in one value, its mode set at run time (both modes'
/// code linked).
pub type RxInbox = Inbox<100, AnyMode, 84, 4>;

/// Creates an empty inbox in `mode` (1 or 2) at `inbox`.
#[unsafe(no_mangle)]
pub extern "C" fn mav_inbox_init(inbox: &mut core::mem::MaybeUninit<RxInbox>, mode: u8) {
    let mode = ApiMode::try_from(mode).unwrap_or(ApiMode::Unescaped);
    inbox.write(Inbox::with_decoder(Decoder::new(mode)));
}

/// A UART receive interrupt on an inbox: the FIFO drained a byte at a time while the
/// queue has room; the main loop's turn: every payload taken; a timer's tick.
#[unsafe(no_mangle)]
pub extern "C" fn mav_inbox(inbox: &mut RxInbox) {
    let full = inbox
        .read_from(|| {
            let mut byte = 0u8;
            // SAFETY: `uart_read` writes at most 1 byte to `byte`.
            (unsafe { uart_read(&mut byte, 1) } == 1).then_some(byte)
        })
        .is_err();
    while let Some(received) = inbox.pop() {
        out(received.data());
        out(&received.src64().to_bytes());
    }
    out(&[u8::from(full), inbox.stats().too_long as u8]);
    inbox.tick();
}

/// The main loop's tick: unsolicited reports, then the telemetry packet.
#[unsafe(no_mangle)]
pub extern "C" fn mav_tick(state: &mut State) {
    let mode = state.decoder.mode();
    state.mav.tick(mode);
}

/// Packets a firmware writes itself: a telemetry packet of up to four values, a text
/// message, a time report and a status request.
#[unsafe(no_mangle)]
pub extern "C" fn mav_encode(values: &[f32; 4], buf: &mut [u8; 84]) {
    let mut telemetry = [0u8; 21];
    if let Ok(mut builder) = TelemetryBuilder::new(&mut telemetry) {
        for (id, value) in (1..).zip(values) {
            if builder.push(TelemetryId::from(id), *value).is_err() {
                break;
            }
        }
        let n = builder.finish();
        out(telemetry.get(..n).unwrap_or_default());
    }
    let packets: [Packet<&[u8]>; 3] = [
        Packet::Message(Text::new(b"MAV started")),
        Packet::Report(Report::Time(1_700_000_000)),
        Packet::Command(Command::StatusRequest(StatusRequest::Landing)),
    ];
    for packet in packets {
        if let Ok(n) = packet.encode(buf) {
            out(buf.get(..n).unwrap_or_default());
        }
    }
}

/// Telemetry to the coordinator built in the frame buffer it goes out from: the
/// Transmit Request's header, the packet written after it, then framed (and in mode 2
/// escaped) in place.
#[unsafe(no_mangle)]
pub extern "C" fn mav_telemetry_in_place(values: &[f32; 4], mode: u8, frame: &mut [u8; 200]) {
    let mode = ApiMode::try_from(mode).unwrap_or(ApiMode::Unescaped);
    let header = TransmitRequestRepr::unicast(Address64::COORDINATOR, &[]);
    let Ok(mut built) = InPlaceFrame::new(frame, &header) else {
        return;
    };
    let room = built.data_mut();
    let end = room.len().min(84);
    let Ok(mut builder) = TelemetryBuilder::new(room.get_mut(..end).unwrap_or_default()) else {
        return;
    };
    for (id, value) in (1..).zip(values) {
        if builder.push(TelemetryId::from(id), *value).is_err() {
            break;
        }
    }
    let n = builder.finish();
    if let Ok(wire) = built.finish(n, mode) {
        out(wire);
    }
}

/// A decoder whose type fixes API mode 2, in a static of its own: it is all zeros when
/// new, so it goes to `.bss` and takes no flash (`check.sh` checks where it lands).
#[unsafe(no_mangle)]
pub static mut MAV_MODE2_DECODER: Decoder<64, Mode2> = Decoder::fixed();

/// Frames read from a UART through `embedded-io` (`io::FrameReader`, blocking and async,
/// a read or an event at a time)
/// and written to it (`io::write_frame`, `io::write_encoded` and their async forms),
/// whatever the UART reads and however few bytes it takes a write.
#[unsafe(no_mangle)]
pub extern "C" fn mav_uart() {
    let mut reader: FrameReader<Uart, 100, Mode1> = FrameReader::fixed(Uart);
    for _ in 0..4 {
        let _ = reader.read_events(|event| {
            if let Ok(frame) = event {
                out(frame.data());
            }
        });
        let _ = poll_once(reader.read_events_async(|event| {
            if let Ok(frame) = event {
                out(frame.data());
            }
        }));
        // One event a call, blocking and async, mixed with the above.
        if let Ok(Some(Ok(frame))) = reader.read_event() {
            out(frame.data());
        }
        if let Some(Ok(Some(Ok(frame)))) = poll_once(reader.read_event_async()) {
            out(frame.data());
        }
        // A frame in progress given up, as on a line gone quiet.
        while let Some(event) = reader.drop_partial() {
            if let Ok(frame) = event {
                out(frame.data());
            }
        }
    }
    let request = TransmitRequestRepr::unicast(Address64::COORDINATOR, b"m on the UART");
    let _ = io::write_frame(&mut Uart, ApiMode::Escaped, &request);
    let mut buffer = [0u8; 64];
    if let Ok(n) = request.encode(ApiMode::Escaped, &mut buffer) {
        let _ = io::write_encoded(&mut Uart, buffer.get(..n).unwrap_or_default());
        let _ = poll_once(io::write_encoded_async(
            &mut Uart,
            buffer.get(..n).unwrap_or_default(),
        ));
    }
    let _ = poll_once(io::write_frame_async(
        &mut Uart,
        ApiMode::Unescaped,
        &request,
        &mut buffer,
    ));
}
