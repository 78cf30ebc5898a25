//! Framing: a tokio-util [`Decoder`]/[`Encoder`] for XBee API frames over
//! [`xbee_api::Decoder`].
//!
//! A corrupt frame never ends the stream (an `Err` from a codec would end a framed stream
//! for good): it comes out as [`CodecItem::Error`], is counted and logged, and decoding
//! resumes at the next start delimiter.

use std::sync::Arc;
use std::time::Duration;

use tokio::time::Instant;

use bytes::{Buf, Bytes, BytesMut};
use tokio_util::codec::{Decoder, Encoder};
use xbee_api::{ApiMode, DecodeError, EncodeFrame};

use crate::event::OwnedFrame;
use crate::stats::Counters;

/// Largest frame data length the codec can accept (mode 2; 4 less in mode 1): the
/// capacity of the underlying decoder, well above the ~273 bytes a radio sends.
pub const MAX_FRAME_DATA: usize = xbee_api::DEFAULT_CAPACITY;

/// Largest frame data (frame type byte included) of a request a ground station or a
/// device writes to its radio, 275 bytes: an Explicit Addressing Command (0x11), 20
/// bytes of fixed fields, with the longest payload a radio carries (255 bytes,
/// fragmented: [`mcp_core::MAX_PAYLOAD`]). The other requests are shorter: a Transmit
/// Request (0x10) with that payload takes 269 bytes, an AT Command (0x08, 0x09) 4 bytes
/// and its parameter, a Remote AT Command (0x17) 15 (a radio's parameters run to a
/// 20-character node identifier or a 32-byte key), and so is every frame a Zigbee or
/// DigiMesh radio sends (at most 273 bytes: an Explicit Rx Indicator with that payload;
/// the IPv4 frames of Wi-Fi and Cellular modules, 0x20 and 0xB0, run longer, and need a
/// larger limit). The devices of a
/// virtual [`Network`](crate::radio::Network) are read with this limit, and a
/// [`Hub`](crate::hub::Hub) open to untrusted clients should be given it as its
/// [`LinkOptions::max_frame_len`](crate::LinkOptions::max_frame_len): in API mode 1 a
/// longer length field is then dropped as oversize at once, rather than costing a
/// rescan of as many bytes (see the `Worst case` of [`xbee_api::Decoder`]).
pub const MAX_REQUEST_DATA: usize =
    xbee_api::frame::explicit_addressing_command::field::HEADER_LEN + mcp_core::MAX_PAYLOAD;

/// What the codec yields.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum CodecItem {
    /// A frame with a good checksum.
    Frame(OwnedFrame),
    /// A candidate frame was dropped; decoding goes on.
    Error(DecodeError),
}

/// The XBee API frame codec, for one API mode.
///
/// Decoding yields [`CodecItem`]s and never fails except on I/O errors; encoding writes
/// any [`EncodeFrame`] (typed frame reprs of `xbee-api`, or a [`xbee_api::RawFrame`]).
///
/// ```
/// use mcp_host::bytes::BytesMut;
/// use mcp_host::codec::{CodecItem, XBeeCodec};
/// use mcp_host::tokio_util::codec::Decoder;
/// use mcp_host::xbee_api::ApiMode;
///
/// let mut codec = XBeeCodec::new(ApiMode::Unescaped);
/// // Garbage, a frame with a bad checksum, then a Modem Status frame.
/// let mut buf = BytesMut::from(&[0x01, 0x7E, 0x00, 0x02, 0x8A, 0x06, 0x00,
///                                0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F][..]);
/// assert!(matches!(codec.decode(&mut buf)?, Some(CodecItem::Error(_))));
/// match codec.decode(&mut buf)? {
///     Some(CodecItem::Frame(frame)) => assert_eq!(&frame.data()[..], [0x8A, 0x06]),
///     other => panic!("{other:?}"),
/// }
/// assert_eq!(codec.stats().bad_checksum, 1);
/// # Ok::<(), std::io::Error>(())
/// ```
#[derive(Debug)]
pub struct XBeeCodec {
    decoder: Box<xbee_api::Decoder>,
    mode: ApiMode,
    counters: Arc<Counters>,
    seen: xbee_api::DecoderStats,
    /// When `decode` last got bytes.
    last_input: Instant,
}

impl XBeeCodec {
    /// A codec for `mode` accepting frames up to [`MAX_FRAME_DATA`].
    pub fn new(mode: ApiMode) -> Self {
        Self::with_counters(mode, MAX_FRAME_DATA, Arc::default())
    }

    pub(crate) fn with_counters(
        mode: ApiMode,
        max_frame_len: usize,
        counters: Arc<Counters>,
    ) -> Self {
        XBeeCodec {
            // The limit applies at the length field, so that in mode 1 a frame over it is
            // scanned again like any failed candidate and no frame inside it is lost.
            decoder: Box::new(xbee_api::Decoder::with_max_len(mode, max_frame_len)),
            mode,
            counters,
            seen: xbee_api::DecoderStats::default(),
            last_input: Instant::now(),
        }
    }

    /// When the bytes of a partial frame last came in; `None` between frames. (After
    /// `decode` returns `None`, nothing but a partial frame can be pending.)
    pub fn partial_since(&self) -> Option<Instant> {
        (!self.decoder.is_idle()).then_some(self.last_input)
    }

    /// Gives up on the partial frame, as at the end of input: its error (truncated)
    /// and, in API mode 1, what the bytes after its start delimiter hold (frames,
    /// errors; a new partial frame among them stays pending). For a link that has gone
    /// quiet: in mode 1 a stray 0x7E can hold back the frames behind it until its
    /// length is reached.
    ///
    /// ```
    /// use mcp_host::bytes::BytesMut;
    /// use mcp_host::codec::{CodecItem, XBeeCodec};
    /// use mcp_host::tokio_util::codec::Decoder;
    /// use mcp_host::xbee_api::ApiMode;
    ///
    /// let mut codec = XBeeCodec::new(ApiMode::Unescaped);
    /// // A stray 0x7E and length, then a whole Modem Status frame.
    /// let mut buf = BytesMut::from(&[0x7E, 0x00, 0xFF, 0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F][..]);
    /// assert_eq!(codec.decode(&mut buf)?, None);
    /// assert!(codec.partial_since().is_some());
    /// let items = codec.drop_partial();
    /// assert!(matches!(items[0], CodecItem::Error(mcp_host::xbee_api::DecodeError::Truncated { .. })));
    /// assert!(matches!(&items[1], CodecItem::Frame(f) if f.data()[..] == [0x8A, 0x06]));
    /// assert_eq!(codec.partial_since(), None);
    /// # Ok::<(), std::io::Error>(())
    /// ```
    pub fn drop_partial(&mut self) -> Vec<CodecItem> {
        let mut items = Vec::new();
        // `finish` once drops the partial frame; `poll` then delivers the rescan
        // without ending a new partial frame as `finish` would.
        let mut next = convert(self.decoder.finish());
        while let Some(item) = self.account(next) {
            items.push(item);
            next = convert(self.decoder.poll());
        }
        items
    }

    /// When a reader that gives up a partial frame after `timeout` without a new byte
    /// (API mode 1 only, as [`drop_partial`](Self::drop_partial) explains) is to look at
    /// it next: when it goes stale or, with none pending, `timeout` from now (the bytes
    /// of a partial frame come in without an item to wake the reader). `None` in mode 2
    /// or without a timeout.
    pub(crate) fn stale_check_at(&self, timeout: Option<Duration>) -> Option<Instant> {
        let timeout = timeout.filter(|_| self.mode == ApiMode::Unescaped)?;
        let since = self.partial_since().unwrap_or_else(Instant::now);
        Some(crate::options::later(since, timeout))
    }

    /// Whether a partial frame is pending that has had no new byte for `timeout` at
    /// `now` (API mode 1 only).
    pub(crate) fn is_stale(&self, timeout: Option<Duration>, now: Instant) -> bool {
        let Some(timeout) = timeout.filter(|_| self.mode == ApiMode::Unescaped) else {
            return false;
        };
        self.partial_since()
            .is_some_and(|since| crate::options::later(since, timeout) <= now)
    }

    /// The API mode.
    pub fn mode(&self) -> ApiMode {
        self.mode
    }

    /// Counters of this codec (frames, errors by kind, bytes skipped).
    pub fn stats(&self) -> crate::Stats {
        self.counters.snapshot()
    }

    /// Copies the decoder's counters that moved into the shared ones.
    fn sync_counters(&mut self) {
        let now = *self.decoder.stats();
        self.counters
            .add_all(&crate::Stats::decoder_since(&now, &self.seen));
        self.seen = now;
    }

    /// Updates the counters for `item` and logs it.
    fn account(&mut self, item: Option<CodecItem>) -> Option<CodecItem> {
        self.sync_counters();
        if let Some(CodecItem::Error(error)) = &item {
            tracing::debug!(%error, "frame dropped");
        }
        item
    }
}

fn convert(event: Option<xbee_api::DecodeEvent<'_>>) -> Option<CodecItem> {
    Some(match event? {
        Ok(frame) => match OwnedFrame::new(Bytes::copy_from_slice(frame.data())) {
            Some(frame) => CodecItem::Frame(frame),
            None => CodecItem::Error(DecodeError::EmptyFrame),
        },
        Err(error) => CodecItem::Error(error),
    })
}

impl Decoder for XBeeCodec {
    type Item = CodecItem;
    type Error = std::io::Error;

    fn decode(&mut self, src: &mut BytesMut) -> Result<Option<CodecItem>, std::io::Error> {
        if !src.is_empty() {
            self.last_input = Instant::now();
        }
        let (consumed, event) = self.decoder.decode(&src[..]);
        let item = convert(event);
        src.advance(consumed);
        Ok(self.account(item))
    }

    fn decode_eof(&mut self, src: &mut BytesMut) -> Result<Option<CodecItem>, std::io::Error> {
        if let Some(item) = self.decode(src)? {
            return Ok(Some(item));
        }
        let item = convert(self.decoder.finish());
        Ok(self.account(item))
    }
}

impl<F: EncodeFrame + ?Sized> Encoder<&F> for XBeeCodec {
    type Error = std::io::Error;

    /// Appends the encoded frame; a frame too long for the wire is an
    /// [`std::io::ErrorKind::InvalidInput`] error.
    fn encode(&mut self, frame: &F, dst: &mut BytesMut) -> Result<(), Self::Error> {
        encode_frame(frame, self.mode, dst)
            .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidInput, e))
    }
}

/// Appends `frame`, encoded in `mode`, to `dst`.
pub(crate) fn encode_frame<F: EncodeFrame + ?Sized>(
    frame: &F,
    mode: ApiMode,
    dst: &mut BytesMut,
) -> Result<(), xbee_api::EncodeError> {
    let start = dst.len();
    let len = frame.encoded_len(mode);
    dst.resize(start + len, 0);
    match frame.encode(mode, &mut dst[start..]) {
        Ok(n) => {
            dst.truncate(start + n);
            Ok(())
        }
        Err(e) => {
            dst.truncate(start);
            Err(e)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use futures::StreamExt;
    use proptest::prelude::*;
    use tokio_util::codec::FramedRead;
    use xbee_api::RawFrame;

    fn encode(mode: ApiMode, data: &[u8]) -> Vec<u8> {
        let mut out = BytesMut::new();
        encode_frame(&RawFrame::new(data).unwrap(), mode, &mut out).unwrap();
        out.to_vec()
    }

    #[tokio::test]
    async fn end_of_input_reports_the_cut_off_frame_and_ends() {
        for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
            let mut input = encode(mode, &[0x8A, 0x06]);
            let cut = encode(mode, &[0x8A, 0x02]);
            input.extend(&cut[..cut.len() - 2]);
            let mut framed = FramedRead::new(&input[..], XBeeCodec::new(mode));
            match framed.next().await {
                Some(Ok(CodecItem::Frame(f))) => assert_eq!(&f.data()[..], [0x8A, 0x06]),
                other => panic!("{other:?}"),
            }
            match framed.next().await {
                Some(Ok(CodecItem::Error(DecodeError::Truncated { .. }))) => {}
                other => panic!("{mode}: {other:?}"),
            }
            assert!(framed.next().await.is_none());
            let stats = framed.decoder().stats();
            assert_eq!((stats.frames, stats.truncated), (1, 1));
        }
    }

    #[test]
    fn frames_beyond_the_configured_limit_are_oversize() {
        let mut codec =
            XBeeCodec::with_counters(ApiMode::Unescaped, 3, Arc::new(Counters::default()));
        let mut buf = BytesMut::from(&encode(ApiMode::Unescaped, &[0x23, 1, 2, 3])[..]);
        buf.extend_from_slice(&encode(ApiMode::Unescaped, &[0x23, 1])[..]);
        assert_eq!(
            codec.decode(&mut buf).unwrap(),
            Some(CodecItem::Error(DecodeError::Oversize {
                length: 4,
                capacity: 3
            }))
        );
        assert!(matches!(
            codec.decode(&mut buf).unwrap(),
            Some(CodecItem::Frame(_))
        ));
        assert_eq!(codec.decode(&mut buf).unwrap(), None);
        let stats = codec.stats();
        assert_eq!((stats.frames, stats.oversize), (1, 1));
    }

    #[test]
    fn encoder_writes_what_the_decoder_reads() {
        for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
            let mut codec = XBeeCodec::new(mode);
            let mut buf = BytesMut::new();
            let frame = RawFrame::new(&[0x10, 0x7E, 0x7D, 0x11, 0x13]).unwrap();
            Encoder::<&RawFrame<'_>>::encode(&mut codec, &frame, &mut buf).unwrap();
            match codec.decode(&mut buf).unwrap() {
                Some(CodecItem::Frame(f)) => assert_eq!(&f.data()[..], frame.data()),
                other => panic!("{other:?}"),
            }
            assert!(buf.is_empty());
        }
    }

    proptest! {
        /// Valid frames separated by garbage without start delimiters, fed in random
        /// chunks: every frame comes out, in order, and decoding never fails.
        #[test]
        fn every_frame_survives_any_chunking(
            mode2 in any::<bool>(),
            frames in prop::collection::vec(prop::collection::vec(any::<u8>(), 1..40), 1..20),
            garbage in prop::collection::vec(prop::collection::vec(0u8..0x7E, 0..10), 20),
            chunks in prop::collection::vec(1usize..64, 1..50),
        ) {
            let mode = if mode2 { ApiMode::Escaped } else { ApiMode::Unescaped };
            let mut input = Vec::new();
            for (i, f) in frames.iter().enumerate() {
                input.extend(&garbage[i]);
                input.extend(encode(mode, f));
            }
            let mut codec = XBeeCodec::new(mode);
            let mut buf = BytesMut::new();
            let mut out = Vec::new();
            let mut rest = &input[..];
            let mut sizes = chunks.iter().cycle();
            while !rest.is_empty() {
                let n = (*sizes.next().unwrap()).min(rest.len());
                buf.extend_from_slice(&rest[..n]);
                rest = &rest[n..];
                while let Some(item) = codec.decode(&mut buf).unwrap() {
                    out.push(item);
                }
            }
            while let Some(item) = codec.decode_eof(&mut buf).unwrap() {
                out.push(item);
            }
            let got: Vec<Vec<u8>> = out
                .into_iter()
                .filter_map(|item| match item {
                    CodecItem::Frame(f) => Some(f.data().to_vec()),
                    CodecItem::Error(_) => None,
                })
                .collect();
            prop_assert_eq!(got, frames);
        }
    }
}
