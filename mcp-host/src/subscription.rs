//! More readers of a link's events: [`Subscription`], from
//! [`CommandSender::subscribe`](crate::CommandSender::subscribe), and of its frames both
//! ways, from [`CommandSender::tap_frames`](crate::CommandSender::tap_frames).

use std::pin::Pin;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::task::{Context, Poll};

use futures::stream::{BoxStream, Fuse, FusedStream, StreamExt};
use tokio::sync::broadcast;

use crate::mutex::lock;
use crate::record::Record;
use crate::{Event, Received};

/// Every [`Event`] of a link from the moment it was taken, for a task other than the
/// one that reads the [`PacketStream`](crate::PacketStream): a user interface, a logger
/// and a mission script can each have one. A `Subscription<Record>` from
/// [`CommandSender::tap_frames`](crate::CommandSender::tap_frames) gives the link's
/// frames both ways instead, and behaves the same.
///
/// It holds at least [`LinkOptions::event_capacity`](crate::LinkOptions::event_capacity)
/// events for its reader (that, rounded up to a power of two). A reader that falls
/// further behind misses the oldest ones, link events among them (unlike the
/// [`PacketStream`](crate::PacketStream), which holds those back), and goes on with the
/// rest ([`missed`](Self::missed) counts them; read
/// [`CommandSender::link_state`](crate::CommandSender::link_state) after missing some);
/// it never holds up the link or the other readers. It ends after [`LinkEvent::Closed`](crate::LinkEvent::Closed) (whose reason says
/// when the link ended because its stream and every sender were dropped), or at once
/// when taken from a link that has ended.
///
/// It starts with the events that come after it was taken: a link that is up already
/// sent its [`LinkEvent::Connected`](crate::LinkEvent::Connected) before, so read
/// [`CommandSender::link_state`](crate::CommandSender::link_state) after subscribing
/// to know where the link is.
///
/// The channel behind the subscriptions is made when the first is taken: a link
/// without any costs nothing for them.
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
pub struct Subscription<T = Event> {
    /// In a mutex only to be `Sync`, as the link's other handles are: polling takes
    /// `&mut self`, which reaches the stream without locking.
    /// Fused: read again after its end, it gives `None` again.
    events: Mutex<Fuse<BoxStream<'static, T>>>,
    missed: Arc<AtomicU64>,
}

/// The subscriptions of one link, to its events and to its frames, shared by its driver
/// and its senders.
#[derive(Debug)]
pub(crate) struct Subscribers {
    capacity: usize,
    events: Mutex<State<Event>>,
    frames: Mutex<State<Record>>,
}

#[derive(Debug)]
enum State<T> {
    /// No subscription taken yet.
    Idle,
    Open(broadcast::Sender<T>),
    /// The link has ended: no more subscriptions, no more events.
    Ended,
}

impl<T: Clone + Send + 'static> State<T> {
    /// A new subscription, the channel made for the first.
    fn subscribe(&mut self, capacity: usize) -> Subscription<T> {
        let receiver = match &*self {
            State::Ended => None,
            State::Open(tx) => Some(tx.subscribe()),
            State::Idle => {
                let (tx, rx) = broadcast::channel(capacity);
                *self = State::Open(tx);
                Some(rx)
            }
        };
        Subscription::new(receiver)
    }

    /// Whether a subscription would get what is published now.
    fn wanted(&self) -> bool {
        matches!(self, State::Open(tx) if tx.receiver_count() > 0)
    }

    /// Hands what `make` makes to the subscriptions, if there are any (it is not made
    /// otherwise).
    fn publish(&self, make: impl FnOnce() -> T) {
        if let (true, State::Open(tx)) = (self.wanted(), self) {
            let _ = tx.send(make());
        }
    }
}

impl Subscribers {
    /// Subscriptions that hold `capacity` events for their readers.
    pub(crate) fn new(capacity: usize) -> Self {
        Subscribers {
            capacity,
            events: Mutex::new(State::Idle),
            frames: Mutex::new(State::Idle),
        }
    }

    /// A new subscription to the events.
    pub(crate) fn subscribe(&self) -> Subscription {
        lock(&self.events).subscribe(self.capacity)
    }

    /// A new subscription to the frames.
    pub(crate) fn tap_frames(&self) -> Subscription<Record> {
        lock(&self.frames).subscribe(self.capacity)
    }

    /// Hands `event` to the subscriptions, if there are any.
    pub(crate) fn publish(&self, event: &Event) {
        lock(&self.events).publish(|| event.clone());
    }

    /// Whether a subscription to the frames is there to take them.
    pub(crate) fn frames_wanted(&self) -> bool {
        lock(&self.frames).wanted()
    }

    /// Hands the record `make` makes to the subscriptions to the frames, if there are
    /// any (it is not made otherwise).
    pub(crate) fn publish_frame(&self, make: impl FnOnce() -> Record) {
        lock(&self.frames).publish(make);
    }

    /// The link has ended, with `last` its last event: the subscriptions end after it.
    pub(crate) fn end(&self, last: Option<&Event>) {
        if let Some(last) = last {
            self.publish(last);
        }
        *lock(&self.events) = State::Ended;
        *lock(&self.frames) = State::Ended;
    }
}

impl<T: Clone + Send + 'static> Subscription<T> {
    /// Reads what `receiver` gets, counting what it misses.
    pub(crate) fn new(receiver: Option<broadcast::Receiver<T>>) -> Self {
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
        .boxed()
        .fuse();
        Subscription {
            events: Mutex::new(events),
            missed,
        }
    }
}

impl<T: Send + 'static> Subscription<T> {
    /// What `f` makes of each item, where it makes something; what was missed before
    /// and after counts on.
    fn filter_map<U: Send + 'static>(
        self,
        mut f: impl FnMut(T) -> Option<U> + Send + 'static,
    ) -> Subscription<U> {
        let events = self
            .events
            .into_inner()
            .unwrap_or_else(PoisonError::into_inner)
            .filter_map(move |item| futures::future::ready(f(item)))
            .boxed()
            .fuse();
        Subscription {
            events: Mutex::new(events),
            missed: self.missed,
        }
    }
}

impl Subscription<Event> {
    /// The MCP packets alone ([`Event::Packet`]), from every radio. It ends with the
    /// link; [`missed`](Self::missed) counts every event missed, packets or not.
    pub fn packets(self) -> Subscription<Received> {
        self.filter_map(Event::into_packet)
    }

    /// The MCP packets from the radio `src64` alone: one MAV's telemetry and reports
    /// among many. It ends with the link; [`missed`](Self::missed) counts every event
    /// missed, whoever it came from. It holds no link events: a reader that must also
    /// see reconnections, in line with the packets, filters the whole subscription
    /// itself.
    ///
    /// ```
    /// # async fn run(sender: mcp_host::CommandSender) {
    /// use futures::StreamExt;
    /// use mcp_host::xbee_api::Address64;
    ///
    /// let mav = Address64(0x0013_A200_40B5_99B9);
    /// let mut from_mav = sender.subscribe().packets_from(mav);
    /// while let Some(rx) = from_mav.next().await {
    ///     assert_eq!(rx.origin.src64, mav);
    ///     println!("{}", rx.packet);
    /// }
    /// # }
    /// ```
    pub fn packets_from(self, src64: xbee_api::Address64) -> Subscription<Received> {
        self.filter_map(move |event| event.into_packet().filter(|rx| rx.origin.src64 == src64))
    }
}

impl<T> Subscription<T> {
    /// Events (or frames) this reader missed by falling too far behind.
    pub fn missed(&self) -> u64 {
        self.missed.load(Ordering::Relaxed)
    }
}

impl<T> std::fmt::Debug for Subscription<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Subscription")
            .field("missed", &self.missed())
            .finish_non_exhaustive()
    }
}

/// Read again after its end (in a `select!` loop, say), it ends again.
impl<T> FusedStream for Subscription<T> {
    fn is_terminated(&self) -> bool {
        lock(&self.events).is_terminated()
    }
}

impl<T> futures::Stream for Subscription<T> {
    type Item = T;

    fn poll_next(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Option<T>> {
        self.events
            .get_mut()
            .unwrap_or_else(PoisonError::into_inner)
            .poll_next_unpin(cx)
    }
}
