//! `mcp-gs radio`: a virtual XBee network between links.

use std::collections::HashMap;
use std::time::{Duration, SystemTime};

use clap::Args;
use mcp_host::Link;
use mcp_host::radio::{
    AddedNode, Faults, MAX_UNICAST, MAX_UNICAST_FRAGMENTED, NetEvent, Network, NetworkConfig,
    NodeOptions,
};
use tokio::sync::broadcast;
use tokio::time::Instant;
use xbee_api::{Address64, ApiMode, DeliveryStatus};

use crate::{ApiModeArg, Failure};

/// Arguments of `radio`.
#[derive(Debug, Args)]
#[command(after_long_help = RADIO_HELP)]
pub(crate) struct RadioArgs {
    /// The coordinator's link (64-bit address 0000000000000000, 16-bit 0000), where the
    /// ground station is: LINK or LINK@MODE (e.g. `pty`, `tcp-listen:0.0.0.0:9750@2`).
    #[arg(long, value_name = "LINK[@MODE]")]
    coordinator: LinkArg,
    /// A node: its 64-bit address and the link to its device, ADDR=LINK or
    /// ADDR=LINK@MODE (e.g. `0013A20040B599B9=tcp:127.0.0.1:5000@1`). Repeat for more.
    #[arg(long = "node", value_name = "ADDR=LINK[@MODE]")]
    nodes: Vec<NodeArg>,
    /// API mode of links given without @MODE: 1, 2, or 0 for a radio in transparent
    /// mode (AP=0) as XBee modules leave the factory, which `mcp-gs setup` puts into API
    /// mode.
    #[arg(long, default_value = "1", value_name = "0|1|2")]
    api_mode: RadioModeArg,
    #[command(flatten)]
    net: NetArgs,
    /// Print every delivery, not only connections and failures.
    #[arg(long, short)]
    verbose: bool,
    /// Stop after this many seconds; 0, the default, runs until Ctrl-C.
    #[arg(long, value_name = "SECONDS", value_parser = parse_duration)]
    duration: Option<Duration>,
}

const RADIO_HELP: &str = "\
Links: serial:PATH[:BAUD][:rtscts], tcp:HOST:PORT, tcp-listen:ADDR:PORT (each new peer is the device \
back), pty (the path to open is printed). A link's API mode is given after an @ \
(LINK@1, LINK@2, or LINK@0: transparent mode), else --api-mode.

Faults apply to the frames the network writes to a link: --loss, --latency, --jitter, \
--duplicate, --reorder and --corrupt for every link, --faults ADDR=SPEC for one (SPEC: \
comma-separated loss=P, latency=MS, jitter=MS, duplicate=P, reorder=P, corrupt=P; ADDR \
`coordinator` or a 64-bit address). The seed is printed at start when there are faults; \
--seed replays a run. \
--cut ADDR@START+LENGTH takes a node out of range for a while (its transmissions and the \
ones to it fail with 0x21 network ACK failure).

Example: a ground station on a pty, a MAV firmware's UART on TCP port 5000:
  mcp-gs radio --coordinator pty --node 0013A20040B599B9=tcp:127.0.0.1:5000";

/// The longest latency or jitter, milliseconds: an hour.
const MAX_DELAY_MS: u64 = 3_600_000;
/// The longest `--duration`, seconds (about 31 years).
const MAX_DURATION_S: f64 = 1e9;

/// `--duration` of `radio`, `sim` and `demo`: a number of seconds, 0 or more, where 0
/// means no limit (run until Ctrl-C) in every subcommand. A time above 0 too short to
/// count is one nanosecond, not 0.
pub(crate) fn parse_duration(s: &str) -> Result<Duration, String> {
    s.parse::<f64>()
        .ok()
        .filter(|x| (0.0..=MAX_DURATION_S).contains(x))
        .map(|x| match Duration::from_secs_f64(x) {
            d if d.is_zero() && x > 0.0 => Duration::from_nanos(1),
            d => d,
        })
        .ok_or_else(|| {
            format!(
                "expected a number of seconds from 0 (no limit: until Ctrl-C) to \
                 {MAX_DURATION_S}, got `{s}`"
            )
        })
}

/// A probability (`--loss` and the other fault rates): a number from 0 to 1.
pub(crate) fn parse_probability(s: &str) -> Result<f64, String> {
    s.parse::<f64>()
        .ok()
        .filter(|p| (0.0..=1.0).contains(p))
        .ok_or_else(|| format!("expected a probability from 0 to 1 (e.g. 0.05), got `{s}`"))
}

/// Network-wide settings shared by `radio` and `sim`.
#[derive(Debug, Args)]
pub(crate) struct NetArgs {
    /// Seed of the fault generators (default: from the clock; printed at start).
    #[arg(long, value_name = "N")]
    seed: Option<u64>,
    /// Largest unicast payload (84 without fragmentation, at most 255). Default: 84 for
    /// `radio`, 255 for `sim` (MCP packets go up to 255 bytes).
    #[arg(long, value_name = "N", value_parser = crate::whole_number(1u16, 255))]
    max_unicast: Option<u16>,
    /// Assume fragmentation: unicast payloads up to 255 bytes.
    #[arg(long, conflicts_with = "max_unicast")]
    fragmentation: bool,
    /// Probability that a frame to a link is lost.
    #[arg(long, value_name = "P", default_value_t = 0.0, value_parser = parse_probability)]
    loss: f64,
    /// Delay before a frame is written to a link, milliseconds (at most an hour).
    #[arg(long, value_name = "MS", default_value_t = 0,
          value_parser = crate::whole_number(0, MAX_DELAY_MS))]
    latency: u64,
    /// Random extra delay, up to this many milliseconds (at most an hour).
    #[arg(long, value_name = "MS", default_value_t = 0,
          value_parser = crate::whole_number(0, MAX_DELAY_MS))]
    jitter: u64,
    /// Probability that a frame is written twice.
    #[arg(long, value_name = "P", default_value_t = 0.0, value_parser = parse_probability)]
    duplicate: f64,
    /// Probability that a frame is held back behind the next one.
    #[arg(long, value_name = "P", default_value_t = 0.0, value_parser = parse_probability)]
    reorder: f64,
    /// Probability that a frame's bytes are corrupted (bad checksum).
    #[arg(long, value_name = "P", default_value_t = 0.0, value_parser = parse_probability)]
    corrupt: f64,
    /// Faults of one link, ADDR=SPEC (see below). Repeat for more.
    #[arg(long = "faults", value_name = "ADDR=SPEC")]
    link_faults: Vec<LinkFaults>,
    /// Take a node out of radio range for a while: ADDR@START+LENGTH, seconds from
    /// start (e.g. `0013A20040B599B9@5+2.5`). Repeat for more.
    #[arg(long = "cut", value_name = "ADDR@S+S")]
    cuts: Vec<CutArg>,
}

impl NetArgs {
    /// The network settings; `default_max_unicast` unless given.
    pub(crate) fn config(&self, default_max_unicast: usize) -> Result<NetworkConfig, Failure> {
        let seed = self.seed.unwrap_or_else(|| {
            SystemTime::now()
                .duration_since(SystemTime::UNIX_EPOCH)
                .map(|d| d.as_nanos() as u64)
                .unwrap_or(0)
        });
        let max_unicast = match (self.fragmentation, self.max_unicast) {
            (true, _) => MAX_UNICAST_FRAGMENTED,
            (false, Some(n)) => usize::from(n),
            (false, None) => default_max_unicast,
        };
        Ok(NetworkConfig {
            seed,
            faults: Faults {
                loss: self.loss,
                latency: Duration::from_millis(self.latency),
                jitter: Duration::from_millis(self.jitter),
                duplicate: self.duplicate,
                reorder: self.reorder,
                corrupt: self.corrupt,
                ..Faults::default()
            },
            max_unicast,
            ..NetworkConfig::default()
        })
    }

    /// Checks, before anything starts, that every `--cut` and `--faults` names the
    /// coordinator or one of `nodes` (the network's addresses besides the
    /// coordinator's): a fault on a node that is not there would silently do nothing.
    pub(crate) fn check_nodes(&self, nodes: &[Address64], what: &str) -> Result<(), Failure> {
        let known =
            |address: Address64| address == Address64::COORDINATOR || nodes.contains(&address);
        let list = || {
            let mut shown: Vec<String> = nodes.iter().take(8).map(ToString::to_string).collect();
            if nodes.len() > shown.len() {
                shown.push(format!("{} more", nodes.len() - shown.len()));
            }
            match shown.is_empty() {
                true => "the network has only the coordinator".to_owned(),
                false => format!("the network has the coordinator and {}", shown.join(", ")),
            }
        };
        if let Some(cut) = self.cuts.iter().find(|c| !known(c.address)) {
            return Err(Failure::input(format!(
                "--cut {}: no {what} has that address ({})",
                cut.address,
                list()
            )));
        }
        if let Some(faults) = self.link_faults.iter().find(|f| !known(f.address)) {
            return Err(Failure::input(format!(
                "--faults {}: no {what} has that address ({})",
                faults.address,
                list()
            )));
        }
        Ok(())
    }

    /// The per-link faults of `address`, if given.
    pub(crate) fn faults_of(&self, address: Address64) -> Option<Faults> {
        self.link_faults
            .iter()
            .rev()
            .find(|f| f.address == address)
            .map(|f| f.faults)
    }

    /// Prints the faults, and the seed they are drawn with (when there are any).
    pub(crate) fn describe(&self, config: &NetworkConfig) {
        if self.seed.is_some() || !config.faults.is_none() || !self.link_faults.is_empty() {
            out!("seed {} (replay with --seed {})", config.seed, config.seed);
        }
        out!(
            "virtual XBee network: unicast payloads up to {} bytes, broadcast up to {}",
            config.max_unicast,
            config.max_broadcast
        );
        if !config.faults.is_none() {
            out!("faults on every link: {}", describe_faults(&config.faults));
        }
        for f in &self.link_faults {
            out!("faults on {}: {}", f.address, describe_faults(&f.faults));
        }
        for c in &self.cuts {
            out!(
                "{} out of range from {} to {} after start",
                c.address,
                mcp_host::render::Seconds(c.start),
                mcp_host::render::Seconds(c.start + c.length)
            );
        }
    }

    /// The cuts and restores, in time order from `start`: (when, node, cut).
    pub(crate) fn timeline(&self, start: Instant) -> Vec<(Instant, Address64, bool)> {
        let mut steps: Vec<_> = self
            .cuts
            .iter()
            .flat_map(|c| {
                [
                    (start + c.start, c.address, true),
                    (start + c.start + c.length, c.address, false),
                ]
            })
            .collect();
        steps.sort_by_key(|s| s.0);
        steps
    }
}

fn describe_faults(f: &Faults) -> String {
    format!(
        "loss {}, latency {} ms, jitter {} ms, duplicate {}, reorder {}, corrupt {}",
        f.loss,
        f.latency.as_millis(),
        f.jitter.as_millis(),
        f.duplicate,
        f.reorder,
        f.corrupt
    )
}

/// Checks, before anything starts, that the node addresses given have no address
/// twice and neither the coordinator's nor the broadcast address (`what`: what a node
/// is, for the message).
pub(crate) fn check_distinct(nodes: &[Address64], what: &str) -> Result<(), Failure> {
    for (i, node) in nodes.iter().enumerate() {
        if *node == Address64::COORDINATOR || *node == Address64::BROADCAST {
            return Err(Failure::input(format!(
                "{node} is the coordinator's or the broadcast address: give each {what} \
                 another one"
            )));
        }
        if nodes[..i].contains(node) {
            return Err(Failure::input(format!(
                "{node} is given twice: each {what} needs an address of its own"
            )));
        }
    }
    Ok(())
}

/// `ADDR@START+LENGTH`.
#[derive(Debug, Clone)]
pub(crate) struct CutArg {
    address: Address64,
    start: Duration,
    length: Duration,
}

impl std::str::FromStr for CutArg {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("expected ADDR@START+LENGTH (seconds), got `{s}`");
        let (address, times) = s.split_once('@').ok_or_else(bad)?;
        let (start, length) = times.split_once('+').ok_or_else(bad)?;
        let secs = |t: &str| {
            t.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite() && *x >= 0.0 && *x < 1e9)
                .map(Duration::from_secs_f64)
                .ok_or_else(bad)
        };
        Ok(CutArg {
            address: parse_address(address)?,
            start: secs(start)?,
            length: secs(length)?,
        })
    }
}

/// The mode an emulated radio starts in: `AP` 1 or 2, or 0, transparent mode.
#[derive(Debug, Clone, Copy)]
pub(crate) struct RadioModeArg {
    pub(crate) api_mode: ApiMode,
    pub(crate) transparent: bool,
}

impl std::str::FromStr for RadioModeArg {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s == "0" {
            return Ok(RadioModeArg {
                api_mode: ApiMode::Unescaped,
                transparent: true,
            });
        }
        s.parse::<ApiModeArg>()
            .map(|mode| RadioModeArg {
                api_mode: mode.0,
                transparent: false,
            })
            .map_err(|_| format!("API mode must be 1, 2 or 0 (transparent mode), got `{s}`"))
    }
}

/// `LINK` or `LINK@MODE`.
#[derive(Debug, Clone)]
pub(crate) struct LinkArg {
    pub(crate) link: Link,
    pub(crate) mode: Option<RadioModeArg>,
}

impl std::str::FromStr for LinkArg {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (link, mode) = match s.rsplit_once('@') {
            Some((link, mode)) => (link, Some(mode.parse::<RadioModeArg>()?)),
            None => (s, None),
        };
        let link = crate::link_args::parse_link(link)?;
        Ok(LinkArg { link, mode })
    }
}

/// `ADDR=LINK[@MODE]`.
#[derive(Debug, Clone)]
pub(crate) struct NodeArg {
    address: Address64,
    link: LinkArg,
}

impl std::str::FromStr for NodeArg {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (address, link) = s
            .split_once('=')
            .ok_or_else(|| format!("expected ADDR=LINK[@MODE], got `{s}`"))?;
        Ok(NodeArg {
            address: parse_address(address)?,
            link: link.parse()?,
        })
    }
}

/// `ADDR=SPEC`.
#[derive(Debug, Clone)]
pub(crate) struct LinkFaults {
    address: Address64,
    faults: Faults,
}

impl std::str::FromStr for LinkFaults {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (address, spec) = s
            .split_once('=')
            .ok_or_else(|| format!("expected ADDR=SPEC, got `{s}`"))?;
        let mut faults = Faults::default();
        for item in spec.split(',').filter(|i| !i.is_empty()) {
            let (key, value) = item
                .split_once('=')
                .ok_or_else(|| format!("expected KEY=VALUE in `{item}`"))?;
            let number: f64 = value
                .parse()
                .map_err(|_| format!("`{value}` is not a number (in `{item}`)"))?;
            let probability = || {
                (0.0..=1.0)
                    .contains(&number)
                    .then_some(number)
                    .ok_or_else(|| format!("{key} must be a probability from 0 to 1, got {value}"))
            };
            let millis = || {
                (0.0..=MAX_DELAY_MS as f64)
                    .contains(&number)
                    .then(|| Duration::from_secs_f64(number / 1000.0))
                    .ok_or_else(|| {
                        format!("{key} must be a number of milliseconds from 0 to {MAX_DELAY_MS}")
                    })
            };
            match key {
                "loss" => faults.loss = probability()?,
                "duplicate" => faults.duplicate = probability()?,
                "reorder" => faults.reorder = probability()?,
                "corrupt" => faults.corrupt = probability()?,
                "latency" => faults.latency = millis()?,
                "jitter" => faults.jitter = millis()?,
                other => return Err(format!("unknown fault `{other}`")),
            }
        }
        Ok(LinkFaults {
            address: parse_address(address)?,
            faults,
        })
    }
}

/// A 64-bit address, or `coordinator`.
pub(crate) fn parse_address(s: &str) -> Result<Address64, String> {
    if s.eq_ignore_ascii_case("coordinator") {
        return Ok(Address64::COORDINATOR);
    }
    s.parse::<Address64>()
        .map_err(|e| format!("bad 64-bit address `{s}`: {e}"))
}

/// Where a node's device connects, as a line.
pub(crate) fn describe_node(name: &str, info: &AddedNode, link: &Link) -> String {
    // A radio as from the factory runs its UART at 9600 baud, one in API mode at
    // 115200 (the links' default), and a pseudo-terminal set to another rate gets
    // garbage.
    let rate = if info.transparent { ":9600" } else { "" };
    let at = match (&info.pty_path, &info.local_addr) {
        (Some(path), _) => format!(
            "pseudo-terminal {} (open it as serial:{}{rate})",
            path.display(),
            path.display()
        ),
        (_, Some(addr)) => format!("listening on {addr} (connect with tcp:{addr})"),
        _ => format!("link {link}"),
    };
    let mode = if info.transparent {
        "transparent mode (AP=0, as from the factory: `mcp-gs setup` puts it into API mode)"
            .to_owned()
    } else {
        format!("API mode {}", u8::from(info.api_mode))
    };
    format!("{name} {}/{}: {at}, {mode}", info.addr64, info.addr16)
}

/// One line for a network event at `now`, or `None` to stay quiet.
pub(crate) fn event_line(event: &NetEvent, verbose: bool, now: SystemTime) -> Option<String> {
    let now = mcp_host::render::text::time(now);
    let text = match event {
        NetEvent::Connected { node, peer } if verbose || peer != "in-process" => {
            format!("{node} connected ({peer})")
        }
        NetEvent::Disconnected { node, reason } => format!("{node} disconnected: {reason}"),
        NetEvent::Failed {
            from,
            to,
            len,
            status,
        } => format!(
            "{from} -> {to}: {len} bytes not delivered: {status} (0x{:02x})",
            u8::from(*status)
        ),
        NetEvent::DecodeError { node, error } => format!("{node}: frame dropped: {error}"),
        NetEvent::Delivered { from, to, len } if verbose => {
            format!("{from} -> {to}: {len} bytes delivered")
        }
        NetEvent::Broadcast {
            from,
            len,
            receivers,
        } if verbose => format!("{from} -> broadcast: {len} bytes to {receivers} nodes"),
        NetEvent::AtCommand {
            node,
            command,
            status,
        } if verbose => format!(
            "{node}: AT {} answered {status} (0x{:02x})",
            mcp_host::render::text::at_name(*command),
            u8::from(*status)
        ),
        NetEvent::Ignored { node, frame_type } if verbose => {
            format!("{node}: frame type 0x{frame_type:02x} ignored")
        }
        _ => return None,
    };
    Some(format!("{now} {text}"))
}

/// How long a failed delivery from one node to another with one status is not printed
/// again after it was: a MAV's 20 Hz telemetry to a coordinator with no ground station
/// would otherwise print 20 lines a second.
const REPEAT_QUIET: Duration = Duration::from_secs(5);

/// The failures [`Repeats`] remembers at most: a device on a node's link that sends to
/// ever new destinations makes a failure of each, and must not make the map grow
/// without end.
const REPEAT_KEYS: usize = 1024;

/// Failed deliveries printed lately, by sender, destination and status, with how many
/// like each were not printed since; [`REPEAT_KEYS`] at most.
#[derive(Default)]
struct Repeats {
    seen: HashMap<(Address64, Address64, DeliveryStatus), (Instant, u64)>,
    /// When those printed [`REPEAT_QUIET`] ago or more were last forgotten.
    pruned: Option<Instant>,
}

impl Repeats {
    /// Whether to print a failure with `key` at `now`: `Some(n)` with the number of
    /// failures like it not printed since the last one, or `None` to stay quiet. When
    /// [`REPEAT_KEYS`] are remembered, those printed [`REPEAT_QUIET`] ago or more are
    /// forgotten (once a [`REPEAT_QUIET`] at most: each look goes through them all),
    /// with the failures like them not printed; while as many were printed lately, a
    /// new one is printed and not remembered.
    fn admit(&mut self, key: (Address64, Address64, DeliveryStatus), now: Instant) -> Option<u64> {
        if self.seen.len() >= REPEAT_KEYS
            && !self.seen.contains_key(&key)
            && self
                .pruned
                .is_none_or(|pruned| now.duration_since(pruned) >= REPEAT_QUIET)
        {
            self.pruned = Some(now);
            self.seen
                .retain(|_, (printed, _)| now.duration_since(*printed) < REPEAT_QUIET);
        }
        match self.seen.get_mut(&key) {
            Some((printed, quiet)) if now.duration_since(*printed) < REPEAT_QUIET => {
                *quiet += 1;
                None
            }
            Some((printed, quiet)) => {
                *printed = now;
                Some(std::mem::take(quiet))
            }
            None => {
                if self.seen.len() < REPEAT_KEYS {
                    self.seen.insert(key, (now, 0));
                }
                Some(0)
            }
        }
    }
}

/// A node's link as the operator gave it, and what to call it in a line about it ("the
/// ground station's link serial:/dev/ttyUSB0:115200").
pub(crate) struct NamedLink {
    pub(crate) node: Address64,
    pub(crate) name: String,
    pub(crate) link: Link,
}

impl NamedLink {
    /// The link of `node`, called `name` and then the link.
    pub(crate) fn new(node: Address64, name: &str, link: &Link) -> Self {
        NamedLink {
            node,
            name: format!("{name} {link}"),
            link: link.clone(),
        }
    }
}

/// The failure of the first of `links` that ended for good, if one did before `events`
/// were subscribed to (after that, the event says it).
fn ended_before(network: &Network, links: &[NamedLink]) -> Option<Failure> {
    links.iter().find_map(|named| {
        let error = network.link_ended(named.node)?;
        Some(ended_failure(named, &error))
    })
}

/// The failure of `named`, whose link ended for good with `error`: `radio` and `sim`
/// stop, rather than run on with a link that will never be there.
fn ended_failure(named: &NamedLink, error: &str) -> Failure {
    crate::hints::link_ended_failure(&named.name, &named.link, error)
}

/// The line saying the network runs: until Ctrl-C, or for `duration` (0: no limit).
fn running_line(duration: Option<Duration>) -> String {
    match duration.filter(|d| !d.is_zero()) {
        Some(d) => format!(
            "running for {}; Ctrl-C stops it sooner",
            mcp_host::render::Seconds(d)
        ),
        None => "running; Ctrl-C stops".to_owned(),
    }
}

/// Says it runs, then prints network events and carries out the cuts until Ctrl-C or
/// `duration` (0: no limit), whichever comes first. A failed delivery like one printed
/// less than five seconds before is counted, not printed. One of `links` that ends
/// for good ends the run, as a link failure.
pub(crate) async fn watch(
    network: &Network,
    mut events: broadcast::Receiver<NetEvent>,
    net: &NetArgs,
    verbose: bool,
    duration: Option<Duration>,
    links: &[NamedLink],
) -> Result<(), Failure> {
    if let Some(failure) = ended_before(network, links) {
        return Err(failure);
    }
    let mut timeline = net.timeline(Instant::now()).into_iter().peekable();
    let deadline = duration
        .filter(|d| !d.is_zero())
        .map(|d| Instant::now() + d);
    let ctrl_c = crate::interrupt::ctrl_c();
    out!("{}", running_line(duration));
    // The signal that stopped the run, or none when the time ran out: either is said, as
    // the last line of a log that would otherwise end without a word.
    let stop = async {
        let time_up = async {
            match deadline {
                Some(d) => tokio::time::sleep_until(d).await,
                None => std::future::pending().await,
            }
        };
        tokio::select! {
            () = time_up => None,
            by = ctrl_c => Some(by),
        }
    };
    tokio::pin!(stop);
    let mut failures = Repeats::default();
    // Nodes whose link is down that a failed delivery to was said of since: the next
    // failures to them are not (every frame to such a node fails until it is back).
    let mut told_down = std::collections::HashSet::new();
    // The date before the first timestamped line and at each new day.
    let mut dates = mcp_host::render::text::DateLines::new();
    let mut date_line = |now: SystemTime| {
        if let Some(date) = dates.before(now) {
            out!("{date}");
        }
    };
    loop {
        let next = timeline.peek().map(|step| step.0);
        tokio::select! {
            by = &mut stop => {
                let now = SystemTime::now();
                date_line(now);
                let time = mcp_host::render::text::time(now);
                match (by, duration) {
                    (Some(by), _) => out!("{time} stopped by {by}"),
                    (None, Some(duration)) => out!(
                        "{time} stopped after {} (--duration)",
                        mcp_host::render::Seconds(duration)
                    ),
                    // No deadline: only a signal stops the run.
                    (None, None) => {}
                }
                return Ok(());
            }
            () = tokio::time::sleep_until(next.unwrap_or_else(Instant::now)), if next.is_some() => {
                if let Some((_, node, cut)) = timeline.next() {
                    let known = if cut { network.cut(node) } else { network.restore(node) };
                    let what = if cut { "out of range (cut)" } else { "back in range" };
                    let time = SystemTime::now();
                    date_line(time);
                    let now = mcp_host::render::text::time(time);
                    match known {
                        true => out!("{now} {node} {what}"),
                        false => out!("{now} {node}: no such node to cut"),
                    }
                }
            },
            event = events.recv() => match event {
                Ok(NetEvent::LinkEnded { node, error }) => {
                    if let Some(named) = links.iter().find(|named| named.node == node) {
                        return Err(ended_failure(named, &error));
                    }
                }
                Ok(event) => {
                    if let NetEvent::Connected { node, .. } | NetEvent::Disconnected { node, .. } =
                        &event
                    {
                        told_down.remove(node);
                    }
                    // To a node whose link is down (no ground station on the
                    // coordinator, say): said once, not every five seconds until it is
                    // back.
                    if let NetEvent::Failed { from, to, status, .. } = &event {
                        if *status == DeliveryStatus::NetworkAckFailure
                            && !network.is_connected(*to)
                        {
                            if told_down.insert(*to) {
                                let now = SystemTime::now();
                                date_line(now);
                                let time = mcp_host::render::text::time(now);
                                out!(
                                    "{time} {from} -> {to}: not delivered while {to}'s link is \
                                     down (network_ack_failure), nor anything more to it \
                                     until it is back (not shown)"
                                );
                            }
                            continue;
                        }
                    }
                    let repeats = match &event {
                        NetEvent::Failed { from, to, status, .. } => {
                            match failures.admit((*from, *to, *status), Instant::now()) {
                                Some(n) => n,
                                None => continue,
                            }
                        }
                        _ => 0,
                    };
                    let now = SystemTime::now();
                    if let Some(line) = event_line(&event, verbose, now) {
                        date_line(now);
                        match repeats {
                            0 => out!("{line}"),
                            n => out!("{line} (and {n} more like it not shown)"),
                        }
                    }
                }
                Err(broadcast::error::RecvError::Lagged(n)) => {
                    // A node's coming back may be among them.
                    told_down.clear();
                    out!("({n} events not shown)");
                }
                Err(broadcast::error::RecvError::Closed) => return Ok(()),
            },
        }
    }
}

/// Runs `radio`.
pub(crate) async fn run(args: RadioArgs) -> Result<(), Failure> {
    let links = std::iter::once(&args.coordinator).chain(args.nodes.iter().map(|n| &n.link));
    for link in links {
        crate::hints::check_serial_path(&link.link, false)?;
    }
    let config = args.net.config(MAX_UNICAST)?;
    let addresses: Vec<Address64> = args.nodes.iter().map(|n| n.address).collect();
    check_distinct(&addresses, "node")?;
    args.net.check_nodes(&addresses, "node")?;
    // Said once the links are open: a link that cannot be opened is the one line.
    let described = config.clone();
    let network = Network::new(config);
    let events = network.subscribe();
    let default_mode = args.api_mode;
    let mut opened = Vec::new();
    let mut named = Vec::new();
    let coordinator = std::iter::once((Address64::COORDINATOR, args.coordinator.clone()));
    let nodes = args.nodes.iter().map(|n| (n.address, n.link.clone()));
    for (address, link) in coordinator.chain(nodes) {
        let mode = link.mode.unwrap_or(default_mode);
        let options = NodeOptions {
            api_mode: mode.api_mode,
            transparent: mode.transparent,
            faults: args.net.faults_of(address),
            ..NodeOptions::default()
        };
        let info = network
            .add_link(address, &link.link, options)
            .await
            .map_err(|e| crate::hints::network_failure(e, &link.link))?;
        let (name, called) = if address == Address64::COORDINATOR {
            ("coordinator", "the coordinator's link".to_owned())
        } else {
            ("node", format!("node {address}'s link"))
        };
        opened.push(describe_node(name, &info, &link.link));
        named.push(NamedLink::new(address, &called, &link.link));
    }
    args.net.describe(&described);
    for line in opened {
        out!("{line}");
    }
    let (verbose, duration) = (args.verbose, args.duration);
    watch(&network, events, &args.net, verbose, duration, &named).await
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_at_command_name_that_is_not_printable_is_shown_in_hex() {
        // Any device on the network may send an AT command of any two bytes: ESC c
        // would reset the operator's terminal.
        let event = NetEvent::AtCommand {
            node: Address64::COORDINATOR,
            command: *b"\x1bc",
            status: xbee_api::AtStatus::InvalidCommand,
        };
        let line = event_line(&event, true, SystemTime::now()).expect("a line");
        assert!(
            line.ends_with(": AT 1b63 answered invalid_command (0x02)"),
            "{line:?}"
        );
    }

    #[test]
    fn repeated_failures_are_counted_then_printed_again() {
        let mav = Address64(0x0013_A200_40B5_99B9);
        let key = (
            mav,
            Address64::COORDINATOR,
            DeliveryStatus::NetworkAckFailure,
        );
        let other = (mav, Address64::COORDINATOR, DeliveryStatus::AddressNotFound);
        let start = Instant::now();
        let mut repeats = Repeats::default();
        assert_eq!(repeats.admit(key, start), Some(0));
        for i in 1..=99 {
            assert_eq!(
                repeats.admit(key, start + Duration::from_millis(50 * i)),
                None
            );
        }
        // Another status is news.
        assert_eq!(repeats.admit(other, start), Some(0));
        assert_eq!(repeats.admit(key, start + REPEAT_QUIET), Some(99));
        assert_eq!(repeats.admit(key, start + REPEAT_QUIET), None);
    }

    #[test]
    fn failures_to_ever_new_destinations_are_remembered_a_bounded_number_at_a_time() {
        let from = Address64::COORDINATOR;
        let key = |n: u64| (from, Address64(n), DeliveryStatus::AddressNotFound);
        let start = Instant::now();
        let mut repeats = Repeats::default();
        // Each new destination is news, printed; the map stops growing at its bound.
        for n in 0..5 * REPEAT_KEYS as u64 {
            assert_eq!(repeats.admit(key(n), start), Some(0));
        }
        assert_eq!(repeats.seen.len(), REPEAT_KEYS);
        // Those remembered are still counted while quiet.
        assert_eq!(repeats.admit(key(7), start), None);
        // Once they have been quiet long enough, new ones take their places.
        let later = start + REPEAT_QUIET;
        for n in 0..3 * REPEAT_KEYS as u64 {
            assert_eq!(repeats.admit(key(1 << 32 | n), later), Some(0));
        }
        assert_eq!(repeats.seen.len(), REPEAT_KEYS);
        assert_eq!(repeats.admit(key(1 << 32 | 5), later), None);
        assert_eq!(repeats.admit(key(7), later), Some(0));
    }
}
