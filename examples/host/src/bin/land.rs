//! A command, its delivery, and the MAV's report that it took it: the landing command
//! sent with `send_confirmed`, which asks the landing status once the command is
//! delivered and succeeds only if the report shows the MAV landing (or on the ground;
//! taking off, stabilizing or in flight for `off`).
//!
//! `land [LINK] [MAV] [on|off]` (default `on`).

use mcp_host::mcp_core::Command;
use mcp_host::{ConfirmError, DeliveryReport, LinkOptions};

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
    // The radio's delivery status (the MAV's radio got it), then the MAV's own word on
    // it, each waited for the link's default timeout (12 s).
    match sender.send_confirmed(mav, &Command::landing(on)).await {
        Ok(confirmed) => {
            if let DeliveryReport::Delivered { retries, .. } = confirmed.delivery {
                println!("delivered after {retries} retries");
            }
            println!("{}", confirmed.report);
        }
        // The MAV says it is in another state: it did not take the command.
        Err(ConfirmError::NotTaken { report, .. }) => {
            return Err(format!("the MAV did not take it: {report}").into());
        }
        // A timeout is worth another try; anything else is not.
        Err(e) if e.is_timeout() => return Err(format!("{e} (try again)").into()),
        Err(e) => return Err(e.into()),
    }
    sender.close();
    sender.closed().await;
    Ok(())
}
