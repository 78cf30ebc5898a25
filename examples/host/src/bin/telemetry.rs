//! A MAV's altitude telemetry for a while, turned on again each time the link comes back:
//! a MAV restarted, or a radio plugged in again, has forgotten what it was asked.
//!
//! `telemetry [LINK] [MAV] [SECONDS]` (default 10 s).

use std::time::Duration;

use futures::StreamExt;
use mcp_host::mcp_core::{Command, Packet, TelemetryId};
use mcp_host::{Event, LinkEvent, LinkOptions};

#[tokio::main]
async fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let link = mcp_host_examples::link(args.next())?;
    let mav = mcp_host_examples::mav(args.next())?;
    let seconds: u64 = args.next().map_or(Ok(10), |s| s.parse())?;

    let (stream, sender) = mcp_host::connect(&link, LinkOptions::default()).await?;
    let on = Command::telemetry_to_coordinator(true, TelemetryId::Altitude);
    // Resolves once the MAV's radio confirmed delivery.
    sender.send(mav, &on).await?;

    // Every event until the time is up (or the link has ended).
    let end = tokio::time::sleep(Duration::from_secs(seconds));
    let mut events = std::pin::pin!(stream.take_until(end));
    while let Some(event) = events.next().await {
        match event {
            Event::Packet(rx) if rx.origin.src64 == mav => match &rx.packet {
                Packet::Telemetry(telemetry) => {
                    for record in telemetry {
                        println!("{} = {}", record.id, record.value);
                    }
                }
                other => println!("{other}"),
            },
            Event::Link(LinkEvent::Reconnected { .. }) => {
                println!("{event}");
                // In a task of its own: the stream goes on being read meanwhile.
                let sender = sender.clone();
                tokio::spawn(async move {
                    if let Err(e) = sender.send(mav, &on).await {
                        eprintln!("telemetry not turned on again: {e}");
                    }
                });
            }
            other => println!("{other}"),
        }
    }
    sender.close();
    sender.closed().await;
    Ok(())
}
