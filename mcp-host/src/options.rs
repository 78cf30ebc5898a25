//! Link and send options.

use std::time::Duration;

use crate::error::OptionsError;

/// Default of [`LinkOptions::send_timeout`], for a delivery status or a response: longer
/// than a Zigbee route discovery (10 s).
pub const DEFAULT_SEND_TIMEOUT: Duration = Duration::from_secs(12);
/// Default of [`LinkOptions::partial_frame_timeout`].
pub const DEFAULT_PARTIAL_FRAME_TIMEOUT: Duration = Duration::from_secs(1);
/// Default of [`LinkOptions::connect_timeout`]: for opening a TCP connection or an `io:`
/// link's stream.
pub const DEFAULT_CONNECT_TIMEOUT: Duration = Duration::from_secs(5);

/// `start + d`, or about thirty years after `start` where that would overflow: a
/// timeout of `Duration::MAX` means "never", not a panic.
pub(crate) fn later(start: tokio::time::Instant, d: Duration) -> tokio::time::Instant {
    const FAR: Duration = Duration::from_secs(30 * 365 * 86_400);
    start
        .checked_add(d.min(FAR))
        .or_else(|| start.checked_add(Duration::from_secs(86_400)))
        .unwrap_or(start)
}

/// The least [`ReconnectPolicy::max_delay`] of a policy that reconnects
/// ([`LinkOptions::check`]).
pub const MIN_RECONNECT_DELAY: Duration = Duration::from_millis(10);

/// How a link reconnects after its transport goes away (serial device unplugged, TCP peer
/// gone).
///
/// `max_delay` is at least [`MIN_RECONNECT_DELAY`] and no less than `initial_delay`
/// (which may be zero, for a first attempt at once), or
/// [`connect`](crate::connect) refuses the options
/// ([`OptionsError::ReconnectDelay`]).
///
/// Attempts are spaced by an exponential backoff: the first one waits `initial_delay`,
/// each failure doubles the delay up to `max_delay`. The delay returns to `initial_delay`
/// once a connection has carried data (and, for `serial` and `tcp` links, stayed up for
/// `max_delay`), so a port that opens and fails at once keeps backing off instead of
/// spinning, and so does a TCP peer that sends a frame and hangs up, again and again.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReconnectPolicy {
    /// Reconnect at all; when false the link ends at the first disconnection.
    pub enabled: bool,
    /// Delay before the first attempt.
    pub initial_delay: Duration,
    /// Upper bound of the delay between attempts.
    pub max_delay: Duration,
}

impl ReconnectPolicy {
    /// No reconnection: the first disconnection ends the link.
    pub fn disabled() -> Self {
        ReconnectPolicy {
            enabled: false,
            ..Self::default()
        }
    }

    /// The delay after `delay`: doubled, capped at `max_delay`, never zero.
    pub(crate) fn next_delay(&self, delay: Duration) -> Duration {
        delay
            .saturating_mul(2)
            .min(self.max_delay)
            .max(Duration::from_millis(1))
    }
}

impl Default for ReconnectPolicy {
    /// Enabled, 100 ms initial delay, 5 s maximum.
    fn default() -> Self {
        ReconnectPolicy {
            enabled: true,
            initial_delay: Duration::from_millis(100),
            max_delay: Duration::from_secs(5),
        }
    }
}

/// Options of a link: XBee API mode, framing limit, timeouts and reconnection.
///
/// Set the fields that differ from the defaults, the rest with `..Default::default()`:
///
/// ```
/// use std::time::Duration;
/// use mcp_host::xbee_api::ApiMode;
/// use mcp_host::{LinkOptions, ReconnectPolicy};
///
/// // A radio set to AP=2, plugged in after the program starts, whose statuses take
/// // long (a network of many hops).
/// let options = LinkOptions {
///     api_mode: ApiMode::Escaped,
///     wait_for_link: true,
///     send_timeout: Duration::from_secs(20),
///     ..LinkOptions::default()
/// };
/// assert!(options.reconnect.enabled);
/// assert_eq!(options.reconnect.max_delay, Duration::from_secs(5));
///
/// // A one-shot tool: the first disconnection ends the link, no reconnection.
/// let once = LinkOptions {
///     reconnect: ReconnectPolicy::disabled(),
///     ..LinkOptions::default()
/// };
/// assert!(!once.reconnect.enabled);
/// ```
///
/// They go to [`connect`](crate::connect) with the link.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LinkOptions {
    /// XBee API mode of the local radio (`AP` setting): 1 (unescaped, as the deployed
    /// MAVs use) or 2 (escaped).
    ///
    /// In mode 1 a payload from the air can hold the bytes of a whole frame (0x7E is not
    /// escaped), and when the frame around it is damaged (a checksum error, or a stall
    /// past [`Self::partial_frame_timeout`]) the decoder finds that inner frame, as it
    /// must find every real frame after a damaged one. A node that can send payloads can
    /// thus plant, say, a Transmit Status for a request in flight. Mode 2 escapes 0x7E
    /// in frame data, so no payload can be read as a frame: prefer it wherever the
    /// radios may carry hostile data. Default mode 1.
    pub api_mode: xbee_api::ApiMode,
    /// Largest frame data length (frame type byte included) accepted from the radio;
    /// longer frames are dropped as soon as their length field is read and counted as
    /// oversize (in API mode 1 the bytes after their start delimiter are scanned again,
    /// so that no frame inside one is lost). Default and largest value
    /// [`crate::codec::MAX_FRAME_DATA`]; in API mode 1 a value above
    /// `MAX_FRAME_DATA - 4`, the decoder's capacity there, is taken as that.
    pub max_frame_len: usize,
    /// Timeout for opening a TCP connection, or an `io:` link's stream
    /// ([`connect_with`](crate::connect_with)); serial ports and pseudo-terminals open at
    /// once or fail. Default [`DEFAULT_CONNECT_TIMEOUT`], 5 s.
    pub connect_timeout: Duration,
    /// Default timeout of [`crate::CommandSender::send`] and friends (delivery status or
    /// response). Default [`DEFAULT_SEND_TIMEOUT`], 12 s.
    pub send_timeout: Duration,
    /// Reconnection after the transport goes away. Default: enabled, from 0.1 s to 5 s
    /// between tries ([`ReconnectPolicy::default`]).
    pub reconnect: ReconnectPolicy,
    /// `serial`, `tcp` and `io:` links: when the first open fails in a way a later try may
    /// fix (the device is not plugged in yet, nothing listens yet),
    /// [`connect`](crate::connect) returns anyway, in
    /// [`LinkState::Connecting`](crate::LinkState::Connecting), and the link is opened
    /// in the background under [`reconnect`](Self::reconnect)'s delays;
    /// [`LinkEvent::Connected`](crate::LinkEvent::Connected) says when it is up, and
    /// requests fail at once until then. Waiting needs reconnection enabled: without
    /// it, `connect` fails at once as usual. Any failure a retry may fix counts (see
    /// [`LinkError::is_retryable`](crate::LinkError::is_retryable)), a mistyped device
    /// path or host name among them: the first one is logged as a warning. Default
    /// `false`: `connect` fails at once. (`tcp-listen` and `pty` links always wait for
    /// their first peer.)
    pub wait_for_link: bool,
    /// API mode 1 only: a partial frame that gets no new byte for this long is dropped
    /// (an [`crate::Event::DecodeError`], truncated) and the bytes after its start
    /// delimiter are scanned again. In mode 1 a 0x7E in noise or in the tail of a frame
    /// cut off when the port was opened starts a candidate frame that holds back every
    /// frame behind it until its length is reached; on a quiet link that could be never.
    /// `None` waits for more bytes however long it takes. Default 1 s (a radio sends a
    /// frame's bytes back to back: at 9600 baud, 273 bytes take 0.3 s).
    pub partial_frame_timeout: Option<Duration>,
    /// Capacity of the event queue between the background task and the
    /// [`crate::PacketStream`]; when the consumer falls behind by this many events, newer
    /// packets and frames are dropped and counted ([`crate::Stats::events_dropped`]);
    /// link events are held back, 64 at most (beyond that the oldest are dropped and
    /// counted too), and the stream always ends with
    /// [`LinkEvent::Closed`](crate::LinkEvent::Closed). At most [`MAX_EVENT_CAPACITY`]; each
    /// [`crate::Subscription`] channel takes room for this many events (rounded up to a
    /// power of two) when the first is taken. Default 1024.
    pub event_capacity: usize,
}

/// The largest [`LinkOptions::event_capacity`]: about a million events, minutes of
/// every frame a radio can pass.
pub const MAX_EVENT_CAPACITY: usize = 1 << 20;

impl LinkOptions {
    /// Whether every option is in its range, as [`connect`](crate::connect) and
    /// [`connect_with`](crate::connect_with) check before they open anything (they fail
    /// with [`ConnectError::Options`](crate::ConnectError::Options) otherwise).
    ///
    /// ```
    /// use mcp_host::{LinkOptions, OptionsError, codec::MAX_FRAME_DATA};
    /// assert_eq!(LinkOptions::default().check(), Ok(()));
    /// let long = LinkOptions { max_frame_len: MAX_FRAME_DATA + 1, ..LinkOptions::default() };
    /// assert!(matches!(long.check(), Err(OptionsError::MaxFrameLen { .. })));
    /// ```
    pub fn check(&self) -> Result<(), OptionsError> {
        if !(1..=MAX_EVENT_CAPACITY).contains(&self.event_capacity) {
            return Err(OptionsError::EventCapacity {
                value: self.event_capacity,
                max: MAX_EVENT_CAPACITY,
            });
        }
        if !(1..=crate::codec::MAX_FRAME_DATA).contains(&self.max_frame_len) {
            return Err(OptionsError::MaxFrameLen {
                value: self.max_frame_len,
                max: crate::codec::MAX_FRAME_DATA,
            });
        }
        let ReconnectPolicy {
            enabled,
            initial_delay,
            max_delay,
        } = self.reconnect;
        if enabled && (max_delay < MIN_RECONNECT_DELAY || max_delay < initial_delay) {
            return Err(OptionsError::ReconnectDelay {
                initial_delay,
                max_delay,
            });
        }
        Ok(())
    }
}

impl Default for LinkOptions {
    /// API mode 1 (as the deployed MAVs' radios), frames up to
    /// [`MAX_FRAME_DATA`](crate::codec::MAX_FRAME_DATA), a 5 s connect timeout, a 12 s
    /// send timeout, reconnection from 0.1 s to 5 s between tries, no waiting for a
    /// first link, partial frames given up after 1 s, 1024 events queued.
    fn default() -> Self {
        LinkOptions {
            api_mode: xbee_api::ApiMode::Unescaped,
            max_frame_len: crate::codec::MAX_FRAME_DATA,
            connect_timeout: DEFAULT_CONNECT_TIMEOUT,
            send_timeout: DEFAULT_SEND_TIMEOUT,
            reconnect: ReconnectPolicy::default(),
            wait_for_link: false,
            partial_frame_timeout: Some(DEFAULT_PARTIAL_FRAME_TIMEOUT),
            event_capacity: 1024,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_policy_that_would_spin_is_refused() {
        let with = |enabled, initial, max| LinkOptions {
            reconnect: ReconnectPolicy {
                enabled,
                initial_delay: Duration::from_millis(initial),
                max_delay: Duration::from_millis(max),
            },
            ..LinkOptions::default()
        };
        for (initial, max) in [(0, 0), (0, 9), (50, 1), (100, 99)] {
            let error = with(true, initial, max).check().unwrap_err();
            assert_eq!(
                error,
                OptionsError::ReconnectDelay {
                    initial_delay: Duration::from_millis(initial),
                    max_delay: Duration::from_millis(max),
                }
            );
        }
        assert_eq!(
            with(true, 50, 1).check().unwrap_err().to_string(),
            "reconnect.max_delay is 0.001 s, less than 0.01 s or than \
             reconnect.initial_delay (0.05 s): a link that cannot connect would try again \
             hundreds of times a second"
        );
        // A first attempt at once is fine; so is anything that does not reconnect.
        for (enabled, initial, max) in [(true, 0, 10), (true, 100, 100), (false, 50, 0)] {
            assert_eq!(with(enabled, initial, max).check(), Ok(()));
        }
        assert_eq!(LinkOptions::default().check(), Ok(()));
    }

    #[test]
    fn backoff_doubles_up_to_the_cap() {
        let policy = ReconnectPolicy {
            enabled: true,
            initial_delay: Duration::from_millis(100),
            max_delay: Duration::from_millis(700),
        };
        let mut delay = policy.initial_delay;
        let mut seen = vec![];
        for _ in 0..5 {
            seen.push(delay.as_millis());
            delay = policy.next_delay(delay);
        }
        assert_eq!(seen, [100, 200, 400, 700, 700]);
        let zero = ReconnectPolicy {
            initial_delay: Duration::ZERO,
            ..policy
        };
        assert_eq!(zero.next_delay(Duration::ZERO), Duration::from_millis(1));
    }
}
