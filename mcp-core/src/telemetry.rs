//! Telemetry packets (`t`, table 16): a view over the records and a builder.

use core::iter::FusedIterator;

use crate::{
    error::{BufferTooSmall, Error, ErrorKind, Expected, Full},
    field::{self, record},
    id::{Category, TelemetryId},
    write::{Writer, packet_room},
};

/// One telemetry record: an id and its value.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TelemetryRecord {
    /// Which quantity.
    pub id: TelemetryId,
    /// Its value.
    pub value: f32,
}

/// A telemetry packet: a view over its records (the bytes after the `t`), 5 bytes
/// each: id, then a little-endian `f32`.
///
/// The records are read in place, with no copy and no fixed maximum. `B` is any byte
/// storage (`&[u8]`, an owned buffer, `bytes::Bytes`...).
///
/// ```
/// use mcp_core::{Telemetry, TelemetryId};
/// let records = [0x01, 0x00, 0x00, 0xC0, 0x3F];
/// let t = Telemetry::new_checked(&records[..]).unwrap();
/// let r = t.iter().next().unwrap();
/// assert_eq!((r.id, r.value), (TelemetryId::Altitude, 1.5));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Telemetry<B> {
    records: B,
}

impl<B> Telemetry<B> {
    /// Wraps record bytes without checking their length. Accessors never panic: a
    /// trailing partial record is ignored.
    pub const fn new_unchecked(records: B) -> Self {
        Telemetry { records }
    }

    /// The record bytes.
    pub fn into_inner(self) -> B {
        self.records
    }
}

impl<B: AsRef<[u8]>> Telemetry<B> {
    /// Wraps record bytes, checking that they are whole 5-byte records.
    pub fn new_checked(records: B) -> Result<Self, Error> {
        let t = Self::new_unchecked(records);
        t.check_len()?;
        Ok(t)
    }

    /// Checks that the bytes are whole records. Error offsets count from the packet
    /// start, as if the records followed the category byte.
    pub fn check_len(&self) -> Result<(), Error> {
        let len = self.records.as_ref().len();
        let partial = len % record::LEN;
        if partial == 0 {
            return Ok(());
        }
        let got = field::RECORDS + len;
        Err(Error::new(
            ErrorKind::WrongLength {
                category: Category::Telemetry,
                packet_type: None,
                status_request: false,
                expected: Expected::Multiple {
                    base: field::RECORDS,
                    stride: record::LEN,
                },
                got,
            },
            got - partial,
        ))
    }

    /// The record bytes.
    pub fn as_bytes(&self) -> &[u8] {
        self.records.as_ref()
    }

    /// The number of whole records.
    pub fn len(&self) -> usize {
        self.as_bytes().len() / record::LEN
    }

    /// `true` if the packet holds no record (the single byte `t`).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Iterates over the records in packet order.
    pub fn iter(&self) -> TelemetryIter<'_> {
        TelemetryIter {
            rest: self.as_bytes(),
        }
    }

    /// The record at `index`, if there is one.
    pub fn get(&self, index: usize) -> Option<TelemetryRecord> {
        let start = index.checked_mul(record::LEN)?;
        TelemetryIter {
            rest: self.as_bytes().get(start..)?,
        }
        .next()
    }

    /// The value of the first record with this id.
    pub fn value(&self, id: TelemetryId) -> Option<f32> {
        self.iter().find(|r| r.id == id).map(|r| r.value)
    }

    /// The packet length: the category byte and every whole record.
    pub fn encoded_len(&self) -> usize {
        field::RECORDS + self.len() * record::LEN
    }

    /// Writes the packet (`t` and the whole records) into `buf`, returning its length.
    pub fn encode(&self, buf: &mut [u8]) -> Result<usize, BufferTooSmall> {
        let len = self.encoded_len();
        let body = self
            .as_bytes()
            .get(..len - field::RECORDS)
            .unwrap_or_default();
        Writer::new(buf, len)?
            .u8(Category::Telemetry.into())
            .bytes(body)
            .finish()
    }

    /// A view borrowing this one's bytes.
    pub fn as_borrowed(&self) -> Telemetry<&[u8]> {
        Telemetry::new_unchecked(self.as_bytes())
    }
}

impl<'a> Telemetry<&'a [u8]> {
    /// Moves the bytes to another storage, e.g. `|s| bytes.slice_ref(s)`. `f` is
    /// expected to return the same bytes.
    pub fn map_bytes<U>(self, f: impl FnOnce(&'a [u8]) -> U) -> Telemetry<U> {
        Telemetry::new_unchecked(f(self.records))
    }
}

impl<'t, B: AsRef<[u8]>> IntoIterator for &'t Telemetry<B> {
    type Item = TelemetryRecord;
    type IntoIter = TelemetryIter<'t>;

    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

/// Iterator over the records of a [`Telemetry`] packet.
#[derive(Debug, Clone)]
pub struct TelemetryIter<'a> {
    rest: &'a [u8],
}

impl Iterator for TelemetryIter<'_> {
    type Item = TelemetryRecord;

    #[inline]
    fn next(&mut self) -> Option<TelemetryRecord> {
        // A fixed 5-byte record: split it off directly rather than through parser
        // combinators, so that iterating costs a few instructions a record.
        match self.rest.split_first_chunk::<{ record::LEN }>() {
            Some((&[id, v0, v1, v2, v3], rest)) => {
                self.rest = rest;
                Some(TelemetryRecord {
                    id: id.into(),
                    value: f32::from_le_bytes([v0, v1, v2, v3]),
                })
            }
            None => {
                self.rest = &[];
                None
            }
        }
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = self.rest.len() / record::LEN;
        (n, Some(n))
    }
}

impl ExactSizeIterator for TelemetryIter<'_> {}
impl FusedIterator for TelemetryIter<'_> {}

/// Builds a telemetry packet record by record in a caller buffer, stopping cleanly
/// when the buffer or the 255-byte XBee payload limit is full (at most 50 records).
///
/// ```
/// use mcp_core::{TelemetryBuilder, TelemetryId, parse, Packet};
/// let mut buf = [0u8; 64];
/// let mut b = TelemetryBuilder::new(&mut buf).unwrap();
/// b.push(TelemetryId::Altitude, 1.5).unwrap();
/// b.push(TelemetryId::PitchAngle, -0.25).unwrap();
/// let len = b.finish();
/// assert_eq!(len, 11);
/// let Ok(Packet::Telemetry(t)) = parse(buf.get(..len).unwrap_or_default()) else { panic!() };
/// assert_eq!(t.value(TelemetryId::PitchAngle), Some(-0.25));
/// ```
#[derive(Debug)]
pub struct TelemetryBuilder<'a> {
    buf: &'a mut [u8],
    len: usize,
}

impl<'a> TelemetryBuilder<'a> {
    /// Starts a packet in `buf` (writes the `t`). Fails if `buf` is empty.
    pub fn new(buf: &'a mut [u8]) -> Result<Self, BufferTooSmall> {
        Ok(TelemetryBuilder {
            buf: packet_room(buf, Category::Telemetry)?,
            len: field::RECORDS,
        })
    }

    /// Appends a record, or fails with [`Full`] leaving the packet as it was.
    pub fn push(&mut self, id: TelemetryId, value: f32) -> Result<(), Full> {
        let end = self.len + record::LEN;
        let dst = self.buf.get_mut(self.len..end).ok_or(Full)?;
        let mut w = Writer::new(dst, record::LEN).map_err(|_| Full)?;
        w.u8(id.into()).f32(value);
        w.finish().map_err(|_| Full)?;
        self.len = end;
        Ok(())
    }

    /// The number of records pushed.
    pub fn count(&self) -> usize {
        (self.len - field::RECORDS) / record::LEN
    }

    /// The packet written so far.
    pub fn as_bytes(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or_default()
    }

    /// Ends the packet, returning its length: the packet is `buf.get(..len)`, the
    /// bytes [`as_bytes`](Self::as_bytes) gives before `finish`. In firmware, take it
    /// that way rather than as `&buf[..len]`, whose bounds check the compiler cannot
    /// always drop, and so a panic path.
    pub fn finish(self) -> usize {
        self.len
    }
}
