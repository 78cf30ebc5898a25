//! Ctrl-C, for the commands that stop on it (`monitor`, `hub`, `radio`, `sim`, `demo`).

use std::future::Future;

use futures::FutureExt;

/// Completes at Ctrl-C, which from this call on no longer ends the process.
///
/// Tokio's `ctrl_c` only starts listening when it is first polled, so a command that
/// printed "Ctrl-C stops" before polling it could still be killed by a Ctrl-C pressed
/// right then: this one listens at once. If no handler can be installed, it never
/// completes, and Ctrl-C ends the process as it does by default.
pub(crate) fn ctrl_c() -> impl Future<Output = ()> + Send + 'static {
    let mut pressed = Box::pin(tokio::signal::ctrl_c());
    let first = (&mut pressed).now_or_never();
    async move {
        let result = match first {
            Some(result) => result,
            None => pressed.await,
        };
        if result.is_err() {
            std::future::pending::<()>().await;
        }
    }
}
