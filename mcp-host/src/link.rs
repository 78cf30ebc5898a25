//! The [`Link`] address: which serial port, TCP peer or pseudo-terminal carries the XBee
//! API byte stream, written as a short string (see the crate docs for the table).

use std::fmt;
use std::str::FromStr;

/// Baud rate used by `serial:` links that do not name one (the deployed XBee modules run
/// at 115200 baud, 8N1).
pub const DEFAULT_BAUD: u32 = 115_200;

/// Flow control of a `serial:` link.
///
/// XBee modules offer hardware flow control alone: the radio drops CTS while its serial
/// receive buffer is nearly full (`D7` = 1, as it leaves the factory), and with `D6` = 1
/// it holds back what it sends while the host drops RTS. Without flow control (the
/// default, as most USB adapters are used) a host that writes faster than the radio
/// sends over the air, many commands at once through a hub say, can overrun that buffer,
/// and the radio drops the bytes: the frames cut short are never sent, their requests
/// time out. Software flow control (XON/XOFF) is not offered: XBee modules do not speak
/// it, and in API mode 1 the bytes 0x11 and 0x13 occur in frames unescaped.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum FlowControl {
    /// None: the CTS line is ignored and RTS left asserted (raised on opening, with DTR,
    /// on Windows, which opens a port with both off).
    #[default]
    None,
    /// Hardware flow control on RTS/CTS (`serial:PATH:BAUD:rtscts`): nothing is written
    /// while the radio drops CTS. On Unix the driver also drops RTS while its own
    /// receive buffer is full (which holds back a radio with `D6` = 1); on Windows the
    /// serial driver is set to honour CTS alone and keeps RTS raised, so the radio is
    /// never held back there.
    RtsCts,
}

/// Where the XBee API byte stream comes from.
///
/// Parsed from and displayed as a string; `Display` always writes the baud rate of a
/// serial link, so `link.to_string().parse()` gives the same link back (but for the
/// strings no parse takes, built by hand: an `io` link of no name, a serial link whose
/// path ends in a word such as `:rtscts`).
///
/// ```
/// use mcp_host::link::FlowControl;
/// use mcp_host::Link;
///
/// let link: Link = "serial:/dev/ttyUSB0".parse()?;
/// assert_eq!(link, Link::serial("/dev/ttyUSB0", 115_200));
/// assert_eq!(link.to_string(), "serial:/dev/ttyUSB0:115200");
///
/// // A radio whose CTS line the host must honour (hardware flow control).
/// let link: Link = "serial:/dev/ttyUSB0:230400:rtscts".parse()?;
/// assert_eq!(link, Link::serial_with("/dev/ttyUSB0", 230_400, FlowControl::RtsCts));
///
/// let link: Link = "tcp:[::1]:9750".parse()?;
/// assert_eq!(link, Link::tcp("::1", 9750));
/// assert_eq!(Link::from("[::1]:9750".parse::<std::net::SocketAddr>()?), link);
/// assert_eq!(link.to_string(), "tcp:[::1]:9750");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Link {
    /// A serial port (`serial:PATH[:BAUD][:rtscts]`), 8 data bits, no parity, 1 stop bit.
    #[non_exhaustive]
    Serial {
        /// Device path, e.g. `/dev/ttyUSB0`.
        path: String,
        /// Baud rate.
        baud: u32,
        /// Flow control: none (the default, or `:none`), or RTS/CTS (`:rtscts`, after
        /// the baud rate or before it).
        flow_control: FlowControl,
    },
    /// A TCP connection to `HOST:PORT` (`tcp:HOST:PORT`).
    #[non_exhaustive]
    Tcp {
        /// Host name or IP address (IPv6 without brackets).
        host: String,
        /// TCP port.
        port: u16,
    },
    /// A TCP listener on `ADDR:PORT` serving one peer at a time (`tcp-listen:ADDR:PORT`).
    #[non_exhaustive]
    TcpListen {
        /// Local address to bind (IPv6 without brackets).
        addr: String,
        /// TCP port (0 picks a free port; see [`crate::LinkInfo::local_addr`]).
        port: u16,
    },
    /// A fresh pseudo-terminal pair (`pty`), made when the link is opened; the far end's
    /// path is in [`LinkInfo::pty_path`](crate::LinkInfo::pty_path) at once. The link is
    /// up while a device (a simulator, a test) has that path open.
    Pty,
    /// A byte stream the program opens itself (`io:NAME`): a Bluetooth serial socket,
    /// a serial port opened with settings of its own, an in-memory stream in a test.
    /// [`connect_with`](crate::connect_with) and [`connect_io`](crate::connect_io) make
    /// it from the function that opens the stream, or the stream; `NAME` says what it is
    /// in events and logs. [`connect`](crate::connect) cannot open one (it has nothing
    /// to open it with) and says so.
    #[non_exhaustive]
    Io {
        /// What the stream is, as its opener named it.
        name: String,
    },
}

/// Why a link string could not be parsed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum LinkParseError {
    /// The string was empty.
    #[error(
        "empty link string (expected serial:PATH[:BAUD][:rtscts], tcp:HOST:PORT, tcp-listen:ADDR:PORT or pty)"
    )]
    Empty,
    /// The part before the first `:` is not a known link kind.
    #[error("unknown link kind {0:?} (expected serial, tcp, tcp-listen or pty){hint}", hint = bare_path_hint(.0))]
    UnknownKind(String),
    /// A host and port with no link kind before them (`127.0.0.1:9750`): `tcp:` was
    /// meant, most likely.
    #[error("no link kind in {0:?}: to connect to that TCP port, write tcp:{0}")]
    BareHostPort(String),
    /// `serial:` without a device path.
    #[error("serial link without a device path (expected serial:PATH[:BAUD][:rtscts])")]
    MissingPath,
    /// A serial link ending in a word that is neither a baud rate, `rtscts` nor `none`
    /// (`serial:/dev/ttyUSB0:115200:rts`): no device's name ends so, and taken as part of
    /// the path it would be waited for in vain.
    #[error("{}", option_message(.0))]
    UnknownSerialOption(String),
    /// The baud rate is not a positive integer.
    #[error("invalid baud rate {0:?} (expected a positive integer)")]
    InvalidBaud(String),
    /// `tcp:`/`tcp-listen:` without `HOST:PORT`.
    #[error("missing port in {0:?} (expected HOST:PORT)")]
    MissingPort(String),
    /// `tcp:`/`tcp-listen:` with an empty host or address.
    #[error("missing host in {0:?} (expected HOST:PORT)")]
    MissingHost(String),
    /// The host or address holds white space (`tcp: 127.0.0.1:9750`), a control
    /// character, a `/`, or a bracket inside brackets (`tcp:[[]:1`).
    #[error(
        "invalid host {0:?} (a host name or address holds no space, control character, '/', '[' or ']')"
    )]
    InvalidHost(String),
    /// The host holds a `:` outside brackets (`tcp:::1:9750`, `tcp:host:1:2`): which
    /// `:` begins the port cannot be told. An IPv6 address goes in brackets.
    #[error(
        "invalid host {0:?}: an IPv6 address goes in brackets, as in tcp:[::1]:9750, and a host name holds no ':'"
    )]
    UnbracketedHost(String),
    /// The port is not an integer in 0..=65535.
    #[error("invalid port {0:?} (expected 0-65535)")]
    InvalidPort(String),
    /// `tcp:HOST:0`: nothing can be connected to port 0 (only `tcp-listen:` takes it,
    /// for a port the system chooses).
    #[error(
        "port 0 in tcp:{0} cannot be connected to (expected 1-65535; port 0 is for tcp-listen, where the system chooses one)"
    )]
    PortZero(String),
    /// `pty` followed by anything.
    #[error("unexpected text after pty: {0:?}")]
    TrailingPty(String),
    /// `io` or `io:` without the name of the stream (`io:NAME`).
    #[error("io link without a name (expected io:NAME, the name of a stream the program opens)")]
    MissingIoName,
    /// A link written as a URL, `tcp://HOST:PORT`: the kind and the `//`.
    #[error("{0}:// is no link kind: write {0}:HOST:PORT, without //")]
    UrlForm(String),
}

/// For a link string that is a bare device path: the `serial:` link meant; for a kind
/// in capitals: the kind meant.
/// Whether `kind` is a host's name or address a link kind was taken for (`localhost`,
/// `127.0.0.1`).
fn is_host(kind: &str) -> bool {
    kind == "localhost" || kind.parse::<std::net::IpAddr>().is_ok()
}

fn bare_path_hint(kind: &str) -> String {
    let lower = kind.to_ascii_lowercase();
    if lower != kind && matches!(lower.as_str(), "serial" | "tcp" | "tcp-listen" | "pty") {
        return format!("; kinds are lower case: {lower}");
    }
    // `COM3`, `com3`, `\\.\COM10`.
    let port = kind.strip_prefix(r"\\.\").unwrap_or(kind);
    let com_port = port
        .get(..3)
        .is_some_and(|com| com.eq_ignore_ascii_case("com"))
        && port
            .get(3..)
            .is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()));
    let is_path = kind.starts_with('/') || com_port;
    if is_path {
        format!("; for a serial port, write serial:{kind}")
    } else if is_host(kind) {
        format!("; to connect to a TCP port, write tcp:{kind}:PORT")
    } else {
        String::new()
    }
}

impl FromStr for Link {
    type Err = LinkParseError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        if s.is_empty() {
            return Err(LinkParseError::Empty);
        }
        let (kind, rest) = match s.split_once(':') {
            Some((kind, rest)) => (kind, Some(rest)),
            None => (s, None),
        };
        if matches!(kind, "tcp" | "tcp-listen") && rest.is_some_and(|r| r.starts_with("//")) {
            return Err(LinkParseError::UrlForm(kind.to_owned()));
        }
        match kind {
            "pty" => match rest {
                None => Ok(Link::Pty),
                Some(rest) => Err(LinkParseError::TrailingPty(rest.to_owned())),
            },
            "serial" => parse_serial(rest.unwrap_or("")),
            "tcp" => {
                let rest = rest.unwrap_or("");
                match parse_host_port(rest)? {
                    (_, 0) => Err(LinkParseError::PortZero(rest.to_owned())),
                    (host, port) => Ok(Link::Tcp { host, port }),
                }
            }
            "tcp-listen" => {
                let (addr, port) = parse_host_port(rest.unwrap_or(""))?;
                Ok(Link::TcpListen { addr, port })
            }
            "io" => match rest {
                Some(name) if !name.is_empty() => Ok(Link::Io {
                    name: name.to_owned(),
                }),
                _ => Err(LinkParseError::MissingIoName),
            },
            other => match rest {
                // `127.0.0.1:9750`, `localhost:9750`.
                Some(port) if is_host(other) && port.parse::<u16>().is_ok_and(|p| p > 0) => {
                    Err(LinkParseError::BareHostPort(s.to_owned()))
                }
                _ => Err(LinkParseError::UnknownKind(other.to_owned())),
            },
        }
    }
}

/// The message of [`LinkParseError::UnknownSerialOption`].
fn option_message(word: &str) -> String {
    let lower = word.to_ascii_lowercase();
    if matches!(
        lower.as_str(),
        "xonxoff" | "xon/xoff" | "xon-xoff" | "software"
    ) {
        format!(
            "software flow control ({word:?}) is not offered: XBee radios have hardware flow control alone (write :rtscts)"
        )
    } else if is_frame_format(word) {
        format!(
            "the frame format ({word:?}) is no option: XBee radios use 8N1, which the link always does (leave it out, as in serial:/dev/ttyUSB0:115200)"
        )
    } else {
        format!(
            "unknown option {word:?} after the serial port's path (expected :BAUD, :rtscts or both, as in serial:/dev/ttyUSB0:115200:rtscts)"
        )
    }
}

/// Whether the last `:` part of a serial link is a frame format (`8N1`, `7e1`): data
/// bits, parity and stop bits, as other programs take them.
fn is_frame_format(word: &str) -> bool {
    matches!(
        word.trim().as_bytes(),
        [
            b'5'..=b'8',
            b'N' | b'E' | b'O' | b'M' | b'S' | b'n' | b'e' | b'o' | b'm' | b's',
            b'1' | b'2'
        ]
    )
}

/// Whether the last `:` part of a serial link is meant as an option: a word of letters
/// (`rts`, `fast`, `rts/cts`). No device's name ends so; the colons in names such as
/// `/dev/serial/by-path/pci-0000:00:14.0-usb-0:1:1.0-port0` come before digits.
fn is_option_word(word: &str) -> bool {
    // Spaces around it are a typing slip (`:rtscts `), not part of a device's name.
    let word = word.trim();
    word.bytes().any(|b| b.is_ascii_alphabetic())
        && word
            .bytes()
            .all(|b| b.is_ascii_alphabetic() || b == b'/' || b == b'-' || b == b'_')
}

impl Link {
    /// A `serial:` link without flow control, as `serial:PATH:BAUD` parses to.
    pub fn serial(path: impl Into<String>, baud: u32) -> Link {
        Link::serial_with(path, baud, FlowControl::None)
    }

    /// A `serial:` link with the given flow control (`serial:PATH:BAUD:rtscts` for
    /// [`FlowControl::RtsCts`]).
    pub fn serial_with(path: impl Into<String>, baud: u32, flow_control: FlowControl) -> Link {
        Link::Serial {
            path: path.into(),
            baud,
            flow_control,
        }
    }

    /// A `tcp:` link to `host` (a name or an IP address, IPv6 without brackets) and
    /// `port`.
    pub fn tcp(host: impl Into<String>, port: u16) -> Link {
        Link::Tcp {
            host: host.into(),
            port,
        }
    }

    /// An `io:` link named `name`: a stream the program opens itself, which
    /// [`connect_with`](crate::connect_with) serves (not [`connect`](crate::connect)). The
    /// name says what the stream is in messages and logs; as a link string (`io:NAME`)
    /// it cannot be empty.
    pub fn io(name: impl Into<String>) -> Link {
        Link::Io { name: name.into() }
    }

    /// A `tcp-listen:` link on the local address `addr` (IPv6 without brackets) and
    /// `port` (0 for one the system chooses).
    pub fn tcp_listen(addr: impl Into<String>, port: u16) -> Link {
        Link::TcpListen {
            addr: addr.into(),
            port,
        }
    }
}

/// A `tcp:` link to the address, as a program that started a `tcp-listen:` link on port 0
/// (a [`crate::sim::Simulator`], a [`crate::hub::Hub`]) connects to it.
impl From<std::net::SocketAddr> for Link {
    fn from(addr: std::net::SocketAddr) -> Link {
        Link::tcp(addr.ip().to_string(), addr.port())
    }
}

fn parse_serial(rest: &str) -> Result<Link, LinkParseError> {
    // From the end: the flow control (`:rtscts`, `:none`) and the rate (`:DIGITS`), once
    // each and in either order; anything else belongs to the path.
    let (mut path, mut flow_control, mut baud) = (rest, None, None);
    while let Some((head, part)) = path.rsplit_once(':') {
        match part {
            "rtscts" if flow_control.is_none() => flow_control = Some(FlowControl::RtsCts),
            "none" if flow_control.is_none() => flow_control = Some(FlowControl::None),
            _ if baud.is_none() && part.bytes().all(|b| b.is_ascii_digit()) => {
                // An empty part (`serial:COM3:`) leaves the default rate.
                let value = match part {
                    "" => DEFAULT_BAUD,
                    digits => digits
                        .parse::<u32>()
                        .ok()
                        .filter(|b| *b > 0)
                        .ok_or_else(|| LinkParseError::InvalidBaud(digits.to_owned()))?,
                };
                baud = Some(value);
            }
            // A word no device's name ends in: an option mistyped, or given twice.
            _ if is_option_word(part) || is_frame_format(part) => {
                return Err(LinkParseError::UnknownSerialOption(part.to_owned()));
            }
            // A baud rate mistyped (`115k`, `9600 `) rather than part of the path: a
            // device's name holds no such ending (`/dev/serial/by-path/...-usb-0:1:1.0-port0`).
            _ if baud.is_none() && mistyped_baud(part) => {
                return Err(LinkParseError::InvalidBaud(part.to_owned()));
            }
            _ => break,
        }
        path = head;
    }
    if path.is_empty() {
        return Err(LinkParseError::MissingPath);
    }
    Ok(Link::Serial {
        path: path.to_owned(),
        baud: baud.unwrap_or(DEFAULT_BAUD),
        flow_control: flow_control.unwrap_or_default(),
    })
}

/// Whether the last `:` part of a serial link is a baud rate mistyped: digits with a
/// `k` after them (`115k`), or with spaces around them.
fn mistyped_baud(part: &str) -> bool {
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    let trimmed = part.trim();
    digits(trimmed) || trimmed.strip_suffix(['k', 'K']).is_some_and(digits)
}

fn parse_host_port(rest: &str) -> Result<(String, u16), LinkParseError> {
    let missing_port = || LinkParseError::MissingPort(rest.to_owned());
    // An IPv6 host is in brackets, `[::1]:9750`: its colons are not the port's.
    let (host, port) = match rest.strip_prefix('[') {
        Some(bracketed) => {
            let (host, after) = bracketed.split_once(']').ok_or_else(missing_port)?;
            (host, after.strip_prefix(':').ok_or_else(missing_port)?)
        }
        None => rest.rsplit_once(':').ok_or_else(missing_port)?,
    };
    if host.is_empty() {
        return Err(LinkParseError::MissingHost(rest.to_owned()));
    }
    // None could be read back from the link's text: `[` and `]` would end brackets, and a
    // host of `//` would show as the URL form (`tcp://:1`).
    let unfit = |c: char| c.is_whitespace() || c.is_control() || matches!(c, '/' | '[' | ']');
    if host.contains(unfit) {
        return Err(LinkParseError::InvalidHost(host.to_owned()));
    }
    if !rest.starts_with('[') && host.contains(':') {
        return Err(LinkParseError::UnbracketedHost(host.to_owned()));
    }
    if port.is_empty() {
        return Err(LinkParseError::MissingPort(rest.to_owned()));
    }
    let port = port
        .parse::<u16>()
        .map_err(|_| LinkParseError::InvalidPort(port.to_owned()))?;
    Ok((host.to_owned(), port))
}

/// `HOST:PORT`, with brackets around an IPv6 host.
pub(crate) fn host_port(host: &str, port: u16) -> String {
    HostPort(host, port).to_string()
}

struct HostPort<'a>(&'a str, u16);

impl fmt::Display for HostPort<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.0.contains(':') {
            write!(f, "[{}]:{}", self.0, self.1)
        } else {
            write!(f, "{}:{}", self.0, self.1)
        }
    }
}

impl fmt::Display for Link {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Link::Serial {
                path,
                baud,
                flow_control,
            } => {
                write!(f, "serial:{path}:{baud}")?;
                match flow_control {
                    FlowControl::None => Ok(()),
                    FlowControl::RtsCts => f.write_str(":rtscts"),
                }
            }
            Link::Tcp { host, port } => write!(f, "tcp:{}", HostPort(host, *port)),
            Link::TcpListen { addr, port } => write!(f, "tcp-listen:{}", HostPort(addr, *port)),
            Link::Pty => f.write_str("pty"),
            Link::Io { name } => write!(f, "io:{name}"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_each_kind() {
        assert_eq!(
            "serial:/dev/ttyUSB0".parse(),
            Ok(Link::serial("/dev/ttyUSB0", 115_200))
        );
        assert_eq!(
            "serial:/dev/ttyS1:9600".parse(),
            Ok(Link::serial("/dev/ttyS1", 9600))
        );
        assert_eq!("serial:COM3".parse(), Ok(Link::serial("COM3", 115_200)));
        assert_eq!(
            "tcp:localhost:9750".parse(),
            Ok(Link::Tcp {
                host: "localhost".into(),
                port: 9750
            })
        );
        assert_eq!(
            "tcp-listen:0.0.0.0:0".parse(),
            Ok(Link::TcpListen {
                addr: "0.0.0.0".into(),
                port: 0
            })
        );
        assert_eq!(
            "tcp-listen:[::]:80".parse(),
            Ok(Link::TcpListen {
                addr: "::".into(),
                port: 80
            })
        );
        assert_eq!("pty".parse(), Ok(Link::Pty));
    }

    #[test]
    fn rejects_bad_strings() {
        use LinkParseError::*;
        let cases: &[(&str, LinkParseError)] = &[
            ("", Empty),
            ("udp:1.2.3.4:5", UnknownKind("udp".into())),
            ("ttyUSB0", UnknownKind("ttyUSB0".into())),
            ("/dev/ttyUSB0", UnknownKind("/dev/ttyUSB0".into())),
            ("serial", MissingPath),
            ("serial:", MissingPath),
            ("serial::9600", MissingPath),
            ("serial:/dev/ttyS0:0", InvalidBaud("0".into())),
            ("serial:/dev/ttyUSB0:115k", InvalidBaud("115k".into())),
            ("serial:/dev/ttyUSB0:9600 ", InvalidBaud("9600 ".into())),
            ("serial:COM3: 57600", InvalidBaud(" 57600".into())),
            (
                "serial:/dev/ttyS0:99999999999",
                InvalidBaud("99999999999".into()),
            ),
            ("tcp", MissingPort("".into())),
            ("tcp:localhost", MissingPort("localhost".into())),
            ("tcp:localhost:", MissingPort("localhost:".into())),
            ("tcp::80", MissingHost(":80".into())),
            ("tcp:[]:80", MissingHost("[]:80".into())),
            ("tcp:[::1]", MissingPort("[::1]".into())),
            ("tcp:[::1]:", MissingPort("[::1]:".into())),
            ("tcp:[::1:9750", MissingPort("[::1:9750".into())),
            ("tcp-listen:[::]", MissingPort("[::]".into())),
            ("tcp:host:65536", InvalidPort("65536".into())),
            ("tcp:host:1:2", UnbracketedHost("host:1".into())),
            ("tcp:::1:9750", UnbracketedHost("::1".into())),
            ("tcp-listen:::9750", UnbracketedHost(":".into())),
            ("tcp:127.0.0.1:0", PortZero("127.0.0.1:0".into())),
            ("tcp:[::1]:00", PortZero("[::1]:00".into())),
            ("tcp-listen:host:http", InvalidPort("http".into())),
            ("pty:/dev/pts/3", TrailingPty("/dev/pts/3".into())),
            ("tcp://127.0.0.1:9750", UrlForm("tcp".into())),
            ("tcp-listen://0.0.0.0:9750", UrlForm("tcp-listen".into())),
            ("127.0.0.1:9750", BareHostPort("127.0.0.1:9750".into())),
            ("localhost:9750", BareHostPort("localhost:9750".into())),
            ("127.0.0.1:http", UnknownKind("127.0.0.1".into())),
            ("tcp: 127.0.0.1:9750", InvalidHost(" 127.0.0.1".into())),
            ("tcp:[[]:1", InvalidHost("[".into())),
            ("tcp:[//]:1", InvalidHost("//".into())),
            ("tcp:a]b:1", InvalidHost("a]b".into())),
            ("tcp:host\u{0}:1", InvalidHost("host\u{0}".into())),
            ("tcp-listen:0.0.0.0 :9750", InvalidHost("0.0.0.0 ".into())),
            ("TCP:127.0.0.1:9750", UnknownKind("TCP".into())),
            ("io", MissingIoName),
            ("io:", MissingIoName),
        ];
        for (text, expected) in cases {
            assert_eq!(text.parse::<Link>().as_ref(), Err(expected), "{text:?}");
            // Every error has a message that names the problem.
            assert!(!expected.to_string().is_empty());
        }
    }

    #[test]
    fn a_bare_device_path_is_pointed_to_serial() {
        for (text, hint) in [
            ("/dev/ttyUSB0", "serial:/dev/ttyUSB0"),
            ("COM3", "serial:COM3"),
            ("com3", "serial:com3"),
            (r"\\.\COM10", r"serial:\\.\COM10"),
        ] {
            let message = text.parse::<Link>().unwrap_err().to_string();
            assert!(message.contains(&format!("write {hint}")), "{message}");
        }
        let message = "udp:1.2.3.4:5".parse::<Link>().unwrap_err().to_string();
        assert!(!message.contains("write serial:"), "{message}");
        assert!(!message.contains("write tcp:"), "{message}");
        for (text, hint) in [
            ("127.0.0.1:9750", "write tcp:127.0.0.1:9750"),
            ("localhost:9750", "write tcp:localhost:9750"),
            ("127.0.0.1:http", "write tcp:127.0.0.1:PORT"),
            ("tcp://127.0.0.1:9750", "write tcp:HOST:PORT, without //"),
            ("TCP:127.0.0.1:9750", "kinds are lower case: tcp"),
            ("Serial:/dev/ttyUSB0", "kinds are lower case: serial"),
        ] {
            let message = text.parse::<Link>().unwrap_err().to_string();
            assert!(message.contains(hint), "{message}");
        }
    }

    #[test]
    fn a_device_name_with_colons_is_a_path_and_a_mistyped_baud_is_not() {
        let by_path = "/dev/serial/by-path/pci-0000:00:14.0-usb-0:1:1.0-port0";
        assert_eq!(
            format!("serial:{by_path}").parse::<Link>(),
            Ok(Link::serial(by_path, DEFAULT_BAUD))
        );
        let message = "serial:/dev/ttyUSB0:115k"
            .parse::<Link>()
            .unwrap_err()
            .to_string();
        assert_eq!(
            message,
            "invalid baud rate \"115k\" (expected a positive integer)"
        );
    }

    #[test]
    fn flow_control_is_the_last_part_of_a_serial_link() {
        let rts_cts = |path: &str, baud| Link::Serial {
            path: path.to_owned(),
            baud,
            flow_control: FlowControl::RtsCts,
        };
        assert_eq!(
            "serial:/dev/ttyUSB0:230400:rtscts".parse(),
            Ok(rts_cts("/dev/ttyUSB0", 230_400))
        );
        assert_eq!(
            "serial:COM3:rtscts".parse(),
            Ok(rts_cts("COM3", DEFAULT_BAUD))
        );
        assert_eq!(
            "serial:/dev/ttyUSB0:9600:none".parse(),
            Ok(Link::serial("/dev/ttyUSB0", 9600))
        );
        // Before the rate, as well.
        assert_eq!(
            "serial:/dev/ttyUSB0:rtscts:115200".parse(),
            Ok(rts_cts("/dev/ttyUSB0", 115_200))
        );
        assert_eq!(
            "serial:/dev/ttyUSB0:rtscts:".parse(),
            Ok(rts_cts("/dev/ttyUSB0", DEFAULT_BAUD))
        );
        let by_path = "/dev/serial/by-path/pci-0000:00:14.0-usb-0:1:1.0-port0";
        assert_eq!(
            format!("serial:{by_path}:rtscts").parse(),
            Ok(rts_cts(by_path, DEFAULT_BAUD))
        );
        assert_eq!(
            rts_cts("/dev/ttyUSB0", 57_600).to_string(),
            "serial:/dev/ttyUSB0:57600:rtscts"
        );
        for (text, word) in [
            ("serial:/dev/ttyUSB0:115200:RTSCTS", "RTSCTS"),
            ("serial:/dev/ttyUSB0:115200:rts/cts", "rts/cts"),
            ("serial:/dev/ttyUSB0:hardware", "hardware"),
            ("serial:/dev/ttyUSB0:115200:xonxoff", "xonxoff"),
            ("serial:/dev/ttyUSB0:115200:rts", "rts"),
            ("serial:/dev/ttyUSB0:fast", "fast"),
            ("serial:COM3:rts_cts", "rts_cts"),
            ("serial:/dev/ttyUSB0:rts:115200", "rts"),
            ("serial:/dev/ttyUSB0:115200:rtscts ", "rtscts "),
            ("serial:/dev/ttyUSB0:rtscts:rtscts", "rtscts"),
            ("serial:/dev/ttyUSB0:rtscts:none:9600", "rtscts"),
            ("serial:/dev/ttyUSB0:rtscts:9600:none", "rtscts"),
            ("serial:/dev/ttyUSB0:115200:8N1", "8N1"),
            ("serial:COM3:8n1", "8n1"),
            ("serial:/dev/ttyUSB0:9600:7E2", "7E2"),
        ] {
            assert_eq!(
                text.parse::<Link>(),
                Err(LinkParseError::UnknownSerialOption(word.into())),
                "{text}"
            );
        }
        let message = "serial:/dev/ttyUSB0:115200:rts/cts"
            .parse::<Link>()
            .unwrap_err()
            .to_string();
        assert_eq!(
            message,
            "unknown option \"rts/cts\" after the serial port's path (expected :BAUD, :rtscts or both, as in serial:/dev/ttyUSB0:115200:rtscts)"
        );
        let message = "serial:/dev/ttyUSB0:115200:xonxoff"
            .parse::<Link>()
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("XBee radios have hardware flow control alone"),
            "{message}"
        );
        let message = "serial:/dev/ttyUSB0:115200:8N1"
            .parse::<Link>()
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("the frame format (\"8N1\") is no option: XBee radios use 8N1"),
            "{message}"
        );
        // A device whose name ends so is still taken whole, after a rate.
        assert!("serial:/dev/ttyS8N1".parse::<Link>().is_ok());
    }

    #[test]
    fn display_round_trips() {
        for text in [
            "serial:/dev/ttyUSB0:115200",
            "serial:/dev/serial/by-id/usb-FTDI_FT232R-if00:57600",
            "serial:/dev/ttyUSB0:115200:rtscts",
            "tcp:127.0.0.1:9750",
            "tcp:[fe80::1]:1",
            "tcp-listen:0.0.0.0:65535",
            "pty",
        ] {
            let link: Link = text.parse().unwrap();
            assert_eq!(link.to_string(), text);
        }
    }
}
