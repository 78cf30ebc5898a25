//! An async MAV firmware core, as an Embassy user would write it, without a HAL: one
//! task reads XBee API frames from a UART (anything that implements
//! [`embedded_io_async::Read`]) with [`xbee_api::io::FrameReader`], answers MCP
//! commands with [`mcp_core::mav::Mav`], and sends the 20 Hz telemetry, all to the
//! coordinator in Transmit Requests written to the UART's transmit half
//! ([`embedded_io_async::Write`]).
//!
//! The task is [`run`]: it waits on the next frame and the next tick at once
//! (`embassy_futures::select`), so a tick cancels a read in progress; the
//! `FrameReader` documents that as safe, and the tests check it mid-frame. The API mode
//! is fixed in the reader's type (`Mode1` or `Mode2`); replies follow it.
#![no_std]
// `Ticker::next` is an `async fn` in a public trait: fine in a firmware, where the
// executor is single-threaded and no `Send` bound is wanted.
#![allow(async_fn_in_trait)]

pub mod model;

use core::marker::PhantomData;

use embassy_futures::select::{Either, select};
use embedded_io_async::{Read, Write};
use mcp_core::mav::Mav;
use mcp_core::{BufferTooSmall, Command};
use xbee_api::io::{FrameReader, WriteError, write_encoded_async};
use xbee_api::{
    Address64, ApiMode, DecodeEvent, EncodeError, FixedMode, InPlaceFrame, ReceivePacket,
    ReceivePacketRepr, TransmitRequestRepr, decoder_buffer_len, max_encoded_len, transmit_options,
};

use crate::model::Model;

/// The largest MCP payload in one radio packet (84 bytes): what the MAV takes and sends.
pub const PAYLOAD: usize = TransmitRequestRepr::MAX_UNICAST_DATA;

/// The decoder's capacity: a Receive Packet with a `PAYLOAD`-byte payload, in API mode 1
/// (which buffers 4 bytes more than mode 2). The core is generic over the mode, and a
/// const generic cannot be computed from a type parameter on stable Rust
/// (`decoder_buffer_len(.., M::MODE)`), so it takes the larger of the two.
pub const DECODER_CAPACITY: usize =
    decoder_buffer_len(ReceivePacketRepr::HEADER_LEN + PAYLOAD, ApiMode::Unescaped);

/// The transmit buffer: a Transmit Request with a `PAYLOAD`-byte payload, escaped in API
/// mode 2 at worst (the larger of the two modes, for the same reason).
pub const FRAME: usize =
    max_encoded_len(TransmitRequestRepr::HEADER_LEN + PAYLOAD, ApiMode::Escaped);

/// The frame reader the task takes: capacity [`DECODER_CAPACITY`], the mode `M` fixed.
pub type Reader<R, M> = FrameReader<R, DECODER_CAPACITY, M>;

/// The packet sent once at start-up, before any command is read.
pub const STARTUP_MESSAGE: &[u8] = b"mMAV started";

/// The 20 Hz time base (`embassy_time::Ticker::next` has this shape).
pub trait Ticker {
    /// Waits for the next tick. A tick that passed while the caller was busy comes at
    /// once.
    async fn next(&mut self);
}

/// Counters of the application layer (the decoder counts bad frames in its `stats`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Stats {
    /// Events that were not frames (bad checksum, oversize, cut off...).
    pub bad_frames: u32,
    /// Frames other than Receive Packets (modem status, transmit status...), ignored.
    pub other_frames: u32,
    /// Receive Packets whose payload was no valid MCP command (telemetry, reports and
    /// text included: a MAV acts on commands alone), ignored.
    pub invalid_packets: u32,
    /// Answers that could not be built (buffer too small), not sent.
    pub unsent: u32,
    /// Reads that failed (overrun, framing error...); the task goes on.
    pub read_errors: u32,
    /// Writes that failed; the task goes on.
    pub write_errors: u32,
    /// Ticks on which a frame left unfinished by a quiet line was given up.
    pub given_up: u32,
}

/// Why one packet could not be sent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SendError<E> {
    /// The MCP packet did not fit its buffer (mcp-core's `BufferTooSmall`).
    Payload(BufferTooSmall),
    /// The frame could not be built or written (xbee-api's `WriteError`, whose
    /// `Encode` variant holds xbee-api's own `BufferTooSmall`).
    Write(WriteError<E>),
}

impl<E> From<BufferTooSmall> for SendError<E> {
    fn from(e: BufferTooSmall) -> Self {
        SendError::Payload(e)
    }
}

impl<E> From<WriteError<E>> for SendError<E> {
    fn from(e: WriteError<E>) -> Self {
        SendError::Write(e)
    }
}

impl<E> From<EncodeError> for SendError<E> {
    fn from(e: EncodeError) -> Self {
        SendError::Write(WriteError::Encode(e))
    }
}

/// The MAV: the protocol state machine, the aircraft, and the one transmit buffer that
/// every packet is built in (header, MCP payload, then framed in place).
#[derive(Debug)]
pub struct MavCore<V, M> {
    mav: Mav,
    vehicle: V,
    frame: [u8; FRAME],
    stats: Stats,
    mode: PhantomData<M>,
}

impl<V: Model, M: FixedMode> MavCore<V, M> {
    /// A MAV in its start-up state around `vehicle`.
    pub fn new(vehicle: V) -> Self {
        MavCore {
            mav: Mav::new(&vehicle),
            vehicle,
            frame: [0; FRAME],
            stats: Stats::default(),
            mode: PhantomData,
        }
    }

    /// The aircraft.
    pub fn vehicle(&self) -> &V {
        &self.vehicle
    }

    /// The protocol state machine.
    pub fn mav(&self) -> &Mav {
        &self.mav
    }

    /// The counters.
    pub fn stats(&self) -> Stats {
        self.stats
    }

    /// Handles one event of the reader: a Receive Packet's command is carried out and
    /// answered, then the unsolicited reports go out; anything else is counted.
    pub async fn on_event<W: Write>(&mut self, event: DecodeEvent<'_>, tx: &mut W) {
        let Ok(frame) = event else {
            self.stats.bad_frames = self.stats.bad_frames.wrapping_add(1);
            return;
        };
        let Ok(rx) = ReceivePacket::new_checked(frame.data()) else {
            self.stats.other_frames = self.stats.other_frames.wrapping_add(1);
            return;
        };
        // Commands alone: the parsers of the other categories are not linked.
        let Ok(command) = Command::parse(rx.data()) else {
            self.stats.invalid_packets = self.stats.invalid_packets.wrapping_add(1);
            return;
        };
        let result = self
            .send(tx, |mav, vehicle, buf| mav.handle(vehicle, &command, buf))
            .await;
        self.count(result);
        self.report_changes(tx).await;
    }

    /// One tick: steps the model, sends the unsolicited reports and the telemetry.
    pub async fn on_tick<W: Write>(&mut self, tx: &mut W) {
        self.vehicle.step();
        self.report_changes(tx).await;
        let result = self
            .send(tx, |mav, vehicle, buf| mav.telemetry(vehicle, buf))
            .await;
        self.count(result);
    }

    /// Sends [`STARTUP_MESSAGE`].
    pub async fn on_start<W: Write>(&mut self, tx: &mut W) {
        let result = self
            .send(tx, |_, _, buf| {
                let room = buf.len();
                let slot = buf.get_mut(..STARTUP_MESSAGE.len()).ok_or(BufferTooSmall {
                    needed: STARTUP_MESSAGE.len(),
                    available: room,
                })?;
                slot.copy_from_slice(STARTUP_MESSAGE);
                Ok(Some(STARTUP_MESSAGE.len()))
            })
            .await;
        self.count(result);
    }

    async fn report_changes<W: Write>(&mut self, tx: &mut W) {
        loop {
            match self
                .send(tx, |mav, vehicle, buf| mav.poll_changes(vehicle, buf))
                .await
            {
                Ok(true) => {}
                // Nothing changed, or the report could not go out: a change that did
                // not fit stays pending, so stop rather than spin on it.
                other => {
                    self.count(other);
                    return;
                }
            }
        }
    }

    fn count<E>(&mut self, result: Result<bool, SendError<E>>) {
        match result {
            Ok(_) => {}
            Err(SendError::Write(WriteError::Io(_) | WriteError::WriteZero { .. })) => {
                self.stats.write_errors = self.stats.write_errors.wrapping_add(1)
            }
            Err(_) => self.stats.unsent = self.stats.unsent.wrapping_add(1),
        }
    }

    /// Builds an MCP packet with `build` straight into the payload of a Transmit Request
    /// to the coordinator (no retries, frame id 0, as the deployed MAV sends), frames it
    /// in place and writes it. `Ok(false)`: `build` had nothing to send.
    async fn send<W: Write>(
        &mut self,
        tx: &mut W,
        build: impl FnOnce(&mut Mav, &mut V, &mut [u8]) -> Result<Option<usize>, BufferTooSmall>,
    ) -> Result<bool, SendError<W::Error>> {
        let header = TransmitRequestRepr {
            options: transmit_options::DISABLE_RETRIES,
            ..TransmitRequestRepr::unicast(Address64::COORDINATOR, &[])
        };
        let mut frame = InPlaceFrame::new(&mut self.frame, &header)?;
        let payload = frame.data_mut_capped(M::MODE, PAYLOAD);
        let Some(len) = build(&mut self.mav, &mut self.vehicle, payload)? else {
            return Ok(false);
        };
        let wire = frame.finish(len, M::MODE)?;
        write_encoded_async(tx, wire).await?;
        Ok(true)
    }
}

/// The MAV task: sends the start-up message, then forever answers the frames `reader`
/// reads and, on each tick of `ticker`, steps the model and sends the telemetry.
///
/// In API mode 1 a tick gives up a frame the line left unfinished when no byte came
/// since the tick before (50 ms, far longer than a frame takes at 115200 baud): a stray
/// 0x7E would otherwise hold the frames behind it. In mode 2 nothing is given up: the
/// next frame's 0x7E, which no frame holds unescaped, ends a frame cut off at once.
///
/// That check counts bytes, not time: ticks that catch up after the task was busy (as
/// `embassy_time::Ticker`'s do) come back to back, and the second may give up a frame
/// whose next byte is only microseconds away. A firmware with a clock races each read
/// against a quiet-line timeout started with it instead, as [`FrameReader`]'s docs
/// show; this task has only the ticker.
///
/// Read and write errors are counted and the task goes on. Returns at the end of the
/// input (a read of no bytes), which a UART never gives: for the tests.
pub async fn run<R, W, T, V, M>(
    reader: &mut Reader<R, M>,
    tx: &mut W,
    ticker: &mut T,
    core: &mut MavCore<V, M>,
) where
    R: Read,
    W: Write,
    T: Ticker,
    V: Model,
    M: FixedMode,
{
    core.on_start(tx).await;
    let mut seen = reader.bytes_read();
    loop {
        match select(reader.read_event_async(), ticker.next()).await {
            Either::First(Ok(Some(event))) => core.on_event(event, tx).await,
            Either::First(Ok(None)) => return,
            Either::First(Err(_)) => {
                core.stats.read_errors = core.stats.read_errors.wrapping_add(1)
            }
            Either::Second(()) => {
                let quiet = reader.bytes_read() == seen;
                if M::MODE == ApiMode::Unescaped && quiet && !reader.decoder().is_idle() {
                    core.stats.given_up = core.stats.given_up.wrapping_add(1);
                    while let Some(event) = reader.drop_partial() {
                        core.on_event(event, tx).await;
                    }
                }
                seen = reader.bytes_read();
                core.on_tick(tx).await;
            }
        }
    }
}
