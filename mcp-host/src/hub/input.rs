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
/// reading on without a word; each time ahead of the item the codec found after them.
#[derive(Debug)]
pub(super) struct ClientCodec {
    codec: XBeeCodec,
    /// The codec's skipped bytes already yielded.
    skipped: u64,
    /// Whether the last item yielded was a candidate frame dropped.
    after_error: bool,
    /// The codec's item found after bytes it skipped, yielded after them.
    next: Option<CodecItem>,
}

impl ClientCodec {
    /// A codec for a client of a hub in `mode`, reading as `input` says.
    pub(super) fn new(mode: ApiMode, input: ClientInput) -> Self {
        ClientCodec {
            codec: XBeeCodec::with_counters(mode, input.max_frame_len, Default::default()),
            skipped: 0,
            after_error: false,
            next: None,
        }
    }

    /// The frame codec.
    pub(super) fn codec(&self) -> &XBeeCodec {
        &self.codec
    }

    /// Gives up on the partial frame ([`XBeeCodec::drop_partial`]): its error, then what
    /// the bytes after its start delimiter hold, the bytes skipped among them yielded
    /// last, after the error.
    pub(super) fn drop_partial(&mut self) -> Vec<ClientItem> {
        let mut items: Vec<ClientItem> = self
            .next
            .take()
            .map(ClientItem::Codec)
            .into_iter()
            .collect();
        let dropped = self.codec.drop_partial();
        let after_error = self.after_error || !dropped.is_empty();
        items.extend(dropped.into_iter().map(ClientItem::Codec));
        items.extend(self.newly_skipped(after_error));
        // The bytes it held are all scanned: those that come next are new.
        self.after_error = false;
        items
    }

    /// The bytes skipped since they were last yielded, if any, said to have come
    /// `after_error` or not.
    fn newly_skipped(&mut self, after_error: bool) -> Option<ClientItem> {
        let skipped = self.codec.stats().bytes_skipped;
        let new = skipped.checked_sub(self.skipped).filter(|&new| new > 0)?;
        self.skipped = skipped;
        Some(ClientItem::Skipped {
            bytes: new,
            after_error,
        })
    }

    /// What a call of the codec that gave `item` yields: the bytes it skipped first (they
    /// came before `item`, and after the last item yielded), `item` held for the next
    /// call; else `item`.
    fn take(&mut self, item: Option<CodecItem>) -> Option<ClientItem> {
        let skipped = self.newly_skipped(self.after_error);
        if let Some(item) = &item {
            self.after_error = matches!(item, CodecItem::Error(_));
        }
        match skipped {
            Some(skipped) => {
                self.next = item;
                Some(skipped)
            }
            None => item.map(ClientItem::Codec),
        }
    }
}

impl Decoder for ClientCodec {
    type Item = ClientItem;
    type Error = std::io::Error;

    fn decode(&mut self, src: &mut BytesMut) -> Result<Option<ClientItem>, std::io::Error> {
        if let Some(item) = self.next.take() {
            return Ok(Some(ClientItem::Codec(item)));
        }
        let item = self.codec.decode(src)?;
        Ok(self.take(item))
    }

    fn decode_eof(&mut self, src: &mut BytesMut) -> Result<Option<ClientItem>, std::io::Error> {
        if let Some(item) = self.next.take() {
            return Ok(Some(ClientItem::Codec(item)));
        }
        let item = self.codec.decode_eof(src)?;
        Ok(self.take(item))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn codec() -> ClientCodec {
        codec_of(ApiMode::Unescaped, 256)
    }

    fn codec_of(mode: ApiMode, max_frame_len: usize) -> ClientCodec {
        let input = ClientInput {
            max_frame_len,
            partial_frame_timeout: None,
        };
        ClientCodec::new(mode, input)
    }

    fn said(item: ClientItem) -> String {
        match item {
            ClientItem::Skipped { bytes, after_error } => format!(
                "skipped {bytes}{}",
                ["", " after an error"][usize::from(after_error)]
            ),
            ClientItem::Codec(CodecItem::Frame(f)) => format!("frame {:02x?}", &f.data()[..]),
            ClientItem::Codec(CodecItem::Error(e)) => format!("error {e}"),
        }
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
                Some(item) => items.push(said(item)),
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
        bytes.extend(MODEM_STATUS);
        bytes.extend(b"ok");
        assert_eq!(
            items(&mut codec, &bytes, false),
            ["skipped 2", "frame [8a, 06]", "skipped 2"]
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

    const MODEM_STATUS: [u8; 6] = [0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F];

    #[test]
    fn the_rest_of_a_dropped_candidate_is_skipped_after_its_error_and_before_the_next_frame() {
        // Mode 1: `AT AP` with its checksum off by one, then a frame, in one read: the
        // candidate's bytes scanned again come between the two.
        let mut codec = codec();
        let mut bytes = vec![0x7E, 0x00, 0x04, 0x08, 0x01, b'A', b'P', 0x66];
        bytes.extend(MODEM_STATUS);
        assert_eq!(
            items(&mut codec, &bytes, false),
            [
                "error bad checksum: computed 0x65, received 0x66",
                "skipped 7 after an error",
                "frame [8a, 06]"
            ]
        );
        // Mode 2: a frame longer than the hub takes, then a frame.
        let mut codec = codec_of(ApiMode::Escaped, 4);
        let mut bytes = vec![0x7E, 0x00, 0x06, 0x10, 0x01, 1, 2, 3, 4, 0xD9];
        bytes.extend(MODEM_STATUS);
        let said = items(&mut codec, &bytes, false);
        assert_eq!(said.len(), 3, "{said:?}");
        assert!(said[0].starts_with("error "), "{said:?}");
        assert!(said[1].ends_with(" after an error"), "{said:?}");
        assert_eq!(said[2], "frame [8a, 06]");
    }

    #[test]
    fn text_before_a_dropped_candidate_is_skipped_before_its_error() {
        let mut codec = codec();
        let mut bytes = b"hello".to_vec();
        bytes.extend([0x7E, 0x00, 0x04, 0x08, 0x01, b'A', b'P', 0x66]);
        let said = items(&mut codec, &bytes, false);
        assert_eq!(
            said[..2],
            [
                "skipped 5",
                "error bad checksum: computed 0x65, received 0x66"
            ]
        );
        assert!(
            said[2..].iter().all(|s| s.ends_with(" after an error")),
            "{said:?}"
        );
    }

    #[test]
    fn a_partial_frame_given_up_is_its_error_then_its_bytes_skipped() {
        let mut codec = codec();
        assert_eq!(
            items(
                &mut codec,
                &[0x7E, 0x00, 0x10, 0x08, 0x01, b'A', b'P'],
                false
            ),
            Vec::<String>::new()
        );
        let said: Vec<String> = codec.drop_partial().into_iter().map(said).collect();
        assert_eq!(said.len(), 2, "{said:?}");
        assert!(said[0].starts_with("error "), "{said:?}");
        assert_eq!(said[1], "skipped 6 after an error");
        // Text after it is said as text.
        assert_eq!(items(&mut codec, b"hi", false), ["skipped 2"]);
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
