//! `mcp-gs`: the MCP ground station.

/// Prints a line to standard output; exits quietly (status 0) when standard output is
/// closed, as when piped into `head`, instead of panicking like `println!`, and with an
/// error (status 1) when it cannot be written (a full disk).
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::write_line(format_args!($($arg)*))
    };
}

/// `eprintln!` that cannot panic: a standard error that cannot be written (closed by
/// the reader of a pipe, a full disk) loses the line, never the exit status.
macro_rules! err {
    ($($arg:tt)*) => {
        $crate::write_err(format_args!($($arg)*))
    };
}

mod at;
mod command;
mod decode;
mod demo;
mod encode;
mod hex_input;
mod hints;
mod hub;
mod interrupt;
mod link_args;
mod log;
mod monitor;
mod nodes;
mod output;
mod ports;
mod probe;
mod radio;
mod radio_query;
mod recording;
mod replay;
mod send;
mod setup;
mod sim;
mod status;
mod stderr;

use std::process::ExitCode;

use std::ffi::OsString;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use xbee_api::ApiMode;

/// MCP ground station: talk to MAVs through an XBee radio, or to a simulated one.
#[derive(Debug, Parser)]
#[command(name = "mcp-gs", version, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Sub,
}

#[derive(Debug, Subcommand)]
enum Sub {
    /// Print live packets from a link, optionally recording them.
    Monitor(monitor::MonitorArgs),
    /// Send one command to a MAV and print the radio's delivery status.
    Send(send::SendArgs),
    /// Ask a MAV for a status report and print it.
    Status(status::StatusArgs),
    /// Decode a captured byte stream or a recording and print every frame.
    Decode(decode::DecodeArgs),
    /// Print the Transmit Request frame of a command as hex.
    Encode(encode::EncodeArgs),
    /// Play a recording back onto a link.
    Replay(replay::ReplayArgs),
    /// Read or set an AT parameter of the local radio, or of a remote one.
    At(at::AtArgs),
    /// List the radios the local one can reach (node discovery, ND).
    Nodes(nodes::NodesArgs),
    /// List the serial ports present.
    Ports(ports::PortsArgs),
    /// Find the baud rate and mode of a radio on a serial port, trying each rate in API
    /// frames and with +++.
    Probe(probe::ProbeArgs),
    /// Put the local radio into API mode through its AT command mode (+++), as a radio
    /// in transparent mode (AP=0, as it leaves the factory) needs.
    Setup(setup::SetupArgs),
    /// Run a virtual XBee network between links (radios emulated in software).
    Radio(radio::RadioArgs),
    /// Run simulated MAVs behind a virtual XBee network on a link.
    Sim(sim::SimArgs),
    /// Share one radio with other commands through a TCP port (monitor and send at once).
    Hub(hub::HubArgs),
    /// A ground station and a simulated MAV in one process: no hardware needed.
    Demo(demo::DemoArgs),
}

/// The command line parsed, or the process ended with clap's message. A negative number
/// is taken as an option's value (`--duration -1`), for the option's own message on what
/// it takes, not as an unknown option.
fn parse(args: Vec<OsString>) -> Cli {
    let command = Cli::command().mut_subcommands(negative_numbers);
    let matches = command
        .try_get_matches_from(args)
        .unwrap_or_else(|e| exit_on(e));
    Cli::from_arg_matches(&matches).unwrap_or_else(|e| exit_on(e))
}

/// Ends the program on what the argument parser says: an error (exit 2), or the help or
/// version asked for, on standard output, which must take it (as any output: see
/// [`output_failure`]).
fn exit_on(e: clap::Error) -> ! {
    if e.use_stderr() {
        e.exit()
    }
    let code = match e
        .print()
        .and_then(|()| std::io::Write::flush(&mut std::io::stdout()))
    {
        Ok(()) => 0,
        Err(error) => match output_failure(&error) {
            None => 0,
            Some(failure) => {
                err!("mcp-gs: {}", failure.message);
                failure.code.into()
            }
        },
    };
    std::process::exit(code)
}

/// `sub` and its own subcommands (`send`'s COMMAND words) taking negative numbers.
fn negative_numbers(sub: clap::Command) -> clap::Command {
    sub.allow_negative_numbers(true)
        .mut_subcommands(negative_numbers)
}

/// The subcommands with a COMMAND word of their own (`send`, `encode`) take their options
/// after it too, as operators type them (`send --link L landing on --to ADDR`): such
/// options are moved before the word. Anything after `--` stays where it is.
fn hoist_options(args: Vec<OsString>) -> Vec<OsString> {
    let cli = Cli::command();
    let sub = args
        .get(1)
        .and_then(|name| name.to_str())
        .and_then(|name| cli.find_subcommand(name));
    let Some(sub) = sub.filter(|sub| sub.has_subcommands()) else {
        return args;
    };
    // The subcommand's own long options, and whether each takes a value.
    let takes_value = |token: &OsString| -> Option<bool> {
        let long = token.to_str()?.strip_prefix("--")?;
        let (name, inline) = match long.split_once('=') {
            Some((name, _)) => (name, true),
            None => (long, false),
        };
        let arg = sub.get_arguments().find(|a| a.get_long() == Some(name))?;
        Some(arg.get_action().takes_values() && !inline)
    };
    // The COMMAND word: the first token that is neither an option nor its value.
    let mut word = 2;
    while let Some(token) = args.get(word) {
        if token == "--" {
            return args;
        }
        match takes_value(token) {
            Some(true) => word += 2,
            Some(false) => word += 1,
            None if token.to_str().is_some_and(|t| t.starts_with('-')) => word += 1,
            None => break,
        }
    }
    let mut before: Vec<OsString> = args.iter().take(word).cloned().collect();
    let mut after = Vec::new();
    let mut rest = args.iter().skip(word);
    while let Some(token) = rest.next() {
        if token == "--" {
            after.push(token.clone());
            after.extend(rest.cloned());
            break;
        }
        match takes_value(token) {
            Some(value) => {
                before.push(token.clone());
                if value {
                    before.extend(rest.next().cloned());
                }
            }
            None => after.push(token.clone()),
        }
    }
    before.extend(after);
    before
}

/// Writes one line to standard output, exiting quietly if it is closed and with an
/// error if it cannot be written.
pub(crate) fn write_line(line: std::fmt::Arguments<'_>) {
    use std::io::Write;
    let mut stdout = std::io::stdout().lock();
    if let Err(e) = writeln!(stdout, "{line}").and_then(|()| stdout.flush()) {
        match output_failure(&e) {
            None => {
                stderr::finish();
                std::process::exit(0)
            }
            Some(failure) => {
                err!("mcp-gs: {}", failure.message);
                stderr::finish();
                std::process::exit(failure.code.into());
            }
        }
    }
}

/// Writes one line to standard error, by its own thread once the logger is installed
/// ([`stderr`]), losing it if standard error cannot be written: the command's exit
/// status says what happened.
pub(crate) fn write_err(line: std::fmt::Arguments<'_>) {
    stderr::write(format!("{line}\n").into_bytes());
}

/// What an error writing standard output ends the program with: `None` when standard
/// output was closed by its reader (piped into `head`), which ends it quietly and
/// successfully; a failure otherwise (a full disk), which a script must not take for
/// success.
pub(crate) fn output_failure(error: &std::io::Error) -> Option<Failure> {
    (error.kind() != std::io::ErrorKind::BrokenPipe).then(|| {
        Failure::new(
            Failure::OTHER,
            format!("cannot write to standard output: {error}"),
        )
    })
}

/// Output format of the subcommands that print what the radio said.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(crate) enum Format {
    /// Readable lines, as the option says what each is.
    Text,
    /// JSON Lines: one object a line, as the option says what each is (schema in the
    /// README).
    Json,
}

/// An XBee API mode on the command line: 1 or 2.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ApiModeArg(pub ApiMode);

impl std::str::FromStr for ApiModeArg {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        s.parse::<u8>()
            .ok()
            .and_then(|n| ApiMode::try_from(n).ok())
            .map(Self)
            .ok_or_else(|| format!("API mode must be 1 or 2, got `{s}`"))
    }
}

/// Why a subcommand failed: a one-line message and an exit code.
#[derive(Debug)]
pub(crate) struct Failure {
    message: String,
    code: u8,
}

impl Failure {
    /// Exit code of other failures.
    pub(crate) const OTHER: u8 = 1;
    /// Exit code of bad arguments or input (as clap's usage errors).
    pub(crate) const INPUT: u8 = 2;
    /// Exit code of a link that cannot be opened or that went away.
    pub(crate) const LINK: u8 = 3;
    /// Exit code of a timeout: no transmit status, response or report in time.
    pub(crate) const TIMEOUT: u8 = 4;
    /// Exit code of a delivery the radio reported as failed.
    pub(crate) const DELIVERY: u8 = 5;

    /// A failure with `code`.
    pub(crate) fn new(code: u8, message: impl Into<String>) -> Self {
        Self {
            message: message.into(),
            code,
        }
    }

    /// Bad input or arguments.
    pub(crate) fn input(message: impl Into<String>) -> Self {
        Self::new(Self::INPUT, message)
    }

    /// A link that cannot be opened or went away.
    pub(crate) fn link(message: impl Into<String>) -> Self {
        Self::new(Self::LINK, message)
    }

    /// The exit code.
    pub(crate) fn code(&self) -> u8 {
        self.code
    }

    /// Its message without the hints after it.
    pub(crate) fn reason(&self) -> &str {
        self.message.lines().next().unwrap_or_default()
    }

    /// The same failure with a hint line after its message.
    pub(crate) fn with_hint(mut self, hint: String) -> Self {
        self.message = format!("{}\nmcp-gs: {hint}", self.message);
        self
    }
}

/// `n` and `noun`, which takes an `s` unless `n` is 1: `1 frame`, `2 frames`.
pub(crate) fn counted(n: impl Into<u64>, noun: &str) -> String {
    match n.into() {
        1 => format!("1 {noun}"),
        n => format!("{n} {noun}s"),
    }
}

/// A value parser for a whole number from `min` to `max`, whose error says so (`expected
/// a whole number from 1 to 4096, got `0``) where clap's range says `0 is not in 1..=4096`,
/// Rust's syntax.
pub(crate) fn whole_number<T>(
    min: T,
    max: T,
) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static
where
    T: std::str::FromStr + PartialOrd + std::fmt::Display + Copy + Send + Sync + 'static,
{
    move |s: &str| {
        s.trim()
            .parse::<T>()
            .ok()
            .filter(|n| (min..=max).contains(n))
            .ok_or_else(|| format!("expected a whole number from {min} to {max}, got `{s}`"))
    }
}

#[tokio::main]
async fn main() -> ExitCode {
    let cli = parse(hoist_options(std::env::args_os().collect()));
    log::init(matches!(cli.command, Sub::Hub(_)));
    // What a bug report needs first.
    tracing::debug!(
        version = env!("CARGO_PKG_VERSION"),
        args = ?std::env::args_os().skip(1).collect::<Vec<_>>(),
        "mcp-gs starting"
    );
    let result = match cli.command {
        Sub::Monitor(args) => monitor::run(args).await,
        Sub::Send(args) => send::run(args).await,
        Sub::Status(args) => status::run(args).await,
        Sub::Replay(args) => replay::run(args).await,
        Sub::At(args) => at::run(args).await,
        Sub::Nodes(args) => nodes::run(args).await,
        Sub::Ports(args) => ports::run(args),
        Sub::Probe(args) => probe::run(args).await,
        Sub::Setup(args) => setup::run(args).await,
        Sub::Decode(args) => decode::run(args),
        Sub::Encode(args) => encode::run(args),
        Sub::Radio(args) => radio::run(args).await,
        Sub::Sim(args) => sim::run(args).await,
        Sub::Hub(args) => hub::run(args).await,
        Sub::Demo(args) => demo::run(args).await,
    };
    let code = match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(failure) => {
            err!("mcp-gs: {}", failure.message);
            ExitCode::from(failure.code)
        }
    };
    stderr::finish();
    code
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_subcommand_says_what_its_timeout_waits_for() {
        let cli = Cli::command();
        let helps: Vec<(String, String)> = cli
            .get_subcommands()
            .filter_map(|sub| {
                let timeout = sub.get_arguments().find(|a| a.get_id() == "timeout")?;
                let help = timeout.get_help().map(ToString::to_string)?;
                Some((sub.get_name().to_owned(), help))
            })
            .collect();
        assert!(helps.len() >= 7, "{helps:?}");
        for (i, (name, help)) in helps.iter().enumerate() {
            for (other, its) in &helps[i + 1..] {
                assert_ne!(help, its, "{name} and {other}");
            }
            // Not another subcommand's case.
            if name != "monitor" {
                assert!(!help.contains("monitor"), "{name}: {help}");
            }
            if name != "at" {
                assert!(!help.contains("local parameter"), "{name}: {help}");
            }
        }
    }

    #[test]
    fn a_number_out_of_range_is_said_in_words() {
        let parse = whole_number(1u16, 4096);
        assert_eq!(parse("4096"), Ok(4096));
        assert_eq!(
            parse("0"),
            Err("expected a whole number from 1 to 4096, got `0`".to_owned())
        );
        assert!(parse("-1").is_err() && parse("x").is_err());
    }
}
