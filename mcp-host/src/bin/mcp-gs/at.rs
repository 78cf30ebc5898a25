//! `mcp-gs at`: read or set an AT parameter of the local radio or of a remote one.

use clap::Args;
use xbee_api::{Address64, AtStatus, Frame};

use crate::Failure;
use crate::link_args::{LinkArgs, send_failure};
use mcp_host::render::json::hex;

/// Arguments of `at`.
#[derive(Debug, Args)]
pub(crate) struct AtArgs {
    #[command(flatten)]
    link: LinkArgs,
    /// Ask a remote radio (Remote AT Command, 0x17) instead of the local one.
    #[arg(long, value_name = "ADDR", value_parser = crate::link_args::parse_address64)]
    to: Option<Address64>,
    /// VALUE is text (e.g. for NI), not hex.
    #[arg(long)]
    text: bool,
    /// For a remote radio: do not apply the change at once (queue it until AC).
    #[arg(long)]
    no_apply: bool,
    /// The two-letter AT command, e.g. AP, NP, NI, SH, SL, MY, ID, CH.
    command: String,
    /// The value to set, in hex (e.g. `2` for AP=2) or text with --text; omit to read.
    value: Option<String>,
}

fn parse_value(value: &str, text: bool) -> Result<Vec<u8>, String> {
    if text {
        return Ok(value.as_bytes().to_vec());
    }
    let digits = value
        .strip_prefix("0x")
        .or_else(|| value.strip_prefix("0X"))
        .unwrap_or(value);
    if digits.is_empty() || !digits.chars().all(|c| c.is_ascii_hexdigit()) {
        return Err(format!("value `{value}` is not hex (use --text for text)"));
    }
    let padded = if digits.len() % 2 == 1 {
        format!("0{digits}")
    } else {
        digits.to_string()
    };
    Ok((0..padded.len())
        .step_by(2)
        .filter_map(|i| u8::from_str_radix(&padded[i..i + 2], 16).ok())
        .collect())
}

/// Runs `at`.
pub(crate) async fn run(args: AtArgs) -> Result<(), Failure> {
    let command: [u8; 2] = args
        .command
        .to_ascii_uppercase()
        .as_bytes()
        .try_into()
        .ok()
        .filter(|c: &[u8; 2]| c.iter().all(u8::is_ascii_alphanumeric))
        .ok_or_else(|| {
            Failure::input(format!("`{}` is not a two-letter AT command", args.command))
        })?;
    let parameter = match &args.value {
        Some(value) => parse_value(value, args.text).map_err(Failure::input)?,
        None => Vec::new(),
    };
    let (_stream, sender) = args.link.open(false).await?;
    let timeout = Some(args.link.timeout());
    let response = match args.to {
        None => sender.at(command, &parameter, timeout).await,
        Some(to) => {
            sender
                .remote_at(to, command, &parameter, !args.no_apply, timeout)
                .await
        }
    }
    .map_err(send_failure)?;
    let (status, data) = match response.parse() {
        Ok(Frame::AtCommandResponse(at)) => (at.status, at.data),
        Ok(Frame::RemoteAtResponse(at)) => (at.status, at.data),
        _ => {
            return Err(Failure::new(
                Failure::OTHER,
                format!("unexpected answer: {}", hex(response.data())),
            ));
        }
    };
    let name = String::from_utf8_lossy(&command).into_owned();
    if status != AtStatus::Ok {
        return Err(Failure::new(
            Failure::OTHER,
            format!(
                "{name}: the radio answered {status} (0x{:02x})",
                u8::from(status)
            ),
        ));
    }
    if data.is_empty() {
        out!("{name}: ok");
    } else if data.iter().all(|b| b.is_ascii_graphic() || *b == b' ') && data.len() > 2 {
        out!(
            "{name} = \"{}\" (hex {})",
            String::from_utf8_lossy(data),
            hex(data)
        );
    } else {
        let number = data.iter().fold(0u128, |n, &b| (n << 8) | u128::from(b));
        out!(
            "{name} = {} (0x{}, {number})",
            hex(data).to_uppercase(),
            hex(data)
        );
    }
    Ok(())
}
