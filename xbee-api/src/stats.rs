//! Counters a [`Decoder`](crate::Decoder) keeps.

/// What a [`Decoder`](crate::Decoder) has seen since it was made. Counters wrap at
/// `u32::MAX`.
///
/// A host link's counters (`mcp_host::Stats`) add these up across reconnections, as
/// `u64`: `frames_ok` is `frames` there, [`errors`](Self::errors) is `decode_errors`.
///
/// In API mode 1 the bytes of a failed candidate frame are scanned again, so a byte can
/// be part of a failed candidate and then be counted in `bytes_skipped` too.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DecoderStats {
    /// Frames yielded with a good checksum.
    pub frames_ok: u32,
    /// Candidate frames whose checksum did not match.
    pub bad_checksum: u32,
    /// Candidate frames whose length field exceeded the decoder's capacity.
    pub oversize: u32,
    /// Candidate frames whose length field was 0 (not even a frame type).
    pub empty: u32,
    /// Candidate frames cut off by a new start delimiter (mode 2) or by the end of input.
    pub truncated: u32,
    /// Candidate frames with an invalid escape sequence (mode 2).
    pub bad_escape: u32,
    /// Bytes dropped while hunting for a start delimiter, and bytes
    /// [`push`](crate::Decoder::push)ed in mode 1 while the buffer was full of pending
    /// bytes (events not yet taken with [`poll`](crate::Decoder::poll)).
    pub bytes_skipped: u32,
}

impl DecoderStats {
    /// All failed candidate frames, of every kind.
    pub const fn errors(&self) -> u32 {
        self.bad_checksum
            .wrapping_add(self.oversize)
            .wrapping_add(self.empty)
            .wrapping_add(self.truncated)
            .wrapping_add(self.bad_escape)
    }
}
