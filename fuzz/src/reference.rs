//! Reference decoders: what `xbee_api::Decoder` must yield for a whole stream followed
//! by `finish`, written as plainly as possible over the whole input (no buffer, no
//! state carried across reads), to compare the streaming decoder against.
//!
//! Both return the events and the number of bytes skipped while hunting for a start
//! delimiter.

use xbee_api::DecodeError;

use crate::events::Event;

const START: u8 = 0x7E;
const ESCAPE: u8 = 0x7D;

fn checksum(data: &[u8]) -> u8 {
    0xFF - data.iter().fold(0u8, |s, &b| s.wrapping_add(b))
}

/// API mode 1 with frame data of up to `capacity` bytes: each start delimiter begins a
/// candidate; a failed candidate is dropped and the scan resumes at the byte after its
/// delimiter; a good frame resumes it after the frame. At the end of input a candidate
/// short of bytes is truncated.
pub fn mode1(stream: &[u8], capacity: usize) -> (Vec<Event>, u64) {
    let mut events = Vec::new();
    let mut skipped = 0u64;
    let mut i = 0;
    while i < stream.len() {
        let Some(k) = stream[i..].iter().position(|&b| b == START) else {
            skipped += (stream.len() - i) as u64;
            break;
        };
        skipped += k as u64;
        let j = i + k;
        let after = &stream[j + 1..];
        i = j + 1;
        if after.len() < 2 {
            events.push(Event::Error(DecodeError::Truncated {
                length: None,
                received: 0,
            }));
            continue;
        }
        let len = usize::from(u16::from_be_bytes([after[0], after[1]]));
        if len == 0 {
            events.push(Event::Error(DecodeError::EmptyFrame));
            continue;
        }
        if len > capacity {
            events.push(Event::Error(DecodeError::Oversize {
                length: len as u16,
                capacity,
            }));
            continue;
        }
        let body = &after[2..];
        if body.len() < len + 1 {
            events.push(Event::Error(DecodeError::Truncated {
                length: Some(len as u16),
                received: body.len().min(len),
            }));
            continue;
        }
        let data = &body[..len];
        let expected = checksum(data);
        let got = body[len];
        if got == expected {
            events.push(Event::Frame(data.to_vec()));
            i = j + 4 + len;
        } else {
            events.push(Event::Error(DecodeError::BadChecksum { expected, got }));
        }
    }
    (events, skipped)
}

/// API mode 2 with frame data of up to `capacity` bytes: a raw 0x7E always starts a
/// candidate and cuts the previous one; the bytes up to the next raw 0x7E are
/// unescaped one by one; after the frame or an error in them, the rest are skipped.
pub fn mode2(stream: &[u8], capacity: usize) -> (Vec<Event>, u64) {
    let mut events = Vec::new();
    let mut segments = stream.split(|&b| b == START);
    let before = segments.next().unwrap_or_default();
    let mut skipped = before.len() as u64;
    let count = stream.iter().filter(|&&b| b == START).count();
    for (n, segment) in segments.enumerate() {
        let last = n + 1 == count;
        let (event, rest) = segment2(segment, last, capacity);
        if let Some(event) = event {
            events.push(event);
        }
        skipped += rest as u64;
    }
    (events, skipped)
}

/// One mode 2 candidate: the bytes after a raw 0x7E up to the next one (`last`: up to
/// the end of input instead). Returns its event and how many of its bytes were skipped
/// after it.
fn segment2(segment: &[u8], last: bool, capacity: usize) -> (Option<Event>, usize) {
    // Unescaped bytes so far: 2 of length, then data, then the checksum.
    let mut header = Vec::new();
    let mut data = Vec::new();
    let mut len = None;
    let mut iter = segment.iter().enumerate();
    let truncated = |len: Option<usize>, data: &Vec<u8>| DecodeError::Truncated {
        length: len.map(|l| l as u16),
        received: data.len(),
    };
    while let Some((at, &raw)) = iter.next() {
        let byte = if raw == ESCAPE {
            match iter.next() {
                Some((_, &next)) => {
                    let byte = next ^ 0x20;
                    if !matches!(byte, 0x7E | 0x7D | 0x11 | 0x13) {
                        let error = DecodeError::BadEscape {
                            byte: next,
                            received: data.len(),
                        };
                        return (Some(Event::Error(error)), segment.len() - at - 2);
                    }
                    byte
                }
                // 0x7D right before a raw 0x7E, or at the end of input.
                None if last => return (Some(Event::Error(truncated(len, &data))), 0),
                None => {
                    let error = DecodeError::BadEscape {
                        byte: START,
                        received: data.len(),
                    };
                    return (Some(Event::Error(error)), 0);
                }
            }
        } else {
            raw
        };
        let consumed = segment.len() - iter.len();
        match len {
            None => {
                header.push(byte);
                if header.len() == 2 {
                    let l = usize::from(u16::from_be_bytes([header[0], header[1]]));
                    let error = if l == 0 {
                        Some(DecodeError::EmptyFrame)
                    } else if l > capacity {
                        Some(DecodeError::Oversize {
                            length: l as u16,
                            capacity,
                        })
                    } else {
                        None
                    };
                    if let Some(error) = error {
                        return (Some(Event::Error(error)), segment.len() - consumed);
                    }
                    len = Some(l);
                }
            }
            Some(l) if data.len() < l => data.push(byte),
            Some(_) => {
                let expected = checksum(&data);
                let event = if byte == expected {
                    Event::Frame(data)
                } else {
                    Event::Error(DecodeError::BadChecksum {
                        expected,
                        got: byte,
                    })
                };
                return (Some(event), segment.len() - consumed);
            }
        }
    }
    (Some(Event::Error(truncated(len, &data))), 0)
}
