//! What the link's senders ask its driver to do ([`Op`]), and how one it cannot carry
//! out is refused.

use std::time::Duration;

use bytes::Bytes;
use tokio::sync::{mpsc, oneshot};
use tokio::time::Instant;
use xbee_api::Address64;

use crate::error::{RequestError, SendError};
use crate::event::OwnedFrame;
use crate::sender::DeliveryReport;

/// A request from a [`crate::CommandSender`] to the background task.
#[derive(Debug)]
pub(crate) enum Op {
    Transmit {
        to: Address64,
        payload: Bytes,
        with_status: bool,
        deadline: Instant,
        timeout: Duration,
        reply: oneshot::Sender<Result<DeliveryReport, SendError>>,
    },
    Request {
        to: Address64,
        payload: Bytes,
        request: mcp_core::StatusRequest,
        deadline: Instant,
        timeout: Duration,
        reply: oneshot::Sender<Result<mcp_core::Report<Bytes>, RequestError>>,
    },
    Frame {
        data: Bytes,
        deadline: Instant,
        timeout: Duration,
        reply: oneshot::Sender<Result<OwnedFrame, SendError>>,
    },
    Write {
        data: Bytes,
        /// For [`write_frame`](crate::CommandSender::write_frame): when its caller stops
        /// waiting, and its timeout; a write not taken by then is not written. `None`
        /// for a sink's packets, which are handed over.
        deadline: Option<(Instant, Duration)>,
        reply: oneshot::Sender<Result<(), SendError>>,
    },
    /// A frame whose answers are gathered until the deadline, not just the first.
    Answers {
        data: Bytes,
        deadline: Instant,
        timeout: Duration,
        answers: AnswerSender,
    },
}

/// Where the answers of an [`Op::Answers`] go, with the error that ends them early.
pub(crate) type AnswerSender = mpsc::Sender<Result<OwnedFrame, SendError>>;

/// Answers to one request held for its caller at most ([`crate::Answers`]); later
/// ones are dropped until the caller takes some. One more place is kept for the error
/// that may end them.
pub(crate) const ANSWERS_HELD: usize = 256;

/// Ends the answers of `answers` with `error` (the place for it is kept free).
pub(super) fn fail_answers(answers: &AnswerSender, error: SendError) {
    let _ = answers.try_send(Err(error));
}

impl Op {
    /// Whether the request needs a frame id of its own (it awaits a status or response).
    pub(crate) fn needs_id(&self) -> bool {
        match self {
            Op::Transmit { with_status, .. } => *with_status,
            Op::Request { .. } | Op::Frame { .. } | Op::Answers { .. } => true,
            Op::Write { .. } => false,
        }
    }

    /// When the request times out (`None` for a sink's writes, which do not wait).
    pub(super) fn deadline(&self) -> Option<Instant> {
        match self {
            Op::Transmit { deadline, .. }
            | Op::Request { deadline, .. }
            | Op::Frame { deadline, .. }
            | Op::Answers { deadline, .. } => Some(*deadline),
            Op::Write { deadline, .. } => deadline.map(|(at, _)| at),
        }
    }

    /// Whether the caller stopped waiting for the answer (a raw write is written all the
    /// same).
    pub(super) fn caller_gone(&self) -> bool {
        match self {
            Op::Transmit { reply, .. } => reply.is_closed(),
            Op::Request { reply, .. } => reply.is_closed(),
            Op::Frame { reply, .. } => reply.is_closed(),
            Op::Answers { answers, .. } => answers.is_closed(),
            Op::Write { .. } => false,
        }
    }

    /// Answers a request that timed out before it was sent: if `parked`, it waited
    /// for a frame id ([`SendError::NoFreeFrameId`]); else its deadline had passed when
    /// it was taken ([`SendError::NotSent`]). Whether its caller was there to be told
    /// (the timeouts counted are those).
    pub(super) fn time_out(self, parked: bool) -> bool {
        let error = |timeout| {
            if parked {
                SendError::NoFreeFrameId { timeout }
            } else {
                SendError::NotSent { timeout }
            }
        };
        match self {
            Op::Transmit { timeout, reply, .. } => reply.send(Err(error(timeout))).is_ok(),
            Op::Request { timeout, reply, .. } => reply.send(Err(error(timeout).into())).is_ok(),
            Op::Frame { timeout, reply, .. } => reply.send(Err(error(timeout))).is_ok(),
            Op::Answers {
                timeout, answers, ..
            } => answers.try_send(Err(error(timeout))).is_ok(),
            // Never parked: it needs no frame id.
            Op::Write {
                deadline, reply, ..
            } => {
                let timeout = deadline.map_or(Duration::ZERO, |(_, timeout)| timeout);
                reply.send(Err(SendError::NotSent { timeout })).is_ok()
            }
        }
    }
}

/// Answers a request made while the transport is down.
pub(super) fn refuse(op: Op, why: &str) {
    let error = SendError::Disconnected {
        reason: why.to_owned(),
    };
    match op {
        Op::Transmit { reply, .. } => {
            let _ = reply.send(Err(error));
        }
        Op::Request { reply, .. } => {
            let _ = reply.send(Err(error.into()));
        }
        Op::Frame { reply, .. } => {
            let _ = reply.send(Err(error));
        }
        Op::Write { reply, .. } => {
            let _ = reply.send(Err(error));
        }
        Op::Answers { answers, .. } => fail_answers(&answers, error),
    }
}

pub(super) fn refuse_closed(op: Op) {
    match op {
        Op::Transmit { reply, .. } => {
            let _ = reply.send(Err(SendError::Closed));
        }
        Op::Request { reply, .. } => {
            let _ = reply.send(Err(SendError::Closed.into()));
        }
        Op::Frame { reply, .. } => {
            let _ = reply.send(Err(SendError::Closed));
        }
        Op::Write { reply, .. } => {
            let _ = reply.send(Err(SendError::Closed));
        }
        Op::Answers { answers, .. } => fail_answers(&answers, SendError::Closed),
    }
}
