//! `mcp-gs send`: send one command and print the delivery status.

use std::time::Duration;

use clap::Args;
use futures::StreamExt;
use mcp_core::{Command, Packet, Report, Waypoint};
use mcp_host::render::Seconds;
use mcp_host::{
    ConfirmError, DeliveryReport, Event, FrameId, PacketStream, SendError, SendOptions,
};
use xbee_api::{Address64, DeliveryStatus, DiscoveryStatus, ReceivePacketRepr};

use crate::command::CommandArgs;
use crate::hints::{diagnosed, diagnosed_send};
use crate::link_args::LinkArgs;
use crate::{Failure, Format};

/// Arguments of `send`.
#[derive(Debug, Args)]
#[command(mut_arg("timeout", |arg| arg.help(
    "Seconds to wait to connect, for the radio's transmit status, and, for a \
trajectory to one MAV or with --confirm, for each of the MAV's reports [default: 12]"
)))]
#[command(mut_arg("link", |arg| arg.help(crate::link_args::ONE_SHOT_LINK_HELP)))]
pub(crate) struct SendArgs {
    #[command(flatten)]
    link: LinkArgs,
    /// Destination: a MAV's 64-bit address (16 hex digits), or 000000000000FFFF to
    /// broadcast.
    #[arg(long, value_name = "ADDR", value_parser = crate::link_args::parse_address64)]
    to: Address64,
    /// Fire and forget: frame id 0, the radio sends no transmit status.
    #[arg(long, conflicts_with = "confirm")]
    no_status: bool,
    /// Once the command is delivered, ask the MAV the matching status request and
    /// fail unless its report shows the command taken (exit 1 if it shows otherwise
    /// or cannot say, 4 if no report comes in time): landing on confirmed by `landing`
    /// or `on_ground`, a controller by being active, ... (a trajectory to one MAV is
    /// checked without it, by the report the MAV answers it with); a position set, a
    /// status request, a message or a broadcast cannot be.
    #[arg(long)]
    confirm: bool,
    /// Output format: `json` prints one object, `{"result":"delivered",...}` or
    /// `{"result":"failed",...}` with the transmit status's fields,
    /// `{"result":"timeout",...}` when no status came in time,
    /// `{"result":"disconnected",...}` when the link went away meanwhile,
    /// `{"result":"not_sent",...}` when it could not be opened, or
    /// `{"result":"written",...}` (--no-status); the packet as `mcp`; for a
    /// trajectory to one MAV with a status asked, `trajectory_confirmed` (and, when
    /// false, `trajectory_reported`: the waypoints the MAV reported instead, or null
    /// when it reported none in time); with --confirm, `confirmed` and `reported` (the
    /// MAV's report as `monitor` prints a report's fields, or null when none came).
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
    /// The command.
    #[command(subcommand)]
    command: CommandArgs,
}

/// The receive buffer of the deployed MAV firmware, in bytes of API frame: it drops
/// longer frames.
const DEPLOYED_MAV_FRAME: usize = 60;

/// Warns of a payload that the deployed MAV firmware drops for its size, or that no
/// radio broadcasts (a broadcast goes out in one radio packet, never in fragments).
pub(crate) fn warn_of_size(command: &CommandArgs, payload: &[u8], to: Address64) {
    // The MAV receives the payload in a Receive Packet: 4 framing bytes and 12 of header.
    let frame = payload.len() + 4 + ReceivePacketRepr::HEADER_LEN;
    if frame > DEPLOYED_MAV_FRAME {
        let largest = DEPLOYED_MAV_FRAME - 4 - ReceivePacketRepr::HEADER_LEN;
        let what = match command {
            // A trajectory set: category, type and count, then 16 bytes a waypoint.
            CommandArgs::Trajectory { .. } => {
                format!("a trajectory of more than {} waypoints", (largest - 3) / 16)
            }
            // A message: the category, then the text.
            CommandArgs::Message { .. } => {
                format!("a message of more than {} bytes", largest - 1)
            }
            _ => format!("a packet of more than {largest} bytes"),
        };
        err!(
            "mcp-gs: warning: this {}-byte packet reaches the MAV in a {frame}-byte frame; the \
             deployed MAV firmware drops frames over {DEPLOYED_MAV_FRAME} bytes ({what})",
            payload.len(),
        );
    }
    let most = xbee_api::TransmitRequestRepr::MAX_BROADCAST_DATA;
    if to == Address64::BROADCAST && payload.len() > most {
        err!(
            "mcp-gs: warning: this {}-byte packet is broadcast, and a broadcast carries at \
             most {most} bytes (in one radio packet, never in fragments): a Zigbee radio \
             refuses it (payload_too_large); send it to each MAV instead",
            payload.len(),
        );
    }
}

/// Runs `send`.
pub(crate) async fn run(args: SendArgs) -> Result<(), Failure> {
    let payload = args.command.payload().map_err(Failure::input)?;
    let confirm = match args.confirm {
        true => Some(to_confirm(&args, &payload)?),
        false => None,
    };
    warn_of_size(&args.command, &payload, args.to);
    let (mut stream, sender) = args.link.open(false).await.inspect_err(|failure| {
        if args.format == Format::Json {
            let mcp = mcp_host::render::json::mcp(&payload);
            let fields = serde_json::json!({ "dst64": args.to.to_string(), "mcp": mcp });
            out!("{}", crate::link_args::not_sent_json(failure, fields));
        }
    })?;
    let options = SendOptions {
        timeout: Some(args.link.timeout()),
        frame_id: if args.no_status {
            FrameId::None
        } else {
            FrameId::Auto
        },
    };
    let report = sender.send_payload(args.to, payload.clone(), options).await;
    // The radio's refusal is an answer too, and so is its silence: JSON prints them,
    // with the failure on standard error.
    if let (Format::Json, Err(error)) = (args.format, &report) {
        if let Some(json) = failure_json(error, args.to, mcp_host::render::json::mcp(&payload)) {
            out!("{json}");
        }
    }
    let report = report.map_err(|e| diagnosed_send(e, &args.link, &sender.stats()))?;
    let mut json = (args.format == Format::Json).then(|| report_json(&report, &args, &payload));
    if json.is_none() {
        let what = mcp_host::render::text::mcp(&payload);
        match report {
            DeliveryReport::Delivered {
                frame_id,
                dst16,
                retries,
                discovery,
                ..
            } => out!(
                "delivered to {}/{dst16} (frame id {frame_id}, retries {retries}, discovery {discovery}): {what}",
                args.to
            ),
            DeliveryReport::Written => out!("written, no status asked (frame id 0): {what}"),
            other => out!("{other:?}: {what}"),
        }
    }
    match &args.command {
        // The MAV answers a trajectory set at once with the trajectory it took (unless
        // the command went out fire and forget).
        CommandArgs::Trajectory { waypoints }
            if args.to != Address64::BROADCAST && !args.no_status && confirm.is_none() =>
        {
            let checked = check_trajectory(&mut stream, &args, waypoints).await;
            if let Some(mut json) = json.take() {
                json["trajectory_confirmed"] = checked.is_ok().into();
                if let Err(unconfirmed) = &checked {
                    json["trajectory_reported"] = unconfirmed.reported_json();
                }
                out!("{json}");
            }
            if let Err(Unconfirmed { reported: None, .. }) = checked {
                args.link.check_mode_after_silence(&sender).await;
            }
            checked.map_err(|unconfirmed| {
                let failure = unconfirmed.failure(args.to, waypoints);
                diagnosed(failure, &args.link, &sender.stats())
            })?;
            if args.format == Format::Text {
                out!("the MAV reports the trajectory as sent");
            }
        }
        CommandArgs::Status { .. } => err!(
            "mcp-gs: note: the MAV answers with a report on the link; `mcp-gs status` waits \
             for it and prints it"
        ),
        _ => {
            if let Some(command) = confirm {
                let confirmed = sender
                    .confirm_with(args.to, &command, Some(args.link.timeout()))
                    .await;
                if let Some(json) = &mut json {
                    let reported = match &confirmed {
                        Ok(report)
                        | Err(
                            ConfirmError::NotTaken { report, .. }
                            | ConfirmError::Unverifiable { report, .. },
                        ) => mcp_host::render::json::packet_json(&Packet::Report(report.clone())),
                        Err(_) => serde_json::Value::Null,
                    };
                    json["confirmed"] = confirmed.is_ok().into();
                    json["reported"] = reported;
                }
                let failure = match confirmed {
                    Ok(report) => {
                        if args.format == Format::Text {
                            out!("confirmed: {}", Packet::Report(report));
                        }
                        None
                    }
                    Err(ConfirmError::Request(error)) => {
                        Some(crate::status::request_failure(error, &args.link, &sender).await)
                    }
                    Err(other) => Some(Failure::new(Failure::OTHER, other.to_string())),
                };
                if let Some(failure) = failure {
                    if let Some(json) = json {
                        out!("{json}");
                    }
                    return Err(failure);
                }
            }
        }
    }
    if let Some(json) = json {
        out!("{json}");
    }
    // A frame sent without a status is written out before the process ends. (The
    // stream is dropped first: its queue, full of what nobody read, would hold up the
    // last event of the link.)
    drop(stream);
    sender.close();
    sender.closed().await;
    Ok(())
}

/// The command `--confirm` confirms, or why it cannot be (nothing is sent then).
fn to_confirm(args: &SendArgs, payload: &[u8]) -> Result<Command<Vec<u8>>, Failure> {
    let command = match mcp_core::parse(payload) {
        Ok(Packet::Command(command)) => command,
        _ => {
            return Err(Failure::input(
                "--confirm confirms a command by the MAV's report: a message or another \
                 packet cannot be confirmed",
            ));
        }
    };
    if args.to == Address64::BROADCAST {
        return Err(Failure::input(
            "--confirm asks one MAV for its report, which cannot speak for the others: send \
             the command to each MAV's address",
        ));
    }
    if command.confirming_request().is_none() {
        let what = match command.is_status_request() {
            true => "a status request is not confirmed: `mcp-gs status` waits for its report",
            false => {
                "a position_set command cannot be confirmed: no report says whether a \
                      MAV took it"
            }
        };
        return Err(Failure::input(format!("{what} (drop --confirm)")));
    }
    Ok(command.map_bytes(<[u8]>::to_vec))
}

/// The delivery report as a JSON object, with the fields of a transmit status frame's
/// (`id`, `dst16`, `retries`, `discovery`), where the MAV is and what went.
fn report_json(report: &DeliveryReport, args: &SendArgs, payload: &[u8]) -> serde_json::Value {
    let result = match report {
        DeliveryReport::Delivered { .. } => "delivered",
        DeliveryReport::Written => "written",
        _ => "other",
    };
    let mut json = serde_json::json!({ "result": result, "dst64": args.to.to_string() });
    match *report {
        DeliveryReport::Delivered {
            frame_id,
            dst16,
            retries,
            discovery,
            ..
        } => {
            json["id"] = frame_id.into();
            json["dst16"] = dst16.to_string().into();
            status_fields(&mut json, DeliveryStatus::Success, retries, discovery);
        }
        DeliveryReport::Written => json["id"] = 0.into(),
        _ => {}
    }
    json["mcp"] = mcp_host::render::json::mcp(payload);
    json
}

/// A send's failure as a JSON object, where the MAV is and what went (`mcp`): a
/// delivery the radio reported failed as `{"result":"failed",...}` with the transmit
/// status's fields, no status in time as [`timeout_json`], a link that went away as
/// `{"result":"disconnected",...}` with its `reason`; `None` for another failure.
pub(crate) fn failure_json(
    error: &SendError,
    to: Address64,
    mcp: serde_json::Value,
) -> Option<serde_json::Value> {
    match *error {
        SendError::Delivery {
            frame_id,
            dst16,
            status,
            retries,
            discovery,
            ..
        } => {
            let mut json = serde_json::json!({ "result": "failed", "dst64": to.to_string() });
            // As a delivered one says them: the frame id and the 16-bit address first.
            json["id"] = frame_id.into();
            json["dst16"] = dst16.to_string().into();
            status_fields(&mut json, status, retries, discovery);
            json["mcp"] = mcp;
            Some(json)
        }
        _ if error.is_timeout() => Some(timeout_json(to, error.frame_id(), false, mcp)),
        _ => link_lost(error).map(|reason| {
            let mut json = serde_json::json!({ "result": "disconnected", "dst64": to.to_string() });
            json["reason"] = reason.into();
            json["mcp"] = mcp;
            json
        }),
    }
}

/// Why the link went away, when that is why `error` came: the request may or may not
/// have gone out (`"result":"disconnected"` in JSON).
pub(crate) fn link_lost(error: &SendError) -> Option<String> {
    match error {
        SendError::Disconnected { reason, .. } => Some(reason.clone()),
        SendError::Closed => Some("link closed".to_owned()),
        _ => None,
    }
}

/// No answer in time as a JSON object: `{"result":"timeout",...}` with where the MAV
/// is, the frame id when one went out, whether the radio confirmed delivery (`status`
/// waits for a report after that) and what went (`mcp`).
pub(crate) fn timeout_json(
    to: Address64,
    frame_id: Option<u8>,
    delivered: bool,
    mcp: serde_json::Value,
) -> serde_json::Value {
    let mut json = serde_json::json!({ "result": "timeout", "dst64": to.to_string() });
    if let Some(frame_id) = frame_id {
        json["id"] = frame_id.into();
    }
    json["delivered"] = delivered.into();
    json["mcp"] = mcp;
    json
}

/// A transmit status's delivery, retries and discovery, codes with their names beside
/// them, as a `transmit_status` frame's object has them.
fn status_fields(
    json: &mut serde_json::Value,
    delivery: DeliveryStatus,
    retries: u8,
    discovery: DiscoveryStatus,
) {
    json["delivery"] = u8::from(delivery).into();
    if let Some(name) = delivery.name() {
        json["delivery_name"] = name.into();
    }
    json["retries"] = retries.into();
    json["discovery"] = u8::from(discovery).into();
    if let Some(name) = discovery.name() {
        json["discovery_name"] = name.into();
    }
}

/// A trajectory the MAV did not report as sent, within `timeout`: `reported` holds the
/// waypoints of the last trajectory it reported meanwhile, `None` when it reported none.
struct Unconfirmed {
    reported: Option<Vec<Waypoint>>,
    timeout: Duration,
    /// The link closed before the timeout ran out.
    closed: bool,
}

impl Unconfirmed {
    /// `trajectory_reported` in JSON: the waypoints the MAV reported instead, as the
    /// packet's `waypoints` are, or `null` when no report came in time.
    fn reported_json(&self) -> serde_json::Value {
        self.reported.as_ref().map_or(serde_json::Value::Null, |w| {
            w.iter().map(mcp_host::render::json::waypoint).collect()
        })
    }

    /// The failure to print: another trajectory (exit 1) or none in time (exit 4).
    fn failure(&self, to: Address64, sent: &[Waypoint]) -> Failure {
        let show = |w: &[Waypoint]| {
            w.iter()
                .map(|w| format!("{},{},{},{}", w.time, w.elevator, w.aileron, w.altitude))
                .collect::<Vec<_>>()
                .join(" ")
        };
        match &self.reported {
            Some(report) => Failure::new(
                Failure::OTHER,
                format!(
                    "the MAV reports another trajectory than the one sent: {} [{}], \
                     sent {} [{}] (it may have kept fewer, or another ground station set one \
                     meanwhile)",
                    crate::counted(report.len() as u64, "waypoint"),
                    show(report),
                    sent.len(),
                    show(sent)
                ),
            ),
            None if self.closed => Failure::link(format!(
                "the link closed before a trajectory report came from {to}: whether the MAV \
                 took the trajectory is not known"
            )),
            None => Failure::new(
                Failure::TIMEOUT,
                format!(
                    "no trajectory report from {to} within {}: the MAV did not take the \
                     trajectory, or its report was lost on the way",
                    Seconds(self.timeout)
                ),
            ),
        }
    }
}

/// Waits for the MAV's trajectory report holding `sent`. Reports of other trajectories
/// (another ground station may set one meanwhile, or the MAV kept fewer waypoints) are
/// passed over until the timeout, then the last one is the failure.
async fn check_trajectory(
    stream: &mut PacketStream,
    args: &SendArgs,
    sent: &[Waypoint],
) -> Result<(), Unconfirmed> {
    let timeout = args.link.timeout();
    let mut reported = None;
    let wait = async {
        while let Some(report) = trajectory_report(stream, args.to).await {
            if report == sent {
                return true;
            }
            reported = Some(report);
        }
        false
    };
    let closed = match tokio::time::timeout(timeout, wait).await {
        Ok(true) => return Ok(()),
        // The stream ended: the link closed.
        Ok(false) => true,
        Err(_) => false,
    };
    Err(Unconfirmed {
        reported,
        timeout,
        closed,
    })
}

/// The waypoints of the next trajectory report from `from` on the stream; `None` if
/// the stream ends first.
async fn trajectory_report(stream: &mut PacketStream, from: Address64) -> Option<Vec<Waypoint>> {
    while let Some(event) = stream.next().await {
        if let Event::Packet(rx) = event {
            if let (true, Packet::Report(Report::TrajectorySet(w))) =
                (rx.origin.src64 == from, &rx.packet)
            {
                return Some(w.iter().collect());
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn waypoint(time: u32) -> Waypoint {
        Waypoint {
            time,
            elevator: 0.5,
            aileron: -0.25,
            altitude: 2.0,
        }
    }

    #[test]
    fn another_trajectory_is_reported_with_its_waypoints() {
        let sent = [waypoint(1), waypoint(2)];
        let unconfirmed = Unconfirmed {
            reported: Some(vec![waypoint(1)]),
            timeout: Duration::from_secs(1),
            closed: false,
        };
        assert_eq!(
            unconfirmed.reported_json(),
            serde_json::json!([{"time": 1, "elevator": 0.5, "aileron": -0.25, "altitude": 2.0}])
        );
        let failure = unconfirmed.failure(Address64::BROADCAST, &sent);
        assert_eq!(failure.code, Failure::OTHER);
        assert!(
            failure
                .message
                .contains("1 waypoint [1,0.5,-0.25,2], sent 2 [1,0.5,-0.25,2 2,0.5,-0.25,2]"),
            "{}",
            failure.message
        );

        let silent = Unconfirmed {
            reported: None,
            ..unconfirmed
        };
        assert_eq!(silent.reported_json(), serde_json::Value::Null);
        assert_eq!(
            silent.failure(Address64::BROADCAST, &sent).code,
            Failure::TIMEOUT
        );
        // The link closed first: no timeout, and no blame on the MAV.
        let closed = Unconfirmed {
            closed: true,
            ..silent
        };
        let failure = closed.failure(Address64::BROADCAST, &sent);
        assert_eq!(failure.code, Failure::LINK);
        assert!(
            failure
                .message
                .starts_with("the link closed before a trajectory report came"),
            "{}",
            failure.message
        );
    }
}
