//! Ctrl-C, and the signals a service manager or a closed terminal sends, for the commands
//! that stop on them (`monitor`, `hub`, `radio`, `sim`, `demo`).

use std::future::Future;

use futures::FutureExt;

/// Completes at Ctrl-C (SIGINT) and, on Unix, at SIGTERM (`kill`, `timeout`, systemd
/// stopping a service) or SIGHUP (the terminal closed), on Windows at Ctrl-Break or the
/// console closed (and the system shutting down, which Windows says to services alone),
/// which from this call on no longer end the process: the command stops as cleanly as
/// at Ctrl-C (Windows allows a few seconds for it after the console is closed).
///
/// Tokio's `ctrl_c` only starts listening when it is first polled, so a command that
/// printed "Ctrl-C stops" before polling it could still be killed by a Ctrl-C pressed
/// right then: this one listens at once. A signal whose handler cannot be installed
/// keeps its default action (it ends the process).
///
/// It gives which one came, for a command that says why it stopped.
pub(crate) fn ctrl_c() -> impl Future<Output = Interrupt> + Send + 'static {
    let mut pressed = Box::pin(tokio::signal::ctrl_c());
    let first = (&mut pressed).now_or_never();
    let others = other_signals();
    async move {
        let ctrl_c = async {
            let result = match first {
                Some(result) => result,
                None => pressed.await,
            };
            if result.is_err() {
                std::future::pending::<()>().await;
            }
        };
        tokio::select! {
            () = ctrl_c => Interrupt::CtrlC,
            signal = others => signal,
        }
    }
}

/// What stopped a command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
// Each system has signals of its own.
#[allow(dead_code)]
pub(crate) enum Interrupt {
    /// Ctrl-C (SIGINT).
    CtrlC,
    /// SIGTERM.
    Terminate,
    /// SIGHUP.
    HangUp,
    /// Windows: Ctrl-Break.
    CtrlBreak,
    /// Windows: the console window closed.
    ConsoleClosed,
    /// Windows: the system shutting down.
    Shutdown,
}

/// `Ctrl-C`, `SIGTERM`, `SIGHUP`, `Ctrl-Break`, ...
impl std::fmt::Display for Interrupt {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Self::CtrlC => "Ctrl-C",
            Self::Terminate => "SIGTERM",
            Self::HangUp => "SIGHUP",
            Self::CtrlBreak => "Ctrl-Break",
            Self::ConsoleClosed => "closing the console",
            Self::Shutdown => "the system shutting down",
        })
    }
}

/// What `signal` gives, once it comes; never, for a signal whose handler could not be
/// installed (`None`).
#[cfg(any(unix, windows))]
async fn or_never<F: Future>(signal: Option<F>) -> F::Output {
    match signal {
        Some(signal) => signal.await,
        None => std::future::pending().await,
    }
}

/// SIGTERM or SIGHUP, listened to from this call on.
#[cfg(unix)]
fn other_signals() -> impl Future<Output = Interrupt> + Send + 'static {
    use tokio::signal::unix::{SignalKind, signal};
    let next = |kind| signal(kind).ok().map(|mut s| async move { s.recv().await });
    let term = next(SignalKind::terminate());
    let hangup = next(SignalKind::hangup());
    async move {
        tokio::select! {
            _ = or_never(term) => Interrupt::Terminate,
            _ = or_never(hangup) => Interrupt::HangUp,
        }
    }
}

/// Ctrl-Break, the console closed, or the system shutting down, listened to from this
/// call on.
#[cfg(windows)]
fn other_signals() -> impl Future<Output = Interrupt> + Send + 'static {
    use tokio::signal::windows::{ctrl_break, ctrl_close, ctrl_shutdown};
    let brk = ctrl_break().ok().map(|mut s| async move { s.recv().await });
    let close = ctrl_close().ok().map(|mut s| async move { s.recv().await });
    let shutdown = ctrl_shutdown()
        .ok()
        .map(|mut s| async move { s.recv().await });
    async move {
        tokio::select! {
            _ = or_never(brk) => Interrupt::CtrlBreak,
            _ = or_never(close) => Interrupt::ConsoleClosed,
            _ = or_never(shutdown) => Interrupt::Shutdown,
        }
    }
}

/// No other signal to listen to.
#[cfg(not(any(unix, windows)))]
fn other_signals() -> impl Future<Output = Interrupt> + Send + 'static {
    std::future::pending()
}
