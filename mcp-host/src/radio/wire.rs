//! Encoding frames for a link, and corrupting them on purpose.

use bytes::{Bytes, BytesMut};
use xbee_api::{ApiMode, EncodeFrame, Frame};

/// Encodes `frame` for a link in `mode`.
pub(crate) fn encode<F: EncodeFrame + ?Sized>(frame: &F, mode: ApiMode) -> Option<Bytes> {
    let mut out = BytesMut::new();
    crate::codec::encode_frame(frame, mode, &mut out).ok()?;
    Some(out.freeze())
}

/// The frame data of `frame`.
fn frame_data<F: EncodeFrame + ?Sized>(frame: &F) -> Vec<u8> {
    let mut data = Vec::with_capacity(frame.frame_data_len());
    frame.write_frame_data(&mut |chunk: &[u8]| data.extend_from_slice(chunk));
    data
}

/// What a radio in transparent mode writes for `frame`: the payload of a Receive Packet
/// or of an Explicit Rx Indicator; `None` for any other frame (or an empty payload).
pub(crate) fn payload<F: EncodeFrame + ?Sized>(frame: &F) -> Option<Bytes> {
    let data = frame_data(frame);
    let payload = match Frame::parse_bytes(&data).ok()? {
        Frame::ReceivePacket(rx) => rx.data,
        Frame::ExplicitRxIndicator(rx) => rx.data,
        _ => return None,
    };
    (!payload.is_empty()).then(|| Bytes::copy_from_slice(payload))
}

/// `payload` (not empty) with one byte XORed with `mask` (non-zero): what a radio in
/// transparent mode writes for a payload that came in damaged (nothing checks it).
pub(crate) fn corrupt_payload(payload: &Bytes, index: usize, mask: u8) -> Bytes {
    let mut bytes = payload.to_vec();
    let i = index % bytes.len().max(1);
    if let Some(byte) = bytes.get_mut(i) {
        *byte ^= mask.max(1);
    }
    Bytes::from(bytes)
}

/// Encodes `frame` with one byte of its frame data XORed with `mask` (non-zero) but the
/// checksum of the original data, so that a decoder rejects it with a bad checksum.
/// The changed byte never becomes a start delimiter (0x7E), so that the receiver's
/// resynchronisation is not sent into the middle of the frame.
pub(crate) fn encode_corrupt<F: EncodeFrame + ?Sized>(
    frame: &F,
    mode: ApiMode,
    index: usize,
    mask: u8,
) -> Option<Bytes> {
    let mut data = frame_data(frame);
    let len = u16::try_from(data.len()).ok()?;
    let sum = data.iter().fold(0u8, |s, b| s.wrapping_add(*b));
    let checksum = 0xFF - sum;
    let i = index % data.len().max(1);
    let byte = data.get_mut(i)?;
    let mut mask = mask.max(1);
    if *byte ^ mask == 0x7E {
        // Any other non-zero mask keeps the change and avoids the delimiter.
        mask ^= 0x01;
        if mask == 0 {
            mask = 0x02;
        }
    }
    *byte ^= mask;
    let mut out = Vec::with_capacity(data.len() * 2 + 6);
    out.push(0x7E);
    let mut put = |b: u8| match mode {
        ApiMode::Escaped if matches!(b, 0x7E | 0x7D | 0x11 | 0x13) => {
            out.push(0x7D);
            out.push(b ^ 0x20);
        }
        _ => out.push(b),
    };
    for b in len.to_be_bytes() {
        put(b);
    }
    for &b in &data {
        put(b);
    }
    put(checksum);
    Some(Bytes::from(out))
}

#[cfg(test)]
mod tests {
    use super::*;
    use xbee_api::{DecodeError, Decoder, RawFrame};

    #[test]
    fn corrupt_frames_fail_the_checksum_in_both_modes() {
        let data = [0x90, 0x7E, 0x7D, 0x11, 0x13, 0x00, 0xFF, 0x42];
        let frame = RawFrame::new(&data).unwrap();
        for mode in [ApiMode::Unescaped, ApiMode::Escaped] {
            for index in 0..data.len() {
                for mask in 1..=255u8 {
                    let wire = encode_corrupt(&frame, mode, index, mask).unwrap();
                    let mut decoder: Decoder = Decoder::new(mode);
                    let (_, event) = decoder.decode(&wire);
                    assert!(
                        matches!(event, Some(Err(DecodeError::BadChecksum { .. }))),
                        "{mode} index {index} mask {mask:02x}: {event:?}"
                    );
                }
            }
            let good = encode(&frame, mode).unwrap();
            let mut decoder: Decoder = Decoder::new(mode);
            let (_, event) = decoder.decode(&good);
            assert!(matches!(event, Some(Ok(f)) if f.data() == data));
        }
    }
}
