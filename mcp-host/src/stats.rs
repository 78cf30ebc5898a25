//! Link statistics: counters shared by the background task, the stream and the senders.

use std::sync::atomic::{AtomicU64, Ordering};

/// A snapshot of a link's counters since [`connect`](crate::connect), across reconnections.
///
/// The link's decoders count in [`xbee_api::DecoderStats`] (`u32`, wrapping), which
/// these add up across reconnections: its `frames_ok` is [`frames`](Self::frames) here,
/// its `errors()` [`decode_errors`](Self::decode_errors).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
pub struct Stats {
    /// Frames with a good checksum.
    pub frames: u64,
    /// Frames dropped for a bad checksum.
    pub bad_checksum: u64,
    /// Frames dropped for a length beyond the frame size limit.
    pub oversize: u64,
    /// Frames dropped for an announced length of 0.
    pub empty: u64,
    /// Frames cut off (by a new start delimiter, by a disconnection, or in API mode 1 by
    /// [`LinkOptions::partial_frame_timeout`](crate::LinkOptions::partial_frame_timeout)).
    pub truncated: u64,
    /// Frames dropped for an invalid escape (API mode 2).
    pub bad_escape: u64,
    /// Bytes skipped while looking for a start delimiter.
    pub bytes_skipped: u64,
    /// Receive Packets whose payload is not a valid MCP packet.
    pub invalid_packets: u64,
    /// Frames received that the radio announces but the link does not understand (too
    /// short for their frame type).
    pub malformed_frames: u64,
    /// Transmit statuses and responses that matched no request in flight.
    pub unclaimed_responses: u64,
    /// Frames received of a type a radio takes rather than sends (a request: frame
    /// types below 0x80, as an AT Command or a Transmit Request): what a port that hands
    /// back what is written (a loopback, a terminal's echo) gives, never a radio.
    pub echoed: u64,
    /// Requests (sends, frames, status requests) that timed out, their callers told: one
    /// whose caller had given up on it first (dropped its future) is not counted.
    pub timeouts: u64,
    /// Events dropped because the [`crate::PacketStream`] consumer fell behind.
    pub events_dropped: u64,
    /// Times the transport went away.
    pub disconnects: u64,
    /// Times the transport came back.
    pub reconnects: u64,
}

impl Stats {
    /// Frames dropped for any framing error.
    pub fn decode_errors(&self) -> u64 {
        [self.oversize, self.empty, self.truncated, self.bad_escape]
            .iter()
            .fold(self.bad_checksum, |sum, n| sum.saturating_add(*n))
    }

    /// What an [`xbee_api::Decoder`] counted between two snapshots of its counters,
    /// `earlier` and `now`, as 64-bit counts (the framing counters and
    /// `bytes_skipped`; the others 0). The decoder's counters are 32-bit and wrap:
    /// the difference is right as long as fewer than 2^32 of each came between the two,
    /// so adding up the pieces of a long stream, a read at a time, counts it whole.
    ///
    /// ```
    /// use mcp_host::Stats;
    /// let earlier = mcp_host::xbee_api::DecoderStats { bytes_skipped: u32::MAX - 1, ..Default::default() };
    /// let now = mcp_host::xbee_api::DecoderStats { frames_ok: 3, bytes_skipped: 2, ..Default::default() };
    /// let mut total = Stats { bytes_skipped: u64::from(u32::MAX - 1), ..Stats::default() };
    /// // 3 frames, and 4 bytes skipped across the wrap of the decoder's counter.
    /// total += Stats::decoder_since(&now, &earlier);
    /// assert_eq!((total.frames, total.bytes_skipped), (3, u64::from(u32::MAX) + 3));
    /// ```
    pub fn decoder_since(now: &xbee_api::DecoderStats, earlier: &xbee_api::DecoderStats) -> Stats {
        let delta = |now: u32, earlier: u32| u64::from(now.wrapping_sub(earlier));
        Stats {
            frames: delta(now.frames_ok, earlier.frames_ok),
            bad_checksum: delta(now.bad_checksum, earlier.bad_checksum),
            oversize: delta(now.oversize, earlier.oversize),
            empty: delta(now.empty, earlier.empty),
            truncated: delta(now.truncated, earlier.truncated),
            bad_escape: delta(now.bad_escape, earlier.bad_escape),
            bytes_skipped: delta(now.bytes_skipped, earlier.bytes_skipped),
            ..Stats::default()
        }
    }
}

macro_rules! counters {
    ($($name:ident),* $(,)?) => {
        /// The live counters behind [`Stats`].
        #[derive(Debug, Default)]
        pub(crate) struct Counters {
            $(pub(crate) $name: AtomicU64,)*
        }

        impl Counters {
            pub(crate) fn snapshot(&self) -> Stats {
                Stats { $($name: self.$name.load(Ordering::Relaxed),)* }
            }
        }

        impl Stats {
            /// What was counted since `earlier`, a snapshot of the same link taken
            /// before this one (each counter's difference, 0 rather than negative).
            ///
            /// ```
            /// use mcp_host::Stats;
            /// let earlier = Stats { frames: 10, bad_checksum: 2, ..Stats::default() };
            /// let now = Stats { frames: 15, bad_checksum: 2, ..Stats::default() };
            /// assert_eq!(now.since(&earlier), Stats { frames: 5, ..Stats::default() });
            /// ```
            pub fn since(&self, earlier: &Stats) -> Stats {
                Stats { $($name: self.$name.saturating_sub(earlier.$name),)* }
            }
        }

        /// Adds each counter of `other` to this one's (saturating, as
        /// [`since`](Stats::since) does): totals of several links, or of
        /// [`Stats::decoder_since`] pieces.
        impl std::ops::AddAssign for Stats {
            fn add_assign(&mut self, other: Stats) {
                $(self.$name = self.$name.saturating_add(other.$name);)*
            }
        }

        impl Counters {
            /// Adds each counter of `delta` that moved.
            pub(crate) fn add_all(&self, delta: &Stats) {
                $(if delta.$name > 0 {
                    add(&self.$name, delta.$name);
                })*
            }
        }
    };
}

counters!(
    frames,
    bad_checksum,
    oversize,
    empty,
    truncated,
    bad_escape,
    bytes_skipped,
    invalid_packets,
    malformed_frames,
    unclaimed_responses,
    echoed,
    timeouts,
    events_dropped,
    disconnects,
    reconnects,
);

/// Adds `n` to a counter.
pub(crate) fn add(counter: &AtomicU64, n: u64) {
    counter.fetch_add(n, Ordering::Relaxed);
}

/// Adds one to a counter.
pub(crate) fn bump(counter: &AtomicU64) {
    add(counter, 1);
}
