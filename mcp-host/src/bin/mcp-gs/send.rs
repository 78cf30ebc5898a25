//! `mcp-gs send`: send one command and print the delivery status.

use clap::Args;
use mcp_host::{DeliveryReport, FrameId, SendOptions};
use xbee_api::Address64;

use crate::Failure;
use crate::command::CommandArgs;
use crate::link_args::{LinkArgs, send_failure};

/// Arguments of `send`.
#[derive(Debug, Args)]
pub(crate) struct SendArgs {
    #[command(flatten)]
    link: LinkArgs,
    /// Destination: a MAV's 64-bit address (16 hex digits), or 000000000000FFFF to
    /// broadcast.
    #[arg(long, value_name = "ADDR", value_parser = crate::link_args::parse_address64)]
    to: Address64,
    /// Fire and forget: frame id 0, the radio sends no transmit status.
    #[arg(long)]
    no_status: bool,
    /// The command.
    #[command(subcommand)]
    command: CommandArgs,
}

/// Runs `send`.
pub(crate) async fn run(args: SendArgs) -> Result<(), Failure> {
    let payload = args.command.payload().map_err(Failure::input)?;
    let (_stream, sender) = args.link.open(false).await?;
    let options = SendOptions {
        timeout: Some(args.link.timeout()),
        frame_id: if args.no_status {
            FrameId::None
        } else {
            FrameId::Auto
        },
    };
    let report = sender
        .send_payload(args.to, payload.clone(), options)
        .await
        .map_err(send_failure)?;
    let what = mcp_host::render::text::mcp(&payload);
    match report {
        DeliveryReport::Delivered {
            frame_id,
            dst16,
            retries,
            discovery,
        } => out!(
            "delivered to {}/{dst16} (frame id {frame_id}, retries {retries}, discovery {discovery}): {what}",
            args.to
        ),
        DeliveryReport::Written => out!("written, no status asked (frame id 0): {what}"),
    }
    Ok(())
}
