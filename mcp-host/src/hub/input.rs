//! How the hub reads a client's bytes: as it reads the radio's, frame by frame with its
//! [`LinkOptions`](crate::LinkOptions), and with the bytes that begin no frame told as
//! they are skipped. A radio skips them without a word too, but a client that sends
//! them (text typed into `nc`, a program in transparent mode) hears nothing back and
//! waits for answers that never come: the hub says so.

use std::time::Duration;

use bytes::BytesMut;
use tokio_util::codec::Decoder;
use xbee_api::ApiMode;

use crate::codec::{CodecItem, XBeeCodec};

/// How the hub reads its clients' frames: as it reads the radio's, with its
/// [`LinkOptions`](crate::LinkOptions).
#[derive(Debug, Clone, Copy)]
pub(super) struct ClientInput {
    /// Frames longer than this ([`LinkOptions::max_frame_len`](crate::LinkOptions::max_frame_len))
    /// are refused as soon as their length is read.
    pub(super) max_frame_len: usize,
    /// API mode 1: a partial frame that gets no new byte for this long is given up,
    /// and the bytes after its start delimiter scanned again
    /// ([`LinkOptions::partial_frame_timeout`](crate::LinkOptions::partial_frame_timeout)).
    pub(super) partial_frame_timeout: Option<Duration>,
}

/// What [`ClientCodec`] yields.
#[derive(Debug)]
pub(super) enum ClientItem {
    /// A frame, or a candidate frame dropped, as the radio's link reads them.
    Codec(CodecItem),
    /// More bytes that began no frame, skipped.
    Skipped {
        /// How many.
        bytes: u64,
        /// Whether they came after a candidate frame was dropped, with no frame since:
        /// in API mode 1 the bytes of a dropped candidate are scanned again for a
        /// start delimiter, and count as skipped if they hold none, so that such bytes
        /// may be the rest of a frame, already said as dropped, rather than bytes that
        /// never looked like one.
        after_error: bool,
    },
}

/// The [`XBeeCodec`] of a client's connection, which also yields the bytes it skipped
/// (outside any frame, before a start delimiter) as they are skipped, rather than
/// reading on without a word.
#[derive(Debug)]
pub(super) struct ClientCodec {
    codec: XBeeCodec,
    /// The codec's skipped bytes already yielded.
    skipped: u64,
    /// Whether a candidate frame was dropped, with no frame since.
    after_error: bool,
}

impl ClientCodec {
    /// A codec for a client of a hub in `mode`, reading as `input` says.
    pub(super) fn new(mode: ApiMode, input: ClientInput) -> Self {
        ClientCodec {
            codec: XBeeCodec::with_counters(mode, input.max_frame_len, Default::default()),
            skipped: 0,
            after_error: false,
        }
    }

    /// The frame codec.
    pub(super) fn codec(&self) -> &XBeeCodec {
        &self.codec
    }

    /// The frame codec, to give up a partial frame.
    pub(super) fn codec_mut(&mut self) -> &mut XBeeCodec {
        &mut self.codec
    }

    /// The bytes skipped since they were last yielded, if any.
    fn newly_skipped(&mut self) -> Option<ClientItem> {
        let skipped = self.codec.stats().bytes_skipped;
        let new = skipped.checked_sub(self.skipped).filter(|&new| new > 0)?;
        self.skipped = skipped;
        Some(ClientItem::Skipped {
            bytes: new,
            after_error: self.after_error,
        })
    }

    /// `item` of the codec, or bytes it skipped (those skipped before a frame are
    /// yielded after it, at the next call).
    fn next(&mut self, item: Option<CodecItem>) -> Option<ClientItem> {
        match item {
            Some(item) => {
                self.after_error = matches!(item, CodecItem::Error(_));
                Some(ClientItem::Codec(item))
            }
            None => self.newly_skipped(),
        }
    }
}

impl Decoder for ClientCodec {
    type Item = ClientItem;
    type Error = std::io::Error;

    fn decode(&mut self, src: &mut BytesMut) -> Result<Option<ClientItem>, std::io::Error> {
        if let Some(skipped) = self.newly_skipped() {
            return Ok(Some(skipped));
        }
        let item = self.codec.decode(src)?;
        Ok(self.next(item))
    }

    fn decode_eof(&mut self, src: &mut BytesMut) -> Result<Option<ClientItem>, std::io::Error> {
        if let Some(skipped) = self.newly_skipped() {
            return Ok(Some(skipped));
        }
        let item = self.codec.decode_eof(src)?;
        Ok(self.next(item))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn codec() -> ClientCodec {
        let input = ClientInput {
            max_frame_len: 256,
            partial_frame_timeout: None,
        };
        ClientCodec::new(ApiMode::Unescaped, input)
    }

    fn items(codec: &mut ClientCodec, bytes: &[u8], eof: bool) -> Vec<String> {
        let mut buf = BytesMut::from(bytes);
        let mut items = Vec::new();
        loop {
            let item = if eof {
                codec.decode_eof(&mut buf)
            } else {
                codec.decode(&mut buf)
            };
            match item.unwrap() {
                Some(ClientItem::Skipped { bytes, after_error }) => {
                    items.push(format!(
                        "skipped {bytes}{}",
                        ["", " after an error"][usize::from(after_error)]
                    ));
                }
                Some(ClientItem::Codec(CodecItem::Frame(f))) => {
                    items.push(format!("frame {:02x?}", &f.data()[..]));
                }
                Some(ClientItem::Codec(CodecItem::Error(e))) => items.push(format!("error {e}")),
                None => return items,
            }
        }
    }

    #[test]
    fn bytes_that_begin_no_frame_are_yielded_as_they_are_skipped() {
        let mut codec = codec();
        // Text alone: nothing else would come of it.
        assert_eq!(items(&mut codec, b"hello\n", false), ["skipped 6"]);
        // Text, a Modem Status frame, more text: each in its turn, counted once.
        let mut bytes = b"AT".to_vec();
        bytes.extend([0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F]);
        bytes.extend(b"ok");
        assert_eq!(
            items(&mut codec, &bytes, false),
            ["frame [8a, 06]", "skipped 2", "skipped 2"]
        );
        assert_eq!(items(&mut codec, b"!", true), ["skipped 1"]);
        assert_eq!(codec.codec().stats().bytes_skipped, 11);
    }

    #[test]
    fn bytes_of_a_dropped_candidate_scanned_again_are_skipped_after_an_error() {
        let mut codec = codec();
        // `AT AP` with its checksum off by one, then text: all after the error, until a
        // frame comes.
        let mut bytes = vec![0x7E, 0x00, 0x04, 0x08, 0x01, b'A', b'P', 0x66];
        bytes.extend(b"hello");
        assert_eq!(
            items(&mut codec, &bytes, false),
            [
                "error bad checksum: computed 0x65, received 0x66",
                "skipped 12 after an error"
            ]
        );
        let mut bytes = vec![0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];
        bytes.extend(b"hello");
        assert_eq!(
            items(&mut codec, &bytes, false),
            ["frame [8a, 06]", "skipped 5"]
        );
    }

    #[test]
    fn frames_alone_yield_no_skipped_bytes() {
        let mut codec = codec();
        let frame = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];
        assert_eq!(
            items(&mut codec, &[frame, frame].concat(), false),
            ["frame [8a, 06]", "frame [8a, 06]"]
        );
        assert_eq!(items(&mut codec, &[], true), Vec::<String>::new());
    }
}
