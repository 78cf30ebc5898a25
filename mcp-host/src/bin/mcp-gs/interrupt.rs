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

/// SIGTERM or SIGHUP, listened to from this call on.
#[cfg(unix)]
fn other_signals() -> impl Future<Output = Interrupt> + Send + 'static {
    use tokio::signal::unix::{SignalKind, signal};
    let term = signal(SignalKind::terminate()).ok();
    let hangup = signal(SignalKind::hangup()).ok();
    async move {
        let wait = |s: Option<tokio::signal::unix::Signal>| async move {
            match s {
                Some(mut s) => {
                    s.recv().await;
                }
                None => std::future::pending::<()>().await,
            }
        };
        tokio::select! {
            () = wait(term) => Interrupt::Terminate,
            () = wait(hangup) => Interrupt::HangUp,
        }
    }
}

/// Ctrl-Break, the console closed, or the system shutting down, listened to from this
/// call on.
#[cfg(windows)]
fn other_signals() -> impl Future<Output = Interrupt> + Send + 'static {
    use tokio::signal::windows::{ctrl_break, ctrl_close, ctrl_shutdown};
    let mut brk = ctrl_break().ok();
    let mut close = ctrl_close().ok();
    let mut shutdown = ctrl_shutdown().ok();
    async move {
        // A handler that could not be installed: never.
        let brk = async {
            match &mut brk {
                Some(s) => s.recv().await,
                None => std::future::pending().await,
            }
        };
        let close = async {
            match &mut close {
                Some(s) => s.recv().await,
                None => std::future::pending().await,
            }
        };
        let shutdown = async {
            match &mut shutdown {
                Some(s) => s.recv().await,
                None => std::future::pending().await,
            }
        };
        tokio::select! {
            _ = brk => Interrupt::CtrlBreak,
            _ = close => Interrupt::ConsoleClosed,
            _ = shutdown => Interrupt::Shutdown,
        }
    }
}

/// No other signal to listen to.
#[cfg(not(any(unix, windows)))]
fn other_signals() -> impl Future<Output = Interrupt> + Send + 'static {
    std::future::pending()
}
