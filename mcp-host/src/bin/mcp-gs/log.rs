//! What the library logs, on standard error: by default its warnings, each a line
//! `mcp-gs: warning: MESSAGE: ERROR (key value, ...)` like the command's own warnings
//! (and, for `hub`, the hub's status lines: the radio there, the radio back); with
//! `MCP_LOG` set (`MCP_LOG=debug`, `MCP_LOG=mcp_host::hub=info`), every event it
//! selects, with the time, the level and where it comes from, for a bug report.

use std::fmt;

use tracing::field::{Field, Visit};
use tracing::{Event, Level, Subscriber};
use tracing_subscriber::fmt::format::Writer;
use tracing_subscriber::fmt::{FmtContext, FormatEvent, FormatFields};
use tracing_subscriber::registry::LookupSpan;

/// Installs the logger; for `hub`, each library line carries the time of day (UTC), for
/// a command that runs for hours, whose outages are read back later, and the hub's
/// status lines are shown beside the warnings.
pub(crate) fn init(hub: bool) {
    // Colours for a terminal only, not for a pipe or a log file; not on Windows, whose
    // console shows the escape codes as they are unless a program turns them on.
    let ansi = std::io::IsTerminal::is_terminal(&std::io::stderr()) && !cfg!(windows);
    // Standard error by its own thread, so that a reader that takes nothing does not
    // hold the command up.
    crate::stderr::start();
    let builder = tracing_subscriber::fmt()
        .with_writer(crate::stderr::log_line)
        .with_ansi(ansi);
    match tracing_subscriber::EnvFilter::try_from_env("MCP_LOG") {
        Ok(filter) => builder.with_env_filter(filter).init(),
        Err(error) => {
            // Set, but not a filter: said, rather than logging as if it were not set.
            if let Some(value) = std::env::var_os("MCP_LOG") {
                err!(
                    "mcp-gs: warning: MCP_LOG={} is no log filter ({error}): logging \
                     warnings only; give levels as `debug` or `mcp_host=debug,warn`",
                    value.to_string_lossy()
                );
            }
            builder
                // The library's warnings about the radio's settings are said here as
                // hints with the options to give.
                .with_env_filter(tracing_subscriber::EnvFilter::new(if hub {
                    format!(
                        "warn,{}=info,mcp_host::diagnosis=off",
                        mcp_host::hub::STATUS_TARGET
                    )
                } else {
                    "warn,mcp_host::diagnosis=off".to_owned()
                }))
                .event_format(Plain { timed: hub })
                .init()
        }
    }
}

/// An event as one of the command's own lines: `mcp-gs: `, the time of day if `timed`,
/// `error: ` for an error or `warning: ` for a warning, then the message, its `error` field after a colon, and any
/// other fields in parentheses.
struct Plain {
    timed: bool,
}

/// The fields of an event, as [`Plain`] writes them.
#[derive(Default)]
struct Line {
    message: String,
    error: Option<String>,
    others: Vec<String>,
}

impl Visit for Line {
    fn record_str(&mut self, field: &Field, value: &str) {
        self.record(field, value.to_owned());
    }

    fn record_debug(&mut self, field: &Field, value: &dyn fmt::Debug) {
        self.record(field, format!("{value:?}"));
    }
}

impl Line {
    fn record(&mut self, field: &Field, value: String) {
        match field.name() {
            "message" => self.message = value,
            "error" => self.error = Some(value),
            name => self
                .others
                .push(format!("{} {value}", name.replace('_', " "))),
        }
    }
}

impl fmt::Display for Line {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)?;
        if let Some(error) = &self.error {
            write!(f, ": {error}")?;
        }
        if !self.others.is_empty() {
            write!(f, " ({})", self.others.join(", "))?;
        }
        Ok(())
    }
}

impl<S, N> FormatEvent<S, N> for Plain
where
    S: Subscriber + for<'a> LookupSpan<'a>,
    N: for<'a> FormatFields<'a> + 'static,
{
    fn format_event(
        &self,
        _ctx: &FmtContext<'_, S, N>,
        mut writer: Writer<'_>,
        event: &Event<'_>,
    ) -> fmt::Result {
        writer.write_str("mcp-gs: ")?;
        if self.timed {
            let now = mcp_host::render::text::time(std::time::SystemTime::now());
            write!(writer, "{now} ")?;
        }
        match *event.metadata().level() {
            Level::ERROR => writer.write_str("error: ")?,
            Level::WARN => writer.write_str("warning: ")?,
            _ => {}
        }
        let mut line = Line::default();
        event.record(&mut line);
        writeln!(writer, "{line}")
    }
}
