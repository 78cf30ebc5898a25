//! A command, its delivery, and the MAV's report of what it did: the landing command,
//! then a landing status request, whose report is matched to it by type and source.
//!
//! `land [LINK] [MAV] [on|off]` (default `on`).

use mcp_host::mcp_core::{Command, StatusRequest};
use mcp_host::{DeliveryReport, LinkOptions};

#[tokio::main]
async fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let link = mcp_host_examples::link(args.next())?;
    let mav = mcp_host_examples::mav(args.next())?;
    let on = match args.next().as_deref() {
        None | Some("on") => true,
        Some("off") => false,
        Some(other) => return Err(format!("expected on or off, got `{other}`").into()),
    };

    let (_stream, sender) = mcp_host::connect(&link, LinkOptions::default()).await?;
    // The radio's delivery status: the MAV's radio got it.
    if let DeliveryReport::Delivered { retries, .. } =
        sender.send(mav, &Command::landing(on)).await?
    {
        println!("delivered after {retries} retries");
    }
    // The MAV's own word on it, with the link's default timeout (12 s).
    match sender.request(mav, StatusRequest::Landing).await {
        Ok(report) => println!("{report}"),
        // A timeout is worth another try; anything else is not.
        Err(e) if e.is_timeout() => return Err(format!("{e} (try again)").into()),
        Err(e) => return Err(e.into()),
    }
    sender.close();
    sender.closed().await;
    Ok(())
}
