//! `mcp-gs nodes`: the radios the local one can reach (node discovery, `ND`).

use std::time::Duration;

use clap::Args;
use mcp_host::SendError;
use mcp_host::discovery::DiscoverError;

use crate::at::{outcome_json, timeout_json};

use crate::hints::{diagnosed_send, with_mode_hint};
use crate::link_args::LinkArgs;
use crate::{Failure, Format};

/// Arguments of `nodes`.
#[derive(Debug, Args)]
#[command(mut_arg("timeout", |arg| arg.help(
    "Seconds to wait to connect, and for the radio's discovery time (N? or NT) \
asked first [default: 12]; the answers are gathered for --window"
)))]
#[command(mut_arg("link", |arg| arg.help(crate::link_args::ONE_SHOT_LINK_HELP)))]
pub(crate) struct NodesArgs {
    #[command(flatten)]
    link: LinkArgs,
    /// Seconds to gather answers (default: the radio's discovery time, N? or NT, and a
    /// second more).
    #[arg(long, value_name = "SECONDS", value_parser = crate::link_args::parse_seconds)]
    window: Option<f64>,
    /// Output format: a line per radio, or a JSON object per radio; a discovery that
    /// lists none prints one object that says why, as `at` does:
    /// `{"result":"timeout","command":"ND"}` when no radio answered,
    /// `{"result":"unreadable","command":"ND","unreadable":N}` when none of the answers
    /// could be read, `{"result":"failed","command":"ND","status":...}` when the radio
    /// refused ND, `{"result":"disconnected",...}` when the link went away, or
    /// `{"result":"not_sent",...}` when it could not be opened.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

/// The AT command `nodes` is, in its JSON outcomes.
const ND: &str = "ND";

/// Runs `nodes`.
pub(crate) async fn run(args: NodesArgs) -> Result<(), Failure> {
    let json = args.format == Format::Json;
    let (_stream, sender) = args.link.open(false).await.inspect_err(|failure| {
        if json {
            let fields = outcome_json("not_sent", ND, None);
            out!("{}", crate::link_args::not_sent_json(failure, fields));
        }
    })?;
    // A link lost, or a radio that does not answer, is an outcome too, in JSON.
    let failed = |e: SendError| {
        if let (true, Some(mut outcome)) = (json, timeout_json(&e, ND, None)) {
            // The outcome of `nodes` as a whole: the frame id of what timed out (ND, or
            // the N? or NT asked first) would say another command's.
            if let Some(fields) = outcome.as_object_mut() {
                fields.remove("id");
            }
            out!("{outcome}");
        }
        diagnosed_send(e, &args.link, &sender.stats())
    };
    let window = match args.window {
        Some(seconds) => Duration::from_secs_f64(seconds),
        None => mcp_host::discovery::window(&sender).await.map_err(failed)?,
    };
    err!(
        "mcp-gs: asking who is there (ND), answers for {}",
        mcp_host::render::Seconds(window)
    );
    crate::hints::warn_hub_window(&args.link.link, window);
    let found = sender.discover(Some(window)).await.map_err(|e| match e {
        DiscoverError::Send(e) => failed(e),
        other => {
            if let (true, DiscoverError::Refused { status, .. }) = (json, &other) {
                let mut outcome = outcome_json("failed", ND, None);
                outcome["status"] = u8::from(*status).into();
                if let Some(name) = status.meaning().name() {
                    outcome["status_name"] = name.into();
                }
                out!("{outcome}");
            }
            Failure::new(Failure::OTHER, other.to_string())
        }
    })?;
    if found.unreadable > 0 {
        let unreadable = format!(
            "{} could not be read as a Zigbee or DigiMesh radio's (an 802.15.4 radio's \
             answers are not read here)",
            crate::counted(found.unreadable as u64, "answer")
        );
        // Radios answered, but none could be listed: no list, and no success.
        if found.nodes.is_empty() {
            if json {
                let mut outcome = outcome_json("unreadable", ND, None);
                outcome["unreadable"] = found.unreadable.into();
                out!("{outcome}");
            }
            return Err(Failure::new(Failure::OTHER, unreadable));
        }
        err!("mcp-gs: {unreadable}");
    } else if found.nodes.is_empty() {
        let stats = sender.stats();
        let failure = Failure::new(
            Failure::TIMEOUT,
            match stats.decode_errors() {
                // Frames came that could not be read: answers, perhaps, in another mode.
                0 => "no radio answered: the others are off, out of range, or in another \
                      network (ID, CH)"
                    .to_owned(),
                failed => format!(
                    "no answer could be read: {} from the radio failed to decode",
                    crate::counted(failed, "frame")
                ),
            },
        );
        if json {
            out!("{}", outcome_json("timeout", ND, None));
        }
        // Answers that failed their checksum: the local radio may be in the other mode.
        return Err(with_mode_hint(failure, &args.link, &stats));
    }
    if found.left_out > 0 {
        err!(
            "mcp-gs: warning: {} left out: no more than {} are listed (is this a radio?)",
            crate::counted(found.left_out as u64, "more radio"),
            mcp_host::discovery::MAX_NODES
        );
    }
    for node in &found.nodes {
        match args.format {
            Format::Text => out!("{node}"),
            Format::Json => out!("{}", mcp_host::render::json::node(node)),
        }
    }
    Ok(())
}
