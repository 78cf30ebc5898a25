//! `mcp-gs setup`: put the local radio into API mode through its AT command mode (`+++`),
//! as a radio fresh from the factory (transparent mode, `AP=0`) needs before anything
//! else here can talk to it. A radio that does not take `+++` (older firmware takes it in
//! transparent mode only) is set up in API frames instead, and left as it is if it is
//! set up already.

use std::time::Duration;

use clap::Args;
use futures::StreamExt;
use mcp_host::command_mode::{BAUD_RATES, CommandMode, CommandModeError};
use mcp_host::render::Seconds;
use mcp_host::{Link, LinkOptions, ReconnectPolicy};
use xbee_api::{ApiMode, Frame};

use crate::hints::{connect_failure, send_failure, serial_at};
use crate::link_args::parse_seconds;
use crate::radio_query::{ask_ap, ask_parameter, at_exchange, at_number, open_once};
use crate::{ApiModeArg, Failure};

/// Arguments of `setup`.
#[derive(Debug, Args)]
pub(crate) struct SetupArgs {
    #[arg(
        long,
        value_name = "LINK",
        value_parser = crate::link_args::parse_link,
        help = "The local radio: serial:PATH[:BAUD][:rtscts] (XBee modules leave the factory at 9600 \
                baud: serial:/dev/ttyUSB0:9600) or tcp:HOST:PORT (a serial-to-TCP bridge, not \
                a hub: a radio set to another mode would be cut off from it)"
    )]
    link: Link,
    /// The API mode to set (AP): 1, as the deployed MAVs use, or 2 (escaped).
    #[arg(long, value_name = "1|2", default_value = "1")]
    api_mode: ApiModeArg,
    #[command(flatten)]
    guard: GuardTime,
    /// Also set the radio's UART baud rate (BD): 1200, 2400, 4800, 9600, 19200, 38400,
    /// 57600, 115200 (the links' default) or 230400. A serial link is checked at the new
    /// rate; a serial-to-TCP bridge must be set to it by hand.
    #[arg(long, value_name = "BAUD", value_parser = parse_baud)]
    baud: Option<u32>,
    /// Seconds to wait for each answer of the radio.
    #[arg(long, value_name = "SECONDS", default_value_t = 3.0, value_parser = parse_seconds)]
    timeout: f64,
}

/// `--guard-time` of `setup` and `probe`.
#[derive(Debug, Args)]
pub(crate) struct GuardTime {
    /// The radio's guard time (its GT), in milliseconds: the silence it needs before and
    /// after +++.
    #[arg(
        long = "guard-time",
        value_name = "MS",
        default_value_t = 1000,
        value_parser = crate::whole_number(1u64, 10_000)
    )]
    ms: u64,
}

impl GuardTime {
    /// The guard time.
    pub(crate) fn duration(&self) -> Duration {
        Duration::from_millis(self.ms)
    }
}

fn parse_baud(s: &str) -> Result<u32, String> {
    s.parse::<u32>()
        .ok()
        .filter(|baud| BAUD_RATES.contains(baud))
        .ok_or_else(|| {
            let rates: Vec<String> = BAUD_RATES.iter().map(u32::to_string).collect();
            format!(
                "a baud rate the radio takes: {}; got `{s}`",
                rates.join(", ")
            )
        })
}

/// The `BD` value of `baud`, one of [`BAUD_RATES`] (`parse_baud` took no other).
fn bd_value(baud: u32) -> u8 {
    BAUD_RATES
        .iter()
        .position(|&b| b == baud)
        .and_then(|index| u8::try_from(index).ok())
        .unwrap_or_default()
}

/// What a `BD` value means: the baud rate, or the value as the radio gave it.
fn baud_of(bd: &str) -> String {
    usize::from_str_radix(bd, 16)
        .ok()
        .and_then(|i| BAUD_RATES.get(i))
        .map_or_else(|| format!("0x{bd}"), u32::to_string)
}

/// `AP`'s value for `mode`.
fn ap(mode: ApiMode) -> u8 {
    match mode {
        ApiMode::Unescaped => 1,
        ApiMode::Escaped => 2,
    }
}

/// The line saying what `AP` was (`was`, as the radio reads it) and becomes (`target`),
/// and whether it changes.
fn ap_line(was: &str, target: &str) -> (String, bool) {
    if was == target {
        (format!("AP = {was} ({}) already", meaning(was)), false)
    } else {
        let line = format!(
            "AP = {was} ({}) -> {target} ({})",
            meaning(was),
            meaning(target)
        );
        (line, true)
    }
}

/// The line saying what `BD` was (`was`, in hex as the radio reads it; `None` if it did
/// not say) and becomes (the value of `baud`), and whether it changes.
fn bd_line(was: Option<&str>, baud: u32) -> (String, bool) {
    let wanted = format!("{:X}", bd_value(baud));
    match was {
        Some(was) if was == wanted => (format!("BD = {was} ({baud} baud) already"), false),
        Some(was) => {
            let rate = baud_of(was);
            let line = format!("BD = {was} ({rate} baud) -> {wanted} ({baud} baud)");
            (line, true)
        }
        None => (format!("BD (unknown) -> {wanted} ({baud} baud)"), true),
    }
}

/// Prints the lines of what was set up, those of changes marked as saved.
fn print_lines(lines: &[(String, bool)]) {
    for (line, changed) in lines {
        if *changed {
            out!("{line}, saved");
        } else {
            out!("{line}");
        }
    }
}

/// What an `AP` value means.
fn meaning(ap: &str) -> &'static str {
    match ap {
        "0" => "transparent mode",
        "1" => "API mode 1",
        "2" => "API mode 2, escaped",
        _ => "a mode this ground station does not speak",
    }
}

/// Runs `setup`.
pub(crate) async fn run(args: SetupArgs) -> Result<(), Failure> {
    if !matches!(args.link, Link::Serial { .. } | Link::Tcp { .. }) {
        return Err(Failure::input(
            "setup needs a link to a radio that is there: serial:PATH[:BAUD] or tcp:HOST:PORT",
        ));
    }
    crate::hints::warn_unusual_baud(&args.link);
    let timeout = Duration::from_secs_f64(args.timeout);
    let guard = args.guard.duration();
    let target = ap(args.api_mode.0);
    let options = LinkOptions {
        connect_timeout: timeout,
        reconnect: ReconnectPolicy::disabled(),
        ..LinkOptions::default()
    };
    let port = open_once(&args.link, timeout).await?;
    err!(
        "mcp-gs: entering the radio's command mode (+++ between {} of silence)",
        Seconds(guard)
    );
    let failed = |e| command_failure(e, &args.link);
    let mut radio = match CommandMode::enter(port, guard, timeout).await {
        Ok(radio) => radio,
        // A radio in API mode already may not take +++ (older firmware takes it in
        // transparent mode only): it may be set up already.
        Err(error @ CommandModeError::NoAnswer { .. }) => {
            return set_up_in_api_frames(&args, options, timeout)
                .await?
                .ok_or_else(|| failed(error));
        }
        Err(error) => return Err(failed(error)),
    };
    // What each parameter was, and whether it was changed (then saved below).
    let mut lines: Vec<(String, bool)> = Vec::new();
    if let Err(error) = change_in_command_mode(&mut radio, &args, target, &mut lines).await {
        // Changes made before the failure take effect when command mode is left: now,
        // rather than when the radio's command mode times out while the operator
        // believes nothing changed.
        if lines.iter().any(|(_, changed)| *changed) {
            let _ = radio.exit().await;
        }
        return Err(unsaved(&lines)(failed(error)));
    }
    print_lines(&lines);
    // Leaving command mode applies the changes; the port is closed for the check.
    drop(radio.exit().await.map_err(failed)?);
    let link = match (&args.link, args.baud) {
        (
            Link::Serial {
                path, flow_control, ..
            },
            Some(baud),
        ) => Link::serial_with(path.clone(), baud, *flow_control),
        (Link::Tcp { .. }, Some(baud)) => {
            err!(
                "mcp-gs: the radio's UART now runs at {baud} baud: set the bridge's serial \
                 side to it before the check below can pass"
            );
            args.link.clone()
        }
        (link, _) => link.clone(),
    };
    check(&link, args.api_mode.0, options, timeout).await
}

/// Reads `AP` (and `BD` with `--baud`) in command mode, sets those not as asked and
/// saves them (`WR`); each line of `lines` says what a parameter was, and whether it
/// was changed, as soon as it was.
async fn change_in_command_mode<T: tokio::io::AsyncRead + tokio::io::AsyncWrite + Unpin>(
    radio: &mut CommandMode<T>,
    args: &SetupArgs,
    target: u8,
    lines: &mut Vec<(String, bool)>,
) -> Result<(), CommandModeError> {
    let was = radio.read(*b"AP").await?;
    let target_text = target.to_string();
    let (line, change) = ap_line(&was, &target_text);
    if change {
        set_or_say(radio, *b"AP", &target_text, &line, lines).await?;
    }
    lines.push((line, change));
    if let Some(baud) = args.baud {
        let was = radio.read(*b"BD").await?;
        let (line, change) = bd_line(Some(&was), baud);
        if change {
            let bd = format!("{:X}", bd_value(baud));
            set_or_say(radio, *b"BD", &bd, &line, lines).await?;
        }
        lines.push((line, change));
    }
    if lines.iter().any(|(_, changed)| *changed) {
        radio.set(*b"WR", "").await?;
    }
    Ok(())
}

/// Sets `command` to `value` in command mode; if the radio did not answer in time, it
/// may have taken it: `line` goes into `lines` as a change perhaps made, so that it is
/// said, and command mode left.
async fn set_or_say<T: tokio::io::AsyncRead + tokio::io::AsyncWrite + Unpin>(
    radio: &mut CommandMode<T>,
    command: [u8; 2],
    value: &str,
    line: &str,
    lines: &mut Vec<(String, bool)>,
) -> Result<(), CommandModeError> {
    let set = radio.set(command, value).await;
    if let Err(CommandModeError::NoAnswer { .. }) = &set {
        lines.push((format!("{line} (not answered: perhaps)"), true));
    }
    set
}

/// For a radio that did not answer `+++` (older firmware takes it in transparent mode
/// only): if it answers API frames, it is set up in them instead, as in command mode,
/// each frame in the mode and at the rate the one before left (a change made in an API
/// frame applies once answered), and checked. `None` if it does not answer them either.
async fn set_up_in_api_frames(
    args: &SetupArgs,
    options: LinkOptions,
    timeout: Duration,
) -> Result<Option<()>, Failure> {
    let target = ap(args.api_mode.0);
    // The radio as it is now: its link (the rate) and its API mode.
    let asked = |link: &Link, mode: ApiMode| {
        let options = LinkOptions {
            api_mode: mode,
            send_timeout: timeout,
            ..options.clone()
        };
        (link.clone(), options)
    };
    let (link, first) = asked(&args.link, ApiMode::Unescaped);
    let was = match ask_ap(&link, first).await? {
        Ok(Some(was)) => was,
        Ok(None) => {
            return Err(Failure::new(
                Failure::OTHER,
                "the radio did not answer +++, and answered AT AP in an API frame with no \
                 value (an error status, or another frame): its API mode is unknown",
            ));
        }
        Err(_) => return Ok(None),
    };
    let Ok(mode) = ApiMode::try_from(was) else {
        return Err(Failure::new(
            Failure::OTHER,
            format!(
                "the radio did not answer +++ but answers API frames, and reads its AP as \
                 {was} ({}): this ground station cannot set it",
                meaning(&was.to_string())
            ),
        ));
    };
    let bd = match args.baud {
        Some(_) => {
            let (link, options) = asked(&args.link, mode);
            let value = ask_parameter(&link, options, *b"BD")
                .await?
                .map_err(send_failure)?;
            // The whole value: a radio set to a rate of its own reads more than one byte.
            value.map(|bytes| at_number(&bytes))
        }
        None => None,
    };
    let new_bd = args
        .baud
        .map(|baud| (baud, bd_value(baud)))
        .filter(|(_, wanted)| bd != Some(u64::from(*wanted)));
    if let (Some((baud, wanted)), Link::Tcp { .. }) = (new_bd, &args.link) {
        // The bridge's serial side would have to follow between two frames.
        let flag = if target == 2 { " --api-mode 2" } else { "" };
        let link = &args.link;
        let ap = if was == target {
            String::new()
        } else {
            let flag = if was == 2 { " --api-mode 2" } else { "" };
            format!("`mcp-gs at --link {link}{flag} AP {target}`, then ")
        };
        return Err(Failure::new(
            Failure::OTHER,
            format!(
                "the radio did not answer +++ but answers API frames in mode {was}; through \
                 a bridge its baud rate is set by hand: {ap}`mcp-gs at --link {link}{flag} \
                 BD {wanted:X}`, then set the bridge's serial side to {baud} baud, then \
                 `mcp-gs at --link {link}{flag} WR`"
            ),
        ));
    }
    if was != target || new_bd.is_some() {
        err!(
            "mcp-gs: the radio did not answer +++ (older firmware takes it in transparent \
             mode only) but answers API frames in mode {was}: setting it up in API frames"
        );
    }
    // What each parameter was, and whether it was changed (then saved below).
    let mut lines: Vec<(String, bool)> = Vec::new();
    let mut now = (args.link.clone(), mode);
    let (line, change) = ap_line(&was.to_string(), &target.to_string());
    if change {
        set(&now, &asked, *b"AP", &[target]).await?;
        now.1 = args.api_mode.0;
        if let Link::Tcp { .. } = &args.link {
            hub_restart_note(&args.link, target);
        }
    }
    lines.push((line, change));
    if let Some(baud) = args.baud {
        let was = bd.map(|bd| format!("{bd:X}"));
        let (line, change) = bd_line(was.as_deref(), baud);
        // Through a bridge, a change was refused above.
        if let (
            true,
            Link::Serial {
                path, flow_control, ..
            },
        ) = (change, &args.link)
        {
            set(&now, &asked, *b"BD", &[bd_value(baud)])
                .await
                .map_err(unsaved(&lines))?;
            now.0 = Link::serial_with(path.clone(), baud, *flow_control);
        }
        lines.push((line, change));
    }
    if lines.iter().any(|(_, changed)| *changed) {
        set(&now, &asked, *b"WR", &[])
            .await
            .map_err(unsaved(&lines))?;
    }
    print_lines(&lines);
    check(&now.0, args.api_mode.0, options, timeout).await?;
    Ok(Some(()))
}

/// Says that a hub at `link` must be restarted in the radio's new API mode `target`: a
/// hub speaks to its radio in the mode it was started with, and from now on cannot read
/// the radio's frames, whatever its clients speak.
fn hub_restart_note(link: &Link, target: u8) {
    let flags = if target == 2 {
        " --api-mode 2"
    } else {
        " no --api-mode (mode 1),"
    };
    err!(
        "mcp-gs: note: if {link} is a hub, restart it with{flags} --link to the radio: it \
         speaks to its radio in the API mode it was started with, and cannot read the \
         radio's frames in API mode {target}"
    );
}

/// A failure after the changes in `lines` were made (in API frames, or in command mode
/// then left), saying that they are in effect but not saved.
fn unsaved(lines: &[(String, bool)]) -> impl Fn(Failure) -> Failure + '_ {
    move |failure| {
        let made: Vec<&str> = lines
            .iter()
            .filter(|(_, changed)| *changed)
            .map(|(line, _)| line.as_str())
            .collect();
        if made.is_empty() {
            return failure;
        }
        failure.with_hint(format!(
            "made already, in effect but not saved: {} (powering the radio off and on \
             undoes it; setup can be run again as the radio is now)",
            made.join("; ")
        ))
    }
}

/// Sets `command` to `value` in an API frame, on the radio as `now` (its link and API
/// mode) has it; an error if the radio does not answer or refuses it.
async fn set(
    now: &(Link, ApiMode),
    asked: &impl Fn(&Link, ApiMode) -> (Link, LinkOptions),
    command: [u8; 2],
    value: &[u8],
) -> Result<(), Failure> {
    let (link, options) = asked(&now.0, now.1);
    match at_exchange(&link, options, command, value)
        .await?
        .map_err(send_failure)?
    {
        Some(_) => Ok(()),
        None => Err(Failure::new(
            Failure::OTHER,
            format!(
                "the radio refused {} {value:02X?} in an API frame",
                String::from_utf8_lossy(&command)
            ),
        )),
    }
}

/// Asks the radio its `AP` in API frames of the mode set: that it answers is the proof.
async fn check(
    link: &Link,
    mode: ApiMode,
    options: LinkOptions,
    timeout: Duration,
) -> Result<(), Failure> {
    let options = LinkOptions {
        api_mode: mode,
        send_timeout: timeout,
        ..options
    };
    let (mut stream, sender) = mcp_host::connect(link, options)
        .await
        .map_err(|e| connect_failure(link, e))?;
    let mut answer = sender.at(*b"AP", &[], None).await;
    if matches!(answer, Err(mcp_host::SendError::Timeout { .. })) {
        // Asked once more: the radio may have been setting its UART up after leaving
        // command mode.
        answer = sender.at(*b"AP", &[], None).await;
    }
    sender.close();
    while stream.next().await.is_some() {}
    let answer = answer.map_err(send_failure)?;
    match answer.parse() {
        Ok(Frame::AtCommandResponse(at)) if at.status.is_ok() && at.data == [ap(mode)] => {
            let flag = match mode {
                ApiMode::Unescaped => String::new(),
                ApiMode::Escaped => " with --api-mode 2".to_owned(),
            };
            out!(
                "checked: the radio answers API frames in mode {} (use --link {link}{flag})",
                ap(mode)
            );
            Ok(())
        }
        _ => Err(Failure::new(
            Failure::OTHER,
            format!(
                "the radio answered AT AP in API mode {} with {}, not AP = {}",
                ap(mode),
                mcp_host::render::json::hex(answer.data()),
                ap(mode)
            ),
        )),
    }
}

/// A failed command mode exchange, with what the operator can do about it.
fn command_failure(error: CommandModeError, link: &Link) -> Failure {
    match error {
        CommandModeError::NoAnswer { ref sent, .. } if sent == "+++" => {
            let rates = match link {
                // The factory's rate, unless it was the one tried.
                Link::Serial {
                    path,
                    baud: 9600,
                    flow_control,
                    ..
                } => format!(
                    "`mcp-gs probe --link {}` tries every rate",
                    serial_at(path, *flow_control, None)
                ),
                Link::Serial {
                    path, flow_control, ..
                } => format!(
                    "XBee modules leave the factory at 9600: {}; `mcp-gs probe --link {}` \
                     tries every rate",
                    serial_at(path, *flow_control, Some("9600")),
                    serial_at(path, *flow_control, None)
                ),
                _ => "XBee modules leave the factory at 9600: set the bridge's serial side to \
                      the radio's rate"
                    .to_owned(),
            };
            Failure::new(
                Failure::TIMEOUT,
                format!(
                    "{error}, nor to an API frame asking its mode: the radio may be at \
                     another baud rate ({rates}), need a longer --guard-time (its GT), or \
                     still be in command mode from a run less than 10 s ago (try again)"
                ),
            )
        }
        CommandModeError::NoAnswer { .. } => Failure::new(Failure::TIMEOUT, error.to_string()),
        CommandModeError::Io(_) | CommandModeError::Closed => Failure::link(error.to_string()),
        other => Failure::new(Failure::OTHER, other.to_string()),
    }
}
