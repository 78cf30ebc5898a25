//! Every measured loop finds in its stream exactly what the generator put there, and
//! the MAVLink stream is what the `mavlink` crate reads.

use perf::run::{run_fifo, run_floor, run_pipeline, run_pipeline_push, run_push, run_slice};
use perf::{Totals, VALUES_PER_PACKET, mavlink_stream, mcp_stream};
use xbee_api::ApiMode;

#[path = "../benches/common/mavlink_run.rs"]
mod mavlink_run;

const BYTES: usize = 64 * 1024;

fn frames_only(t: Totals) -> Totals {
    Totals {
        values: 0,
        sum: 0.0,
        ..t
    }
}

#[test]
fn decoders_find_every_frame_and_value() {
    for mode in [ApiMode::Escaped, ApiMode::Unescaped] {
        let stream = mcp_stream(mode, BYTES);
        let expected = stream.totals;
        assert!(stream.bytes.len() >= BYTES);
        assert_eq!(expected.values, expected.frames * VALUES_PER_PACKET);
        assert_eq!(
            run_slice(&stream.bytes, mode),
            frames_only(expected),
            "{mode:?}"
        );
        assert_eq!(
            run_push(&stream.bytes, mode),
            frames_only(expected),
            "{mode:?}"
        );
        for chunk in [1, 3, 8, 16, 17, 64] {
            assert_eq!(
                run_fifo(&stream.bytes, mode, chunk),
                frames_only(expected),
                "{mode:?} in chunks of {chunk}"
            );
        }
        assert_eq!(run_pipeline(&stream.bytes, mode), expected, "{mode:?}");
        assert_eq!(run_pipeline_push(&stream.bytes, mode), expected, "{mode:?}");
    }
}

#[test]
fn floors_split_streams_into_the_frames_the_decoder_finds() {
    for mode in [ApiMode::Escaped, ApiMode::Unescaped] {
        let stream = mcp_stream(mode, BYTES);
        assert_eq!(
            run_floor(&stream.bytes, mode),
            frames_only(stream.totals),
            "{mode:?}"
        );
    }
}

#[test]
fn mode_2_stream_has_escapes_and_mode_1_none() {
    let escaped = mcp_stream(ApiMode::Escaped, BYTES);
    let plain = mcp_stream(ApiMode::Unescaped, BYTES);
    assert_eq!(plain.bytes.len(), plain.totals.frames * 57);
    // The same packets, some longer for their escapes.
    assert!(escaped.totals.frames < plain.totals.frames);
    assert_eq!(escaped.bytes.get(..3), Some(&[0x7E, 0x00, 0x35][..]));
    assert!(escaped.bytes.contains(&0x7D));
}

#[test]
fn mavlink_crate_reads_the_generated_stream() {
    let xbee = mcp_stream(ApiMode::Escaped, BYTES);
    let stream = mavlink_stream(xbee.totals.values);
    assert!(stream.totals.values >= xbee.totals.values);
    assert!(stream.totals.values < xbee.totals.values + perf::ATTITUDE_VALUES);
    let got = mavlink_run::run_mavlink(&stream.bytes);
    assert_eq!(
        got,
        Totals {
            data_bytes: 0,
            ..stream.totals
        }
    );
}

#[test]
fn mavlink_checksum_rejects_a_flipped_byte() {
    let mut stream = mavlink_stream(12);
    stream.bytes[12] ^= 0x01;
    let got = mavlink_run::run_mavlink(&stream.bytes);
    assert_eq!(got.frames, 1);
}
