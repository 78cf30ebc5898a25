//! What the ground station says when a link fails or stays quiet: the likely cause
//! (another API mode or baud rate, a device that is no serial port, a port in use)
//! and the command that would tell, from the link and its counters.

use std::time::Duration;

use mcp_host::render::Seconds;
use mcp_host::{ConnectError, Diagnosis, Link, LinkError, SendError, Stats};
use xbee_api::{ApiMode, DeliveryStatus};

use crate::Failure;
use crate::link_args::{ApiModeChoice, LinkArgs};

/// Warns that answers gathered for `window` through a hub (a `tcp:` link may be one)
/// stop coming after the hub's answer window.
pub(crate) fn warn_hub_window(link: &Link, window: Duration) {
    if matches!(link, Link::Tcp { .. }) && window > mcp_host::hub::ANSWER_WINDOW {
        err!(
            "mcp-gs: through a hub, answers come for {} after it writes the request, \
             not for all of the {} asked",
            Seconds(mcp_host::hub::ANSWER_WINDOW),
            Seconds(window)
        );
    }
}

/// Says where the radio side of a link that waits for it comes: the pseudo-terminal's
/// path (`pty`), or the address bound (`tcp-listen:`, where port 0 picks one).
pub(crate) fn announce_radio_side(info: &mcp_host::LinkInfo) {
    if let Some(path) = &info.pty_path {
        err!(
            "mcp-gs: pseudo-terminal for the radio side: {}",
            path.display()
        );
    }
    if let Some(addr) = info.local_addr {
        err!("mcp-gs: listening for the radio side on {addr} (connect with tcp:{addr})");
    }
}

/// Warns when a serial link's baud rate is none of the standard ones an XBee is set to
/// (`BD` 0 to 8): a typo, most likely (`96000`), though a radio can be set to another.
pub(crate) fn warn_unusual_baud(link: &Link) {
    use mcp_host::command_mode::BAUD_RATES;
    if let Link::Serial { baud, .. } = link {
        if !BAUD_RATES.contains(baud) {
            let rates: Vec<String> = BAUD_RATES.iter().map(u32::to_string).collect();
            err!(
                "mcp-gs: warning: {baud} baud is none of the standard XBee rates ({}): \
                 nothing will be understood unless the radio was set to exactly that",
                rates.join(", ")
            );
        }
    }
}

/// Warns when the radio's AP setting, read as `radio` on `link`, is another API mode
/// than the configured one: its frames will be dropped or garbled. On a `tcp:` link
/// (a hub, maybe) the hub must speak it too. A value that is neither 1 nor 2 is no mode
/// to give with --api-mode.
pub(crate) fn warn_mode_mismatch(radio: u8, configured: ApiMode, link: &Link) {
    let configured = u8::from(configured);
    if !matches!(radio, 1 | 2) {
        // Transparent mode answers no API frame; another value is none of the modes
        // spoken here (or no answer to AP at all).
        err!(
            "mcp-gs: warning: the radio reads its API mode as {radio} (AP={radio}), which \
             this ground station does not speak: `mcp-gs setup --link {link}` sets 1"
        );
    } else if radio != configured {
        let hub = match link {
            Link::Tcp { .. } => format!(
                " (through a hub, the hub itself must be started with --api-mode {radio}: it \
                 drops the frames it cannot read)"
            ),
            _ => String::new(),
        };
        err!(
            "mcp-gs: warning: the radio is in API mode {radio} (AP={radio}) but --api-mode is \
             {configured}: frames will be dropped or garbled; use --api-mode {radio} or auto{hub}"
        );
    }
}

/// What the link's counters found wrong with the radio's settings
/// ([`Stats::diagnose`], [`Stats::diagnose_running`]), as a hint with what to give on
/// the command line.
pub(crate) fn hint(found: Diagnosis, link: &Link) -> String {
    let advice = match found {
        Diagnosis::OtherApiMode { radio, .. } => {
            let radio = u8::from(radio);
            format!("try --api-mode {radio} or --api-mode auto")
        }
        Diagnosis::NoFrames { .. } => format!(
            "`mcp-gs setup` puts a radio in transparent mode into API mode; {}",
            baud_advice(link)
        ),
        Diagnosis::Echo { .. } => {
            "is the radio on this port (`mcp-gs ports` lists them), and its cable the \
             right way round?"
                .to_owned()
        }
        _ => baud_advice(link),
    };
    format!("hint: {found}; {advice}")
}

/// A serial link's string at the rate `baud` (a number, `BAUD`; `None`: no rate, for
/// `probe`), its flow control kept: `serial:/dev/ttyUSB0:9600:rtscts`.
pub(crate) fn serial_at(
    path: &str,
    flow_control: mcp_host::link::FlowControl,
    baud: Option<&str>,
) -> String {
    let flow = match flow_control {
        mcp_host::link::FlowControl::RtsCts => ":rtscts",
        _ => "",
    };
    match baud {
        Some(baud) => format!("serial:{path}:{baud}{flow}"),
        None => format!("serial:{path}{flow}"),
    }
}

/// What to do about a baud rate that may differ from the radio's, on `link`.
fn baud_advice(link: &Link) -> String {
    match link {
        Link::Serial {
            path,
            baud,
            flow_control,
            ..
        } => format!(
            "the link runs at {baud} baud: give the radio's rate as {} (XBee modules ship \
             at 9600), or let `mcp-gs probe --link {}` find it",
            serial_at(path, *flow_control, Some("BAUD")),
            serial_at(path, *flow_control, None),
        ),
        _ => "the radio's baud rate is set where it is attached (XBee modules ship at 9600)"
            .to_owned(),
    }
}

/// The [`hint`] of the link's counters, when its API mode was given (one found by
/// asking the radio is right).
pub(crate) fn counters_hint(link: &LinkArgs, stats: &Stats) -> Option<String> {
    match link.api_mode {
        ApiModeChoice::Fixed(mode) => stats.diagnose(mode).map(|found| hint(found, &link.link)),
        ApiModeChoice::Auto => None,
    }
}

/// `failure` (nobody answered), with a hint when frames from the radio failed their
/// checksum (the radio may be in the other API mode), or when nothing at all came from
/// it: nobody in range is an answer too, but a local radio not set up for the link
/// would be as silent.
pub(crate) fn with_mode_hint(failure: Failure, link: &LinkArgs, stats: &Stats) -> Failure {
    let silent = "nothing at all came from the local radio either: if the others are on and in \
                  range, check its API mode";
    match counters_hint(link, stats).or_else(|| silence_hint(&link.link, stats, silent)) {
        Some(hint) => failure.with_hint(hint),
        None => failure,
    }
}

/// What may be wrong when a wait timed out: the [`counters_hint`], or, if nothing at
/// all came from the radio, what keeps a radio silent.
fn timeout_hint(link: &LinkArgs, stats: &Stats) -> Option<String> {
    let silent = "nothing at all came from the radio: check its API mode";
    counters_hint(link, stats).or_else(|| silence_hint(&link.link, stats, silent))
}

/// If nothing at all came from the radio, `lead` (which ends asking to check the API
/// mode) and what else keeps a radio silent.
pub(crate) fn silence_hint(link: &Link, stats: &Stats, lead: &str) -> Option<String> {
    nothing_came(stats).then(|| match link {
        // A tcp-listen peer (sim, radio) that serves another connection lets this
        // one wait for its turn, silently; a hub that cannot read its radio drops what
        // it hears, and says so in its own lines.
        Link::Tcp { .. } => format!(
            "hint: {lead} (--api-mode, or auto to ask it), and whether the peer serves \
             another connection (mcp-gs sim and radio serve one at a time and let the next \
             wait; to share one, use mcp-gs hub); if the peer is mcp-gs hub, its own lines \
             say whether it hears its radio, and one stopped (Ctrl-Z) still takes \
             connections but answers nothing"
        ),
        _ => format!(
            "hint: {lead} (--api-mode, or auto to ask it), the baud rate (serial:PATH:BAUD), \
             and that no other program reads the port (to share it, use mcp-gs hub); a radio \
             new from the factory is in transparent mode at 9600 baud: `mcp-gs probe --link \
             {}` finds what it is set to",
            probe_link(link)
        ),
    })
}

/// The link `mcp-gs probe` is pointed at for `link`: a serial port without its baud
/// rate (probe then tries the factory's first), as is.
fn probe_link(link: &Link) -> String {
    match link {
        Link::Serial {
            path, flow_control, ..
        } => serial_at(path, *flow_control, None),
        other => other.to_string(),
    }
}

/// `failure`, with the [`timeout_hint`] when it is a timeout, or the
/// [`turned_away_hint`] when a TCP peer ended the link before anything came from it.
pub(crate) fn diagnosed(failure: Failure, link: &LinkArgs, stats: &Stats) -> Failure {
    let hint = match failure.code() {
        Failure::TIMEOUT => timeout_hint(link, stats),
        Failure::LINK if matches!(link.link, Link::Tcp { .. }) && nothing_came(stats) => {
            Some(turned_away_hint())
        }
        _ => None,
    };
    match hint {
        Some(hint) => failure.with_hint(hint),
        None => failure,
    }
}

/// Whether nothing at all came from the radio: no frame, no failed one, no byte
/// skipped.
pub(crate) fn nothing_came(stats: &Stats) -> bool {
    stats.frames == 0 && stats.decode_errors() == 0 && stats.bytes_skipped == 0
}

/// Why a TCP peer may close a connection before anything came from it.
pub(crate) fn turned_away_hint() -> String {
    "hint: the peer closed the connection before anything came from the radio: mcp-gs sim \
     and radio serve one connection at a time, let one more wait its turn and close any \
     other at once (to share one, use mcp-gs hub); a hub closes its clients' connections \
     when it loses its radio, and turns new ones away while it serves 64 (its own lines \
     say so)"
        .to_owned()
}

/// The link of `link`, with `--api-mode` when it is not the default: the arguments of
/// another `mcp-gs` command on the same radio.
fn link_and_mode(link: &LinkArgs) -> String {
    let mode = match link.api_mode {
        ApiModeChoice::Fixed(ApiMode::Unescaped) => String::new(),
        ApiModeChoice::Fixed(mode) => format!(" --api-mode {}", u8::from(mode)),
        ApiModeChoice::Auto => " --api-mode auto".to_owned(),
    };
    format!("{}{mode}", link.link)
}

/// A request's failure, [`diagnosed_unanswered`] when no answer to its frame id came
/// (not even the local radio's status), else [`diagnosed`].
pub(crate) fn diagnosed_send(error: SendError, link: &LinkArgs, stats: &Stats) -> Failure {
    // What the error itself says to do, rather than what the link's counters say.
    let own = match &error {
        // The frame never left: the radio's settings have nothing to do with it.
        SendError::NotSent { .. } => Some(
            "hint: the link did not take the frame in time: give a longer --timeout (a \
             slow serial link, a busy hub or many commands at once take longer), or the \
             link takes no bytes (hardware flow control held, a peer that does not read)"
                .to_owned(),
        ),
        SendError::Delivery { status, .. } if *status == DeliveryStatus::AddressNotFound => {
            Some(format!(
                "hint: no radio of the network has that address: `mcp-gs nodes --link {}` \
                 lists the radios that answer",
                link_and_mode(link)
            ))
        }
        // Digi's words for a destination that did not acknowledge: 802.15.4 (0x01),
        // Zigbee and DigiMesh (0x21), no route to it (0x25).
        SendError::Delivery {
            status:
                DeliveryStatus::MacAckFailure
                | DeliveryStatus::NetworkAckFailure
                | DeliveryStatus::RouteNotFound,
            ..
        } => Some(format!(
            "hint: the MAV's radio did not acknowledge it: it is off, out of range, or in \
                 another network (its ID and CH must be this radio's); `mcp-gs nodes --link {}` \
                 lists the radios that answer",
            link_and_mode(link)
        )),
        SendError::Delivery { status, .. } if *status == DeliveryStatus::NotJoinedToNetwork => {
            Some(format!(
                "hint: this radio has joined no network: is its coordinator on, and its ID \
                 and CH the network's? (`mcp-gs at --link {} AI` says how joining went)",
                link_and_mode(link)
            ))
        }
        SendError::Delivery { status, .. } if *status == DeliveryStatus::PayloadTooLarge => {
            Some(format!(
                "hint: the packet is larger than the radio carries to that address (`mcp-gs at \
                 --link {} NP` gives the most it sends in one radio packet; a broadcast is never \
                 cut into fragments): send a shorter one (fewer waypoints, a shorter message)",
                link_and_mode(link)
            ))
        }
        SendError::Delivery { status, .. } if *status == DeliveryStatus::ResourceError => Some(
            "hint: the radio had no room for the frame (buffers, timers), or a hub between \
             had no frame id free for it in time (many requests of its clients waiting for \
             answers): try again shortly"
                .to_owned(),
        ),
        _ => None,
    };
    let unanswered = matches!(error, SendError::Timeout { .. });
    let failure = send_failure(error);
    if let Some(hint) = own {
        return failure.with_hint(hint);
    }
    if unanswered {
        diagnosed_unanswered(failure, link, stats)
    } else {
        diagnosed(failure, link, stats)
    }
}

/// A timeout of a frame the local radio never answered (no transmit status, no
/// response), with the [`timeout_hint`], or, when other frames from the radio came
/// through, a pointer to the API mode: a frame with a byte to escape passes in one mode
/// only.
pub(crate) fn diagnosed_unanswered(failure: Failure, link: &LinkArgs, stats: &Stats) -> Failure {
    if failure.code() != Failure::TIMEOUT {
        return failure;
    }
    let mode_hint = || match link.api_mode {
        ApiModeChoice::Fixed(mode) if stats.frames > 0 => Some(format!(
            "hint: other frames came from the radio, but no answer to this one: if the \
             radio is not in API mode {} (AP={}), only frames with no byte to escape get \
             through; `mcp-gs at --link {} --api-mode auto AP` reads its mode",
            u8::from(mode),
            u8::from(mode),
            link.link
        )),
        _ => None,
    };
    match timeout_hint(link, stats).or_else(mode_hint) {
        Some(hint) => failure.with_hint(hint),
        None => failure,
    }
}

/// For a serial link: that its path is a serial port, or may become one. Checked
/// before `radio` and `sim` start, which keep reopening a link that went away (a USB
/// adapter pulled out and plugged in again): for a mistyped path, that would be forever.
///
/// A path that is there must be a terminal device: a regular file (as `echo >
/// /dev/ttyUSB0` leaves before the adapter is plugged in), a directory or a device that
/// is no terminal (`/dev/null`) never becomes one. With `wait` (`monitor --wait`), a
/// path that is not there yet may come (a radio plugged in later), and a device this
/// user may not open yet is waited for, with what to do about it said once.
///
/// On Windows, where a port's name (`COM3`) is no file path, nothing is checked.
pub(crate) fn check_serial_path(link: &Link, wait: bool) -> Result<(), Failure> {
    let Link::Serial { path, .. } = link else {
        return Ok(());
    };
    if cfg!(windows) {
        return Ok(());
    }
    match std::fs::metadata(path) {
        Ok(meta) => match no_device_kind(&meta) {
            Some(what) => Err(no_serial_device(link, path, what)),
            None => check_terminal(link, path, wait),
        },
        Err(_) if wait => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let hint = match misread_baud(link) {
                Some((path, baud)) => format!(
                    "`{baud}` was read as part of the path: a baud rate is digits alone, as in \
                     serial:{path}:9600"
                ),
                None => "`mcp-gs ports` lists the serial ports present".to_owned(),
            };
            Err(Failure::link(format!(
                "cannot open {link}: no such device ({hint})"
            )))
        }
        Err(e) => Err(Failure::link(format!("cannot open {link}: {e}"))),
    }
}

/// For a character device at `path`: that it is a terminal, as a serial port is. It is
/// opened for a moment, as the link would open it but without waiting for a carrier.
/// A device this user may not open is refused with what to do about it, or with `wait`
/// said so once and waited for; any other failure to open it is left to the link to
/// report.
fn check_terminal(link: &Link, path: &str, wait: bool) -> Result<(), Failure> {
    match open_device(path) {
        Ok(device) if std::io::IsTerminal::is_terminal(&device) => Ok(()),
        Ok(_) => Err(no_serial_device(link, path, NO_TERMINAL)),
        Err(e) if e.kind() == std::io::ErrorKind::PermissionDenied && wait => {
            err!("mcp-gs: warning: cannot open {path} yet: {PERMISSION_HINT}");
            Ok(())
        }
        Err(e) if e.kind() == std::io::ErrorKind::PermissionDenied => Err(Failure::link(format!(
            "cannot open {link}: permission denied ({PERMISSION_HINT})"
        ))),
        Err(_) => Ok(()),
    }
}

/// Opens the device at `path` for reading and writing, as a serial port is opened, but
/// without blocking (a serial port may wait for a carrier) and without making it the
/// process's controlling terminal.
fn open_device(path: &str) -> std::io::Result<std::fs::File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true).write(true);
    #[cfg(unix)]
    std::os::unix::fs::OpenOptionsExt::custom_flags(
        &mut options,
        libc::O_NONBLOCK | libc::O_NOCTTY,
    );
    options.open(path)
}

/// The failure of a serial link whose path is there but is no serial device: `what` it
/// is instead, as [`not_a_serial_port`] says it when the link is opened.
fn no_serial_device(link: &Link, path: &str, what: &str) -> Failure {
    Failure::link(format!(
        "cannot open {link}: {path} is not a serial device but {what} (`mcp-gs ports` lists \
         the serial ports present)"
    ))
}

/// What a command opening a link does with it, for what to say when another program
/// holds its serial port.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Role {
    /// A command that could share the radio through a hub (monitor, send, ...), or that
    /// needs the port itself for a while (setup, probe).
    Client,
    /// A hub, which holds the port for others.
    Hub,
    /// An emulated network (sim, radio), whose nodes hold their ports.
    Network,
}

/// A failure to open `link`, for a [`Role::Client`].
pub(crate) fn connect_failure(link: &Link, error: ConnectError) -> Failure {
    connect_failure_as(link, error, Role::Client)
}

/// A failure to open `link`, said to a command in `role`.
pub(crate) fn connect_failure_as(link: &Link, error: ConnectError, role: Role) -> Failure {
    match error {
        ConnectError::Options(what) => Failure::input(format!("invalid link options: {what}")),
        ConnectError::Link(e) => {
            let hint = link_hint(&e, link, role)
                .map(|h| format!(" ({h})"))
                .unwrap_or_default();
            // Most say what they could not open, and how: once is enough.
            let names_it = matches!(
                e,
                LinkError::Serial { .. }
                    | LinkError::Connect { .. }
                    | LinkError::ConnectTimeout { .. }
                    | LinkError::Listen { .. }
                    | LinkError::Accept { .. }
                    | LinkError::Io { .. }
            );
            match names_it {
                true => Failure::link(format!("{e}{hint}")),
                false => Failure::link(format!("cannot open {link}: {e}{hint}")),
            }
        }
        other => Failure::link(format!("cannot open {link}: {other}")),
    }
}

/// What an operator can do about a link that cannot be opened, where the cause is
/// a common one, said to a command in `role`.
fn link_hint(error: &LinkError, link: &Link, role: Role) -> Option<String> {
    use std::io::ErrorKind as Io;
    use tokio_serial::ErrorKind as Serial;
    match error {
        LinkError::Serial { error, .. } => match error.kind {
            Serial::Io(Io::NotFound) => Some(match misread_baud(link) {
                Some((path, baud)) => format!(
                    "no such device; `{baud}` was read as part of the path: a baud rate is \
                     digits alone, as in serial:{path}:9600"
                ),
                None => "no such device: `mcp-gs ports` lists the serial ports present".into(),
            }),
            Serial::Io(Io::PermissionDenied) => Some(PERMISSION_HINT.into()),
            // On Unix: the port is open for exclusive use elsewhere (TIOCEXCL or flock).
            // On Windows, serialport also reports a port that does not exist (or may
            // not be opened) as NoDevice: the hint cannot claim it is in use.
            Serial::NoDevice => {
                let busy = if cfg!(windows) {
                    "the port is missing (`mcp-gs ports` lists the serial ports present), or \
                     another program, perhaps another mcp-gs, has it open"
                } else {
                    "another program has the port open, perhaps another mcp-gs"
                };
                let then = match role {
                    Role::Client => format!(
                        " (a hub, say: setup and probe need the port itself); to share the \
                         radio among monitor, send, status and the like, let `mcp-gs hub \
                         --link {link}` hold it and give them --link tcp:127.0.0.1:9750"
                    ),
                    Role::Hub => " first (a hub that holds it already shares it: give \
                                  monitor, send and the like its --link tcp:ADDR:PORT rather \
                                  than start another)"
                        .to_owned(),
                    Role::Network => " first".to_owned(),
                };
                Some(format!(
                    "{busy}: one program at a time can use a serial port: stop the other{then}"
                ))
            }
            _ => not_a_serial_port(&error.description, link),
        },
        LinkError::Connect { error, .. } if error.kind() == Io::ConnectionRefused => Some(
            "nothing listens there: is the radio bridge, `mcp-gs hub` or `mcp-gs sim` \
             running? A hub whose radio is disconnected refuses connections"
                .into(),
        ),
        LinkError::Listen { error, .. } => match error.kind() {
            Io::AddrInUse => Some(
                "another program, perhaps another mcp-gs, listens there: give another port, \
                 or port 0 for any free one"
                    .into(),
            ),
            _ => listen_hint(error).map(str::to_owned),
        },
        _ => None,
    }
}

/// What to do about an address that cannot be listened on, but for one in use (whose
/// cause depends on who listens).
pub(crate) fn listen_hint(error: &std::io::Error) -> Option<&'static str> {
    use std::io::ErrorKind;
    match error.kind() {
        ErrorKind::AddrNotAvailable => Some(
            "no network interface of this machine has that address: give 127.0.0.1 for this \
             machine alone, or 0.0.0.0 for every interface",
        ),
        ErrorKind::PermissionDenied => Some("ports below 1024 need privileges: use 1024 or above"),
        _ => None,
    }
}

/// The failure of an emulated network (`radio`, `sim`) that could not be set up: a
/// node's link that cannot be opened, with what to do about it, is a link failure;
/// anything else, bad input.
pub(crate) fn network_failure(error: mcp_host::radio::NetworkError, link: &Link) -> Failure {
    match &error {
        mcp_host::radio::NetworkError::Link { error: cause, .. } => {
            let hint = link_hint(cause, link, Role::Network)
                .map(|h| format!(" ({h})"))
                .unwrap_or_default();
            Failure::link(format!("{error}{hint}"))
        }
        _ => Failure::input(error.to_string()),
    }
}

/// The failure of a node's link (`radio`, `sim`) that ended for good with `error`:
/// `name`, as "the ground station's link serial:/dev/ttyUSB0:115200", why, and what to
/// do about a path that is no serial port.
pub(crate) fn link_ended_failure(name: &str, link: &Link, error: &str) -> Failure {
    let hint = not_a_serial_port(error, link)
        .map(|h| format!(" ({h})"))
        .unwrap_or_default();
    Failure::link(format!(
        "{name} ended: it cannot be opened, and waiting will not change that: {error}{hint}"
    ))
}

/// For a serial link whose path does not exist but would without its last `:` part (as
/// in `serial:/dev/ttyUSB0:9600baud`): the path that exists and that part, which was
/// meant as a baud rate. Paths may hold colons (`/dev/serial/by-path/...`), so only a
/// trailing `:DIGITS` is read as the baud rate.
fn misread_baud(link: &Link) -> Option<(&str, &str)> {
    let Link::Serial { path, .. } = link else {
        return None;
    };
    let (device, baud) = path.rsplit_once(':')?;
    std::path::Path::new(device)
        .exists()
        .then_some((device, baud))
}

/// What to do about a device this user may not open.
const PERMISSION_HINT: &str = "this user may not open the device: on Linux, add the user to \
     the group that owns it (often dialout: `sudo usermod -aG dialout $USER`, then log in \
     again)";

/// The hint for a serial link whose path is no serial port: a regular file, a
/// directory, or a device that is no terminal (`/dev/null`: opening it fails with
/// ENOTTY, whose text depends on the C library).
fn not_a_serial_port(description: &str, link: &Link) -> Option<String> {
    let Link::Serial { path, .. } = link else {
        return None;
    };
    let what = what_it_is(path, description)?;
    Some(format!(
        "not a serial port ({path} is {what}): `mcp-gs ports` lists the serial ports present"
    ))
}

/// What `path` is when it is no serial port: what [`no_device_kind`] says of a file
/// that is no character device, or, when `description` (the error opening it) says it
/// is no terminal, a device that is none.
fn what_it_is(path: &str, description: &str) -> Option<&'static str> {
    let kind = std::fs::metadata(path)
        .ok()
        .and_then(|meta| no_device_kind(&meta));
    kind.or_else(|| {
        ["Not a typewriter", "Inappropriate ioctl", "Not a tty"]
            .iter()
            .any(|text| description.contains(text))
            .then_some(NO_TERMINAL)
    })
}

/// A character device that is no terminal, as `/dev/null`.
const NO_TERMINAL: &str = "a device that is no terminal";

/// What a file is that can be no serial port, or `None` for a character device (which
/// is one if it is a terminal).
fn no_device_kind(meta: &std::fs::Metadata) -> Option<&'static str> {
    let kind = meta.file_type();
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_char_device() {
            return None;
        }
        if kind.is_block_device() {
            return Some("a block device");
        }
        if kind.is_fifo() {
            return Some("a named pipe");
        }
        if kind.is_socket() {
            return Some("a socket");
        }
    }
    if kind.is_dir() {
        Some("a directory")
    } else if kind.is_file() {
        Some("a regular file")
    } else {
        None
    }
}

/// A send that did not succeed.
pub(crate) fn send_failure(error: SendError) -> Failure {
    let code = match &error {
        SendError::Delivery { .. } => Failure::DELIVERY,
        e if e.is_timeout() => Failure::TIMEOUT,
        SendError::Disconnected { .. } | SendError::Closed => Failure::LINK,
        SendError::TooLarge { .. }
        | SendError::NoFrameId(_)
        | SendError::NoFrameIdByte(_)
        | SendError::EmptyFrame => Failure::INPUT,
        _ => Failure::OTHER,
    };
    match error {
        // No answer is no proof that nothing happened.
        SendError::Timeout { .. } => Failure::new(
            code,
            format!("{error}; the frame may still have gone out and been carried out"),
        ),
        _ => Failure::new(code, error.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_baud_rate_hint_says_the_rate_the_link_runs_at_and_how_to_find_the_radios() {
        // Only frames of impossible lengths and bytes that are no frames.
        let stats = Stats {
            oversize: 10,
            bytes_skipped: 40,
            ..Stats::default()
        };
        let found = stats.diagnose(ApiMode::Unescaped).expect("a diagnosis");
        let serial = Link::serial("/dev/ttyUSB0", 9600);
        let text = hint(found, &serial);
        assert!(
            text.contains(
                "the link runs at 9600 baud: give the radio's rate as serial:/dev/ttyUSB0:BAUD"
            ),
            "{text}"
        );
        assert!(
            text.contains("`mcp-gs probe --link serial:/dev/ttyUSB0` find it"),
            "{text}"
        );
        // The link's flow control goes with it.
        let rts_cts = mcp_host::link::FlowControl::RtsCts;
        let text = hint(found, &Link::serial_with("/dev/ttyUSB0", 9600, rts_cts));
        assert!(
            text.contains("as serial:/dev/ttyUSB0:BAUD:rtscts (XBee")
                && text.contains("`mcp-gs probe --link serial:/dev/ttyUSB0:rtscts` find it"),
            "{text}"
        );
        // Over TCP the rate is not the link's to give.
        let tcp = Link::tcp("127.0.0.1", 9750);
        let text = hint(found, &tcp);
        assert!(
            text.contains("the radio's baud rate is set where it is attached"),
            "{text}"
        );
    }
}
