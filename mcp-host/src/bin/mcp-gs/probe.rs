//! `mcp-gs probe`: find a radio's baud rate and mode on a serial port, as it is before
//! anything here can talk to it.

use std::time::Duration;

use clap::Args;
use mcp_host::command_mode::CommandMode;
use mcp_host::{Link, LinkOptions, ReconnectPolicy};
use xbee_api::ApiMode;

use crate::Failure;
use crate::link_args::parse_seconds;
use crate::radio_query::{ask_ap, open_once};
use crate::setup::GuardTime;

/// Arguments of `probe`.
#[derive(Debug, Args)]
pub(crate) struct ProbeArgs {
    /// The serial port the radio is on: serial:PATH, or serial:PATH:BAUD to try that
    /// rate first (then every other rate the radio takes).
    #[arg(long, value_name = "LINK", value_parser = parse_probe_link)]
    link: ProbeLink,
    /// Seconds to wait for the radio's answer at each rate.
    #[arg(long, value_name = "SECONDS", default_value_t = 0.5, value_parser = parse_seconds)]
    timeout: f64,
    #[command(flatten)]
    guard: GuardTime,
}

/// The order rates are tried in: the factory's, the links' default, then the others
/// from the fastest down.
const ORDER: [u32; 9] = [
    9600, 115_200, 230_400, 57_600, 38_400, 19_200, 4800, 2400, 1200,
];

/// `--link`: the link, and the baud rate written in it, if one is.
#[derive(Debug, Clone)]
struct ProbeLink {
    link: Link,
    given: Option<u32>,
}

fn parse_probe_link(s: &str) -> Result<ProbeLink, String> {
    let link = crate::link_args::parse_link(s)?;
    // After where the link parser took the path to end, a rate was written if a part
    // is digits (`serial:115200` is a path; `:rtscts` may come before or after it).
    let given = match &link {
        Link::Serial { path, baud, .. } => s
            .strip_prefix("serial:")
            .and_then(|rest| rest.strip_prefix(path.as_str()))
            .is_some_and(|rest| {
                rest.split(':')
                    .any(|part| !part.is_empty() && part.bytes().all(|b| b.is_ascii_digit()))
            })
            .then_some(*baud),
        _ => None,
    };
    Ok(ProbeLink { link, given })
}

/// The rates to try, in order: `given` first, then [`ORDER`] without it.
fn rates(given: Option<u32>) -> impl Iterator<Item = u32> {
    given
        .into_iter()
        .chain(ORDER.into_iter().filter(move |&baud| Some(baud) != given))
}

/// What answered at a baud rate.
#[derive(Debug, PartialEq, Eq)]
enum Found {
    /// API frames, in this mode.
    Api(u8),
    /// AT command mode: the radio is in transparent mode (`AP` read there).
    CommandMode(String),
}

/// Runs `probe`.
pub(crate) async fn run(args: ProbeArgs) -> Result<(), Failure> {
    let Link::Serial {
        path, flow_control, ..
    } = &args.link.link
    else {
        return Err(Failure::input(
            "probe tries the baud rates of a serial port: give serial:PATH",
        ));
    };
    // Named at the first rate to try: the link's own (115200 unless given) may be none
    // of those tried first.
    let first = rates(args.link.given).next().unwrap_or(ORDER[0]);
    crate::hints::check_serial_path(
        &Link::serial_with(path.clone(), first, *flow_control),
        false,
    )?;
    let timeout = Duration::from_secs_f64(args.timeout);
    let guard = args.guard.duration();
    for baud in rates(args.link.given) {
        let link = Link::serial_with(path.clone(), baud, *flow_control);
        err!("mcp-gs: {baud} baud...");
        let found = match ask_api(&link, timeout).await? {
            Some(mode) => Found::Api(mode),
            None => match ask_command_mode(&link, guard, timeout).await? {
                CommandModeAnswer::Ap(ap) => Found::CommandMode(ap),
                CommandModeAnswer::NoAp(error) => {
                    // The rate is right (+++ was answered): no use trying the others.
                    return Err(Failure::new(
                        Failure::OTHER,
                        format!(
                            "{link}: something answered +++ with OK, but not ATAP ({error}): \
                             a radio slow to answer (give a longer --timeout), an XBee whose \
                             firmware has no API mode, or no XBee"
                        ),
                    ));
                }
                CommandModeAnswer::None => continue,
            },
        };
        match found {
            Found::Api(mode @ (1 | 2)) => {
                let flag = if mode == 2 { " --api-mode 2" } else { "" };
                out!("{link}: API mode {mode} (use --link {link}{flag})");
            }
            Found::Api(mode) => out!(
                "{link}: the radio answers API frames but reads its API mode as {mode}, which \
                 this ground station does not speak: `mcp-gs setup --link {link}` sets 1"
            ),
            Found::CommandMode(ap) if ap == "0" => out!(
                "{link}: transparent mode (AP=0): `mcp-gs setup --link {link}` puts it into \
                 API mode"
            ),
            Found::CommandMode(ap) => out!(
                "{link}: the radio answered +++ and reads AP={ap}: try --link {link} \
                 --api-mode {ap}"
            ),
        }
        return Ok(());
    }
    Err(Failure::new(
        Failure::TIMEOUT,
        format!(
            "no radio answered on serial:{path} at any baud rate, in API frames or to +++: \
             check that the radio is powered and on this port (`mcp-gs ports`), that no \
             other program has the port open, and its guard time (--guard-time)"
        ),
    ))
}

/// The radio's `AP` asked in an API frame ([`ask_ap`]); `None` if nothing answered in
/// time.
async fn ask_api(link: &Link, timeout: Duration) -> Result<Option<u8>, Failure> {
    let options = LinkOptions {
        api_mode: ApiMode::Unescaped,
        connect_timeout: connect_timeout(timeout),
        send_timeout: timeout,
        reconnect: ReconnectPolicy::disabled(),
        ..LinkOptions::default()
    };
    Ok(ask_ap(link, options).await?.ok().flatten())
}

/// How long opening the port may take: a serial port opens at once, but not under a
/// short answer timeout.
fn connect_timeout(timeout: Duration) -> Duration {
    timeout.max(Duration::from_secs(3))
}

/// What a radio said in AT command mode.
enum CommandModeAnswer {
    /// No `OK` to `+++`.
    None,
    /// `OK` to `+++`, and `AP` read.
    Ap(String),
    /// `OK` to `+++`, but `ATAP` refused or not answered in time.
    NoAp(mcp_host::command_mode::CommandModeError),
}

/// `AP` read in AT command mode, left again at once.
async fn ask_command_mode(
    link: &Link,
    guard: Duration,
    timeout: Duration,
) -> Result<CommandModeAnswer, Failure> {
    let port = open_once(link, connect_timeout(timeout)).await?;
    let Ok(mut radio) = CommandMode::enter(port, guard, timeout).await else {
        return Ok(CommandModeAnswer::None);
    };
    let ap = radio.read(*b"AP").await;
    // Left as found: nothing was set.
    let _ = radio.exit().await;
    Ok(match ap {
        Ok(ap) => CommandModeAnswer::Ap(ap),
        Err(error) => CommandModeAnswer::NoAp(error),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcp_host::command_mode::BAUD_RATES;

    #[test]
    fn every_rate_the_radio_takes_is_tried_once() {
        let mut tried = ORDER.to_vec();
        tried.sort_unstable();
        assert_eq!(tried, BAUD_RATES);
        // A rate given is tried first, and not again.
        for given in [None, Some(9600), Some(115_200), Some(1200)] {
            let mut tried: Vec<u32> = rates(given).collect();
            assert_eq!(tried.first(), Some(&given.unwrap_or(9600)));
            tried.sort_unstable();
            assert_eq!(tried, BAUD_RATES, "{given:?}");
        }
        // One the radio does not list (a BD set to a rate of its own) is tried too.
        assert_eq!(rates(Some(250_000)).count(), ORDER.len() + 1);
    }

    #[test]
    fn a_rate_is_given_only_when_written() {
        let given = |s: &str| parse_probe_link(s).unwrap().given;
        assert_eq!(given("serial:/dev/ttyUSB0"), None);
        assert_eq!(given("serial:/dev/ttyUSB0:115200"), Some(115_200));
        assert_eq!(given("serial:COM3:9600"), Some(9600));
        assert_eq!(given("serial:COM3"), None);
        assert_eq!(given("serial:115200"), None);
        assert_eq!(given("serial:/dev/ttyUSB0:"), None);
        assert_eq!(given("serial:/dev/ttyUSB0:rtscts"), None);
        assert_eq!(given("serial:/dev/ttyUSB0::rtscts"), None);
        assert_eq!(given("serial:/dev/ttyUSB0:57600:rtscts"), Some(57_600));
        assert_eq!(given("serial:/dev/ttyUSB0:rtscts:57600"), Some(57_600));
        assert_eq!(given("serial:/dev/ttyUSB0:none:"), None);
        assert_eq!(given("tcp:127.0.0.1:9750"), None);
        assert!(parse_probe_link("serial:/dev/ttyUSB0:0").is_err());
    }
}
