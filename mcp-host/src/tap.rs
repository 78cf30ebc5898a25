//! The frames a link writes, read back from the bytes as they go out, for
//! [`CommandSender::tap_frames`](crate::CommandSender::tap_frames).

use std::time::SystemTime;

use xbee_api::{ApiMode, Decoder, MAX_FRAME_DATA_LEN};

use crate::record::{Direction, Record};
use crate::subscription::Subscribers;

/// The largest frame a link writes (a raw frame of any length the API allows) in
/// API mode 1, where the decoder holds the whole frame, delimiter to checksum.
const CAPACITY: usize = MAX_FRAME_DATA_LEN + 4;

/// Decodes the bytes written to one transport, once a subscription to the frames is
/// there: each frame written whole is published as [`Direction::Sent`], when its last
/// byte went out.
///
/// The written bytes are frames back to back, so decoding them from a frame's start
/// finds every frame, in either API mode. A subscription taken while a frame is part
/// written is served from the next frame's start: in API mode 2 the decoder starts at
/// once and finds it (no frame holds an unescaped start delimiter, the rest of the
/// frame part written is skipped); in mode 1, where a frame's data may hold what looks
/// like a frame, it starts only at a frame's start it knows, once every byte queued
/// has gone out.
pub(crate) struct SentFrames {
    mode: ApiMode,
    /// Holds a frame as its bytes go out (64 KiB): there only while a subscription
    /// wants the frames.
    decoder: Option<Box<Decoder<CAPACITY>>>,
    /// The next byte written begins a frame: every byte queued before it went out.
    at_frame_start: bool,
}

impl SentFrames {
    /// For a transport in `mode`, with nothing written to it yet.
    pub(crate) fn new(mode: ApiMode) -> Self {
        SentFrames {
            mode,
            decoder: None,
            at_frame_start: true,
        }
    }

    /// `written` went out; `rest` is what waits to be written after it.
    pub(crate) fn written(&mut self, written: &[u8], rest: &[u8], subscribers: &Subscribers) {
        if !subscribers.frames_wanted() {
            self.decoder = None;
        } else if self.decoder.is_none() && (self.at_frame_start || self.mode == ApiMode::Escaped) {
            self.decoder = Some(Box::new(Decoder::new(self.mode)));
        }
        if let Some(decoder) = &mut self.decoder {
            decoder.decode_each(written, |event| {
                // The link wrote frames it encoded itself: an error is not expected,
                // and has no frame to record.
                if let Ok(frame) = event {
                    subscribers.publish_frame(Record {
                        time: SystemTime::now(),
                        direction: Direction::Sent,
                        frame: frame.data().to_vec(),
                    });
                }
            });
        }
        self.at_frame_start = rest.is_empty();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use futures::StreamExt;
    use xbee_api::{EncodeFrame, Frame};

    /// `data`'s frame, encoded in `mode`.
    fn frame(mode: ApiMode, data: &[u8]) -> Vec<u8> {
        let frame = Frame::parse_bytes(data).unwrap();
        let mut bytes = vec![0; frame.encoded_len(mode)];
        let n = frame.encode(mode, &mut bytes).unwrap();
        bytes.truncate(n);
        bytes
    }

    /// The frames `tap` has now.
    fn taken(tap: &mut crate::Subscription<Record>) -> Vec<Vec<u8>> {
        std::iter::from_fn(|| futures::FutureExt::now_or_never(tap.next()).flatten())
            .map(|record| {
                assert_eq!(record.direction, Direction::Sent);
                record.frame
            })
            .collect()
    }

    #[test]
    fn a_tap_taken_part_way_through_a_frame_starts_at_a_frame_it_can_tell() {
        // Frames whose data hold a start delimiter: an AT command's parameter.
        let data = [
            [0x08, 0x01, b'N', b'I', 0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F],
            [0x08, 0x02, b'N', b'I', 0x7E, 0x7D, 0x11, 0x13, 0x00, 0x00],
            [0x08, 0x03, b'N', b'I', 0x00, 0x01, 0x02, 0x03, 0x04, 0x05],
        ];
        for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
            let subscribers = Subscribers::new(16);
            let mut sent = SentFrames::new(mode);
            let frames: Vec<Vec<u8>> = data.iter().map(|d| frame(mode, d)).collect();
            let all = frames.concat();
            // The first frame is part written when the tap is taken; the queue empties
            // only after the second.
            let (first, second) = (frames[0].len(), frames[1].len());
            sent.written(&all[..5], &all[5..], &subscribers);
            let mut tap = subscribers.tap_frames();
            sent.written(&all[5..first + 3], &all[first + 3..], &subscribers);
            sent.written(
                &all[first + 3..first + second],
                &all[first + second..],
                &subscribers,
            );
            sent.written(&all[first + second..], &[], &subscribers);
            let expected: &[&[u8]] = match mode {
                // Not the first frame's tail, which holds a whole frame of its own.
                ApiMode::Escaped => &[&data[1], &data[2]],
                // From the first frame's start after the queue emptied.
                ApiMode::Unescaped => &[],
            };
            assert_eq!(taken(&mut tap), expected, "{mode:?}");
            // Once the queue is empty, every frame after it.
            sent.written(&frames[2], &[], &subscribers);
            sent.written(&frames[0], &[], &subscribers);
            assert_eq!(taken(&mut tap), [&data[2][..], &data[0]], "{mode:?}");
            // Dropped, the tap costs nothing: the decoder goes.
            drop(tap);
            sent.written(&frames[1], &[], &subscribers);
            assert!(sent.decoder.is_none());
        }
    }
}
