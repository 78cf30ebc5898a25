//! The MAV task fed real byte streams through an in-memory UART that implements the
//! `embedded-io-async` traits: the reply bytes are checked against frames built here by
//! hand (not by xbee-api), in API mode 1 and 2.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::future::poll_fn;
use std::rc::Rc;
use std::task::Poll;

use embedded_io_async::{ErrorKind, ErrorType, Read, Write};
use mav_firmware_async::model::FlightModel;
use mav_firmware_async::{MavCore, Reader, STARTUP_MESSAGE, Stats, Ticker, run};
use xbee_api::{FixedMode, Mode1, Mode2};

/// What the line does next.
#[derive(Debug, Clone)]
enum Step {
    /// Bytes the UART has received.
    Bytes(Vec<u8>),
    /// A read error (overrun, framing).
    Error,
    /// The line is quiet until the ticker ticks once.
    Tick,
    /// The test stops the task here, without an end of input (which would finish the
    /// decoder).
    Stop,
}

type Script = Rc<RefCell<VecDeque<Step>>>;

/// The receive half: hands over the script's bytes, at most `max_read` a read; pending
/// while a tick comes first; end of input when the script is done.
struct Rx {
    script: Script,
    max_read: usize,
}

impl ErrorType for Rx {
    type Error = ErrorKind;
}

impl Read for Rx {
    async fn read(&mut self, buf: &mut [u8]) -> Result<usize, ErrorKind> {
        poll_fn(|cx| {
            let mut script = self.script.borrow_mut();
            match script.front_mut() {
                None => Poll::Ready(Ok(0)),
                Some(Step::Tick | Step::Stop) => {
                    cx.waker().wake_by_ref();
                    Poll::Pending
                }
                Some(Step::Error) => {
                    script.pop_front();
                    Poll::Ready(Err(ErrorKind::Other))
                }
                Some(Step::Bytes(bytes)) => {
                    let n = bytes.len().min(buf.len()).min(self.max_read);
                    buf[..n].copy_from_slice(&bytes[..n]);
                    bytes.drain(..n);
                    if bytes.is_empty() {
                        script.pop_front();
                    }
                    Poll::Ready(Ok(n))
                }
            }
        })
        .await
    }
}

/// The ticker: ticks when the script says so, else waits.
struct ScriptTicker {
    script: Script,
    ticks: usize,
}

impl Ticker for ScriptTicker {
    async fn next(&mut self) {
        poll_fn(|cx| {
            let mut script = self.script.borrow_mut();
            if let Some(Step::Tick) = script.front() {
                script.pop_front();
                self.ticks += 1;
                Poll::Ready(())
            } else {
                cx.waker().wake_by_ref();
                Poll::Pending
            }
        })
        .await
    }
}

/// The transmit half: collects the bytes, taking at most `max_write` a write.
#[derive(Default)]
struct Tx {
    out: Vec<u8>,
    max_write: usize,
    flushes: usize,
}

impl ErrorType for Tx {
    type Error = ErrorKind;
}

impl Write for Tx {
    async fn write(&mut self, buf: &[u8]) -> Result<usize, ErrorKind> {
        let n = buf.len().min(self.max_write);
        self.out.extend_from_slice(&buf[..n]);
        Ok(n)
    }

    async fn flush(&mut self) -> Result<(), ErrorKind> {
        self.flushes += 1;
        Ok(())
    }
}

/// Runs the task over `steps` until the script ends; the bytes written and the counters.
fn run_script<M: FixedMode>(
    steps: Vec<Step>,
    max_read: usize,
    max_write: usize,
) -> (Vec<u8>, Stats) {
    let script: Script = Rc::new(RefCell::new(steps.into()));
    let mut reader: Reader<Rx, M> = Reader::fixed(Rx {
        script: script.clone(),
        max_read,
    });
    let mut tx = Tx {
        max_write,
        ..Tx::default()
    };
    let mut ticker = ScriptTicker {
        script: script.clone(),
        ticks: 0,
    };
    let mut mav: MavCore<FlightModel, M> = MavCore::new(FlightModel::new());
    let stop = poll_fn(|cx| {
        if let Some(Step::Stop) = script.borrow().front() {
            Poll::Ready(())
        } else {
            cx.waker().wake_by_ref();
            Poll::Pending
        }
    });
    embassy_futures::block_on(embassy_futures::select::select(
        run(&mut reader, &mut tx, &mut ticker, &mut mav),
        stop,
    ));
    (tx.out, mav.stats())
}

// Frames built by hand, independently of xbee-api.

/// `7E | len | data | checksum`, escaped after the delimiter when `escaped`.
fn api_frame(data: &[u8], escaped: bool) -> Vec<u8> {
    let sum: u32 = data.iter().map(|&b| u32::from(b)).sum();
    let checksum = 0xFF - (sum & 0xFF) as u8;
    let mut body = vec![(data.len() >> 8) as u8, data.len() as u8];
    body.extend_from_slice(data);
    body.push(checksum);
    let mut out = vec![0x7E];
    for b in body {
        if escaped && matches!(b, 0x7E | 0x7D | 0x11 | 0x13) {
            out.extend_from_slice(&[0x7D, b ^ 0x20]);
        } else {
            out.push(b);
        }
    }
    out
}

/// A Receive Packet (0x90) from `src64`, 16-bit FFFE, options 01 (acknowledged).
fn receive_packet(src64: u64, payload: &[u8]) -> Vec<u8> {
    let mut data = vec![0x90];
    data.extend_from_slice(&src64.to_be_bytes());
    data.extend_from_slice(&[0xFF, 0xFE, 0x01]);
    data.extend_from_slice(payload);
    data
}

/// A Transmit Request (0x10) to the coordinator, frame id 0, 16-bit FFFE, radius 0,
/// options 01 (no retries).
fn transmit_request(payload: &[u8]) -> Vec<u8> {
    let mut data = vec![0x10, 0x00];
    data.extend_from_slice(&[0; 8]);
    data.extend_from_slice(&[0xFF, 0xFE, 0x00, 0x01]);
    data.extend_from_slice(payload);
    data
}

fn reply(payload: &[u8], escaped: bool) -> Vec<u8> {
    api_frame(&transmit_request(payload), escaped)
}

fn startup(escaped: bool) -> Vec<u8> {
    reply(STARTUP_MESSAGE, escaped)
}

const MAV_SRC: u64 = 0x0013_A200_4052_2BAA;
/// `c 02 FF`: landing status request.
const LANDING_REQUEST: &[u8] = b"c\x02\xff";
/// `r 02 00`: landing state on ground.
const ON_GROUND: &[u8] = b"r\x02\x00";

/// Line noise that holds no 0x7E, then a status request with a bad checksum, then a
/// good one.
fn noisy_request(escaped: bool) -> Vec<u8> {
    let mut wire = vec![0x00, 0x13, 0xFF, 0x11, 0x7D, 0x31, 0xAA];
    let mut bad = api_frame(&receive_packet(MAV_SRC, b"c\x06\xff"), escaped);
    *bad.last_mut().unwrap() ^= 0x01;
    wire.extend(bad);
    wire.extend(api_frame(
        &receive_packet(MAV_SRC, LANDING_REQUEST),
        escaped,
    ));
    wire
}

#[test]
fn reply_bytes_are_the_hand_computed_ones() {
    // 17 bytes of frame data, checksum 0x7D; in mode 2 the length 0x11 and the checksum
    // 0x7D go out escaped.
    let mode1 = [
        0x7E, 0x00, 0x11, 0x10, 0x00, 0, 0, 0, 0, 0, 0, 0, 0, 0xFF, 0xFE, 0x00, 0x01, b'r', 0x02,
        0x00, 0x7D,
    ];
    let mode2 = [
        0x7E, 0x00, 0x7D, 0x31, 0x10, 0x00, 0, 0, 0, 0, 0, 0, 0, 0, 0xFF, 0xFE, 0x00, 0x01, b'r',
        0x02, 0x00, 0x7D, 0x5D,
    ];
    assert_eq!(reply(ON_GROUND, false), mode1);
    assert_eq!(reply(ON_GROUND, true), mode2);
}

#[test]
fn mode1_status_request_after_noise_and_bad_checksum() {
    let (out, stats) = run_script::<Mode1>(vec![Step::Bytes(noisy_request(false))], 32, usize::MAX);
    assert_eq!(out, [startup(false), reply(ON_GROUND, false)].concat());
    assert_eq!(stats.bad_frames, 1);
    assert_eq!(stats.invalid_packets, 0);
}

#[test]
fn mode2_status_request_after_noise_and_bad_checksum() {
    let wire = noisy_request(true);
    // The source address's 0x13 is escaped on the wire.
    assert!(wire.windows(2).any(|w| w == [0x7D, 0x33]));
    let (out, stats) = run_script::<Mode2>(vec![Step::Bytes(wire)], 32, usize::MAX);
    assert_eq!(out, [startup(true), reply(ON_GROUND, true)].concat());
    assert!(stats.bad_frames >= 1, "{stats:?}");
}

#[test]
fn byte_at_a_time_reads_and_writes() {
    for escaped in [false, true] {
        let steps = vec![Step::Bytes(noisy_request(escaped))];
        let (out, _) = if escaped {
            run_script::<Mode2>(steps, 1, 1)
        } else {
            run_script::<Mode1>(steps, 1, 1)
        };
        assert_eq!(out, [startup(escaped), reply(ON_GROUND, escaped)].concat());
    }
}

/// A tick part way through a frame drops the pending `read_event_async` (the `select`
/// in `run`); the frame still comes out whole once its rest arrives.
#[test]
fn a_tick_mid_frame_cancels_the_read_without_losing_bytes() {
    for escaped in [false, true] {
        let wire = api_frame(&receive_packet(MAV_SRC, LANDING_REQUEST), escaped);
        for cut in 1..wire.len() {
            let steps = vec![
                Step::Bytes(wire[..cut].to_vec()),
                Step::Tick,
                Step::Bytes(wire[cut..].to_vec()),
            ];
            let (out, stats) = if escaped {
                run_script::<Mode2>(steps, 32, usize::MAX)
            } else {
                run_script::<Mode1>(steps, 32, usize::MAX)
            };
            assert_eq!(
                out,
                [startup(escaped), reply(ON_GROUND, escaped)].concat(),
                "cut at {cut}, escaped {escaped}"
            );
            assert_eq!(stats.given_up, 0);
        }
    }
}

/// Mode 1: a stray 0x7E whose length field reaches past the real frame holds it until
/// the line has been quiet for a whole tick; the tick after that gives it up.
#[test]
fn mode1_stray_delimiter_is_given_up_on_a_quiet_tick() {
    let mut wire = vec![0x7E, 0x00, 0x40];
    wire.extend(api_frame(&receive_packet(MAV_SRC, LANDING_REQUEST), false));

    let (out, _) = run_script::<Mode1>(
        vec![Step::Bytes(wire.clone()), Step::Tick, Step::Stop],
        32,
        usize::MAX,
    );
    assert_eq!(
        out,
        startup(false),
        "held after one tick (bytes came since the last)"
    );

    let (out, stats) = run_script::<Mode1>(
        vec![Step::Bytes(wire), Step::Tick, Step::Tick, Step::Stop],
        32,
        usize::MAX,
    );
    assert_eq!(out, [startup(false), reply(ON_GROUND, false)].concat());
    assert_eq!(stats.given_up, 1);
}

/// Mode 2: the real frame's delimiter ends the stray candidate at once.
#[test]
fn mode2_stray_delimiter_needs_no_tick() {
    let mut wire = vec![0x7E, 0x00, 0x40];
    wire.extend(api_frame(&receive_packet(MAV_SRC, LANDING_REQUEST), true));
    let (out, _) = run_script::<Mode2>(vec![Step::Bytes(wire)], 32, usize::MAX);
    assert_eq!(out, [startup(true), reply(ON_GROUND, true)].concat());
}

/// Mode 2: ticks that come back to back (catching up after the task was busy) give up
/// no frame, whose rest still comes whole.
#[test]
fn mode2_gives_up_no_frame_on_quiet_ticks() {
    let wire = api_frame(&receive_packet(MAV_SRC, LANDING_REQUEST), true);
    let steps = vec![
        Step::Bytes(wire[..5].to_vec()),
        Step::Tick,
        Step::Tick,
        Step::Bytes(wire[5..].to_vec()),
    ];
    let (out, stats) = run_script::<Mode2>(steps, 32, usize::MAX);
    assert_eq!(out[..startup(true).len()], startup(true));
    assert!(
        out.ends_with(&reply(ON_GROUND, true)),
        "the command is answered: {out:02x?}"
    );
    assert_eq!(stats.given_up, 0);
}

/// Take-off: the unsolicited landing report right after the command, then at each tick
/// the telemetry (altitude, once enabled) as the model climbs.
#[test]
fn telemetry_and_unsolicited_reports_at_20_hz() {
    for escaped in [false, true] {
        let cmd = |p: &[u8]| api_frame(&receive_packet(MAV_SRC, p), escaped);
        let steps = vec![
            Step::Tick,                         // no telemetry enabled: nothing sent
            Step::Bytes(cmd(b"c\x01\x01\x01")), // altitude to the coordinator
            Step::Bytes(cmd(b"c\x02\x00")),     // landing off: take off
            Step::Tick,
            Step::Tick,
        ];
        let (out, _) = if escaped {
            run_script::<Mode2>(steps, 32, usize::MAX)
        } else {
            run_script::<Mode1>(steps, 32, usize::MAX)
        };
        let telemetry = |altitude: f32| {
            let mut p = vec![b't', 0x01];
            p.extend_from_slice(&altitude.to_le_bytes());
            reply(&p, escaped)
        };
        let expected = [
            startup(escaped),
            reply(b"r\x02\x03", escaped), // take-off
            telemetry(0.025),
            telemetry(0.05),
        ]
        .concat();
        assert_eq!(out, expected, "escaped {escaped}");
    }
}

#[test]
fn read_errors_are_counted_and_the_task_goes_on() {
    let wire = api_frame(&receive_packet(MAV_SRC, LANDING_REQUEST), false);
    let steps = vec![
        Step::Bytes(wire[..5].to_vec()),
        Step::Error,
        Step::Bytes(wire[5..].to_vec()),
    ];
    let (out, stats) = run_script::<Mode1>(steps, 32, usize::MAX);
    assert_eq!(stats.read_errors, 1);
    assert_eq!(out, [startup(false), reply(ON_GROUND, false)].concat());
}

#[test]
fn invalid_packets_and_other_frames_get_no_reply() {
    let steps = vec![Step::Bytes(
        [
            api_frame(&receive_packet(MAV_SRC, b"x"), false), // not MCP
            api_frame(&[0x8A, 0x06], false),                  // modem status
            api_frame(&receive_packet(MAV_SRC, b"t\x01\0\0\0\0"), false), // telemetry, not a command
        ]
        .concat(),
    )];
    let (out, stats) = run_script::<Mode1>(steps, 32, usize::MAX);
    assert_eq!(out, startup(false));
    // No MCP packet, and telemetry: no command either way.
    assert_eq!(stats.invalid_packets, 2);
    assert_eq!(stats.other_frames, 1);
}

/// A read that holds a whole frame and the start of the next, a tick falling due while
/// the first is answered, the rest of the second after it: the tick gives up nothing
/// (bytes came since the tick before), and both commands are answered.
#[test]
fn a_frame_whose_rest_comes_after_a_tick_is_answered() {
    let first = api_frame(&receive_packet(MAV_SRC, LANDING_REQUEST), false);
    let second = api_frame(&receive_packet(MAV_SRC, b"c\x03\xff"), false);
    let mut chunk = first.clone();
    chunk.extend_from_slice(&second[..6]);
    let steps = vec![
        Step::Bytes(chunk),
        Step::Tick,
        Step::Bytes(second[6..].to_vec()),
        Step::Stop,
    ];
    let controllers = reply(b"r\x03\x01", false); // manual
    let (out, stats) = run_script::<Mode1>(steps, 32, usize::MAX);
    assert_eq!(
        out,
        [startup(false), reply(ON_GROUND, false), controllers].concat()
    );
    assert_eq!(stats.given_up, 0);
}
