//! Errors of the sender API.

use std::time::Duration;

use mcp_core::StatusRequest;
use xbee_api::{Address16, Address64, DeliveryStatus, DiscoveryStatus};

use crate::driver::ReportKey;
use crate::render::Seconds;
use crate::transport::LinkError;

/// Why [`crate::connect`] failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ConnectError {
    /// The link could not be opened.
    #[error(transparent)]
    Link(#[from] LinkError),
    /// The options are out of range ([`LinkOptions::check`](crate::LinkOptions::check)
    /// says the same before connecting).
    #[error("invalid link options: {0}")]
    Options(#[from] OptionsError),
}

/// Which of the [`LinkOptions`](crate::LinkOptions) is out of range, and its range.
///
/// ```
/// use mcp_host::{LinkOptions, OptionsError};
/// let options = LinkOptions { event_capacity: 0, ..LinkOptions::default() };
/// let err = options.check().unwrap_err();
/// assert!(matches!(err, OptionsError::EventCapacity { value: 0, .. }));
/// assert_eq!(
///     err.to_string(),
///     "event_capacity is 0, outside its range 1..=1048576",
/// );
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum OptionsError {
    /// [`LinkOptions::event_capacity`](crate::LinkOptions::event_capacity) is 0 or more
    /// than [`MAX_EVENT_CAPACITY`](crate::MAX_EVENT_CAPACITY).
    #[error("event_capacity is {value}, outside its range 1..={max}")]
    #[non_exhaustive]
    EventCapacity {
        /// The value given.
        value: usize,
        /// The largest value taken.
        max: usize,
    },
    /// [`LinkOptions::max_frame_len`](crate::LinkOptions::max_frame_len) is 0 or more
    /// than [`MAX_FRAME_DATA`](crate::codec::MAX_FRAME_DATA).
    #[error("max_frame_len is {value}, outside its range 1..={max}")]
    #[non_exhaustive]
    MaxFrameLen {
        /// The value given.
        value: usize,
        /// The largest value taken.
        max: usize,
    },
    /// [`ReconnectPolicy::max_delay`](crate::ReconnectPolicy::max_delay) of a policy
    /// that reconnects is less than
    /// [`MIN_RECONNECT_DELAY`](crate::options::MIN_RECONNECT_DELAY) or than its
    /// `initial_delay`: a link that cannot connect would try again hundreds of times a
    /// second.
    #[error(
        "reconnect.max_delay is {max}, less than {min} or than reconnect.initial_delay \
         ({initial}): a link that cannot connect would try again hundreds of times a second",
        max = Seconds(*.max_delay),
        min = Seconds(crate::options::MIN_RECONNECT_DELAY),
        initial = Seconds(*.initial_delay)
    )]
    #[non_exhaustive]
    ReconnectDelay {
        /// The policy's initial delay.
        initial_delay: Duration,
        /// The policy's maximum delay.
        max_delay: Duration,
    },
}

impl ConnectError {
    /// Whether connecting again later may succeed (the device may come back, a peer
    /// may start listening), as [`LinkError::is_retryable`] says; never for options
    /// that are wrong. [`LinkOptions::wait_for_link`](crate::LinkOptions::wait_for_link)
    /// has `connect` wait through such failures itself.
    ///
    /// ```
    /// # #[tokio::main(flavor = "current_thread")]
    /// # async fn main() {
    /// use mcp_host::{Link, LinkOptions};
    /// let link: Link = "serial:/dev/no-such-radio".parse().unwrap();
    /// let err = mcp_host::connect(&link, LinkOptions::default()).await.unwrap_err();
    /// assert!(err.is_retryable(), "{err}"); // it may yet be plugged in
    /// let bad = LinkOptions { event_capacity: 0, ..LinkOptions::default() };
    /// assert!(!mcp_host::connect(&link, bad).await.unwrap_err().is_retryable());
    /// # }
    /// ```
    pub fn is_retryable(&self) -> bool {
        match self {
            ConnectError::Link(e) => e.is_retryable(),
            ConnectError::Options(_) => false,
        }
    }
}

/// Why a send did not succeed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum SendError {
    /// The radio reported a delivery failure in its Transmit Status.
    #[error(
        "delivery to {to} failed: {status} (Digi status 0x{code:02X}, retries {retries}, discovery {discovery})",
        code = u8::from(*.status)
    )]
    #[non_exhaustive]
    Delivery {
        /// Destination.
        to: Address64,
        /// The frame id the request went under (its Transmit Status's).
        frame_id: u8,
        /// The 16-bit address the Transmit Status gives (FFFD or FFFE when the radio
        /// did not find one).
        dst16: Address16,
        /// Digi's delivery status code (never success).
        status: DeliveryStatus,
        /// Transmit retries the radio made.
        retries: u8,
        /// Route discovery the radio did.
        discovery: DiscoveryStatus,
    },
    /// No status or response came before the timeout. The request went out (under
    /// `frame_id`): the radio may still carry it out. Its frame id is kept from new
    /// requests for a while, so that a late answer is passed on as an unclaimed frame,
    /// never taken for another request's.
    #[error(
        "no answer{} within {secs}{}",
        frame_id.map(|id| format!(" to frame id {id}")).unwrap_or_default(),
        if *heard { "" } else { " (no valid frame has come from the radio since the link came up)" },
        secs = Seconds(*.timeout)
    )]
    #[non_exhaustive]
    Timeout {
        /// The frame id the request went out under. `None` when the link's task itself
        /// did not answer in time (a runtime held up past the timeout): whether the
        /// request went out, and under which id, is not known then.
        frame_id: Option<u8>,
        /// The timeout that expired.
        timeout: Duration,
        /// Whether a frame came from the radio on this connection before the timeout
        /// (true where the link cannot tell). If none did, the radio may not speak the
        /// link's API mode or baud rate, or be in transparent mode, or the peer may
        /// serve another connection first (a simulator or `tcp-listen:` link lets the
        /// next one wait): see [`Stats::diagnose`](crate::Stats::diagnose).
        heard: bool,
    },
    /// The request waited for a frame id for all of its timeout and was never sent: all
    /// 255 were taken by requests whose answers had not come (a radio that does not
    /// answer, e.g. one in another API mode). The id of a request that timed out after
    /// its frame went out stays taken 10 s more, for its late answer: against a radio
    /// that never answers, more than 255 requests in their timeout and 10 s end so.
    #[error(
        "not sent: all 255 frame ids were waiting for answers for {secs}",
        secs = Seconds(*.timeout)
    )]
    #[non_exhaustive]
    NoFreeFrameId {
        /// The timeout that expired.
        timeout: Duration,
    },
    /// The request's timeout ran out before it was sent, without waiting for a frame
    /// id: a timeout too short to hand the request to the link in (zero, say), a link
    /// whose queue stayed full, or a frame still waiting to be written when its
    /// timeout ran out (a transport that takes bytes more slowly than requests come),
    /// which is then taken back: none of it reaches the radio.
    #[error(
        "not sent: its timeout of {secs} ran out before it went out to the radio",
        secs = Seconds(*.timeout)
    )]
    #[non_exhaustive]
    NotSent {
        /// The timeout that expired.
        timeout: Duration,
    },
    /// The transport went away while the request was in flight, or is down now: gone
    /// and reconnecting, or not connected yet (a `tcp-listen:` or `pty` link before its
    /// first peer, a link waiting for its device), as `reason` says.
    #[error("link down: {reason}")]
    #[non_exhaustive]
    Disconnected {
        /// Why the transport is down (`not connected yet to LINK`, or why it went away).
        reason: String,
    },
    /// The link has ended for good (a request made after it ended; one in flight when
    /// it ended fails with [`Disconnected`](Self::Disconnected), as it may have gone
    /// out).
    #[error("link closed")]
    Closed,
    /// The packet does not fit the payload limit.
    #[error("packet of {len} bytes exceeds the {max}-byte payload limit")]
    #[non_exhaustive]
    TooLarge {
        /// Encoded length.
        len: usize,
        /// The limit.
        max: usize,
    },
    /// A frame given to [`crate::CommandSender::send_frame`] is of no request type
    /// known to carry a frame id.
    #[error(
        "frame type 0x{0:02X} is no request known to carry a frame id, so no response can \
         be matched (write it with write_frame)"
    )]
    NoFrameId(u8),
    /// A frame given to [`crate::CommandSender::send_frame`] is of a type that carries a
    /// frame id, in its second byte, and ends before it: its frame type alone.
    #[error(
        "frame type 0x{0:02X} carries a frame id in its second byte, and the frame data ends before it"
    )]
    NoFrameIdByte(u8),
    /// A frame given to [`crate::CommandSender::send_frame`] or
    /// [`write_frame`](crate::CommandSender::write_frame) is empty (no frame type).
    #[error("empty frame data (no frame type byte)")]
    EmptyFrame,
}

impl SendError {
    /// Whether the request ran out of time: no status or response came
    /// ([`Timeout`](Self::Timeout)), or it was never sent, waiting for a frame id or for
    /// room in the link's queue ([`NoFreeFrameId`](Self::NoFreeFrameId),
    /// [`NotSent`](Self::NotSent)). The radio and the MAV may be fine: a longer timeout
    /// may do, where a delivery failure, a closed link or a refused frame would not.
    ///
    /// ```
    /// use mcp_host::SendError;
    /// assert!(!SendError::Closed.is_timeout());
    /// ```
    pub fn is_timeout(&self) -> bool {
        matches!(
            self,
            SendError::Timeout { .. } | SendError::NoFreeFrameId { .. } | SendError::NotSent { .. }
        )
    }

    /// Whether the link failed, not the radio or the MAV: it is down
    /// ([`Disconnected`](Self::Disconnected): gone and reconnecting, or not connected
    /// yet) or ended ([`Closed`](Self::Closed)). The link's own
    /// [`LinkEvent`](crate::LinkEvent)s say when it is back.
    ///
    /// ```
    /// use mcp_host::SendError;
    /// assert!(SendError::Closed.is_link_down());
    /// assert!(!SendError::EmptyFrame.is_link_down());
    /// ```
    pub fn is_link_down(&self) -> bool {
        matches!(self, SendError::Disconnected { .. } | SendError::Closed)
    }

    /// The frame id the request went out under, when it went out with one and failed
    /// for want of an answer or of delivery ([`Timeout`](Self::Timeout),
    /// [`Delivery`](Self::Delivery)); `None` otherwise.
    pub fn frame_id(&self) -> Option<u8> {
        match *self {
            SendError::Timeout { frame_id, .. } => frame_id,
            SendError::Delivery { frame_id, .. } => Some(frame_id),
            _ => None,
        }
    }
}

/// Why a status request did not produce a report.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum RequestError {
    /// Sending the request failed (delivery failure, disconnection, ...). A link that
    /// went down while the request was in flight may have delivered it first.
    #[error("status request failed: {0}")]
    Send(SendError),
    /// The request was delivered (or no status came) but no matching report arrived in
    /// time.
    #[error(
        "no {what} report from {from} within {secs} ({})",
        timeout_cause(*delivered, *heard, *undecodable),
        what = ReportKey::of_request(.request),
        secs = Seconds(*.timeout)
    )]
    #[non_exhaustive]
    Timeout {
        /// Whom the request went to.
        from: Address64,
        /// The request that got no report.
        request: StatusRequest,
        /// The timeout that expired.
        timeout: Duration,
        /// Whether the radio confirmed delivery of the request (a Transmit Status
        /// success): if it did, the MAV got it and did not answer in time; if not, the
        /// radio itself did not answer (off, another API mode or baud rate, ...).
        delivered: bool,
        /// Frames from the radio dropped undecodable while the report was awaited: if
        /// any, the report may have been one of them ([`Stats::diagnose`] on the link's
        /// counters says why they failed).
        ///
        /// [`Stats::diagnose`]: crate::Stats::diagnose
        undecodable: u64,
        /// Whether a frame came from the radio on this connection before the timeout,
        /// as in [`SendError::Timeout`] (true where the link cannot tell): if none did
        /// and delivery was not confirmed, the radio may not speak the link's API mode
        /// or baud rate, or the peer may serve another connection first.
        heard: bool,
    },
}

/// The message says why the request could not be sent: no
/// [`source`](std::error::Error::source), so that a chain of errors says it once.
impl From<SendError> for RequestError {
    fn from(error: SendError) -> Self {
        RequestError::Send(error)
    }
}

impl RequestError {
    /// Whether the request ran out of time: no report came
    /// ([`Timeout`](Self::Timeout)), or sending it did ([`SendError::is_timeout`]). The
    /// MAV may be fine: asking again, or with a longer timeout, may do.
    ///
    /// ```
    /// use mcp_host::{RequestError, SendError};
    ///
    /// let closed = RequestError::from(SendError::Closed);
    /// assert!(!closed.is_timeout());
    /// ```
    pub fn is_timeout(&self) -> bool {
        match self {
            RequestError::Send(error) => error.is_timeout(),
            RequestError::Timeout { .. } => true,
        }
    }

    /// Whether the request failed because the link is down or ended, as
    /// [`SendError::is_link_down`] says: not for want of an answer from the radio or the
    /// MAV.
    ///
    /// ```
    /// use mcp_host::{RequestError, SendError};
    /// assert!(RequestError::from(SendError::Closed).is_link_down());
    /// ```
    pub fn is_link_down(&self) -> bool {
        match self {
            RequestError::Send(error) => error.is_link_down(),
            RequestError::Timeout { .. } => false,
        }
    }
}

/// Why a report did not come, as far as the link can tell.
fn timeout_cause(delivered: bool, heard: bool, undecodable: u64) -> String {
    let lost = (undecodable > 0).then(|| {
        format!(
            "{} from the radio could not be decoded meanwhile",
            crate::diagnosis::counted(undecodable, "frame")
        )
    });
    match (delivered, lost) {
        (true, None) => "the radio delivered the request; the MAV did not answer, or its \
                         report was lost on the way"
            .to_owned(),
        (true, Some(lost)) => {
            format!("the radio delivered the request, but {lost}: the report may have been one")
        }
        (false, None) if !heard => "the radio did not confirm delivery; no valid frame has come \
                                    from the radio since the link came up"
            .to_owned(),
        (false, None) => "the radio did not confirm delivery".to_owned(),
        (false, Some(lost)) => format!("the radio did not confirm delivery, and {lost}"),
    }
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use xbee_api::{Address16, Address64, DeliveryStatus, DiscoveryStatus};

    use super::{RequestError, SendError};

    /// The messages of `error` and of each of its sources.
    fn chain(error: &dyn std::error::Error) -> Vec<String> {
        std::iter::successors(Some(error), |e| e.source())
            .map(ToString::to_string)
            .collect()
    }

    #[test]
    fn a_chain_of_errors_says_each_cause_once() {
        let request = RequestError::from(SendError::Closed);
        assert_eq!(chain(&request), ["status request failed: link closed"]);
        let discovery = crate::discovery::DiscoverError::from(SendError::Closed);
        assert_eq!(chain(&discovery), ["node discovery: link closed"]);
        let io = std::io::Error::other("broken pipe");
        let command_mode = crate::command_mode::CommandModeError::from(io);
        assert_eq!(chain(&command_mode), ["command mode: broken pipe"]);
        let link = crate::LinkError::Connect {
            addr: "127.0.0.1:9".into(),
            error: std::io::Error::other("refused"),
        };
        let node = crate::radio::NetworkError::Link {
            node: Address64::COORDINATOR,
            error: link,
        };
        assert_eq!(
            chain(&node),
            ["node 0000000000000000: cannot connect to 127.0.0.1:9: refused"]
        );
    }

    #[test]
    fn the_timeouts_are_the_requests_that_ran_out_of_time() {
        let timeout = Duration::from_secs(1);
        let timed_out = [
            SendError::Timeout {
                frame_id: Some(7),
                timeout,
                heard: true,
            },
            SendError::NoFreeFrameId { timeout },
            SendError::NotSent { timeout },
            // The link's task ran late: under which id it went, if it went, is unknown.
            SendError::Timeout {
                frame_id: None,
                timeout,
                heard: true,
            },
        ];
        let delivery = SendError::Delivery {
            to: Address64::COORDINATOR,
            frame_id: 9,
            dst16: Address16::UNKNOWN,
            status: DeliveryStatus::from(0x24),
            retries: 0,
            discovery: DiscoveryStatus::from(0),
        };
        let others = [
            delivery.clone(),
            SendError::Closed,
            SendError::Disconnected {
                reason: "gone".into(),
            },
            SendError::TooLarge { len: 300, max: 255 },
            SendError::EmptyFrame,
            SendError::NoFrameIdByte(0x08),
        ];
        assert!(timed_out.iter().all(SendError::is_timeout));
        assert!(!others.iter().any(SendError::is_timeout));
        let ids: Vec<_> = timed_out.iter().map(SendError::frame_id).collect();
        assert_eq!(ids, [Some(7), None, None, None]);
        assert_eq!(
            timed_out[0].to_string(),
            "no answer to frame id 7 within 1 s"
        );
        assert_eq!(timed_out[3].to_string(), "no answer within 1 s");
        assert_eq!(delivery.frame_id(), Some(9));
        assert_eq!(SendError::Closed.frame_id(), None);
    }

    #[test]
    fn a_request_timed_out_when_no_report_came_or_sending_timed_out() {
        let timeout = Duration::from_secs(1);
        let no_report = RequestError::Timeout {
            from: Address64(1),
            request: mcp_core::StatusRequest::Landing,
            timeout,
            delivered: true,
            undecodable: 0,
            heard: true,
        };
        assert!(no_report.is_timeout());
        assert_eq!(
            no_report.to_string(),
            "no landing report from 0000000000000001 within 1 s (the radio delivered the \
             request; the MAV did not answer, or its report was lost on the way)"
        );
        let telemetry = RequestError::Timeout {
            from: Address64(2),
            request: mcp_core::StatusRequest::TelemetryToCoordinator(
                mcp_core::TelemetryId::Altitude,
            ),
            timeout: Duration::from_millis(1500),
            delivered: true,
            undecodable: 0,
            heard: true,
        };
        assert_eq!(
            telemetry.to_string(),
            "no telemetry_to_coordinator (altitude) report from 0000000000000002 within 1.5 s \
             (the radio delivered the request; the MAV did not answer, or its report was \
             lost on the way)"
        );
        let unsent = RequestError::from(SendError::NotSent { timeout });
        assert!(unsent.is_timeout());
        assert!(!RequestError::from(SendError::Closed).is_timeout());
    }
}
