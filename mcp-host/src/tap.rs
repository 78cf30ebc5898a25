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
/// once and finds it (no frame holds an unescaped start delimiter; the rest of the
/// frame part written is skipped); in mode 1, where a frame's data may hold what looks
/// like a frame, the frames' lengths are followed from the first byte (cheaply: no
/// byte is copied), and the decoder starts where the next frame does.
pub(crate) struct SentFrames {
    mode: ApiMode,
    /// Holds a frame as its bytes go out (64 KiB): there only while a subscription
    /// wants the frames.
    decoder: Option<Box<Decoder<CAPACITY>>>,
    /// Mode 1: where the frames written begin.
    starts: FrameStarts,
}

impl SentFrames {
    /// For a transport in `mode`, with nothing written to it yet.
    pub(crate) fn new(mode: ApiMode) -> Self {
        SentFrames {
            mode,
            decoder: None,
            starts: FrameStarts::default(),
        }
    }

    /// `written` went out.
    pub(crate) fn written(&mut self, written: &[u8], subscribers: &Subscribers) {
        let next_start = match self.mode {
            ApiMode::Unescaped => self.starts.first_start(written),
            ApiMode::Escaped => Some(0),
        };
        let from = if !subscribers.frames_wanted() {
            self.decoder = None;
            return;
        } else if self.decoder.is_some() {
            0
        } else if let Some(start) = next_start {
            self.decoder = Some(Box::new(Decoder::new(self.mode)));
            start
        } else {
            return;
        };
        if let Some(decoder) = &mut self.decoder {
            decoder.decode_each(&written[from..], |event| {
                // The link wrote frames it encoded itself: an error is not expected,
                // and has no frame to record.
                if let Ok(frame) = event {
                    subscribers.publish_frame(|| Record {
                        time: SystemTime::now(),
                        direction: Direction::Sent,
                        frame: frame.data().to_vec(),
                    });
                }
            });
        }
    }
}

/// Where an API mode 1 stream of whole frames is: `7E`, the length (two bytes), that many
/// bytes of frame data and the checksum.
#[derive(Debug, Default)]
struct FrameStarts {
    /// Bytes of the current frame's header read: 0 at a frame's start (when `left` is
    /// 0 too), 1 after its delimiter, 2 after the length's first byte.
    header: u8,
    /// The length's first byte.
    length_high: u8,
    /// Bytes of the current frame's data and checksum still to come.
    left: usize,
}

impl FrameStarts {
    /// Follows `bytes`, the next of the stream; where the first frame to begin in them
    /// begins, if one does.
    fn first_start(&mut self, bytes: &[u8]) -> Option<usize> {
        let mut first = None;
        let mut at = 0;
        while at < bytes.len() {
            if self.left > 0 {
                let skipped = self.left.min(bytes.len() - at);
                self.left -= skipped;
                at += skipped;
                continue;
            }
            match self.header {
                0 => {
                    first.get_or_insert(at);
                    self.header = 1;
                }
                1 => {
                    self.length_high = bytes[at];
                    self.header = 2;
                }
                _ => {
                    self.left = usize::from(u16::from_be_bytes([self.length_high, bytes[at]])) + 1;
                    self.header = 0;
                }
            }
            at += 1;
        }
        first
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
    fn a_tap_taken_part_way_through_a_frame_starts_at_the_next_frame() {
        // Frames whose data hold a start delimiter, and a whole frame in mode 1: an AT
        // command's parameter.
        let data = [
            [0x08, 0x01, b'N', b'I', 0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F],
            [0x08, 0x02, b'N', b'I', 0x7E, 0x7D, 0x11, 0x13, 0x00, 0x00],
            [0x08, 0x03, b'N', b'I', 0x00, 0x01, 0x02, 0x03, 0x04, 0x05],
        ];
        for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
            let subscribers = Subscribers::new(16);
            let mut sent = SentFrames::new(mode);
            let frames: Vec<Vec<u8>> = data.iter().map(|d| frame(mode, d)).collect();
            // Writes that never end at a frame's end: the queue never empties.
            let all = frames.concat().repeat(3);
            let first = frames[0].len();
            sent.written(&all[..5], &subscribers);
            let mut tap = subscribers.tap_frames();
            let mut at = 5;
            for piece in all[5..].chunks(7) {
                sent.written(piece, &subscribers);
                at += piece.len();
            }
            assert_eq!(at, all.len());
            // Not the first frame's tail, which holds a whole frame of its own: every
            // frame from the second on.
            let mut expected: Vec<&[u8]> = vec![&data[1], &data[2]];
            for _ in 0..2 {
                expected.extend(data.iter().map(|d| &d[..]));
            }
            assert_eq!(taken(&mut tap), expected, "{mode:?}");
            assert!(first > 5);
            // Dropped, the tap costs nothing: the decoder goes; taken again, it starts
            // at the next frame.
            drop(tap);
            sent.written(&frames[0][..3], &subscribers);
            assert!(sent.decoder.is_none());
            let mut tap = subscribers.tap_frames();
            sent.written(&frames[0][3..], &subscribers);
            sent.written(&frames[1], &subscribers);
            assert_eq!(taken(&mut tap), [&data[1][..]], "{mode:?}");
        }
    }
}
