//! More readers of a link's events: [`Subscription`], from
//! [`CommandSender::subscribe`](crate::CommandSender::subscribe).

use std::pin::Pin;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::task::{Context, Poll};

use futures::stream::{BoxStream, StreamExt};
use tokio::sync::broadcast;

use crate::Event;

/// Every [`Event`] of a link from the moment it was taken, for a task other than the
/// one that reads the [`PacketStream`](crate::PacketStream): a user interface, a logger
/// and a mission script can each have one.
///
/// It holds up to [`LinkOptions::event_capacity`](crate::LinkOptions::event_capacity)
/// events for its reader. A reader that falls further behind misses the oldest ones and
/// goes on with the rest ([`missed`](Self::missed) counts them), and it never holds up
/// the link or the other readers. It ends after [`LinkEvent::Closed`](crate::LinkEvent),
/// or at once when taken from a link that has ended.
///
/// ```
/// # #[tokio::main(flavor = "current_thread")]
/// # async fn main() -> Result<(), Box<dyn std::error::Error>> {
/// use futures::StreamExt;
/// use mcp_host::{Event, Link, LinkEvent, LinkOptions};
///
/// let (_stream, sender) = mcp_host::connect(&Link::Pty, LinkOptions::default()).await?;
/// let mut log = sender.subscribe();
/// let logger = tokio::spawn(async move {
///     let mut seen = Vec::new();
///     while let Some(event) = log.next().await {
///         seen.push(event);
///     }
///     seen
/// });
/// sender.close();
/// let seen = logger.await?;
/// assert!(matches!(seen.last(), Some(Event::Link(LinkEvent::Closed { .. }))));
/// # Ok(())
/// # }
/// ```
pub struct Subscription {
    events: BoxStream<'static, Event>,
    missed: Arc<AtomicU64>,
}

impl Subscription {
    /// Reads what `receiver` gets, counting what it misses.
    pub(crate) fn new(receiver: Option<broadcast::Receiver<Event>>) -> Self {
        let missed = Arc::new(AtomicU64::new(0));
        let count = missed.clone();
        let events = futures::stream::unfold(receiver, move |receiver| {
            let count = count.clone();
            async move {
                let mut receiver = receiver?;
                loop {
                    match receiver.recv().await {
                        Ok(event) => return Some((event, Some(receiver))),
                        Err(broadcast::error::RecvError::Lagged(n)) => {
                            count.fetch_add(n, Ordering::Relaxed);
                        }
                        Err(broadcast::error::RecvError::Closed) => return None,
                    }
                }
            }
        })
        .boxed();
        Subscription { events, missed }
    }

    /// Events this reader missed by falling too far behind.
    pub fn missed(&self) -> u64 {
        self.missed.load(Ordering::Relaxed)
    }
}

impl std::fmt::Debug for Subscription {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Subscription")
            .field("missed", &self.missed())
            .finish_non_exhaustive()
    }
}

impl futures::Stream for Subscription {
    type Item = Event;

    fn poll_next(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Option<Event>> {
        self.events.poll_next_unpin(cx)
    }
}
