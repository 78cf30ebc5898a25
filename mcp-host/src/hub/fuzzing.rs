//! The hub's reading of a client's bytes, for the fuzz targets (feature `fuzzing`):
//! its `ClientCodec` and the checks it makes of a client's frame before it
//! goes to the radio. Not an API: it may change with any release.

use bytes::BytesMut;
use xbee_api::ApiMode;

use crate::codec::CodecItem;

/// What [`ClientCodec`] yields (the hub's `ClientItem`).
#[derive(Debug)]
pub enum ClientItem {
    /// A frame, or a candidate frame dropped.
    Codec(CodecItem),
    /// Bytes that began no frame, skipped.
    Skipped {
        /// How many.
        bytes: u64,
        /// Whether they came after a candidate frame was dropped.
        after_error: bool,
    },
}

impl From<super::input::ClientItem> for ClientItem {
    fn from(item: super::input::ClientItem) -> Self {
        match item {
            super::input::ClientItem::Codec(item) => ClientItem::Codec(item),
            super::input::ClientItem::Skipped { bytes, after_error } => {
                ClientItem::Skipped { bytes, after_error }
            }
        }
    }
}

/// The hub's codec of a client's connection.
#[derive(Debug)]
pub struct ClientCodec(super::input::ClientCodec);

impl ClientCodec {
    /// A client's codec of a hub in `mode` taking frames up to `max_frame_len`.
    pub fn new(mode: ApiMode, max_frame_len: usize) -> Self {
        ClientCodec(super::input::ClientCodec::new(
            mode,
            super::input::ClientInput {
                max_frame_len,
                partial_frame_timeout: None,
            },
        ))
    }

    /// `tokio_util::codec::Decoder::decode`.
    pub fn decode(&mut self, src: &mut BytesMut) -> std::io::Result<Option<ClientItem>> {
        tokio_util::codec::Decoder::decode(&mut self.0, src).map(|i| i.map(Into::into))
    }

    /// `tokio_util::codec::Decoder::decode_eof`.
    pub fn decode_eof(&mut self, src: &mut BytesMut) -> std::io::Result<Option<ClientItem>> {
        tokio_util::codec::Decoder::decode_eof(&mut self.0, src).map(|i| i.map(Into::into))
    }

    /// Gives up the partial frame, as the hub does when it goes stale.
    pub fn drop_partial(&mut self) -> Vec<ClientItem> {
        self.0.drop_partial().into_iter().map(Into::into).collect()
    }

    /// The codec's counters.
    pub fn stats(&self) -> crate::Stats {
        self.0.codec().stats()
    }

    /// Whether a partial frame is pending.
    pub fn partial(&self) -> bool {
        self.0.codec().partial_since().is_some()
    }
}

/// What the hub reads of a client's frame (frame data) before it goes to the
/// radio: its AT command, whether it is answered many times, whether it is a
/// whole request, and the answer given if it is not sent.
#[derive(Debug)]
pub struct Admit {
    /// `at_command`.
    pub at_command: Option<[u8; 2]>,
    /// `answered_many_times`.
    pub answered_many_times: bool,
    /// `is_whole_request`.
    pub is_whole_request: bool,
    /// `xbee_api::frame::frame_type::answer_type` of its type.
    pub answer_type: Option<u8>,
    /// `not_sent_answer`, and it encoded in each mode.
    pub not_sent_answer: Option<(Vec<u8>, Option<bytes::Bytes>, Option<bytes::Bytes>)>,
}

/// The hub's checks of a client's frame data.
pub fn admit(data: &[u8]) -> Admit {
    Admit {
        at_command: super::request::at_command(data),
        answered_many_times: super::request::answered_many_times(data),
        is_whole_request: super::request::is_whole_request(data),
        answer_type: data
            .first()
            .and_then(|&t| xbee_api::frame::frame_type::answer_type(t)),
        not_sent_answer: super::request::not_sent_answer(data).map(|answer| {
            let m1 = super::encode(&answer, ApiMode::Unescaped);
            let m2 = super::encode(&answer, ApiMode::Escaped);
            (answer, m1, m2)
        }),
    }
}
