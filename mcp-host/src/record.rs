//! Recordings: timestamped raw frames, as `mcp-gs monitor --record` and `hub --record`
//! write them (the frames of a link both ways come from
//! [`CommandSender::tap_frames`](crate::CommandSender::tap_frames)) and `mcp-gs decode`
//! and `mcp-gs replay` read them.
//!
//! # Format, version 2
//!
//! A file starts with an 8-byte header: the magic `MCPREC` (6 ASCII bytes) and the
//! format version as a little-endian `u16` (2). Records follow, back to back, until the
//! end of the file:
//!
//! | bytes | field |
//! |---|---|
//! | 8 | timestamp: microseconds since 1970-01-01 00:00:00 UTC, `u64` little-endian |
//! | 1 | direction: 0 received from the radio, 1 sent to the radio (any other value is an error) |
//! | 2 | length N of the frame data, `u16` little-endian (1 to 65 535: 0 is an error) |
//! | N | the API frame's data: frame type byte first, unescaped, without start delimiter, length or checksum |
//! | 4 | CRC-32 of the record's 11 + N bytes before it (not the file's header), `u32` little-endian |
//!
//! The CRC is IEEE 802.3's, as zlib's `crc32` and Python's `zlib.crc32` compute it
//! (CRC-32/ISO-HDLC: polynomial 0x04C11DB7, reflected, initial value and final xor
//! 0xFFFFFFFF; `123456789` gives 0xCBF43926).
//!
//! Frames are stored without their API-mode framing so that a recording replays onto a
//! link in either mode, and so without the XBee checksum: the CRC stands in for it, so
//! that a damaged record (a bit flipped on a disk, a length that reaches into the next
//! record) is found rather than read as another frame, such as another command. Records
//! are in the order they were written, which is the order of their times for one
//! writer, but not always (the system clock set back).
//!
//! A reader stops with an error at a truncated or damaged record, after handing out
//! every whole record before it, and gives no record after it (the bytes after a
//! damaged record cannot be trusted to start one). Recordings joined one after the other
//! (`cat a.mcprec b.mcprec`) read as one: a header where a record would start is passed
//! over, and the records after it are read in its version; one of a version this module
//! does not read is an error there. So that no record is taken for a header, a time
//! whose first 6 bytes read `MCPREC` is written a microsecond later (one microsecond in
//! every 8.9 years); a time before 1970 is written as 0.
//!
//! Version 1 (the header's version 1), which this module reads too, is the same
//! without the CRC.
//!
//! # Writing and reading one
//!
//! ```
//! use std::io::{BufWriter, Write};
//! use std::time::{Duration, UNIX_EPOCH};
//! use mcp_host::record::{Direction, RecordReader, RecordWriter};
//!
//! # fn main() -> std::io::Result<()> {
//! let time = UNIX_EPOCH + Duration::from_secs(1_790_000_000);
//! // A file in a real program (`File::create`): buffered, and flushed at the end.
//! let mut writer = RecordWriter::new(BufWriter::new(Vec::new()))?;
//! // A Modem Status frame from the radio, and an AT Command (`AP`) sent to it.
//! writer.write(time, Direction::Received, &[0x8A, 0x06])?;
//! writer.write(time, Direction::Sent, &[0x08, 0x01, b'A', b'P'])?;
//! writer.flush()?;
//! let bytes = writer.into_inner().into_inner().map_err(|e| e.into_error())?;
//!
//! let mut records = RecordReader::new(&bytes[..])?;
//! let first = records.next_record()?.expect("a record");
//! assert_eq!(first.time, time);
//! assert_eq!(first.direction, Direction::Received);
//! assert_eq!(first.frame, [0x8A, 0x06]);
//! // Or as an iterator of `Result<Record, RecordError>`.
//! let rest: Vec<_> = records.collect::<Result<_, _>>()?;
//! assert_eq!(rest.len(), 1);
//! assert_eq!(rest[0].direction, Direction::Sent);
//! # Ok(())
//! # }
//! ```

use std::io::{self, Read, Write};
use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// The first 6 bytes of a recording.
pub const MAGIC: &[u8; 6] = b"MCPREC";
/// The format version this module writes; it reads this one and version 1 (records
/// without their CRC).
pub const VERSION: u16 = 2;
/// Header length: magic and version.
pub const HEADER_LEN: usize = 8;
/// The length of each record's head: time (8 bytes), direction (1) and the frame data's
/// length (2); the frame data follows.
pub const RECORD_HEAD_LEN: usize = 11;
/// The length of each record's CRC, after its frame data.
pub const RECORD_CRC_LEN: usize = 4;

/// The length of a record holding `frame_len` bytes of frame data, as [`RecordWriter`]
/// writes it: its head, the frame data and the CRC.
pub const fn record_len(frame_len: usize) -> usize {
    RECORD_HEAD_LEN + frame_len + RECORD_CRC_LEN
}

/// Whether a frame came from the radio or went to it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Direction {
    /// Received from the local radio.
    Received,
    /// Sent to the local radio.
    Sent,
}

/// One recorded frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Record {
    /// When the frame was received or sent.
    pub time: SystemTime,
    /// Which way it went.
    pub direction: Direction,
    /// The frame data (type byte first).
    pub frame: Vec<u8>,
}

impl Record {
    /// The frame, typed; an MCP packet is the data of a Receive Packet (or, from the
    /// ground station, of a Transmit Request), which [`mcp_core::parse`] reads.
    ///
    /// ```
    /// use std::time::SystemTime;
    /// use mcp_host::mcp_core::{self, Command, Packet};
    /// use mcp_host::record::{Direction, Record};
    /// use mcp_host::xbee_api::Frame;
    ///
    /// // A landing command as a Receive Packet from 0013A20040B599B9.
    /// let mut frame = vec![0x90, 0x00, 0x13, 0xA2, 0x00, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0x01];
    /// frame.extend_from_slice(b"c\x02\x01");
    /// let record = Record { time: SystemTime::now(), direction: Direction::Received, frame };
    /// let Ok(Frame::ReceivePacket(rx)) = record.parse() else { panic!("a Receive Packet") };
    /// assert_eq!(mcp_core::parse(rx.data), Ok(Packet::Command(Command::landing(true))));
    /// ```
    pub fn parse(&self) -> Result<xbee_api::Frame<'_>, xbee_api::FrameError> {
        xbee_api::Frame::parse_bytes(&self.frame)
    }

    /// The MCP packet the frame carries, with the other radio's address (the MAV a
    /// received packet came from, or the one a sent one went to): the RF data of a
    /// Receive Packet, Explicit Rx Indicator, Transmit Request or Explicit Addressing
    /// Command ([`Frame::rf_data`](xbee_api::Frame::rf_data)), parsed. `None` for any
    /// other frame (AT commands and answers, statuses) and for one that does not read;
    /// the parse's error for data that is no MCP packet.
    ///
    /// ```
    /// use std::time::SystemTime;
    /// use mcp_host::mcp_core::{Command, Packet};
    /// use mcp_host::record::{Direction, Record};
    ///
    /// // A landing command as a Receive Packet from 0013A20040B599B9.
    /// let mut frame = vec![0x90, 0x00, 0x13, 0xA2, 0x00, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0x01];
    /// frame.extend_from_slice(b"c\x02\x01");
    /// let record = Record { time: SystemTime::now(), direction: Direction::Received, frame };
    /// let (from, packet) = record.mcp().expect("a frame that carries data");
    /// assert_eq!(from.to_string(), "0013a20040b599b9");
    /// assert_eq!(packet, Ok(Packet::Command(Command::landing(true))));
    /// ```
    pub fn mcp(&self) -> Option<(xbee_api::Address64, ParsedPacket<'_>)> {
        let (peer, data) = self.parse().ok()?.rf_data()?;
        Some((peer, mcp_core::parse(data)))
    }
}

/// An MCP packet read from a frame's data, borrowing it, or why the data is none
/// ([`Record::mcp`]).
pub type ParsedPacket<'a> = Result<mcp_core::Packet<&'a [u8]>, mcp_core::Error>;

/// Writes a recording.
#[derive(Debug)]
pub struct RecordWriter<W: Write> {
    out: W,
}

impl<W: Write> RecordWriter<W> {
    /// Writes the header and returns the writer.
    pub fn new(mut out: W) -> io::Result<Self> {
        out.write_all(MAGIC)?;
        out.write_all(&VERSION.to_le_bytes())?;
        Ok(Self { out })
    }

    /// Appends one frame: its frame data (frame type first, no delimiter, length or
    /// checksum), taken at `time`. Fails with [`io::ErrorKind::InvalidInput`] for frame
    /// data that is empty or longer than 65535 bytes, and with the writer's errors.
    pub fn write(
        &mut self,
        time: SystemTime,
        direction: Direction,
        frame: &[u8],
    ) -> io::Result<()> {
        let len = u16::try_from(frame.len())
            .ok()
            .filter(|&n| n > 0)
            .ok_or_else(|| {
                io::Error::new(
                    io::ErrorKind::InvalidInput,
                    "frame data must be 1 to 65535 bytes",
                )
            })?;
        let micros = time
            .duration_since(UNIX_EPOCH)
            .unwrap_or_default()
            .as_micros();
        let mut micros = u64::try_from(micros).unwrap_or(u64::MAX);
        // Never read as a header of recordings joined one after the other.
        if micros.to_le_bytes()[..MAGIC.len()] == *MAGIC {
            micros += 1;
        }
        let mut head = [0u8; RECORD_HEAD_LEN];
        head[..8].copy_from_slice(&micros.to_le_bytes());
        head[8] = match direction {
            Direction::Received => 0,
            Direction::Sent => 1,
        };
        head[9..].copy_from_slice(&len.to_le_bytes());
        self.out.write_all(&head)?;
        self.out.write_all(frame)?;
        self.out.write_all(&record_crc(&head, frame).to_le_bytes())
    }

    /// Flushes the underlying writer.
    pub fn flush(&mut self) -> io::Result<()> {
        self.out.flush()
    }

    /// The writer the records go to.
    pub fn get_ref(&self) -> &W {
        &self.out
    }

    /// Ends the recording, handing back the writer (not flushed: [`flush`](Self::flush)
    /// first for a buffered one).
    pub fn into_inner(self) -> W {
        self.out
    }
}

/// Whether `bytes` start like a recording.
pub fn is_recording(bytes: &[u8]) -> bool {
    bytes.starts_with(MAGIC)
}

/// Why a recording could not be read: its input failed ([`RecordError::Io`]), or its
/// bytes are not a recording this program reads, or are damaged or cut off at a record
/// ([`RecordError::offset`] says where). Converts into an [`io::Error`] (of kind
/// `InvalidData` but for [`RecordError::Io`]) where a program handles those.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RecordError {
    /// Reading the input failed.
    #[error(transparent)]
    Io(#[from] io::Error),
    /// The input is shorter than a recording's header.
    #[error("not a recording: shorter than its header")]
    TooShort,
    /// The input does not start with `MCPREC`.
    #[error("not a recording: no MCPREC header")]
    NoHeader,
    /// The recording's format version is not one this program reads (1 or
    /// [`VERSION`]).
    #[error(
        "recording format version {version} is not supported (this program reads versions 1 to {VERSION})"
    )]
    #[non_exhaustive]
    UnsupportedVersion {
        /// The version in its header.
        version: u16,
    },
    /// A header where a record would start (recordings joined one after the other)
    /// is of a format version this program does not read.
    #[error(
        "at offset {offset}, a recording of format version {version} is joined on, which \
         this program does not read (it reads versions 1 to {VERSION})"
    )]
    #[non_exhaustive]
    JoinedVersion {
        /// Where the header starts in the input.
        offset: u64,
        /// The version in it.
        version: u16,
    },
    /// The input ends part way through a record's 11-byte head (time, direction,
    /// length).
    #[error(
        "recording cut off part way through the header of the record at offset {offset}: \
         {got} of its 11 bytes are there"
    )]
    #[non_exhaustive]
    CutOffHead {
        /// Where the record starts in the input.
        offset: u64,
        /// The bytes of its head there are.
        got: usize,
    },
    /// The input ends part way through a record's frame, or its CRC: the recording was
    /// cut off there (a writer stopped, a disk full), or the record's length is damaged
    /// and reaches past the end.
    #[error(
        "recording cut off part way through the record at offset {offset}: {got} of its \
         {len} bytes of frame{} are there",
        if *.crc { " and CRC" } else { "" }
    )]
    #[non_exhaustive]
    CutOffFrame {
        /// Where the record starts in the input.
        offset: u64,
        /// The bytes of frame data (and CRC, in version 2) there are.
        got: usize,
        /// The frame's length, as the record says, and its CRC's in version 2.
        len: usize,
        /// Whether `got` and `len` count the record's CRC (version 2) with its frame.
        crc: bool,
    },
    /// A record's CRC does not match its bytes: the record is damaged (its time,
    /// direction, length or frame).
    #[error(
        "record at offset {offset} is damaged: its CRC is {found:08x}, its bytes' \
         {computed:08x}"
    )]
    #[non_exhaustive]
    Crc {
        /// Where the record starts in the input.
        offset: u64,
        /// The CRC the record holds.
        found: u32,
        /// The CRC of its bytes.
        computed: u32,
    },
    /// A record's direction byte is neither 0 (received) nor 1 (sent).
    #[error("record at offset {offset}: direction byte {byte} is neither 0 nor 1")]
    #[non_exhaustive]
    Direction {
        /// Where the record starts in the input.
        offset: u64,
        /// The byte.
        byte: u8,
    },
    /// A record's frame length is 0.
    #[error("record at offset {offset}: empty frame")]
    #[non_exhaustive]
    EmptyFrame {
        /// Where the record starts in the input.
        offset: u64,
    },
    /// A record's time is past the latest this system's clock can hold.
    #[error(
        "record at offset {offset}: its time ({micros} microseconds since 1970) is past \
         the latest this system can hold"
    )]
    #[non_exhaustive]
    TimeOutOfRange {
        /// Where the record starts in the input.
        offset: u64,
        /// The time, as the record holds it.
        micros: u64,
    },
}

impl RecordError {
    /// Where the damaged or cut-off record starts in the input, for an error of one.
    pub fn offset(&self) -> Option<u64> {
        match *self {
            RecordError::CutOffHead { offset, .. }
            | RecordError::CutOffFrame { offset, .. }
            | RecordError::Direction { offset, .. }
            | RecordError::EmptyFrame { offset }
            | RecordError::Crc { offset, .. }
            | RecordError::JoinedVersion { offset, .. }
            | RecordError::TimeOutOfRange { offset, .. } => Some(offset),
            _ => None,
        }
    }
}

/// [`RecordError::Io`] as the error it holds; any other as `InvalidData`.
impl From<RecordError> for io::Error {
    fn from(error: RecordError) -> io::Error {
        match error {
            RecordError::Io(error) => error,
            other => io::Error::new(io::ErrorKind::InvalidData, other),
        }
    }
}

/// Reads a recording record by record.
#[derive(Debug)]
pub struct RecordReader<R: Read> {
    input: R,
    offset: u64,
    /// The format version of the records read now: the header's last seen.
    version: u16,
    /// A record failed: no more are read.
    failed: bool,
}

impl<R: Read> RecordReader<R> {
    /// Reads and checks the header.
    pub fn new(mut input: R) -> Result<Self, RecordError> {
        let mut header = [0u8; HEADER_LEN];
        input.read_exact(&mut header).map_err(|e| match e.kind() {
            io::ErrorKind::UnexpectedEof => RecordError::TooShort,
            _ => RecordError::Io(e),
        })?;
        if &header[..6] != MAGIC {
            return Err(RecordError::NoHeader);
        }
        let version = u16::from_le_bytes([header[6], header[7]]);
        if !is_read_version(version) {
            return Err(RecordError::UnsupportedVersion { version });
        }
        Ok(Self {
            input,
            offset: HEADER_LEN as u64,
            version,
            failed: false,
        })
    }

    /// The format version of the records being read: the first header's, or the last
    /// one's passed over in recordings joined one after the other.
    pub fn version(&self) -> u16 {
        self.version
    }

    /// Byte offset of the next record in the file.
    pub fn offset(&self) -> u64 {
        self.offset
    }

    /// The next record; `None` at the end of the file, and after an error (a damaged
    /// or truncated record: what follows it is not read).
    pub fn next_record(&mut self) -> Result<Option<Record>, RecordError> {
        if self.failed {
            return Ok(None);
        }
        let record = self.read_record();
        self.failed = record.is_err();
        record
    }

    fn read_record(&mut self) -> Result<Option<Record>, RecordError> {
        let mut head = [0u8; RECORD_HEAD_LEN];
        let mut got = read_full(&mut self.input, &mut head)?;
        // Another recording's header, joined on: passed over.
        while got >= HEADER_LEN
            && head[..6] == *MAGIC
            && is_read_version(u16::from_le_bytes([head[6], head[7]]))
        {
            self.version = u16::from_le_bytes([head[6], head[7]]);
            head.copy_within(HEADER_LEN..got, 0);
            let kept = got - HEADER_LEN;
            got = kept + read_full(&mut self.input, &mut head[kept..])?;
            self.offset += HEADER_LEN as u64;
        }
        if got == 0 {
            return Ok(None);
        }
        let offset = self.offset;
        if got >= HEADER_LEN && head[..6] == *MAGIC {
            let version = u16::from_le_bytes([head[6], head[7]]);
            return Err(RecordError::JoinedVersion { offset, version });
        }
        if got < head.len() {
            return Err(RecordError::CutOffHead { offset, got });
        }
        let micros = u64::from_le_bytes(head[..8].try_into().expect("8 bytes"));
        let direction = match head[8] {
            0 => Direction::Received,
            1 => Direction::Sent,
            byte => return Err(RecordError::Direction { offset, byte }),
        };
        let len = usize::from(u16::from_le_bytes([head[9], head[10]]));
        if len == 0 {
            return Err(RecordError::EmptyFrame { offset });
        }
        // The frame data, and its CRC in version 2.
        let crc_len = match self.version {
            1 => 0,
            _ => RECORD_CRC_LEN,
        };
        let mut frame = vec![0u8; len + crc_len];
        let got = read_full(&mut self.input, &mut frame)?;
        if got < frame.len() {
            return Err(RecordError::CutOffFrame {
                offset,
                got,
                len: frame.len(),
                crc: crc_len > 0,
            });
        }
        if crc_len > 0 {
            let stored = frame.split_off(len);
            let found = u32::from_le_bytes(stored.try_into().expect("4 bytes"));
            let computed = record_crc(&head, &frame);
            if computed != found {
                return Err(RecordError::Crc {
                    offset,
                    found,
                    computed,
                });
            }
        }
        // Every time a record holds is a `SystemTime` on Unix; Windows' ends in 30828.
        let time = UNIX_EPOCH
            .checked_add(Duration::from_micros(micros))
            .ok_or(RecordError::TimeOutOfRange { offset, micros })?;
        self.offset += (head.len() + len + crc_len) as u64;
        Ok(Some(Record {
            time,
            direction,
            frame,
        }))
    }
}

impl<R: Read> Iterator for RecordReader<R> {
    type Item = Result<Record, RecordError>;
    fn next(&mut self) -> Option<Self::Item> {
        self.next_record().transpose()
    }
}

/// The CRC a record of version 2 ends with: of its head and its frame data.
fn record_crc(head: &[u8; RECORD_HEAD_LEN], frame: &[u8]) -> u32 {
    let mut crc = crc32fast::Hasher::new();
    crc.update(head);
    crc.update(frame);
    crc.finalize()
}

/// Whether this module reads recordings of format `version`.
fn is_read_version(version: u16) -> bool {
    (1..=VERSION).contains(&version)
}

/// Reads until `buf` is full or the input ends; returns the bytes read.
fn read_full(input: &mut impl Read, buf: &mut [u8]) -> io::Result<usize> {
    let mut filled = 0;
    while filled < buf.len() {
        match input.read(&mut buf[filled..]) {
            Ok(0) => break,
            Ok(n) => filled += n,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(filled)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_mcp_packet_of_a_record_is_found_both_ways() {
        use xbee_api::{EncodeFrame, ExplicitAddressingCommandRepr, TransmitRequestRepr};
        let mav = xbee_api::Address64(0x0013_A200_40B5_99B9);
        fn data<F: EncodeFrame>(frame: &F) -> Vec<u8> {
            let mut data = Vec::new();
            frame.write_frame_data(&mut |chunk: &[u8]| data.extend_from_slice(chunk));
            data
        }
        let record = |direction, frame| Record {
            time: UNIX_EPOCH,
            direction,
            frame,
        };
        let landing = mcp_core::Packet::Command(mcp_core::Command::landing(true));
        let tx = TransmitRequestRepr::unicast(mav, b"c\x02\x01");
        let sent = record(Direction::Sent, data(&tx));
        assert_eq!(sent.mcp(), Some((mav, Ok(landing))));
        let explicit = ExplicitAddressingCommandRepr {
            frame_id: 8,
            dst64: mav,
            dst16: xbee_api::Address16::UNKNOWN,
            src_endpoint: 0xE8,
            dst_endpoint: 0xE8,
            cluster_id: 0x0011,
            profile_id: 0xC105,
            radius: 0,
            options: 0,
            data: b"c\xff",
        };
        let explicit = record(Direction::Sent, data(&explicit));
        let (to, packet) = explicit.mcp().unwrap();
        assert_eq!(to, mav);
        assert!(packet.is_err(), "{packet:?}");
        // A frame that carries no data over the air, or that does not read: none.
        assert_eq!(record(Direction::Received, vec![0x8A, 0x06]).mcp(), None);
        assert_eq!(record(Direction::Received, vec![0x90, 0x00]).mcp(), None);
    }

    #[test]
    fn round_trip() {
        let t = UNIX_EPOCH + Duration::from_micros(1_763_683_200_123_456);
        let mut w = RecordWriter::new(Vec::new()).unwrap();
        w.write(t, Direction::Received, &[0x8A, 0x06]).unwrap();
        w.write(t, Direction::Sent, &[0x10, 1, 2, 3]).unwrap();
        let bytes = w.into_inner();
        assert!(is_recording(&bytes));
        let records: Vec<_> = RecordReader::new(&bytes[..])
            .unwrap()
            .collect::<Result<_, _>>()
            .unwrap();
        assert_eq!(records.len(), 2);
        assert_eq!(
            records[0],
            Record {
                time: t,
                direction: Direction::Received,
                frame: vec![0x8A, 0x06]
            }
        );
        assert_eq!(records[1].direction, Direction::Sent);
        assert_eq!(records[1].frame, vec![0x10, 1, 2, 3]);
    }

    #[test]
    fn truncated_record_is_an_error_after_whole_ones() {
        let mut w = RecordWriter::new(Vec::new()).unwrap();
        w.write(UNIX_EPOCH, Direction::Received, &[0x8A, 0x06])
            .unwrap();
        w.write(UNIX_EPOCH, Direction::Received, &[0x8A, 0x02])
            .unwrap();
        let mut bytes = w.into_inner();
        assert_eq!(bytes.len(), HEADER_LEN + 2 * record_len(2));
        bytes.truncate(bytes.len() - 5);
        let mut r = RecordReader::new(&bytes[..]).unwrap();
        assert!(r.next_record().unwrap().is_some());
        let err = r.next_record().unwrap_err();
        assert!(
            matches!(
                err,
                RecordError::CutOffFrame {
                    offset: 25,
                    got: 1,
                    len: 6,
                    crc: true
                }
            ),
            "{err:?}"
        );
        assert_eq!(
            err.to_string(),
            "recording cut off part way through the record at offset 25: 1 of its 6 bytes \
             of frame and CRC are there"
        );
        assert_eq!(io::Error::from(err).kind(), io::ErrorKind::InvalidData);
        // Cut in a record's head.
        bytes.truncate(HEADER_LEN + record_len(2) + 5);
        let mut r = RecordReader::new(&bytes[..]).unwrap();
        assert!(r.next_record().unwrap().is_some());
        let err = r.next_record().unwrap_err();
        assert!(
            matches!(err, RecordError::CutOffHead { offset: 25, got: 5 }),
            "{err:?}"
        );
        assert_eq!(err.offset(), Some(25));
    }

    #[test]
    fn version_1_reads_without_a_crc() {
        let record = [&0u64.to_le_bytes()[..], &[0, 2, 0, 0x8A, 0x06]].concat();
        let bytes = [&b"MCPREC\x01\x00"[..], &record, &record].concat();
        let mut r = RecordReader::new(&bytes[..]).unwrap();
        assert_eq!(r.version(), 1);
        assert_eq!(r.next_record().unwrap().unwrap().frame, [0x8A, 0x06]);
        assert_eq!(r.next_record().unwrap().unwrap().frame, [0x8A, 0x06]);
        assert!(r.next_record().unwrap().is_none());
        // Cut off: the message counts the frame alone.
        let err = RecordReader::new(&bytes[..bytes.len() - 1])
            .unwrap()
            .nth(1)
            .unwrap()
            .unwrap_err();
        assert_eq!(
            err.to_string(),
            "recording cut off part way through the record at offset 21: 1 of its 2 bytes \
             of frame are there"
        );
    }

    #[test]
    fn every_bit_flipped_in_a_record_is_found() {
        let mut w = RecordWriter::new(Vec::new()).unwrap();
        let time = UNIX_EPOCH + Duration::from_micros(1_790_000_000_123_456);
        // A landing command to a MAV, then a Modem Status.
        let landing = [
            0x10, 0x01, 0x00, 0x13, 0xA2, 0x00, 0x40, 0xB5, 0x99, 0xB9, 0xFF, 0xFE, 0x00, 0x00,
            b'c', 0x02, 0x01,
        ];
        w.write(time, Direction::Sent, &landing).unwrap();
        w.write(time, Direction::Received, &[0x8A, 0x06]).unwrap();
        let bytes = w.into_inner();
        let first = HEADER_LEN..HEADER_LEN + record_len(landing.len());
        for at in first.clone() {
            for bit in 0..8 {
                let mut damaged = bytes.clone();
                damaged[at] ^= 1 << bit;
                let results: Vec<_> = RecordReader::new(&damaged[..]).unwrap().collect();
                // No record is read: the damaged one is an error, and none follows it.
                assert_eq!(results.len(), 1, "byte {at} bit {bit}: {results:?}");
                let err = results.into_iter().next().unwrap().unwrap_err();
                assert_eq!(err.offset(), Some(HEADER_LEN as u64), "{err:?}");
            }
        }
        // Undamaged, both read.
        let records: Vec<_> = RecordReader::new(&bytes[..]).unwrap().collect();
        assert!(records.iter().all(Result::is_ok) && records.len() == 2);
        assert_eq!(records[0].as_ref().unwrap().frame, landing);
        let mut damaged = bytes.clone();
        damaged[first.end - 1] ^= 0x10;
        let err = RecordReader::new(&damaged[..])
            .unwrap()
            .next()
            .unwrap()
            .unwrap_err();
        assert!(
            err.to_string()
                .starts_with("record at offset 8 is damaged: its CRC is "),
            "{err}"
        );
    }

    #[test]
    fn each_damage_is_its_own_error_with_its_offset() {
        let record = |micros: u64, direction: u8, frame: &[u8]| {
            let mut bytes = micros.to_le_bytes().to_vec();
            bytes.push(direction);
            bytes.extend_from_slice(&u16::try_from(frame.len()).unwrap().to_le_bytes());
            bytes.extend_from_slice(frame);
            bytes
        };
        let first = record(0, 0, &[0x8A, 0x06]);
        let after = |damaged: Vec<u8>| {
            let bytes = [&b"MCPREC\x01\x00"[..], &first, &damaged].concat();
            let mut r = RecordReader::new(&bytes[..]).unwrap();
            assert!(r.next_record().unwrap().is_some());
            r.next_record().unwrap_err()
        };
        assert!(matches!(
            after(record(0, 2, &[0x8A])),
            RecordError::Direction {
                offset: 21,
                byte: 2
            }
        ));
        assert!(matches!(
            after(record(0, 1, &[])),
            RecordError::EmptyFrame { offset: 21 }
        ));
        // Past what a `SystemTime` holds (on Unix, every u64 of microseconds fits).
        if UNIX_EPOCH
            .checked_add(Duration::from_micros(u64::MAX))
            .is_none()
        {
            assert!(matches!(
                after(record(u64::MAX, 0, &[0x8A])),
                RecordError::TimeOutOfRange { offset: 21, .. }
            ));
        }
        // A failed read is the reader's error, as it came.
        #[derive(Debug)]
        struct Failing;
        impl Read for Failing {
            fn read(&mut self, _: &mut [u8]) -> io::Result<usize> {
                Err(io::Error::new(io::ErrorKind::PermissionDenied, "no"))
            }
        }
        let err = RecordReader::new(Failing).unwrap_err();
        assert!(matches!(&err, RecordError::Io(e) if e.kind() == io::ErrorKind::PermissionDenied));
        assert_eq!(err.offset(), None);
        assert_eq!(io::Error::from(err).kind(), io::ErrorKind::PermissionDenied);
    }

    #[test]
    fn after_a_damaged_record_no_record_is_made_up() {
        let mut w = RecordWriter::new(Vec::new()).unwrap();
        for _ in 0..3 {
            w.write(UNIX_EPOCH, Direction::Received, &[0x8A, 0x06])
                .unwrap();
        }
        let mut bytes = w.into_inner();
        // The second record's direction byte damaged: what follows is not read as
        // records (its bytes, read from there, would make some up).
        bytes[HEADER_LEN + record_len(2) + 8] = 0x80;
        let mut r = RecordReader::new(&bytes[..]).unwrap();
        assert!(r.next_record().unwrap().is_some());
        let err = r.next_record().unwrap_err();
        assert!(err.to_string().contains("direction byte 128"), "{err}");
        assert!(r.next_record().unwrap().is_none());
        assert_eq!(r.offset(), (HEADER_LEN + record_len(2)) as u64);
        let r = RecordReader::new(&bytes[..]).unwrap();
        let results: Vec<_> = r.collect();
        assert_eq!(results.len(), 2, "{results:?}");
        assert!(results[1].is_err());
    }

    #[test]
    fn recordings_joined_one_after_the_other_read_as_one() {
        let recording = |frames: &[&[u8]]| {
            let mut w = RecordWriter::new(Vec::new()).unwrap();
            for frame in frames {
                w.write(UNIX_EPOCH, Direction::Received, frame).unwrap();
            }
            w.into_inner()
        };
        let a = recording(&[&[0x8A, 0x01], &[0x8A, 0x02]]);
        let b = recording(&[&[0x8A, 0x03]]);
        let empty = recording(&[]);
        let joined = [&a[..], &empty, &b, &empty].concat();
        let r = RecordReader::new(&joined[..]).unwrap();
        let frames: Vec<Vec<u8>> = r.map(|r| r.unwrap().frame).collect();
        assert_eq!(
            frames,
            [vec![0x8A, 0x01], vec![0x8A, 0x02], vec![0x8A, 0x03]]
        );
        // A recording of version 1 joined on reads in its version.
        let v1 = [
            &b"MCPREC\x01\x00"[..],
            &0u64.to_le_bytes(),
            &[0, 2, 0, 0x8A, 0x04],
        ]
        .concat();
        let joined = [&a[..], &v1, &b].concat();
        let frames: Vec<Vec<u8>> = RecordReader::new(&joined[..])
            .unwrap()
            .map(|r| r.unwrap().frame)
            .collect();
        assert_eq!(frames.len(), 4);
        assert_eq!(frames[2..], [vec![0x8A, 0x04], vec![0x8A, 0x03]]);
        // A header of a version this module does not read is an error there, not a
        // record (in version 1, with no CRC, it would read as one).
        let mut other = b.clone();
        other[6] = 3;
        for first in [&a[..], &v1[..]] {
            let joined = [first, &other].concat();
            let err = RecordReader::new(&joined[..])
                .unwrap()
                .find_map(Result::err)
                .unwrap();
            assert!(
                matches!(err, RecordError::JoinedVersion { offset, version: 3 }
                    if offset == first.len() as u64),
                "{err:?}"
            );
            assert_eq!(err.offset(), Some(first.len() as u64));
        }
        // A time whose first bytes read as a header's is written a microsecond later.
        let magic_time = u64::from_le_bytes(*b"MCPREC\x02\x00");
        let mut w = RecordWriter::new(Vec::new()).unwrap();
        let at = UNIX_EPOCH + Duration::from_micros(magic_time);
        w.write(at, Direction::Received, &[0x8A, 0x06]).unwrap();
        let record = RecordReader::new(&w.into_inner()[..])
            .unwrap()
            .next()
            .unwrap()
            .unwrap();
        assert_eq!(record.time, at + Duration::from_micros(1));
    }

    #[test]
    fn rejects_other_files_and_versions() {
        assert!(matches!(
            RecordReader::new(&b"\x7e\x00\x02\x8a\x06\x6f\x00\x00"[..]),
            Err(RecordError::NoHeader)
        ));
        assert!(matches!(
            RecordReader::new(&b"MCPREC"[..]),
            Err(RecordError::TooShort)
        ));
        let err = RecordReader::new(&b"MCPREC\x03\x00"[..]).unwrap_err();
        assert!(
            matches!(err, RecordError::UnsupportedVersion { version: 3 }),
            "{err:?}"
        );
        assert!(err.to_string().contains("version 3"), "{err}");
        assert!(RecordReader::new(&b"MCPREC\x00\x00"[..]).is_err());
    }
}
