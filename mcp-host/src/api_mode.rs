//! The local radio's API mode, asked of the radio itself: [`detect_api_mode`].

use std::time::Duration;

use futures::StreamExt;
use xbee_api::{ApiMode, Frame};

use crate::{ConnectError, Link, LinkOptions, ReconnectPolicy, SendError};

/// Why [`detect_api_mode`] could not tell the radio's API mode.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum DetectError {
    /// A `pty` or `tcp-listen:` link: it has no radio on it until a peer comes, and
    /// nothing to ask meanwhile.
    #[error("{0} has no radio to ask until a peer comes: give the API mode (1 or 2)")]
    NoRadio(Link),
    /// The link could not be opened.
    #[error(transparent)]
    Connect(#[from] ConnectError),
    /// The radio did not answer `AT AP` in time ([`SendError::Timeout`]): it may be in
    /// transparent mode (`AP=0`, as XBee modules leave the factory, which
    /// [`command_mode`](crate::command_mode) changes) or at another baud rate. Or the
    /// request failed otherwise (the link went down).
    #[error("the radio did not answer AT AP: {0}")]
    NoAnswer(SendError),
    /// The radio answered that it is in transparent mode (`AP=0`): it speaks no API
    /// frames until [`command_mode`](crate::command_mode) changes that (it answered in
    /// an API frame all the same: a radio seldom does).
    #[error("the radio is in transparent mode (AP=0)")]
    Transparent,
    /// The radio answered something else than a mode this crate speaks: `AP=3` and
    /// above (MicroPython, Bluetooth), or an error status (`None`).
    #[error("the radio answered AT AP with {}, not 1 or 2", answer(.0.as_deref()))]
    Unexpected(Option<Vec<u8>>),
}

/// The radio's answer to `AT AP` in words: its value in hex, or the error it gave.
fn answer(value: Option<&[u8]>) -> String {
    match value {
        Some([]) => "no value".to_owned(),
        Some(value) => format!("AP={}", crate::render::json::hex(value)),
        None => "an error status".to_owned(),
    }
}

/// Asks the radio on `link` its API mode (`AT AP`) and returns it, for a link opened
/// then with that mode in [`LinkOptions::api_mode`].
///
/// The link is opened for this alone with `options` (in API mode 1, without
/// reconnection: its `api_mode` and `reconnect` are not used), waits
/// [`send_timeout`](LinkOptions::send_timeout) at most for the answer, and is closed
/// and waited for before this returns, so that a serial port is free again. The
/// request, `AT AP` under frame id 1, has no byte to escape, nor has its answer: they
/// read the same in both modes.
///
/// ```no_run
/// use mcp_host::{Link, LinkOptions};
///
/// # async fn run() -> Result<(), Box<dyn std::error::Error>> {
/// let link: Link = "serial:/dev/ttyUSB0".parse()?;
/// let api_mode = mcp_host::detect_api_mode(&link, LinkOptions::default()).await?;
/// let (stream, sender) =
///     mcp_host::connect(&link, LinkOptions { api_mode, ..LinkOptions::default() }).await?;
/// # Ok(())
/// # }
/// ```
pub async fn detect_api_mode(link: &Link, options: LinkOptions) -> Result<ApiMode, DetectError> {
    if matches!(link, Link::Pty | Link::TcpListen { .. }) {
        return Err(DetectError::NoRadio(link.clone()));
    }
    let timeout: Duration = options.send_timeout;
    let options = LinkOptions {
        api_mode: ApiMode::Unescaped,
        reconnect: ReconnectPolicy::disabled(),
        wait_for_link: false,
        ..options
    };
    let (mut stream, sender) = crate::connect(link, options).await?;
    let answer = sender.at(*b"AP", &[], Some(timeout)).await;
    sender.close();
    while stream.next().await.is_some() {}
    let answer = answer.map_err(DetectError::NoAnswer)?;
    let value = match answer.parse() {
        Ok(Frame::AtCommandResponse(at)) if at.status.is_ok() => at.data.to_vec(),
        _ => return Err(DetectError::Unexpected(None)),
    };
    match xbee_api::at_number(&value) {
        Some(1) => Ok(ApiMode::Unescaped),
        Some(2) => Ok(ApiMode::Escaped),
        Some(0) => Err(DetectError::Transparent),
        _ => Err(DetectError::Unexpected(Some(value))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_answer_that_is_no_mode_is_said_in_words() {
        let said = |value: Option<&[u8]>| DetectError::Unexpected(value.map(<[u8]>::to_vec));
        assert_eq!(
            said(Some(&[3])).to_string(),
            "the radio answered AT AP with AP=03, not 1 or 2"
        );
        assert_eq!(
            said(None).to_string(),
            "the radio answered AT AP with an error status, not 1 or 2"
        );
        assert_eq!(
            said(Some(&[])).to_string(),
            "the radio answered AT AP with no value, not 1 or 2"
        );
    }
}
