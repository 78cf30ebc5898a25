//! What the library logs, on standard error: by default its warnings, each a line
//! `mcp-gs: MESSAGE key=value...` like the command's own messages; with `MCP_LOG` set
//! (`MCP_LOG=debug`, `MCP_LOG=mcp_host::hub=info`), every event it selects, with the
//! time, the level and where it comes from, for a bug report.

use std::fmt;

use tracing::{Event, Level, Subscriber};
use tracing_subscriber::fmt::format::Writer;
use tracing_subscriber::fmt::{FmtContext, FormatEvent, FormatFields};
use tracing_subscriber::registry::LookupSpan;

/// Installs the logger.
pub(crate) fn init() {
    // Colours for a terminal only, not for a pipe or a log file.
    let ansi = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let builder = tracing_subscriber::fmt()
        .with_writer(std::io::stderr)
        .with_ansi(ansi);
    match tracing_subscriber::EnvFilter::try_from_env("MCP_LOG") {
        Ok(filter) => builder.with_env_filter(filter).init(),
        Err(_) => builder
            .with_env_filter(tracing_subscriber::EnvFilter::new("warn"))
            .event_format(Plain)
            .init(),
    }
}

/// An event as one of the command's own lines: `mcp-gs: `, `error: ` for an error, then
/// the message and its fields.
struct Plain;

impl<S, N> FormatEvent<S, N> for Plain
where
    S: Subscriber + for<'a> LookupSpan<'a>,
    N: for<'a> FormatFields<'a> + 'static,
{
    fn format_event(
        &self,
        ctx: &FmtContext<'_, S, N>,
        mut writer: Writer<'_>,
        event: &Event<'_>,
    ) -> fmt::Result {
        writer.write_str("mcp-gs: ")?;
        if *event.metadata().level() == Level::ERROR {
            writer.write_str("error: ")?;
        }
        ctx.field_format().format_fields(writer.by_ref(), event)?;
        writeln!(writer)
    }
}
