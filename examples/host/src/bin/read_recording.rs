//! The MCP packets of a recording (`mcp-gs monitor --record`, `hub --record`, or the
//! `record` example), with their times and directions; other frames by their type.
//!
//! `read_recording FILE`

use std::fs::File;
use std::io::BufReader;
use std::time::UNIX_EPOCH;

use mcp_host::record::{Direction, RecordReader};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args()
        .nth(1)
        .ok_or("usage: read_recording FILE")?;
    let records = RecordReader::new(BufReader::new(File::open(&path)?))?;
    for record in records {
        // A recording cut off part way (a power lost) ends in an error, after every
        // whole record before it.
        let record = record?;
        let time = record.time.duration_since(UNIX_EPOCH)?.as_secs_f64();
        let way = match record.direction {
            Direction::Received => "rx",
            Direction::Sent => "tx",
        };
        // A record holds the frame's data: frame type first, unescaped. An MCP packet
        // is the data of a frame to or from another radio.
        match record.mcp() {
            Some((peer, Ok(packet))) => println!("{time:.3} {way} {peer}: {packet}"),
            Some((peer, Err(e))) => println!("{time:.3} {way} {peer}: not an MCP packet: {e}"),
            None => match record.parse() {
                Ok(other) => println!("{time:.3} {way} frame 0x{:02x}", other.frame_type()),
                Err(e) => println!("{time:.3} {way} unreadable frame: {e}"),
            },
        }
    }
    Ok(())
}
