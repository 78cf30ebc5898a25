//! What a stream holds and what a measured loop found in it.

/// What a decoding loop found: frames, typed values and their sum. The streams carry
/// the totals their decoders must find.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Totals {
    /// Frames (or messages) decoded.
    pub frames: usize,
    /// Bytes of frame data (or payload) delivered; 0 where not counted.
    pub data_bytes: usize,
    /// `f32` values read.
    pub values: usize,
    /// Sum of the values, in stream order, in `f64`.
    pub sum: f64,
}

/// A generated stream and the totals a decoder must find in it.
#[cfg(feature = "std")]
#[derive(Debug, Clone)]
pub struct Stream {
    /// The wire bytes.
    pub bytes: Vec<u8>,
    /// Frames, frame data bytes, values and their sum.
    pub totals: Totals,
}
