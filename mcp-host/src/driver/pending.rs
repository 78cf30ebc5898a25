//! The requests that wait for an answer: under a frame id (a transmit status, an AT
//! response) or for a MAV's report, and who waits for each.

use std::fmt;
use std::ops::Range;
use std::time::Duration;

use bytes::Bytes;
use tokio::sync::oneshot;
use tokio::time::Instant;
use xbee_api::Address64;

use super::op::{AnswerSender, fail_answers};
use crate::error::{RequestError, SendError};
use crate::event::OwnedFrame;
use crate::sender::DeliveryReport;

/// Which report answers a status request: its type, and for telemetry to coordinator
/// the telemetry id.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) struct ReportKey {
    report_type: mcp_core::CommandType,
    telemetry: Option<mcp_core::TelemetryId>,
}

impl ReportKey {
    pub(crate) fn of_request(request: &mcp_core::StatusRequest) -> Self {
        let telemetry = match request {
            mcp_core::StatusRequest::TelemetryToCoordinator(id) => Some(*id),
            _ => None,
        };
        ReportKey {
            report_type: request.command_type(),
            telemetry,
        }
    }

    pub(super) fn of_report<B: AsRef<[u8]>>(report: &mcp_core::Report<B>) -> Self {
        let telemetry = match report {
            mcp_core::Report::TelemetryToCoordinator { id, .. } => Some(*id),
            _ => None,
        };
        ReportKey {
            report_type: report.report_type(),
            telemetry,
        }
    }
}

impl fmt::Display for ReportKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.telemetry {
            Some(id) => write!(f, "{} ({id})", self.report_type),
            None => write!(f, "{}", self.report_type),
        }
    }
}

#[derive(Debug)]
pub(super) struct Pending {
    pub(super) deadline: Instant,
    pub(super) timeout: Duration,
    /// Where its frame is in the bytes queued for the transport, counted from the
    /// transport's first (empty until queued): the frame went out once
    /// [`Driver::written`](super::Driver::written) reaches its end, and none of it has
    /// while that is at most its start.
    pub(super) bytes: Range<u64>,
    pub(super) kind: PendingKind,
}

impl Pending {
    /// A request under a frame id, its frame not queued yet.
    pub(super) fn new(deadline: Instant, timeout: Duration, kind: PendingKind) -> Self {
        Pending {
            deadline,
            timeout,
            bytes: 0..0,
            kind,
        }
    }

    /// Whether none of its frame has gone out: it can still be taken back.
    pub(super) fn unsent(&self, written: u64) -> bool {
        !self.bytes.is_empty() && written <= self.bytes.start
    }

    /// What stays under its id once its caller has its timeout, or has gone, after its
    /// frame went out: the id, kept from new requests until the answer comes or
    /// [`LATE_ANSWER_WINDOW`] has passed, so that a late answer is never taken for a
    /// new request's. `None` for a request already in that state.
    pub(super) fn expired(&self, now: Instant) -> Option<Pending> {
        let (answer_type, single) = match &self.kind {
            PendingKind::Transmit { .. } | PendingKind::Request { .. } => {
                (Some(xbee_api::frame::frame_type::TRANSMIT_STATUS), true)
            }
            PendingKind::Frame { answer_type, .. } => (*answer_type, true),
            PendingKind::Answers { answer_type, .. } => (Some(*answer_type), false),
            PendingKind::Expired { .. } => return None,
        };
        // Answers from every radio keep coming to the end of their window (held that
        // long at most: a window may be an hour, or a disconnection cut it short).
        let from = if single {
            now
        } else {
            self.deadline
                .clamp(now, crate::options::later(now, LATE_ANSWER_WINDOW))
        };
        Some(Pending {
            deadline: crate::options::later(from, LATE_ANSWER_WINDOW),
            timeout: self.timeout,
            bytes: self.bytes.clone(),
            kind: PendingKind::Expired {
                answer_type,
                single,
            },
        })
    }
}

/// How long the frame id of a request that timed out after its frame went out is kept
/// from new requests, waiting for its late answer: a frame may wait in a serial
/// bridge's or the radio's buffers, and a radio takes seconds to report a failed
/// delivery.
pub(super) const LATE_ANSWER_WINDOW: Duration = Duration::from_secs(10);

#[derive(Debug)]
pub(super) enum PendingKind {
    Transmit {
        to: Address64,
        reply: oneshot::Sender<Result<DeliveryReport, SendError>>,
    },
    Request {
        to: Address64,
        waiter: u64,
    },
    Frame {
        reply: oneshot::Sender<Result<OwnedFrame, SendError>>,
        /// The frame type of its answer, when its request's type has a known one
        /// (0x88 for an AT command): a frame of another type under its id is none.
        answer_type: Option<u8>,
    },
    Answers {
        answers: AnswerSender,
        /// The frame type of its answers (0x88 for AT commands, 0x97 for remote ones).
        answer_type: u8,
        /// Answers dropped while [`ANSWERS_HELD`](super::ANSWERS_HELD) waited for the
        /// caller: the first is logged, the count when the window ends.
        dropped: u64,
    },
    /// A request whose caller has its timeout (or is gone), its frame sent: its late
    /// answer comes as an unclaimed frame ([`Pending::expired`]).
    Expired {
        /// The frame type of its answer (`None`: any).
        answer_type: Option<u8>,
        /// Whether one answer ends it (not so for answers from every radio).
        single: bool,
    },
}

impl PendingKind {
    /// Fails the request with `error`. A report request tells its caller nothing here:
    /// its report waiter does.
    pub(super) fn fail(self, error: SendError) {
        match self {
            PendingKind::Transmit { reply, .. } => {
                let _ = reply.send(Err(error));
            }
            PendingKind::Frame { reply, .. } => {
                let _ = reply.send(Err(error));
            }
            PendingKind::Answers { answers, .. } => fail_answers(&answers, error),
            PendingKind::Request { .. } | PendingKind::Expired { .. } => {}
        }
    }
}

#[derive(Debug)]
pub(super) struct Waiter {
    pub(super) id: u64,
    pub(super) from: Address64,
    /// The request, and which report answers it.
    pub(super) request: mcp_core::StatusRequest,
    pub(super) key: ReportKey,
    pub(super) deadline: Instant,
    pub(super) timeout: Duration,
    /// The radio confirmed delivery of the request (Transmit Status success).
    pub(super) delivered: bool,
    /// Frames dropped undecodable when the request was taken.
    pub(super) undecodable_before: u64,
    pub(super) reply: oneshot::Sender<Result<mcp_core::Report<Bytes>, RequestError>>,
}
