//! Options shared by the subcommands that talk over a link, and opening that link.

use std::time::Duration;

use clap::Args;
use futures::StreamExt;
use mcp_host::render::Seconds;
use mcp_host::{
    CommandSender, DetectError, Link, LinkOptions, LinkParseError, PacketStream, ReconnectPolicy,
    SendError,
};
use xbee_api::{Address16, Address64, ApiMode};

use crate::Failure;
use crate::hints::{
    Role, check_serial_path, connect_failure, connect_failure_as, counters_hint, send_failure,
    serial_at, warn_unusual_baud,
};
use crate::radio_query::check_mode;

/// API mode of the local radio on the command line: 1, 2 or `auto`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ApiModeChoice {
    /// This mode.
    Fixed(ApiMode),
    /// Ask the radio (`AT AP`) and use its answer.
    Auto,
}

impl std::str::FromStr for ApiModeChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s.eq_ignore_ascii_case("auto") {
            return Ok(Self::Auto);
        }
        s.parse::<crate::ApiModeArg>()
            .map(|m| Self::Fixed(m.0))
            .map_err(|_| format!("API mode must be 1, 2 or auto, got `{s}`"))
    }
}

/// `--link`, `--api-mode` and `--timeout`.
#[derive(Debug, Clone, Args)]
pub(crate) struct LinkArgs {
    #[arg(
        long,
        value_name = "LINK",
        value_parser = parse_link,
        help = "The local radio: serial:PATH[:BAUD][:rtscts] (default 115200 8N1), tcp:HOST:PORT, \
                tcp-listen:ADDR:PORT or pty"
    )]
    pub(crate) link: Link,
    /// XBee API mode of the local radio (its AP setting): 1, 2, or auto to ask the radio
    /// (its answer waited for 3 s, or --timeout if given).
    #[arg(long, value_name = "1|2|auto", default_value = "1")]
    pub(crate) api_mode: ApiModeChoice,
    /// Seconds to wait to connect, and for what the subcommand waits for [default: 12].
    // Each subcommand says in its help what it waits for (`mut_arg("timeout", ...)`).
    #[arg(long, value_name = "SECONDS", value_parser = parse_seconds)]
    pub(crate) timeout: Option<f64>,
    /// The events the link holds for the subcommand while it falls behind
    /// ([`LinkOptions::event_capacity`]); the library's default if `None`.
    #[arg(skip)]
    pub(crate) event_capacity: Option<usize>,
}

/// The link's events held for `monitor` and `hub` while they fall behind (beyond, lost
/// and counted): the frames a TCP connection's buffers hold, as they come at once when
/// monitor goes on after it was stopped (Ctrl-Z, `SIGSTOP`) or starved a while, and
/// more than a radio at 115200 baud can send while the hub asks it for its API mode
/// before it serves (its frames until then go to no client, and are not lost behind).
pub(crate) const EVENTS_HELD: usize = 1 << 16;

/// `--link` of the subcommands that do one thing and end (`send`, `status`, `at`,
/// `nodes`): a radio that is there, so not `pty`, which makes a new pseudo-terminal.
pub(crate) const ONE_SHOT_LINK_HELP: &str = "The local radio, one that is there: \
     serial:PATH[:BAUD][:rtscts] (default 115200 8N1), tcp:HOST:PORT or tcp-listen:ADDR:PORT. \
     Not pty, which makes a new pseudo-terminal: give the one `mcp-gs sim --link pty` \
     printed as serial:PATH";

/// The `--timeout` when none is given.
const DEFAULT_TIMEOUT: Duration = Duration::from_secs(12);

/// How long `--api-mode auto` waits for the radio's `AP` without a `--timeout`: a
/// radio answers at once, and one that does not is said sooner than the commands'
/// default timeout would.
const DETECT_TIMEOUT: Duration = Duration::from_secs(3);

/// A 64-bit address on the command line: exactly 16 hex digits (an optional `0x`; spaces
/// between them, as XCTU shows SH and SL, are allowed), so that a digit left out is an
/// error rather than another address.
pub(crate) fn parse_address64(s: &str) -> Result<Address64, String> {
    let joined: String = s.split_whitespace().collect();
    let digits = joined
        .strip_prefix("0x")
        .or_else(|| joined.strip_prefix("0X"))
        .unwrap_or(&joined);
    if digits.len() != 16 {
        return Err(format!(
            "a 64-bit address is 16 hex digits (e.g. 0013a20040b599b9; 000000000000ffff \
             broadcasts), got `{s}`"
        ));
    }
    digits
        .parse()
        .map_err(|e| format!("bad 64-bit address `{s}`: {e}"))
}

/// A 16-bit address on the command line: 1 to 4 hex digits (an optional `0x`), its error
/// saying what one looks like.
pub(crate) fn parse_address16(s: &str) -> Result<Address16, String> {
    s.trim().parse().map_err(|e| {
        format!(
            "bad 16-bit address `{s}` (1 to 4 hex digits, e.g. fffe when unknown, 0000 \
             for the coordinator): {e}"
        )
    })
}

/// A request that never went out, its link not opened (or its API mode not found), as
/// `--format json` says it: `{"result":"not_sent",...,"reason":"..."}`, with `fields`
/// (what names the request) between. The exit code is the failure's.
pub(crate) fn not_sent_json(failure: &Failure, fields: serde_json::Value) -> serde_json::Value {
    let mut json = serde_json::json!({ "result": "not_sent" });
    if let (Some(map), serde_json::Value::Object(fields)) = (json.as_object_mut(), fields) {
        map.extend(fields);
    }
    json["reason"] = failure.reason().into();
    json
}

/// A link `mcp-gs` can open: any but `io:`, which a program opens itself.
pub(crate) fn parse_link(s: &str) -> Result<Link, String> {
    match s.parse::<Link>() {
        Ok(Link::Io { .. }) | Err(LinkParseError::MissingIoName) => Err(
            "io: links are for programs that open their stream themselves \
             (mcp_host::connect_with); mcp-gs takes serial:, tcp:, tcp-listen: or pty"
                .to_owned(),
        ),
        Ok(link) => Ok(link),
        Err(e) => Err(e.to_string()),
    }
}

pub(crate) fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 86_400.0 => Ok(v),
        _ => Err(format!(
            "expected a number of seconds above 0 and at most 86400, got `{s}`"
        )),
    }
}

impl LinkArgs {
    /// The timeout as a duration.
    pub(crate) fn timeout(&self) -> Duration {
        self.given_timeout().unwrap_or(DEFAULT_TIMEOUT)
    }

    /// The timeout, if `--timeout` was given.
    pub(crate) fn given_timeout(&self) -> Option<Duration> {
        self.timeout.map(Duration::from_secs_f64)
    }

    /// Opens the link. `reconnect` keeps it alive across disconnections (for long-running
    /// subcommands); one-shot subcommands fail at once instead.
    pub(crate) async fn open(
        &self,
        reconnect: bool,
    ) -> Result<(PacketStream, CommandSender), Failure> {
        self.open_with(reconnect, false).await
    }

    /// [`open`](Self::open); with `wait`, a `serial` or `tcp` link that is not there
    /// yet is waited for (in the background, with the reconnection delays) instead of
    /// failing.
    pub(crate) async fn open_with(
        &self,
        reconnect: bool,
        wait: bool,
    ) -> Result<(PacketStream, CommandSender), Failure> {
        self.check_wait(wait)?;
        if !reconnect && matches!(self.link, Link::Pty) {
            return Err(Failure::input(
                "--link pty makes a new pseudo-terminal, with no radio on it yet: this \
                 subcommand needs one that is there, serial:PATH (e.g. the path `mcp-gs sim \
                 --link pty` prints) or tcp:HOST:PORT, or tcp-listen:ADDR:PORT to wait for \
                 a peer to connect",
            ));
        }
        let options = LinkOptions {
            wait_for_link: wait,
            ..self.options(reconnect, Role::Client).await?
        };
        let (mut stream, sender) = mcp_host::connect(&self.link, options)
            .await
            .map_err(|e| connect_failure(&self.link, e))?;
        if !reconnect {
            if let Some(addr) = stream.info().local_addr {
                // A one-shot subcommand on `tcp-listen:` waits for its peer first.
                err!(
                    "mcp-gs: waiting up to {} for a peer on {addr}",
                    Seconds(self.timeout())
                );
                let connected = async {
                    while let Some(event) = stream.next().await {
                        if let mcp_host::Event::Link(mcp_host::LinkEvent::Connected { .. }) = event
                        {
                            return true;
                        }
                    }
                    false
                };
                // As a `tcp:` link that cannot connect within the timeout: no link, not
                // a radio that did not answer.
                if tokio::time::timeout(self.timeout(), connected).await != Ok(true) {
                    return Err(Failure::link(format!(
                        "no peer connected to {addr} within {}",
                        Seconds(self.timeout())
                    )));
                }
            }
        }
        Ok((stream, sender))
    }

    /// Refuses what `--wait` cannot do: wait for a radio whose mode is to be asked
    /// (`--api-mode auto`), or for a path that is no serial device.
    pub(crate) fn check_wait(&self, wait: bool) -> Result<(), Failure> {
        if !wait {
            return Ok(());
        }
        if self.api_mode == ApiModeChoice::Auto {
            return Err(Failure::input(
                "--wait and --api-mode auto do not go together: the mode is asked of the \
                 radio before anything else, so it must be there; give --api-mode 1 or 2",
            ));
        }
        check_serial_path(&self.link, true)
    }

    /// The link options these arguments give, the API mode asked of the radio for
    /// `--api-mode auto` (a failure to open the link said to a command in `role`).
    /// `reconnect` as for [`open`](Self::open).
    pub(crate) async fn options(
        &self,
        reconnect: bool,
        role: Role,
    ) -> Result<LinkOptions, Failure> {
        warn_unusual_baud(&self.link);
        let mode = match self.api_mode {
            ApiModeChoice::Fixed(mode) => mode,
            ApiModeChoice::Auto => self.detect_mode(role).await?,
        };
        Ok(self.options_in(mode, reconnect))
    }

    fn options_in(&self, mode: ApiMode, reconnect: bool) -> LinkOptions {
        LinkOptions {
            api_mode: mode,
            connect_timeout: self.timeout(),
            send_timeout: self.timeout(),
            reconnect: if reconnect {
                ReconnectPolicy::default()
            } else {
                ReconnectPolicy::disabled()
            },
            event_capacity: self
                .event_capacity
                .unwrap_or(LinkOptions::default().event_capacity),
            ..LinkOptions::default()
        }
    }

    /// Asks the radio for its API mode ([`ask_ap`](crate::radio_query::ask_ap)): within
    /// 3 s, or the `--timeout` given (a slow radio, a link with latency).
    async fn detect_mode(&self, role: Role) -> Result<ApiMode, Failure> {
        let timeout = self
            .given_timeout()
            .unwrap_or(DETECT_TIMEOUT.min(DEFAULT_TIMEOUT));
        let options = LinkOptions {
            send_timeout: timeout,
            ..self.options_in(ApiMode::Unescaped, false)
        };
        let link = &self.link;
        mcp_host::detect_api_mode(link, options)
            .await
            .map_err(|e| match e {
                DetectError::NoRadio(_) => Failure::input(
                    "--api-mode auto needs a link to a radio (serial: or tcp:); give 1 or 2",
                ),
                DetectError::Connect(e) => connect_failure_as(link, e, role),
                DetectError::NoAnswer(SendError::Timeout { .. }) => {
                    let fix = match link {
                        Link::Serial {
                            path, flow_control, ..
                        } => format!(
                            "`mcp-gs probe --link {}` finds its rate and mode, and `mcp-gs \
                             setup` puts it into API mode",
                            serial_at(path, *flow_control, None)
                        ),
                        // A hub or a bridge (for a command that is a hub itself too):
                        // setup and probe need the radio's own port, or the bridge.
                        _ => format!(
                            "if {link} is a hub, stop it and run `mcp-gs probe` on the radio's \
                             serial port; if a serial bridge, `mcp-gs setup --link {link}`"
                        ),
                    };
                    Failure::new(
                        Failure::TIMEOUT,
                        format!(
                            "the radio on {link} did not answer AT AP within {}: it \
                             may be in transparent mode (AP=0) or at another baud rate ({fix})",
                            Seconds(timeout)
                        ),
                    )
                }
                DetectError::NoAnswer(other) => send_failure(other),
                DetectError::Transparent => Failure::input(
                    "the radio is in transparent mode (AP=0): `mcp-gs setup` puts it into API \
                     mode",
                ),
                other => Failure::new(Failure::OTHER, other.to_string()),
            })
    }

    /// After a report that did not come although the radio delivered the request:
    /// unless the link's counters give a hint of their own (frames that failed as in
    /// another mode), asks the radio its `AP` (for a second at most) and warns if it is
    /// in another mode than `--api-mode`. Through a hub in another mode than the radio,
    /// the request goes out and its status comes back, but the report, from an address
    /// with bytes to escape (every `0013A2...`), is dropped by the hub, out of sight. Not
    /// on a link that is down.
    pub(crate) async fn check_mode_after_silence(&self, sender: &CommandSender) {
        let up = sender.link_state() == mcp_host::LinkState::Connected;
        let hinted = counters_hint(self, &sender.stats()).is_some();
        if let (ApiModeChoice::Fixed(mode), true, false) = (self.api_mode, up, hinted) {
            check_mode(sender, mode, mcp_host::hub::MODE_CHECK_TIMEOUT).await;
        }
    }
}
