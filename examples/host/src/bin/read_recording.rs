//! The MCP packets of a recording (`mcp-gs monitor --record`, `hub --record`, or the
//! `record` example), with their times and directions; other frames by their type.
//!
//! `read_recording FILE`

use std::fs::File;
use std::io::BufReader;
use std::time::UNIX_EPOCH;

use mcp_host::record::{Direction, RecordReader};
use mcp_host::xbee_api::Frame;

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
        // A record holds the frame's data: frame type first, unescaped.
        let (peer, payload) = match record.parse() {
            Ok(Frame::ReceivePacket(rx)) => (rx.src64, rx.data),
            Ok(Frame::ExplicitRxIndicator(rx)) => (rx.src64, rx.data),
            Ok(Frame::TransmitRequest(tx)) => (tx.dst64, tx.data),
            Ok(Frame::ExplicitAddressingCommand(tx)) => (tx.dst64, tx.data),
            Ok(other) => {
                println!("{time:.3} {way} frame 0x{:02x}", other.frame_type());
                continue;
            }
            Err(e) => {
                println!("{time:.3} {way} unreadable frame: {e}");
                continue;
            }
        };
        match mcp_host::mcp_core::parse(payload) {
            Ok(packet) => println!("{time:.3} {way} {peer}: {packet}"),
            Err(e) => println!("{time:.3} {way} {peer}: not an MCP packet: {e}"),
        }
    }
    Ok(())
}
