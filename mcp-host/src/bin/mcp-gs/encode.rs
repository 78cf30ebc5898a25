//! `mcp-gs encode`: the Transmit Request frame of a command, as hex.

use clap::Args;
use xbee_api::{Address16, Address64, EncodeFrame, TransmitRequestRepr};

use crate::command::CommandArgs;
use crate::{ApiModeArg, Failure};
use mcp_host::render::json::hex;

/// Arguments of `encode`.
#[derive(Debug, Args)]
pub(crate) struct EncodeArgs {
    /// Destination 64-bit address (16 hex digits; 000000000000FFFF broadcasts).
    #[arg(long, value_name = "ADDR", value_parser = crate::link_args::parse_address64)]
    to: Address64,
    /// Destination 16-bit address (FFFE when unknown).
    #[arg(
        long,
        value_name = "ADDR16",
        default_value = "fffe",
        value_parser = crate::link_args::parse_address16
    )]
    to16: Address16,
    /// Frame id (0 asks the radio for no transmit status; decimal or 0x-hex).
    #[arg(long, default_value = "1", value_parser = crate::command::parse_byte)]
    frame_id: u8,
    /// API mode (2 escapes special bytes).
    #[arg(long, value_name = "1|2", default_value = "1")]
    api_mode: ApiModeArg,
    /// Transmit options byte (decimal or 0x-hex, e.g. 0x01 disables retries).
    #[arg(long, default_value = "0", value_parser = crate::command::parse_byte)]
    options: u8,
    /// Broadcast radius (0: the maximum; decimal or 0x-hex).
    #[arg(long, default_value = "0", value_parser = crate::command::parse_byte)]
    radius: u8,
    /// The command.
    #[command(subcommand)]
    command: CommandArgs,
}

/// Runs `encode`.
pub(crate) fn run(args: EncodeArgs) -> Result<(), Failure> {
    let payload = args.command.payload().map_err(Failure::input)?;
    crate::send::warn_of_size(&args.command, &payload, args.to);
    let frame = TransmitRequestRepr {
        frame_id: args.frame_id,
        dst64: args.to,
        dst16: args.to16,
        radius: args.radius,
        options: args.options,
        data: &payload,
    };
    let mut buf = vec![0u8; frame.encoded_len(args.api_mode.0)];
    let n = frame
        .encode(args.api_mode.0, &mut buf)
        .map_err(|e| Failure::input(e.to_string()))?;
    let hex = hex(&buf[..n]).to_uppercase();
    let spaced: Vec<&str> = (0..hex.len()).step_by(2).map(|i| &hex[i..i + 2]).collect();
    out!("{}", spaced.join(" "));
    Ok(())
}
