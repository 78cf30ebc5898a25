//! `mcp-gs at`: read or set an AT parameter of the local radio or of a remote one.

use std::time::Duration;

use clap::Args;
use mcp_host::command_mode::BAUD_RATES;
use mcp_host::{Link, SendError};
use xbee_api::{Address64, AtStatus, Frame};

use crate::hints::{diagnosed_send, warn_mode_mismatch, with_mode_hint};
use crate::link_args::{ApiModeChoice, LinkArgs};
use crate::{Failure, Format};
use mcp_host::render::json::hex;

/// Arguments of `at`.
#[derive(Debug, Args)]
#[command(mut_arg("timeout", |arg| arg.help(
    "Seconds to wait to connect, and for the radio's answer [default: 3 to read a \
parameter of the local radio, which answers at once; 12 for a change, an \
action, ND, DN, AS, ED, FN or a remote radio]"
)))]
#[command(mut_arg("link", |arg| arg.help(crate::link_args::ONE_SHOT_LINK_HELP)))]
pub(crate) struct AtArgs {
    #[command(flatten)]
    link: LinkArgs,
    /// Ask a remote radio (Remote AT Command, 0x17) instead of the local one. With
    /// 000000000000ffff (broadcast) every radio in range carries the command out, and
    /// each answer is a line: DigiMesh and 802.15.4 radios all answer, but a Zigbee
    /// radio hands over one answer only (to read every radio, list them with `nodes`
    /// and ask each).
    #[arg(long, value_name = "ADDR", value_parser = crate::link_args::parse_address64)]
    to: Option<Address64>,
    /// With --to 000000000000ffff: seconds to gather the radios' answers [default: 3].
    #[arg(long, value_name = "SECONDS", value_parser = crate::link_args::parse_seconds)]
    window: Option<f64>,
    /// VALUE is text, not hex (the default for the text parameters NI, DN, BI and VL).
    #[arg(long, requires = "value")]
    text: bool,
    /// Do not apply the change at once: it waits for an AC command (`mcp-gs at AC`),
    /// which applies every queued change together. Sent as AT Command - Queue Parameter
    /// Value (0x09) to the local radio, without the apply option to a remote one.
    #[arg(long, requires = "value")]
    no_apply: bool,
    /// The two-letter AT command, e.g. AP, NP, NI, SH, SL, MY, ID, CH, N?.
    command: String,
    /// The value to set, in hex (e.g. `2` for AP=2), or text for a text parameter (NI)
    /// or with --text, written as it is printed (ASCII, `\xNN` for any byte, `\\` for a
    /// backslash, `\"` or `"` for a quote); omit to read.
    value: Option<String>,
    /// Output format: `json` prints each answer as the response frame's object (as
    /// `monitor` does), with `"result":"answered"` and `value` added: the value read as
    /// a number, or as text for a text parameter (a refusal is answered too: its
    /// `status` says so); no answer in time as `{"result":"timeout","command":...}`, a link
    /// lost meanwhile as `{"result":"disconnected",...}`, one that could not be opened
    /// as `{"result":"not_sent",...}`.
    #[arg(long, value_enum, default_value_t = Format::Text)]
    format: Format,
}

/// The AT parameters Digi defines as text (printable ASCII) rather than numbers: the
/// node identifier, the destination node (a node identifier to look up), the Bluetooth
/// identifier and the long firmware version. Every other parameter is a number, printed
/// as such even when its bytes happen to be printable.
const TEXT_PARAMETERS: [&[u8; 2]; 4] = [b"NI", b"DN", b"BI", b"VL"];

/// The AT commands Digi defines as actions rather than parameters, which answer with no
/// value: apply changes, write to non-volatile memory, restore defaults, software reset,
/// network reset, exit command mode, sleep immediately and the commissioning button.
/// Their success prints as `AC: ok`, not as a read that found no value.
const ACTIONS: [&[u8; 2]; 8] = [b"AC", b"WR", b"RE", b"FR", b"NR", b"CN", b"SI", b"CB"];

/// How long a local read is waited for when `--timeout` is not given: the local radio
/// answers at once, so a longer wait only delays the hint of what is wrong. (A change
/// or an action may take the radio longer, writing its flash, say, and a timeout would
/// not tell whether it was carried out: those keep the usual timeout.)
const LOCAL_READ_TIMEOUT: Duration = Duration::from_secs(3);

/// The local AT commands whose answer waits on the network: node discovery, a
/// destination node looked up, the active and energy scans, find neighbours. They get
/// the usual timeout.
const NETWORK_COMMANDS: [&[u8; 2]; 5] = [b"ND", b"DN", b"AS", b"ED", b"FN"];

/// How long to wait for the answer to `command`: `--timeout` if given, else
/// [`LOCAL_READ_TIMEOUT`] to read a parameter of the local radio that waits on nothing
/// else, else the default.
fn answer_timeout(args: &AtArgs, command: &[u8; 2]) -> Duration {
    let read = args.value.is_none() && !ACTIONS.contains(&command);
    match (args.link.given_timeout(), args.to) {
        (Some(given), _) => given,
        (None, None) if read && !NETWORK_COMMANDS.contains(&command) => LOCAL_READ_TIMEOUT,
        (None, _) => args.link.timeout(),
    }
}

/// Whether `command`'s value is text.
fn is_text(command: &[u8; 2]) -> bool {
    TEXT_PARAMETERS.contains(&command)
}

/// What a status other than ok means, for the one-line error; tx_failure means the
/// remote command was not delivered.
fn explain(status: AtStatus, name: &str, to: Option<Address64>, set: bool) -> String {
    let code = u8::from(status);
    // Which radio refused: a remote one is named.
    let name = &match to {
        Some(to) if status.meaning() != AtStatus::TxFailure => format!("{name} on {to}"),
        _ => name.to_owned(),
    };
    match (status.meaning(), to) {
        (AtStatus::Error, _) => format!(
            "{name}: the radio answered error (0x{code:02x}): it could not carry out the command"
        ),
        (AtStatus::InvalidCommand, _) => format!(
            "{name}: the radio answered invalid_command (0x{code:02x}): it does not know this \
             AT command"
        ),
        (AtStatus::InvalidParameter, _) if set => format!(
            "{name}: the radio answered invalid_parameter (0x{code:02x}): it refused the value \
             (out of range, or a parameter it does not let be set)"
        ),
        (AtStatus::InvalidParameter, _) => format!(
            "{name}: the radio answered invalid_parameter (0x{code:02x}): it refused the command"
        ),
        (AtStatus::TxFailure, Some(to)) => format!(
            "{name}: the remote AT command was not delivered to {to}: the local radio answered \
             tx_failure (0x{code:02x}); the remote radio is off, out of range or in another network"
        ),
        (status, _) => format!("{name}: the radio answered {status} (0x{code:02x})"),
    }
}

/// The exit code of an AT status other than ok: a command or value the radio refuses
/// as invalid is bad input, as an argument mcp-gs refuses itself; a remote command the
/// radio could not deliver is a delivery failure; anything else (error: the radio
/// could not carry it out) a plain failure.
fn exit_code(status: AtStatus) -> u8 {
    match status.meaning() {
        AtStatus::InvalidCommand | AtStatus::InvalidParameter => Failure::INPUT,
        AtStatus::TxFailure => Failure::DELIVERY,
        _ => Failure::OTHER,
    }
}

/// The line that shows a value read (or echoed) by the radio.
fn value_line(name: &str, command: &[u8; 2], data: &[u8]) -> String {
    if is_text(command) {
        return format!("{name} = {}", mcp_core::Text::new(data).quoted());
    }
    if let (b"BD", Some(rate)) = (command, baud_rate(data)) {
        // As `setup` prints it (the value as the radio's command mode writes it, hex
        // without leading zeros): the rate is what the operator gives a serial link.
        let code = crate::radio_query::at_number(data);
        return format!("{name} = {code:X} ({rate} baud)");
    }
    if data.len() <= 16 {
        let number = data.iter().fold(0u128, |n, &b| (n << 8) | u128::from(b));
        format!(
            "{name} = {} (0x{}, {number})",
            hex(data).to_uppercase(),
            hex(data)
        )
    } else {
        format!("{name} = {}", hex(data).to_uppercase())
    }
}

/// The baud rate a `BD` value stands for, if it is one of the standard ones.
fn baud_rate(bd: &[u8]) -> Option<u32> {
    let index = usize::try_from(crate::radio_query::at_number(bd)).ok()?;
    BAUD_RATES.get(index).copied()
}

/// What the operator must change after the local radio took `value` for `command` and
/// applied it: a new API mode or UART rate leaves every later command on the old
/// settings talking to a radio that no longer understands them.
fn change_note(command: &[u8; 2], value: &[u8], link: &LinkArgs) -> Option<String> {
    let through = match &link.link {
        Link::Tcp { .. } => " (through a hub, restart the hub with it)",
        _ => "",
    };
    // Command mode (`+++`) reaches the radio through its own port, or a bridge, never
    // through a hub, which passes API frames alone.
    let setup = match &link.link {
        Link::Tcp { .. } => format!(
            "`mcp-gs setup` on the radio's own port if {} is a hub (stop it first: it passes \
             API frames alone, not `+++`), or `mcp-gs setup --link {}` through a serial \
             bridge",
            link.link, link.link
        ),
        other => format!("`mcp-gs setup --link {other}`"),
    };
    match command {
        b"AP" => match crate::radio_query::at_number(value) {
            0 => Some(format!(
                "the radio is now in transparent mode (AP=0) and answers no API frame: \
                 {setup} puts it back into API mode"
            )),
            mode @ (1 | 2) => {
                let spoken = match link.api_mode {
                    ApiModeChoice::Fixed(m) => u64::from(u8::from(m)) == mode,
                    ApiModeChoice::Auto => false,
                };
                // Later commands given the same --api-mode already speak it.
                (!spoken).then(|| {
                    format!(
                        "the radio now speaks API mode {mode}: give --api-mode {mode} to \
                         later commands{through}"
                    )
                })
            }
            mode => Some(format!(
                "the radio now reads AP={mode}, a mode this ground station does not speak: \
                 {setup} sets 1"
            )),
        },
        b"BD" => {
            let Some(baud) = baud_rate(value) else {
                return Some(format!(
                    "the radio's UART rate changed (BD={}): later commands need the link's \
                     baud rate to match",
                    hex(value).to_uppercase()
                ));
            };
            let advice = match &link.link {
                Link::Serial {
                    path, flow_control, ..
                } => format!(
                    "use {}",
                    Link::serial_with(path.clone(), baud, *flow_control)
                ),
                Link::Tcp { .. } => format!(
                    "set the serial side of the bridge or hub to {baud} baud (a hub restarted \
                     with serial:PATH:{baud})"
                ),
                _ => format!("use serial:PATH:{baud}"),
            };
            Some(format!(
                "the radio's UART now runs at {baud} baud: {advice}"
            ))
        }
        _ => None,
    }
}

/// The line that shows a successful answer: the value read, or that the change or
/// action was done.
fn answer_line(name: &str, command: &[u8; 2], data: &[u8], set: bool) -> String {
    if data.is_empty() && (set || ACTIONS.contains(&command)) {
        format!("{name}: ok")
    } else if data.is_empty() && !is_text(command) {
        format!("{name}: ok (no value)")
    } else {
        value_line(name, command, data)
    }
}

/// An answer as a JSON object: the response frame's, with `"result":"answered"` (as
/// the other outcomes have a `result`) and `value` added when the answer holds one
/// (text for a text parameter, else a number of up to 6 bytes, which every JSON reader
/// takes exactly; a longer one is in `data` alone).
fn answer_json(frame: &Frame<'_>, command: &[u8; 2], data: &[u8]) -> serde_json::Value {
    let mut json = mcp_host::render::json::frame(frame);
    if let serde_json::Value::Object(map) = &mut json {
        map.insert("result".into(), "answered".into());
    }
    let value = if data.is_empty() {
        None
    } else if is_text(command) {
        Some(mcp_host::render::json::text(data))
    } else if data.len() <= 6 {
        Some(crate::radio_query::at_number(data).into())
    } else {
        None
    };
    if let (serde_json::Value::Object(map), Some(value)) = (&mut json, value) {
        map.insert("value".into(), value);
    }
    json
}

/// `at --to 000000000000ffff`: the command to every radio in range, and a line for each
/// answer handed over, `ADDR: ...`, as they come for `--window` seconds (one in all on
/// Zigbee). Answers that refuse give the exit code a refusal gives ([`exit_code`]; 1 when
/// theirs differ); no answer at all, 4.
async fn broadcast(
    args: &AtArgs,
    sender: &mcp_host::CommandSender,
    command: [u8; 2],
    parameter: &[u8],
) -> Result<(), Failure> {
    let window = std::time::Duration::from_secs_f64(args.window.unwrap_or(BROADCAST_WINDOW));
    crate::hints::warn_hub_window(&args.link.link, window);
    let name = String::from_utf8_lossy(&command).into_owned();
    // A link lost is an outcome too, in JSON as for one radio.
    let failed = |e: SendError| {
        if let (Format::Json, Some(json)) = (
            args.format,
            timeout_json(&e, &name, Some(Address64::BROADCAST)),
        ) {
            out!("{json}");
        }
        diagnosed_send(e, &args.link, &sender.stats())
    };
    let mut answers = sender
        .remote_at_answers(
            Address64::BROADCAST,
            command,
            parameter,
            !args.no_apply,
            window,
        )
        .await
        .map_err(failed)?;
    let set = args.value.is_some();
    let (mut answered, mut refused) = (0u32, 0u32);
    let mut refused_code = Failure::OTHER;
    while let Some(answer) = answers.next().await {
        let answer = answer.map_err(failed)?;
        let Ok(frame @ Frame::RemoteAtResponse(at)) = answer.parse() else {
            continue;
        };
        answered += 1;
        if !at.status.is_ok() {
            let code = exit_code(at.status);
            refused_code = if refused == 0 || code == refused_code {
                code
            } else {
                Failure::OTHER
            };
            refused += 1;
        }
        if args.format == Format::Json {
            out!("{}", answer_json(&frame, &command, at.data));
        } else if at.status.is_ok() {
            out!(
                "{}: {}",
                at.src64,
                answer_line(&name, &command, at.data, set)
            );
        } else {
            out!("{}: {}", at.src64, explain(at.status, &name, None, set));
        }
    }
    if answered == 1 {
        err!(
            "mcp-gs: one radio answered: a Zigbee radio hands over a single answer to a \
             broadcast, however many radios carried it out; `mcp-gs nodes` lists them all, \
             for `--to ADDR` each"
        );
    }
    if answered == 0 && args.format == Format::Json {
        // No answer is an outcome too, as for one radio.
        out!(
            "{}",
            outcome_json("timeout", &name, Some(Address64::BROADCAST))
        );
    }
    match (answered, refused) {
        (0, _) => Err(with_mode_hint(
            Failure::new(
                Failure::TIMEOUT,
                format!(
                    "{name}: no radio answered the broadcast within {}: the others are \
                     off, out of range, or in another network (ID, CH)",
                    mcp_host::render::Seconds(window)
                ),
            ),
            &args.link,
            &sender.stats(),
        )),
        (_, 0) => Ok(()),
        (_, n) => Err(Failure::new(
            refused_code,
            if answered == 1 {
                format!("{name}: the radio that answered refused the command")
            } else {
                format!("{name}: {n} of the {answered} radios that answered refused the command")
            },
        )),
    }
}

/// Whether `name` can be an AT command: letters and digits, `%` first (`%V`, supply
/// voltage) or `?` second (`N?`, the network discovery timeout) as some of Digi's are.
fn is_command_name(name: &[u8; 2]) -> bool {
    let [first, second] = *name;
    (first.is_ascii_alphanumeric() || first == b'%')
        && (second.is_ascii_alphanumeric() || second == b'?')
}

fn parse_value(value: &str, text: bool) -> Result<Vec<u8>, String> {
    if value.is_empty() {
        // The frame would carry no parameter: the radio would read, not set.
        return Err(
            "an empty value cannot be set: an AT command with no value reads the \
             parameter (omit VALUE to read it)"
                .to_owned(),
        );
    }
    if text {
        // As it is printed: a radio's text parameters are ASCII.
        return crate::command::unescape_text(value, "a radio's text parameters are ASCII");
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

/// Seconds a broadcast's answers are gathered for when `--window` is not given.
const BROADCAST_WINDOW: f64 = 3.0;

/// Runs `at`.
pub(crate) async fn run(args: AtArgs) -> Result<(), Failure> {
    if args.window.is_some() && args.to != Some(Address64::BROADCAST) {
        return Err(Failure::input(
            "--window is for a broadcast, --to 000000000000ffff: one radio's answer is \
             waited for with --timeout",
        ));
    }
    let command: [u8; 2] = args
        .command
        .to_ascii_uppercase()
        .as_bytes()
        .try_into()
        .ok()
        .filter(is_command_name)
        .ok_or_else(|| {
            Failure::input(format!(
                "`{}` is not an AT command: two letters or digits (AP, D0), or Digi's few \
                 with a sign (N?, %V)",
                args.command
            ))
        })?;
    let parameter = match &args.value {
        Some(value) => {
            parse_value(value, args.text || is_text(&command)).map_err(Failure::input)?
        }
        None => Vec::new(),
    };
    let (_stream, sender) = args.link.open(false).await.inspect_err(|failure| {
        if args.format == Format::Json {
            let name = String::from_utf8_lossy(&command);
            let fields = outcome_json("not_sent", &name, args.to);
            out!("{}", crate::link_args::not_sent_json(failure, fields));
        }
    })?;
    if args.to == Some(Address64::BROADCAST) {
        return broadcast(&args, &sender, command, &parameter).await;
    }
    let timeout = Some(answer_timeout(&args, &command));
    let response = match args.to {
        None if args.no_apply => sender.at_queued(command, &parameter, timeout).await,
        None => sender.at(command, &parameter, timeout).await,
        Some(to) => {
            sender
                .remote_at(to, command, &parameter, !args.no_apply, timeout)
                .await
        }
    };
    let name = String::from_utf8_lossy(&command).into_owned();
    // No answer is an outcome too: JSON prints it, as `send` does, with the failure on
    // standard error.
    if let (Format::Json, Err(error)) = (args.format, &response) {
        if let Some(json) = timeout_json(error, &name, args.to) {
            out!("{json}");
        }
    }
    let response = response.map_err(|e| diagnosed_send(e, &args.link, &sender.stats()))?;
    let frame = response.parse();
    let (status, data) = match &frame {
        Ok(Frame::AtCommandResponse(at)) => (at.status, at.data),
        Ok(Frame::RemoteAtResponse(at)) => (at.status, at.data),
        _ => {
            return Err(Failure::new(
                Failure::OTHER,
                format!("unexpected answer: {}", hex(response.data())),
            ));
        }
    };
    // A refusal is an answer too: JSON prints it, with the failure on standard error.
    if let (Format::Json, Ok(frame)) = (args.format, &frame) {
        out!("{}", answer_json(frame, &command, data));
    }
    if !status.is_ok() {
        return Err(Failure::new(
            exit_code(status),
            explain(status, &name, args.to, args.value.is_some()),
        ));
    }
    if args.format == Format::Text {
        out!(
            "{}",
            answer_line(&name, &command, data, args.value.is_some())
        );
    }
    if command == *b"ND" && args.to.is_none() && !data.is_empty() {
        err!(
            "mcp-gs: ND: every radio found answers on its own and this is the first answer; \
             `mcp-gs nodes` lists them all"
        );
    }
    if let (None, false, Some(_)) = (args.to, args.no_apply, &args.value) {
        if let Some(note) = change_note(&command, &parameter, &args.link) {
            err!("mcp-gs: note: {note}");
        }
    }
    // The local radio's API mode, read in another than --api-mode (the AP answer reads
    // the same in both modes): the other frames will not.
    if let (None, b"AP", ApiModeChoice::Fixed(mode), &[ap]) =
        (args.to, &command, args.link.api_mode, data)
    {
        warn_mode_mismatch(ap, mode, &args.link.link);
    }
    Ok(())
}

/// An answer that did not come as a JSON object: `{"result":...,"command":"AP"}`, with
/// the remote radio's `dst64`.
pub(crate) fn outcome_json(result: &str, name: &str, to: Option<Address64>) -> serde_json::Value {
    let mut json = serde_json::json!({ "result": result, "command": name });
    if let Some(to) = to {
        json["dst64"] = to.to_string().into();
    }
    json
}

/// No answer in time as a JSON object: `{"result":"timeout","command":"AP"}`, with the
/// remote radio's `dst64` and the frame id when the command went out; a link that went
/// away meanwhile as `{"result":"disconnected",...}` with its `reason`; `None` for
/// another failure.
pub(crate) fn timeout_json(
    error: &SendError,
    name: &str,
    to: Option<Address64>,
) -> Option<serde_json::Value> {
    let lost = crate::send::link_lost(error);
    if !error.is_timeout() && lost.is_none() {
        return None;
    }
    let result = if lost.is_some() {
        "disconnected"
    } else {
        "timeout"
    };
    let mut json = outcome_json(result, name, to);
    if let Some(frame_id) = error.frame_id() {
        json["id"] = frame_id.into();
    }
    if let Some(reason) = lost {
        json["reason"] = reason.into();
    }
    Some(json)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_print_as_numbers_even_when_printable() {
        assert_eq!(
            value_line("DD", b"DD", b"ABCD"),
            "DD = 41424344 (0x41424344, 1094861636)"
        );
        assert_eq!(value_line("NI", b"NI", b"MAV \"1\""), r#"NI = "MAV \"1\"""#);
        assert_eq!(value_line("NI", b"NI", b""), r#"NI = """#);
    }

    #[test]
    fn bd_reads_as_its_baud_rate() {
        assert_eq!(value_line("BD", b"BD", &[3]), "BD = 3 (9600 baud)");
        assert_eq!(
            value_line("BD", b"BD", &[0, 0, 0, 7]),
            "BD = 7 (115200 baud)"
        );
        assert_eq!(value_line("BD", b"BD", &[0x20]), "BD = 20 (0x20, 32)");
        assert_eq!(value_line("ID", b"ID", &[3]), "ID = 03 (0x03, 3)");
    }

    #[test]
    fn a_new_rate_on_a_serial_link_names_the_link_to_use() {
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            link: LinkArgs,
        }
        let link = |argv: &[&str]| {
            let mut all = vec!["at"];
            all.extend(argv);
            <Cli as clap::Parser>::try_parse_from(&all).unwrap().link
        };
        let serial = link(&["--link", "serial:/dev/ttyUSB0:115200:rtscts"]);
        let note = change_note(b"BD", &[3], &serial).unwrap();
        assert!(
            note.ends_with("use serial:/dev/ttyUSB0:9600:rtscts"),
            "{note}"
        );
        let note = change_note(b"AP", &[2], &serial).unwrap();
        assert!(!note.contains("hub"), "{note}");
        let hub = link(&["--link", "tcp:127.0.0.1:9750", "--api-mode", "2"]);
        assert_eq!(change_note(b"AP", &[2], &hub), None);
        let note = change_note(b"AP", &[1], &hub).unwrap();
        assert!(
            note.contains("--api-mode 1") && note.contains("hub"),
            "{note}"
        );
        // Command mode does not pass a hub: setup on the radio's own port.
        let note = change_note(b"AP", &[0], &hub).unwrap();
        assert!(
            note.contains("`mcp-gs setup` on the radio's own port if tcp:127.0.0.1:9750 is a hub")
                && note
                    .contains("`mcp-gs setup --link tcp:127.0.0.1:9750` through a serial bridge"),
            "{note}"
        );
        let note = change_note(b"AP", &[0], &serial).unwrap();
        assert!(
            note.contains("`mcp-gs setup --link serial:/dev/ttyUSB0:115200:rtscts`"),
            "{note}"
        );
        assert_eq!(change_note(b"NI", b"MAV", &hub), None);
    }

    #[test]
    fn text_parameters_take_text_values() {
        assert!(is_text(b"NI") && !is_text(b"ID"));
        assert_eq!(parse_value("20", true).unwrap(), b"20");
        assert_eq!(parse_value("20", false).unwrap(), [0x20]);
        // Written as it is printed: any value printed is set back byte for byte.
        let every: Vec<u8> = (1..=255).collect();
        for value in [&b"MAV \"1\""[..], &every[..127], &every[127..]] {
            let line = value_line("NI", b"NI", value);
            let printed = line
                .strip_prefix("NI = \"")
                .and_then(|rest| rest.strip_suffix('"'))
                .unwrap();
            assert_eq!(parse_value(printed, true).unwrap(), value, "{line}");
        }
        let error = parse_value("Drohne Süd", true).unwrap_err();
        assert!(
            error.starts_with("`ü` is not ASCII: a radio's text parameters are ASCII; give a byte"),
            "{error}"
        );
    }

    #[test]
    fn commands_with_a_sign_are_commands() {
        for name in [b"AP", b"D0", b"N?", b"%V"] {
            assert!(is_command_name(name), "{name:?}");
        }
        for name in [b"?N", b"V%", b"A ", b"-1"] {
            assert!(!is_command_name(name), "{name:?}");
        }
    }

    #[test]
    fn a_local_read_is_waited_for_3_s_unless_it_waits_on_the_network() {
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            at: AtArgs,
        }
        let timeout = |args: &[&str]| {
            let mut argv = vec!["at", "--link", "tcp:127.0.0.1:9750"];
            argv.extend(args);
            let args = <Cli as clap::Parser>::try_parse_from(&argv).unwrap().at;
            let command = args.command.as_bytes().try_into().unwrap();
            answer_timeout(&args, &command)
        };
        assert_eq!(timeout(&["AP"]), Duration::from_secs(3));
        assert_eq!(timeout(&["%V"]), Duration::from_secs(3));
        // Changes and actions: the usual timeout.
        assert_eq!(timeout(&["NI", "MAV"]), Duration::from_secs(12));
        assert_eq!(timeout(&["WR"]), Duration::from_secs(12));
        assert_eq!(timeout(&["AC"]), Duration::from_secs(12));
        for command in ["ND", "DN", "AS", "ED", "FN"] {
            assert_eq!(timeout(&[command]), Duration::from_secs(12), "{command}");
        }
        let remote = ["--to", "0013a20040b599b9", "AP"];
        assert_eq!(timeout(&remote), Duration::from_secs(12));
        assert_eq!(
            timeout(&["--timeout", "0.5", "AP"]),
            Duration::from_millis(500)
        );
        assert_eq!(timeout(&["--timeout", "30", "ND"]), Duration::from_secs(30));
    }

    #[test]
    fn an_empty_value_is_refused_not_read() {
        for text in [true, false] {
            let error = parse_value("", text).unwrap_err();
            assert!(error.contains("reads the parameter"), "{error}");
        }
    }
}
