//! Every frame of a link, both ways, to a recording (`mcp-gs decode FILE` shows it),
//! while asking the MAV's landing state once a second.
//!
//! `record [LINK] [FILE] [SECONDS]` (default `flight.mcprec`, 5 s).

use std::fs::File;
use std::io::BufWriter;
use std::time::Duration;

use futures::StreamExt;
use mcp_host::LinkOptions;
use mcp_host::mcp_core::StatusRequest;
use mcp_host::record::RecordWriter;

#[tokio::main]
async fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let link = mcp_host_examples::link(args.next())?;
    let path = args.next().unwrap_or_else(|| "flight.mcprec".to_owned());
    let seconds: u64 = args.next().map_or(Ok(5), |s| s.parse())?;
    let mav = mcp_host_examples::mav(None)?;

    let (_stream, sender) = mcp_host::connect(&link, LinkOptions::default()).await?;
    // Taken before anything is sent: it starts with what comes after it.
    let mut frames = sender.tap_frames();
    let mut recording = RecordWriter::new(BufWriter::new(File::create(&path)?))?;

    let asking = sender.clone();
    let ask = tokio::spawn(async move {
        let mut every = tokio::time::interval(Duration::from_secs(1));
        for _ in 0..seconds {
            every.tick().await;
            match asking.request(mav, StatusRequest::Landing).await {
                Ok(report) => println!("{report}"),
                Err(e) => eprintln!("{e}"),
            }
        }
        // The link ends, and the tap with it.
        asking.close();
    });
    let mut written = 0u64;
    while let Some(record) = frames.next().await {
        recording.write(record.time, record.direction, &record.frame)?;
        written += 1;
    }
    recording.flush()?;
    ask.await?;
    println!("{written} frames recorded to {path}");
    Ok(())
}
