//! [`Answers`]: every answer to a request that many may answer.

use std::pin::Pin;
use std::task::{Context, Poll};

use futures::Stream;
use tokio::sync::mpsc;

use crate::error::SendError;
use crate::event::OwnedFrame;

/// The answers to one request, as they come: a [`Stream`] of the response frames of its
/// answer type (AT Command Response, 0x88, or Remote AT Command Response, 0x97) that
/// carry its frame id, from [`CommandSender::at_answers`](crate::CommandSender::at_answers)
/// or [`CommandSender::remote_at_answers`](crate::CommandSender::remote_at_answers).
///
/// It ends when the request's window is over. A link that goes down or closes meanwhile
/// ends it with one error ([`SendError::Disconnected`], [`SendError::Closed`]), as does a
/// request that could not be written or found no free frame id in its window. Dropping
/// it gives the frame id back at the next answer (or when a request finds none free);
/// answers that come after, and frames of other types under its id, are
/// [`Event::Frame`](crate::Event::Frame)s of the stream.
///
/// Answers are held for it, [`HELD`](Self::HELD) at most, while it is not read;
/// more are dropped (with a warning in the log).
#[derive(Debug)]
pub struct Answers {
    pub(crate) answers: mpsc::Receiver<Result<OwnedFrame, SendError>>,
    /// It has ended (given `None`): for [`FusedStream`](futures::stream::FusedStream).
    pub(crate) ended: bool,
}

impl Answers {
    /// How many answers are held while the stream is not read.
    pub const HELD: usize = crate::driver::ANSWERS_HELD;

    /// The next answer; `None` once the window is over.
    pub async fn next(&mut self) -> Option<Result<OwnedFrame, SendError>> {
        futures::StreamExt::next(self).await
    }
}

impl Stream for Answers {
    type Item = Result<OwnedFrame, SendError>;

    fn poll_next(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Option<Self::Item>> {
        let this = &mut *self;
        crate::poll_fused(&mut this.answers, &mut this.ended, cx)
    }
}

/// Read again after its end (in a `select!` loop, say), it ends again; terminated once
/// it has given `None`, not with its last answer.
impl futures::stream::FusedStream for Answers {
    fn is_terminated(&self) -> bool {
        self.ended
    }
}
