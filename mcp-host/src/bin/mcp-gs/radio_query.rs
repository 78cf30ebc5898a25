//! Asking the local radio: an AT parameter read in API frames (its `AP`), a link opened
//! once to ask it, and the check that it reads the API mode a command was told.

use std::time::Duration;

use futures::StreamExt;
use mcp_host::render::Seconds;
use mcp_host::{
    CommandSender, ConnectError, Connector, Link, LinkOptions, ReconnectPolicy, SendError,
};
use xbee_api::{ApiMode, Frame};

use crate::Failure;
use crate::hints::{connect_failure, silence_hint, warn_mode_mismatch};

/// The radio's `AP`, asked on a link opened with `options` (API mode 1, no reconnection)
/// for this alone: `AT AP` with frame id 1 reads the same in both modes (no byte of it
/// needs escaping), and so does its answer. `None` for an answer that is no `AP` value.
pub(crate) async fn ask_ap(
    link: &Link,
    options: LinkOptions,
) -> Result<Result<Option<u8>, SendError>, Failure> {
    let value = ask_parameter(link, options, *b"AP").await?;
    Ok(value.map(|value| value.and_then(|bytes| bytes.last().copied())))
}

/// A parameter of the local radio, asked on a link opened with `options` for this
/// alone: its value's bytes; `None` for an answer with an error status. The link is
/// closed and waited for, so that the port (opened for exclusive use) is free again
/// when this returns.
pub(crate) async fn ask_parameter(
    link: &Link,
    options: LinkOptions,
    command: [u8; 2],
) -> Result<Result<Option<Vec<u8>>, SendError>, Failure> {
    at_exchange(link, options, command, &[]).await
}

/// An AT parameter's value as a number, as the radio gives it: 0 for no byte, and of
/// more than 8 bytes the last 8.
pub(crate) fn at_number(bytes: &[u8]) -> u64 {
    xbee_api::at_number(&bytes[bytes.len().saturating_sub(8)..]).unwrap_or(0)
}

/// [`ask_parameter`], with `value` given: the parameter set (or the command carried
/// out), the answer's value (usually none) if the radio took it.
pub(crate) async fn at_exchange(
    link: &Link,
    options: LinkOptions,
    command: [u8; 2],
    value: &[u8],
) -> Result<Result<Option<Vec<u8>>, SendError>, Failure> {
    let timeout = options.send_timeout;
    let (mut stream, sender) = mcp_host::connect(link, options)
        .await
        .map_err(|e| connect_failure(link, e))?;
    let response = sender.at(command, value, Some(timeout)).await;
    sender.close();
    while stream.next().await.is_some() {}
    Ok(response.map(|response| match response.parse() {
        Ok(Frame::AtCommandResponse(at)) if at.status.is_ok() => Some(at.data.to_vec()),
        _ => None,
    }))
}

/// The link opened once, as a byte stream (no reconnection), for an exchange outside
/// API frames (AT command mode).
pub(crate) async fn open_once(
    link: &Link,
    connect_timeout: Duration,
) -> Result<mcp_host::Transport, Failure> {
    let options = LinkOptions {
        connect_timeout,
        reconnect: ReconnectPolicy::disabled(),
        ..LinkOptions::default()
    };
    let opened = async { Connector::new(link, &options).await?.open().await };
    opened
        .await
        .map_err(|e| connect_failure(link, ConnectError::Link(e)))
}

/// Warns once when the radio's API mode differs from the configured one: the commonest
/// cause of silently dropped frames. The radio has `timeout` to answer its `AT AP`.
pub(crate) async fn check_mode(sender: &CommandSender, configured: ApiMode, timeout: Duration) {
    // A link waited for (`--wait`) is asked once it is up.
    let mut state = sender.watch_link_state();
    if state
        .wait_for(|s| *s == mcp_host::LinkState::Connected)
        .await
        .is_err()
    {
        return;
    }
    let response = match sender.at(*b"AP", &[], Some(timeout)).await {
        Ok(response) => response,
        // Nothing at all from the radio meanwhile: what keeps a radio silent (or a
        // peer that lets this connection wait its turn).
        Err(e) if e.is_timeout() => {
            let lead = format!(
                "the radio did not answer AT AP within {}, and nothing at all came from it: check its API mode",
                Seconds(timeout)
            );
            if let Some(hint) = silence_hint(&sender.info().link, &sender.stats(), &lead) {
                err!("mcp-gs: {hint}");
            }
            return;
        }
        Err(_) => return,
    };
    if let Ok(Frame::AtCommandResponse(at)) = response.parse() {
        if let (true, true, &[radio]) = (at.command == *b"AP", at.status.is_ok(), at.data) {
            warn_mode_mismatch(radio, configured, &sender.info().link);
        }
    }
}
