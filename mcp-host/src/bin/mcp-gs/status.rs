//! `mcp-gs status`: send a status request and print the report.

use clap::Args;
use mcp_core::{Command, CommandType, Packet};
use mcp_host::{CommandSender, RequestError};
use xbee_api::Address64;

use crate::command::status_request;
use crate::hints::{diagnosed, diagnosed_send, diagnosed_unanswered};
use crate::link_args::LinkArgs;
use crate::send::{failure_json, timeout_json};
use crate::{Failure, Format};

/// Arguments of `status`.
#[derive(Debug, Args)]
#[command(mut_arg("timeout", |arg| arg.help(
    "Seconds to wait to connect, and for the MAV's report [default: 12]"
)))]
#[command(mut_arg("link", |arg| arg.help(crate::link_args::ONE_SHOT_LINK_HELP)))]
pub(crate) struct StatusArgs {
    #[command(flatten)]
    link: LinkArgs,
    /// The MAV's 64-bit address (16 hex digits).
    #[arg(long, value_name = "ADDR", value_parser = crate::link_args::parse_address64)]
    to: Address64,
    /// Output format: `json` prints the report's object, with `"result":"answered"`,
    /// `src64` and `received_at` added; a failure as `send` does,
    /// `{"result":"failed",...}` with the transmit status's fields,
    /// `{"result":"timeout",...}` with whether the radio delivered the request,
    /// `{"result":"disconnected",...}` when the link went away, or
    /// `{"result":"not_sent",...}` when it could not be opened.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    /// What to ask: telemetry_to_coordinator (or telemetry), landing, controllers
    /// (controller), trajectory_set (trajectory), position_slave_set (slave-set) or time
    /// (or the type number).
    #[arg(value_parser = crate::command::parse_status_kind)]
    kind: CommandType,
    /// For telemetry_to_coordinator: the telemetry id (a name or a number).
    // Parsed once the kind is known: another kind takes no id at all, which is what a
    // wrong one should hear.
    #[arg(long_help = crate::command::telemetry_id_help())]
    id: Option<String>,
}

/// Runs `status`.
pub(crate) async fn run(args: StatusArgs) -> Result<(), Failure> {
    if args.to == Address64::BROADCAST {
        return Err(Failure::input(
            "status asks one MAV and prints its report: give the MAV's address (to ask every \
             MAV, `send --to 000000000000ffff status ...` and watch the reports with `monitor`)",
        ));
    }
    let request = status_request(args.kind, args.id.as_deref()).map_err(Failure::input)?;
    let (_stream, sender) = args.link.open(false).await.inspect_err(|failure| {
        if args.format == Format::Json {
            let mcp = mcp_host::render::json::packet_json(&Packet::<&[u8]>::Command(
                Command::StatusRequest(request),
            ));
            let fields = serde_json::json!({ "dst64": args.to.to_string(), "mcp": mcp });
            out!("{}", crate::link_args::not_sent_json(failure, fields));
        }
    })?;
    let report = sender
        .request_with(args.to, request, Some(args.link.timeout()))
        .await;
    // The radio's refusal is an answer too, and so is a report that did not come: JSON
    // prints them as `send` does, with the failure on standard error.
    if let (Format::Json, Err(error)) = (args.format, &report) {
        let mcp = mcp_host::render::json::packet_json(&Packet::<&[u8]>::Command(
            Command::StatusRequest(request),
        ));
        let json = match error {
            RequestError::Send(error) => failure_json(error, args.to, mcp),
            RequestError::Timeout {
                delivered,
                undecodable,
                ..
            } => {
                let mut json = timeout_json(args.to, None, *delivered, mcp);
                // Frames that failed to decode meanwhile: the report may have been one.
                if *undecodable > 0 {
                    json["undecodable"] = (*undecodable).into();
                }
                Some(json)
            }
            _ => None,
        };
        if let Some(json) = json {
            out!("{json}");
        }
    }
    let report = match report {
        Ok(report) => report,
        Err(error) => return Err(request_failure(error, &args.link, &sender).await),
    };
    let received_at = std::time::SystemTime::now();
    let packet = Packet::Report(report);
    match args.format {
        Format::Text => out!("{}", packet.as_borrowed()),
        Format::Json => {
            let mut json = mcp_host::render::json::packet_json(&packet);
            // That the MAV answered (as a failure says `failed` or `timeout`), which MAV,
            // and when (a time report has a `time` field of its own).
            if let serde_json::Value::Object(map) = &mut json {
                map.insert("result".into(), "answered".into());
                map.insert("src64".into(), args.to.to_string().into());
                let secs = mcp_host::render::json::seconds(received_at);
                map.insert("received_at".into(), secs.into());
            }
            out!("{json}");
        }
    }
    Ok(())
}

/// A status request's failure as the operator hears it (`status`, `send --confirm`): a
/// request not delivered as `send` says it, with what its failure points to (an address
/// no radio has, a frame the link did not take in time); no report in time (exit 4),
/// after checking, when it was delivered and nothing undecodable came, whether a hub in
/// another API mode than the radio's dropped it.
pub(crate) async fn request_failure(
    error: RequestError,
    link: &LinkArgs,
    sender: &CommandSender,
) -> Failure {
    // The local radio never confirmed delivery: as for a send nobody answered.
    let unanswered = matches!(
        error,
        RequestError::Timeout {
            delivered: false,
            ..
        }
    );
    // Delivered, no report, and nothing undecodable here: the report may have been
    // dropped on the way by a hub in another API mode than the radio's.
    if let RequestError::Timeout {
        delivered: true,
        undecodable: 0,
        ..
    } = error
    {
        link.check_mode_after_silence(sender).await;
    }
    let stats = sender.stats();
    match error {
        RequestError::Send(e) => diagnosed_send(e, link, &stats),
        timeout @ RequestError::Timeout { .. } => {
            let failure = Failure::new(Failure::TIMEOUT, timeout.to_string());
            if unanswered {
                diagnosed_unanswered(failure, link, &stats)
            } else {
                diagnosed(failure, link, &stats)
            }
        }
        other => diagnosed(
            Failure::new(Failure::OTHER, other.to_string()),
            link,
            &stats,
        ),
    }
}
