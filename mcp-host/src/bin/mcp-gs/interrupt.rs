//! Ctrl-C, and the signals a service manager or a closed terminal sends, for the commands
//! that stop on them (`monitor`, `hub`, `radio`, `sim`, `demo`).

use std::future::Future;

use futures::FutureExt;

/// Completes at Ctrl-C (SIGINT) and, on Unix, at SIGTERM (`kill`, `timeout`, systemd
/// stopping a service) or SIGHUP (the terminal closed), which from this call on no longer
/// end the process: the command stops as cleanly as at Ctrl-C.
///
/// Tokio's `ctrl_c` only starts listening when it is first polled, so a command that
/// printed "Ctrl-C stops" before polling it could still be killed by a Ctrl-C pressed
/// right then: this one listens at once. A signal whose handler cannot be installed
/// keeps its default action (it ends the process).
pub(crate) fn ctrl_c() -> impl Future<Output = ()> + Send + 'static {
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
            () = ctrl_c => {}
            () = others => {}
        }
    }
}

/// SIGTERM or SIGHUP, listened to from this call on.
#[cfg(unix)]
fn other_signals() -> impl Future<Output = ()> + Send + 'static {
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
            () = wait(term) => {}
            () = wait(hangup) => {}
        }
    }
}

/// No other signal to listen to.
#[cfg(not(unix))]
fn other_signals() -> impl Future<Output = ()> + Send + 'static {
    std::future::pending::<()>()
}
