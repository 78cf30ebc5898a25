//! Recordings, `mcp_host::record::RecordReader`: a file given to `mcp-gs decode` or
//! `replay` may hold any bytes (a recording damaged, cut off, or no recording at all).
//!
//! Input: the file's bytes. A header of format version 1 (records without a CRC) is put
//! in front of inputs that do not start with `MCPREC`, so that most runs reach the
//! records and their frames; an input with a header of its own (version 2, say) is
//! read as it is.
//!
//! Checks: no panic; every record holds 1 to 65 535 frame bytes, its frame and MCP
//! packet parse without panicking, and the reader's offset moves past it; after an
//! error with an offset, the reader stands at that offset and gives no more records;
//! the records read back the same once written again (in version 2, with their CRCs).
#![no_main]

use libfuzzer_sys::fuzz_target;
use mcp_host::record::{HEADER_LEN, MAGIC, RecordReader, RecordWriter};

fuzz_target!(|input: &[u8]| {
    let mut bytes = Vec::with_capacity(HEADER_LEN + input.len());
    if !input.starts_with(MAGIC) {
        bytes.extend_from_slice(MAGIC);
        bytes.extend_from_slice(&1u16.to_le_bytes());
    }
    bytes.extend_from_slice(input);

    let Ok(mut reader) = RecordReader::new(&bytes[..]) else {
        return;
    };
    let mut records = Vec::new();
    let mut offset = reader.offset();
    loop {
        match reader.next_record() {
            Ok(Some(record)) => {
                assert!((1..=usize::from(u16::MAX)).contains(&record.frame.len()));
                let _ = record.parse();
                let _ = record.mcp();
                assert!(reader.offset() > offset);
                offset = reader.offset();
                records.push(record);
            }
            Ok(None) => break,
            Err(error) => {
                if let Some(at) = error.offset() {
                    assert_eq!(at, reader.offset());
                }
                assert!(matches!(reader.next_record(), Ok(None)));
                break;
            }
        }
    }

    let mut writer = RecordWriter::new(Vec::new()).expect("a Vec takes the header");
    for record in &records {
        writer
            .write(record.time, record.direction, &record.frame)
            .expect("a record read is written");
    }
    let written = writer.into_inner();
    let again: Vec<_> = RecordReader::new(&written[..])
        .expect("its own header")
        .collect::<Result<_, _>>()
        .expect("records written read back");
    assert_eq!(again, records);
});
