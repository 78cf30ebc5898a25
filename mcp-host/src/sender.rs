//! [`CommandSender`]: sends MCP packets and XBee frames, awaits their answers.

use std::sync::Arc;
use std::time::Duration;

use bytes::Bytes;
use tokio::sync::{mpsc, oneshot, watch};
use tokio::time::Instant;
use xbee_api::frame::frame_type::carries_frame_id;
use xbee_api::{Address16, Address64, DiscoveryStatus};

use crate::LinkInfo;
use crate::answers::Answers;
use crate::discovery::{DiscoverError, Discovery};
use crate::driver::Op;
use crate::error::{RequestError, SendError};
use crate::event::{LinkState, OwnedFrame};
use crate::stats::{Counters, Stats};

/// How long a caller waits past its deadline for the background task's answer.
const GRACE: Duration = Duration::from_millis(500);

/// Whether a transmission asks the radio for a Transmit Status.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum FrameId {
    /// Allocate a frame id (1..=255) and await the radio's Transmit Status.
    #[default]
    Auto,
    /// Frame id 0: fire and forget, the radio sends no status.
    None,
}

/// Per-call options of [`CommandSender::send_with`], [`CommandSender::send_packet`] and
/// [`CommandSender::send_payload`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SendOptions {
    /// How long to wait for the status; `None` uses the link's
    /// [`crate::LinkOptions::send_timeout`].
    pub timeout: Option<Duration>,
    /// Frame id allocation.
    pub frame_id: FrameId,
}

/// How a transmission went, as far as the local radio knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum DeliveryReport {
    /// The radio reported success in its Transmit Status (0x8B, status 0x00).
    #[non_exhaustive]
    Delivered {
        /// The frame id used.
        frame_id: u8,
        /// The destination's 16-bit address as the radio resolved it.
        dst16: Address16,
        /// Transmit retries.
        retries: u8,
        /// Route discovery overhead.
        discovery: DiscoveryStatus,
    },
    /// Sent with frame id 0: queued for the transport, no status asked for. A
    /// disconnection before the bytes leave loses it silently; [`CommandSender::close`]
    /// writes it out first (waiting at most a second for the transport).
    Written,
}

/// `delivered (16-bit address 7d84, frame id 1, retries 0, discovery
/// no_discovery_overhead)`, or `written (frame id 0: no status asked for)`.
///
/// ```
/// use mcp_host::DeliveryReport;
/// assert_eq!(DeliveryReport::Written.to_string(), "written (frame id 0: no status asked for)");
/// ```
impl std::fmt::Display for DeliveryReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DeliveryReport::Delivered {
                frame_id,
                dst16,
                retries,
                discovery,
            } => write!(
                f,
                "delivered (16-bit address {dst16}, frame id {frame_id}, retries {retries}, \
                 discovery {discovery})"
            ),
            DeliveryReport::Written => f.write_str("written (frame id 0: no status asked for)"),
        }
    }
}

/// Sends MCP packets and XBee frames over a link. Cheap to clone; usable from many tasks
/// at once.
///
/// Waiting times are given one way throughout: a `timeout: Option<Duration>` (for a
/// transmission, in [`SendOptions`]) is how long to wait for the answer (for a
/// transmission without a frame id, [`FrameId::None`], only for the link to take it),
/// `None` taking the link's [`send_timeout`](crate::LinkOptions::send_timeout). A `window` is another
/// thing: how long answers from many radios are gathered ([`at_answers`](Self::at_answers),
/// [`discover`](Self::discover), whose `None` is the radio's own discovery time).
/// [`send_frame`](Self::send_frame) waits for the answer under the frame's id;
/// [`write_frame`](Self::write_frame) for none, only until the link has the frame.
///
/// Every request waits at most its timeout (and half a second's grace for the background
/// task's answer) and fails with a clear [`SendError`] (inside the [`RequestError`],
/// [`ConfirmError`](crate::ConfirmError) or [`DiscoverError`] of the methods that return
/// those) when the link goes down while the request is in flight, or is down when it is
/// made. Waits
/// that are not one request's: [`closed`](Self::closed) waits for the link's end;
/// [`send_confirmed`](Self::send_confirmed) and the trajectories send and wait in steps,
/// each within the timeout; a [`PacketSink`](crate::PacketSink) waits while the link is
/// down, and goes on once it is back.
///
/// Dropping a method's future before it resolves (in a `tokio::time::timeout`, a
/// `select!`, a task aborted) does not take the request back at once: once queued, its
/// frame may still go out. While requests wait for a frame id (none free), the dropped
/// ones are looked for at every turn of the link's task: a dropped request whose frame
/// has not gone out yet is taken back (none of it is sent), one still waiting for an id
/// is dropped unsent, and the frame id of one whose frame went out is kept until its
/// late answer comes (as an [`Event::Frame`](crate::Event::Frame)) or for 10 s after its
/// own deadline (or the end of its window, for a request every radio answers), so that
/// no answer is taken for another request's. Otherwise a dropped request keeps its id
/// to its deadline and those 10 s (22 s with the default timeout). A request that times
/// out, or fails with the link, goes the same way; after a reconnection, the ids of the
/// requests in flight at the disconnection are kept the same 10 s, so a burst of
/// requests right then may find none free ([`SendError::NoFreeFrameId`]).
///
/// A request the link's task has not taken by its deadline (its writes backed up by a
/// radio that takes no bytes, or requests waiting for an id beyond what it holds) is
/// never sent: it fails with [`SendError::Timeout`] without a frame id (which a task
/// merely running late gives too: whether the frame went out is then not known), and
/// [`write_frame`](Self::write_frame) with [`SendError::NotSent`].
/// [`Stats::timeouts`](crate::Stats::timeouts) counts the timeouts callers were told
/// of. The link ends (its transport closed) once its stream and every sender and
/// sink are dropped, even with writes backed up; an [`Answers`] stream still open then
/// ends with [`SendError::Closed`].
#[derive(Debug, Clone)]
pub struct CommandSender {
    /// Requests that need a frame id.
    pub(crate) ops: mpsc::Sender<Op>,
    /// Requests that need none, which go out while those wait for one.
    pub(crate) writes: mpsc::Sender<Op>,
    /// Held, never sent on, by every handle that can send: closed once they are all
    /// dropped.
    pub(crate) alive: mpsc::Sender<()>,
    pub(crate) default_timeout: Duration,
    pub(crate) counters: Arc<Counters>,
    pub(crate) info: Arc<LinkInfo>,
    pub(crate) close_requested: Arc<crate::driver::CloseRequest>,
    pub(crate) state: watch::Receiver<LinkState>,
    /// Where [`subscribe`](Self::subscribe) takes its subscriptions.
    pub(crate) subscribers: Arc<crate::subscription::Subscribers>,
}

impl CommandSender {
    /// Sends an MCP command to `to` (16-bit address FFFE, radius 0, options 0) and waits
    /// for the radio's delivery status.
    ///
    /// Fails with [`SendError::Delivery`] when the radio reports that delivery failed,
    /// [`SendError::Timeout`] when no status came within the link's
    /// [`send_timeout`](crate::LinkOptions::send_timeout), [`SendError::TooLarge`] for a
    /// command that does not fit a frame, and [`SendError::Disconnected`] or
    /// [`SendError::Closed`] when the link is down or closed.
    pub async fn send<B: AsRef<[u8]>>(
        &self,
        to: Address64,
        command: &mcp_core::Command<B>,
    ) -> Result<DeliveryReport, SendError> {
        self.send_with(to, command, SendOptions::default()).await
    }

    /// [`CommandSender::send`] with a per-call timeout or frame id 0.
    ///
    /// ```no_run
    /// # async fn run(sender: mcp_host::CommandSender) -> Result<(), Box<dyn std::error::Error>> {
    /// use std::time::Duration;
    /// use mcp_host::mcp_core::Command;
    /// use mcp_host::{DeliveryReport, FrameId, SendError, SendOptions};
    ///
    /// let mav = "0013A20040B599B9".parse()?;
    /// let land: Command<&[u8]> = Command::Landing { on: true };
    /// // The radio's Transmit Status within 2 s, rather than the link's send timeout.
    /// let quick = SendOptions {
    ///     timeout: Some(Duration::from_secs(2)),
    ///     ..SendOptions::default()
    /// };
    /// match sender.send_with(mav, &land, quick).await {
    ///     Ok(DeliveryReport::Delivered { retries, .. }) => println!("delivered ({retries} retries)"),
    ///     Err(SendError::Delivery { status, .. }) => println!("not delivered: {status}"),
    ///     Err(SendError::Timeout { .. }) => println!("no status from the radio in 2 s"),
    ///     other => println!("{other:?}"),
    /// }
    /// // Fire and forget: frame id 0, no status asked for; done once queued.
    /// let forget = SendOptions {
    ///     frame_id: FrameId::None,
    ///     ..SendOptions::default()
    /// };
    /// assert_eq!(sender.send_with(mav, &land, forget).await?, DeliveryReport::Written);
    /// # Ok(())
    /// # }
    /// ```
    pub async fn send_with<B: AsRef<[u8]>>(
        &self,
        to: Address64,
        command: &mcp_core::Command<B>,
        options: SendOptions,
    ) -> Result<DeliveryReport, SendError> {
        let payload = encode_command(command)?;
        self.send_payload(to, payload, options).await
    }

    /// Sends any MCP packet (command, report, telemetry, message, warning).
    pub async fn send_packet<B: AsRef<[u8]>>(
        &self,
        to: Address64,
        packet: &mcp_core::Packet<B>,
        options: SendOptions,
    ) -> Result<DeliveryReport, SendError> {
        self.send_payload(to, encode_packet(packet)?, options).await
    }

    /// Sends a trajectory set command of `waypoints` (at most 15 fit the 255-byte
    /// payload; the deployed MAV takes at most 2, its receive buffer being 60 bytes) and
    /// waits for the radio's delivery status. The MAV answers with a trajectory report,
    /// which comes on the [`PacketStream`](crate::PacketStream).
    ///
    /// ```no_run
    /// # async fn run(sender: mcp_host::CommandSender) -> Result<(), Box<dyn std::error::Error>> {
    /// use mcp_host::mcp_core::Waypoint;
    /// let mav = "0013A20040B599B9".parse()?;
    /// let waypoint = Waypoint { time: 1_700_000_000, elevator: 0.5, aileron: 0.0, altitude: 1.2 };
    /// sender.send_trajectory(mav, &[waypoint]).await?;
    /// # Ok(())
    /// # }
    /// ```
    pub async fn send_trajectory(
        &self,
        to: Address64,
        waypoints: &[mcp_core::Waypoint],
    ) -> Result<DeliveryReport, SendError> {
        let too_large = || SendError::TooLarge {
            len: mcp_core::Waypoint::packet_len(waypoints.len()),
            max: mcp_core::MAX_PAYLOAD,
        };
        let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
        let mut builder =
            mcp_core::TrajectoryBuilder::command(&mut buf).map_err(|_| too_large())?;
        for &waypoint in waypoints {
            builder.push(waypoint).map_err(|_| too_large())?;
        }
        let len = builder.finish();
        self.send_payload(
            to,
            Bytes::copy_from_slice(&buf[..len]),
            SendOptions::default(),
        )
        .await
    }

    /// Sends raw payload bytes in a Transmit Request (no MCP validation).
    pub async fn send_payload(
        &self,
        to: Address64,
        payload: impl Into<Bytes>,
        options: SendOptions,
    ) -> Result<DeliveryReport, SendError> {
        let payload = payload.into();
        if payload.len() > mcp_core::MAX_PAYLOAD {
            return Err(SendError::TooLarge {
                len: payload.len(),
                max: mcp_core::MAX_PAYLOAD,
            });
        }
        let timeout = options.timeout.unwrap_or(self.default_timeout);
        let deadline = crate::options::later(Instant::now(), timeout);
        let (reply, answer) = oneshot::channel();
        let op = Op::Transmit {
            to,
            payload,
            with_status: options.frame_id == FrameId::Auto,
            deadline,
            timeout,
            reply,
        };
        self.call(op, answer, deadline, timeout).await
    }

    /// Sends a status request to `to` and resolves with the matching report from that
    /// address (for telemetry to coordinator, the report on the same telemetry id), or a
    /// timeout. To [`Address64::BROADCAST`], the first matching report from anyone.
    ///
    /// Reports are matched inside the background task: this works whether or not the
    /// [`crate::PacketStream`] is read. The report also appears on the stream and to
    /// every [`Subscription`](crate::Subscription), handed to them before this
    /// resolves: a subscription taken after it resolved starts after the report. Any
    /// report of the matching kind from `to` that arrives after the request is sent
    /// answers it, so one the MAV sent by itself just before it got the request (the
    /// report that follows a trajectory set or a landing change) may be the answer; it
    /// carries the same state. MCP carries no request id: through a hub, a report that
    /// answers another program's request of the same kind to the same MAV answers this
    /// one too, even if this request itself was lost on its way.
    pub async fn request(
        &self,
        to: Address64,
        request: mcp_core::StatusRequest,
    ) -> Result<mcp_core::Report<Bytes>, RequestError> {
        self.request_with(to, request, None).await
    }

    /// [`CommandSender::request`] with a timeout (`None`: the link's default).
    pub async fn request_with(
        &self,
        to: Address64,
        request: mcp_core::StatusRequest,
        timeout: Option<Duration>,
    ) -> Result<mcp_core::Report<Bytes>, RequestError> {
        let command: mcp_core::Command<&[u8]> = mcp_core::Command::StatusRequest(request);
        let payload = encode_command(&command)?;
        let timeout = timeout.unwrap_or(self.default_timeout);
        let deadline = crate::options::later(Instant::now(), timeout);
        let (reply, answer) = oneshot::channel();
        let op = Op::Request {
            to,
            payload,
            request,
            deadline,
            timeout,
            reply,
        };
        let exchange = async {
            self.enqueue(op, deadline, timeout).await?;
            // As in `call`.
            match tokio::time::timeout_at(deadline + GRACE, answer).await {
                Ok(Ok(result)) => result,
                Ok(Err(_)) => Err(SendError::Closed.into()),
                Err(_) => Err(self.unanswered(timeout).into()),
            }
        };
        exchange.await
    }

    /// Sends any XBee frame that carries a frame id (AT command 0x08, remote AT command
    /// 0x17, Transmit Request 0x10, the 802.15.4 Transmit Requests 0x00 and 0x01, ...)
    /// and resolves with the response frame that carries the same frame id (0x88, 0x97,
    /// 0x8B, 0x89, ...). A frame of another type under that id
    /// is no answer (it goes to the stream as any other) when the request's type has a
    /// known answer type; for another request type, the first frame under the id is.
    ///
    /// `frame_data` is the frame data, frame type first; its frame id byte (the second
    /// byte) is replaced by the allocated id. Refused before anything is sent: empty
    /// ([`SendError::EmptyFrame`]), of a type not known to carry a frame id
    /// ([`SendError::NoFrameId`]), or its frame type alone
    /// ([`SendError::NoFrameIdByte`]).
    pub async fn send_frame(
        &self,
        frame_data: &[u8],
        timeout: Option<Duration>,
    ) -> Result<OwnedFrame, SendError> {
        let frame_type = *frame_data.first().ok_or(SendError::EmptyFrame)?;
        if !carries_frame_id(frame_type) {
            return Err(SendError::NoFrameId(frame_type));
        }
        if frame_data.len() < 2 {
            return Err(SendError::NoFrameIdByte(frame_type));
        }
        let timeout = timeout.unwrap_or(self.default_timeout);
        let deadline = crate::options::later(Instant::now(), timeout);
        let (reply, answer) = oneshot::channel();
        let op = Op::Frame {
            data: Bytes::copy_from_slice(frame_data),
            deadline,
            timeout,
            reply,
        };
        self.call(op, answer, deadline, timeout).await
    }

    /// Writes any XBee frame as given (frame data, frame type first), awaiting nothing
    /// but its being taken: within the link's
    /// [`send_timeout`](crate::LinkOptions::send_timeout), or it fails with
    /// [`SendError::NotSent`] and is never written.
    pub async fn write_frame(&self, frame_data: &[u8]) -> Result<(), SendError> {
        let deadline = crate::options::later(Instant::now(), self.default_timeout);
        self.write_frame_until(frame_data, deadline).await
    }

    /// [`write_frame`](Self::write_frame), taken by `deadline` or never written.
    pub(crate) async fn write_frame_until(
        &self,
        frame_data: &[u8],
        deadline: Instant,
    ) -> Result<(), SendError> {
        let timeout = deadline.saturating_duration_since(Instant::now());
        let (reply, answer) = oneshot::channel();
        let op = Op::Write {
            data: Bytes::copy_from_slice(frame_data),
            deadline: Some((deadline, timeout)),
            reply,
        };
        self.call(op, answer, deadline, timeout).await
    }

    /// Sends a local AT command (0x08) and resolves with its AT Command Response (0x88),
    /// whatever the status the radio answered: parse it and test the status with
    /// [`AtStatus::is_ok`](xbee_api::AtStatus::is_ok).
    ///
    /// ```no_run
    /// # async fn run(sender: mcp_host::CommandSender) -> Result<(), Box<dyn std::error::Error>> {
    /// use mcp_host::xbee_api::Frame;
    /// let response = sender.at(*b"AP", &[], None).await?;
    /// if let Ok(Frame::AtCommandResponse(at)) = response.parse() {
    ///     if at.status.is_ok() {
    ///         println!("API mode {:?}", at.data);
    ///     }
    /// }
    /// # Ok(())
    /// # }
    /// ```
    pub async fn at(
        &self,
        command: [u8; 2],
        parameter: &[u8],
        timeout: Option<Duration>,
    ) -> Result<OwnedFrame, SendError> {
        self.local_at(false, command, parameter, timeout).await
    }

    /// Sends a local AT command to be queued (AT Command - Queue Parameter Value, 0x09)
    /// and resolves with its AT Command Response (0x88), as [`at`](Self::at). A value set
    /// this way waits until an `AC` command (or the next 0x08 frame) applies the queued
    /// values together, as when changing the radio's channel and PAN ID at once.
    ///
    /// ```no_run
    /// # async fn run(sender: mcp_host::CommandSender) -> Result<(), Box<dyn std::error::Error>> {
    /// sender.at_queued(*b"ID", &[0x12, 0x34], None).await?;
    /// sender.at_queued(*b"CH", &[0x0C], None).await?;
    /// sender.at(*b"AC", &[], None).await?; // both take effect now
    /// # Ok(())
    /// # }
    /// ```
    pub async fn at_queued(
        &self,
        command: [u8; 2],
        parameter: &[u8],
        timeout: Option<Duration>,
    ) -> Result<OwnedFrame, SendError> {
        self.local_at(true, command, parameter, timeout).await
    }

    /// A local AT command, 0x09 if `queued`, else 0x08.
    async fn local_at(
        &self,
        queued: bool,
        command: [u8; 2],
        parameter: &[u8],
        timeout: Option<Duration>,
    ) -> Result<OwnedFrame, SendError> {
        let frame = xbee_api::AtCommandRepr {
            queued,
            frame_id: 0,
            command,
            parameter,
        };
        let data = frame_data(&frame)?;
        self.send_frame(&data, timeout).await
    }

    /// Sends a remote AT command (0x17) to `to` and resolves with its Remote AT Command
    /// Response (0x97), whatever its status (as [`at`](Self::at)). `apply` sets the
    /// apply-changes option (0x02).
    pub async fn remote_at(
        &self,
        to: Address64,
        command: [u8; 2],
        parameter: &[u8],
        apply: bool,
        timeout: Option<Duration>,
    ) -> Result<OwnedFrame, SendError> {
        let data = remote_at_frame(to, command, parameter, apply)?;
        self.send_frame(&data, timeout).await
    }

    /// Sends a local AT command (0x08) that many may answer, and gathers every AT
    /// Command Response (0x88) to it for `window`: node discovery (`ND`, one answer per
    /// radio that heard it, until the radio's `NT`) and active scan (`AS`). See
    /// [`discover`](Self::discover) for the nodes of `ND` read out.
    ///
    /// Resolves once the request is queued; the [`Answers`] stream then gives each
    /// answer as it comes and ends with the window.
    ///
    /// ```no_run
    /// # async fn run(sender: mcp_host::CommandSender) -> Result<(), Box<dyn std::error::Error>> {
    /// use std::time::Duration;
    /// // `Answers` is a `Stream` too; its own `next` needs no `StreamExt`.
    /// let mut answers = sender.at_answers(*b"ND", &[], Duration::from_secs(7)).await?;
    /// while let Some(answer) = answers.next().await {
    ///     println!("{:02x?}", answer?.data());
    /// }
    /// # Ok(())
    /// # }
    /// ```
    pub async fn at_answers(
        &self,
        command: [u8; 2],
        parameter: &[u8],
        window: Duration,
    ) -> Result<Answers, SendError> {
        let frame = xbee_api::AtCommandRepr {
            queued: false,
            frame_id: 0,
            command,
            parameter,
        };
        self.answers(&frame_data(&frame)?, window).await
    }

    /// Sends a Remote AT Command (0x17) that many may answer, and gathers every Remote
    /// AT Command Response (0x97) to it for `window`: to
    /// [`Address64::BROADCAST`](xbee_api::Address64::BROADCAST), every radio in range
    /// carries it out; DigiMesh and 802.15.4 radios each answer, with their own address,
    /// but a Zigbee radio hands over a single answer. `apply` as for
    /// [`remote_at`](Self::remote_at).
    ///
    /// ```no_run
    /// # async fn run(sender: mcp_host::CommandSender) -> Result<(), Box<dyn std::error::Error>> {
    /// use std::time::Duration;
    /// use mcp_host::xbee_api::{Address64, Frame};
    /// let to = Address64::BROADCAST;
    /// let mut answers = sender.remote_at_answers(to, *b"VR", &[], true, Duration::from_secs(3)).await?;
    /// while let Some(answer) = answers.next().await {
    ///     if let Ok(Frame::RemoteAtResponse(vr)) = answer?.parse() {
    ///         println!("{}: {:02x?}", vr.src64, vr.data);
    ///     }
    /// }
    /// # Ok(())
    /// # }
    /// ```
    pub async fn remote_at_answers(
        &self,
        to: Address64,
        command: [u8; 2],
        parameter: &[u8],
        apply: bool,
        window: Duration,
    ) -> Result<Answers, SendError> {
        let data = remote_at_frame(to, command, parameter, apply)?;
        self.answers(&data, window).await
    }

    /// Queues the request `data` (a frame id at byte 1) whose answers are gathered for
    /// `window`.
    async fn answers(&self, data: &[u8], window: Duration) -> Result<Answers, SendError> {
        let data = Bytes::copy_from_slice(data);
        let deadline = crate::options::later(Instant::now(), window);
        let (answers, receiver) = mpsc::channel(crate::driver::ANSWERS_HELD + 1);
        let op = Op::Answers {
            data,
            deadline,
            timeout: window,
            answers,
        };
        self.enqueue(op, deadline, window).await?;
        Ok(Answers {
            answers: receiver,
            ended: false,
        })
    }

    /// Node discovery: the radios the local one can reach, each once, in the order
    /// they answered. Sends `ND` and gathers the answers for `window`; `None` waits as
    /// long as the radio's discovery time says
    /// ([`discovery::window`](crate::discovery::window)). The local radio is not among
    /// them, unless its `NO` has it answer for itself. Answers are read as Zigbee and
    /// DigiMesh radios give them; one that cannot be read is left out and counted.
    ///
    /// It returns when the window ends, however soon the radios answered: with `NT`
    /// at Digi's default that is 7 s (the simulator's radios keep that default too). To
    /// act on each radio as it answers, or to stop at the one looked for, read the
    /// answers to `ND` as they come with [`at_answers`](Self::at_answers) and
    /// [`NodeInfo::parse`](xbee_api::NodeInfo::parse).
    ///
    /// Dropping its future before the window ends drops the answers gathered so far;
    /// its frame id goes as any dropped request's does (see [`CommandSender`]).
    ///
    /// ```no_run
    /// # async fn run(sender: mcp_host::CommandSender) -> Result<(), Box<dyn std::error::Error>> {
    /// for node in sender.discover(None).await?.nodes {
    ///     println!("{node}"); // 0013a20040000002 (7d84) router "MAV 1"
    /// }
    /// # Ok(())
    /// # }
    /// ```
    pub async fn discover(&self, window: Option<Duration>) -> Result<Discovery, DiscoverError> {
        crate::discovery::discover(self, window).await
    }

    /// Hands `op` to the link's task, waiting for room in its queue until `deadline`.
    /// A request whose `timeout` ran out meanwhile is not sent
    /// ([`SendError::NotSent`]), and counted with the timeouts, as one the link's task
    /// finds expired is.
    async fn enqueue(&self, op: Op, deadline: Instant, timeout: Duration) -> Result<(), SendError> {
        // Refused at once after `close`, before the link's task may have seen it.
        if self.close_requested.asked() {
            return Err(SendError::Closed);
        }
        match tokio::time::timeout_at(deadline, self.queue(&op).send(op)).await {
            Ok(Ok(())) => Ok(()),
            Ok(Err(_)) => Err(SendError::Closed),
            Err(_) => {
                crate::stats::bump(&self.counters.timeouts);
                Err(SendError::NotSent { timeout })
            }
        }
    }

    /// A [`Sink`](futures::Sink) of MCP packets to this link, each item `(to, packet)`
    /// sent without a transmit status (frame id 0), in order: for feeding a stream of
    /// packets to the radio (see [`PacketSink`](crate::PacketSink)).
    pub fn packet_sink<B: AsRef<[u8]>>(&self) -> crate::PacketSink<B> {
        crate::PacketSink::new(
            self.writes.clone(),
            self.alive.clone(),
            self.state.clone(),
            self.close_requested.clone(),
        )
    }

    /// The link's counters.
    pub fn stats(&self) -> Stats {
        self.counters.snapshot()
    }

    /// What the link is connected to.
    pub fn info(&self) -> &LinkInfo {
        &self.info
    }

    /// What the link's counters since `earlier` say may be wrong with the radio's
    /// settings, read in the link's API mode, as
    /// [`PacketStream::diagnose`](crate::PacketStream::diagnose) says.
    ///
    /// ```no_run
    /// # async fn run(sender: mcp_host::CommandSender) {
    /// let before = sender.stats();
    /// if sender.at(*b"NI", &[], None).await.is_err() {
    ///     if let Some(found) = sender.diagnose(&before) {
    ///         eprintln!("no answer: {found}");
    ///     }
    /// }
    /// # }
    /// ```
    pub fn diagnose(&self, earlier: &Stats) -> Option<crate::Diagnosis> {
        self.info.diagnose(&self.stats().since(earlier))
    }

    /// Ends the link for good, for every holder of it: the transport (serial port,
    /// socket, pseudo-terminal) is closed, requests in flight and later ones fail, and
    /// the [`PacketStream`](crate::PacketStream) yields
    /// [`LinkEvent::Closed`](crate::LinkEvent::Closed) and ends. Returns at once.
    ///
    /// Requests in flight fail as in any disconnection, with [`SendError::Disconnected`]
    /// (reason `closed by the application`): they may have gone out. Later ones fail with
    /// [`SendError::Closed`] at once, also before the link's task has seen the request,
    /// and so do a [`PacketSink`](crate::PacketSink)'s packets.
    ///
    /// The transport is closed before that event, so once the stream has yielded it (or
    /// ended) the same device can be opened again at once: a serial port is opened for
    /// exclusive use, and merely dropping the handles closes it a moment later, in the
    /// background.
    ///
    /// ```no_run
    /// # async fn f() -> Result<(), Box<dyn std::error::Error>> {
    /// use futures::StreamExt;
    /// use mcp_host::{Link, LinkOptions};
    ///
    /// let link: Link = "serial:/dev/ttyUSB0:115200".parse()?;
    /// let (mut stream, sender) = mcp_host::connect(&link, LinkOptions::default()).await?;
    /// // ... use the link, then hand the port to someone else:
    /// sender.close();
    /// while stream.next().await.is_some() {}
    /// let (_stream, _sender) = mcp_host::connect(&link, LinkOptions::default()).await?;
    /// # Ok(())
    /// # }
    /// ```
    pub fn close(&self) {
        self.close_requested.ask();
    }

    /// Where the link is now.
    pub fn link_state(&self) -> LinkState {
        *self.state.borrow()
    }

    /// The link's state as it changes: await a change, or a state, without reading the
    /// [`PacketStream`](crate::PacketStream).
    ///
    /// A watch holds the latest state only: a link that goes down and comes back between
    /// two looks shows no change. What must see every reconnection (to turn a MAV's
    /// telemetry on again, say) reads the [`LinkEvent`](crate::LinkEvent)s, on the stream
    /// or a [`subscribe`](Self::subscribe)r, or compares
    /// [`Stats::reconnects`](crate::Stats::reconnects).
    ///
    /// ```
    /// # #[tokio::main(flavor = "current_thread")]
    /// # async fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use mcp_host::{Link, LinkOptions, LinkState};
    ///
    /// let link: Link = "tcp-listen:127.0.0.1:0".parse()?;
    /// let (stream, sender) = mcp_host::connect(&link, LinkOptions::default()).await?;
    /// let addr = stream.info().local_addr.unwrap();
    /// let _radio = tokio::net::TcpStream::connect(addr).await?;
    /// // Waits for the peer, however long it takes.
    /// let mut state = sender.watch_link_state();
    /// state.wait_for(|s| *s == LinkState::Connected).await?;
    /// # Ok(())
    /// # }
    /// ```
    pub fn watch_link_state(&self) -> watch::Receiver<LinkState> {
        self.state.clone()
    }

    /// Every event of the link from now on, for another reader than the one of the
    /// [`PacketStream`](crate::PacketStream): see [`Subscription`](crate::Subscription).
    /// Taken from a link that has ended, it ends at once.
    pub fn subscribe(&self) -> crate::Subscription {
        self.subscribers.subscribe()
    }

    /// Every frame of the link from now on, both ways, as a
    /// [`RecordWriter`](crate::record::RecordWriter) records it: the frames the radio
    /// sent, as decoded (corrupt ones are [`Event::DecodeError`](crate::Event)s, not
    /// frames), and the frames written to it, as they went out (with the frame ids the
    /// link gave them), each with the time it was read or its last byte written. It
    /// sees what no [`PacketStream`](crate::PacketStream) does: the answers to this
    /// link's own requests, and its writes. It behaves as a [`subscribe`](Self::subscribe)d
    /// [`Subscription`](crate::Subscription) does (its reader falls behind by
    /// [`LinkOptions::event_capacity`](crate::LinkOptions::event_capacity) records at
    /// most, then misses the oldest, counted in
    /// [`missed`](crate::Subscription::missed); it ends with the link).
    ///
    /// A frame being written when it is taken is not in it (its first bytes went out
    /// before): it starts with the next frame the link begins to write. The frames the
    /// link writes out as it closes are in it as they are handed to the transport (a
    /// write that then fails, within the second it is given, did not deliver them).
    ///
    /// ```
    /// # #[tokio::main(flavor = "current_thread")]
    /// # async fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use futures::StreamExt;
    /// use tokio::io::{AsyncReadExt, AsyncWriteExt};
    /// use mcp_host::record::{Direction, RecordWriter};
    /// use mcp_host::{Link, LinkOptions, LinkState};
    ///
    /// let link: Link = "tcp-listen:127.0.0.1:0".parse()?;
    /// let (stream, sender) = mcp_host::connect(&link, LinkOptions::default()).await?;
    /// let mut frames = sender.tap_frames();
    /// // A radio connects, and says "coordinator started" once it has read a frame.
    /// let mut radio = tokio::net::TcpStream::connect(stream.info().local_addr.unwrap()).await?;
    /// sender.watch_link_state().wait_for(|s| *s == LinkState::Connected).await?;
    /// sender.write_frame(&[0x08, 0x00, b'A', b'P']).await?;
    /// radio.read_exact(&mut [0u8; 8]).await?;
    /// radio.write_all(&[0x7E, 0x00, 0x02, 0x8A, 0x06, 0x6F]).await?;
    ///
    /// // A recording of both ways, in memory here; a file in a real program.
    /// let mut recording = RecordWriter::new(Vec::new())?;
    /// for direction in [Direction::Sent, Direction::Received] {
    ///     let record = frames.next().await.expect("a frame");
    ///     assert_eq!(record.direction, direction);
    ///     recording.write(record.time, record.direction, &record.frame)?;
    /// }
    /// # Ok(())
    /// # }
    /// ```
    pub fn tap_frames(&self) -> crate::Subscription<crate::record::Record> {
        self.subscribers.tap_frames()
    }

    /// Waits until the link has ended for good ([`LinkState::Closed`]: after
    /// [`close`](Self::close), or when reconnection gave up) and its transport is closed,
    /// so that the same device can be opened again. This sender keeps the link alive
    /// while it waits: call [`close`](Self::close) first to end it.
    ///
    /// ```
    /// # #[tokio::main(flavor = "current_thread")]
    /// # async fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// use mcp_host::{Link, LinkOptions, LinkState};
    ///
    /// let (_stream, sender) = mcp_host::connect(&Link::Pty, LinkOptions::default()).await?;
    /// sender.close();
    /// sender.closed().await;
    /// assert_eq!(sender.link_state(), LinkState::Closed);
    /// # Ok(())
    /// # }
    /// ```
    pub async fn closed(&self) {
        let mut state = self.state.clone();
        let _ = state.wait_for(|s| *s == LinkState::Closed).await;
    }

    /// The queue for `op`.
    fn queue(&self, op: &Op) -> &mpsc::Sender<Op> {
        if op.needs_id() {
            &self.ops
        } else {
            &self.writes
        }
    }

    /// A write the background task did not take by its deadline (it never writes it
    /// then), counted as a timeout.
    fn not_taken(&self, timeout: Duration) -> SendError {
        crate::stats::bump(&self.counters.timeouts);
        SendError::NotSent { timeout }
    }

    /// A request the background task did not answer by its deadline and the grace
    /// after it (it ran late, or never took the request), counted as a timeout:
    /// whether its frame went out, and under which id, is not known.
    fn unanswered(&self, timeout: Duration) -> SendError {
        crate::stats::bump(&self.counters.timeouts);
        SendError::Timeout {
            frame_id: None,
            timeout,
            heard: self.counters.snapshot().frames > 0,
        }
    }

    async fn call<T>(
        &self,
        op: Op,
        answer: oneshot::Receiver<Result<T, SendError>>,
        deadline: Instant,
        timeout: Duration,
    ) -> Result<T, SendError> {
        // A write is answered as soon as it is taken: one not answered by then was not
        // taken, and never will be. Another request the task answers by its deadline,
        // unless the task runs late (or never took it: whether it went out is not known).
        let write = matches!(op, Op::Write { .. });
        self.enqueue(op, deadline, timeout).await?;
        match tokio::time::timeout_at(deadline + GRACE, answer).await {
            Ok(result) => result.unwrap_or(Err(SendError::Closed)),
            Err(_) if write => Err(self.not_taken(timeout)),
            Err(_) => Err(self.unanswered(timeout)),
        }
    }
}

/// The frame data of a Remote AT Command (frame id 0, set when it is written) to `to`,
/// with the apply-changes option if `apply`.
fn remote_at_frame(
    to: Address64,
    command: [u8; 2],
    parameter: &[u8],
    apply: bool,
) -> Result<Vec<u8>, SendError> {
    frame_data(&xbee_api::RemoteAtCommandRepr {
        frame_id: 0,
        dst64: to,
        dst16: Address16::UNKNOWN,
        options: if apply {
            xbee_api::RemoteAtCommandRepr::APPLY_CHANGES
        } else {
            0
        },
        command,
        parameter,
    })
}

/// The frame data of `frame` (frame type first).
fn frame_data(frame: &impl xbee_api::EncodeFrame) -> Result<Vec<u8>, SendError> {
    let len = frame.frame_data_len();
    let mut data = vec![0u8; len];
    frame
        .emit_frame_data(&mut data)
        .map_err(|_| SendError::TooLarge {
            len,
            max: xbee_api::MAX_FRAME_DATA_LEN,
        })?;
    Ok(data)
}

/// The payload of `packet`, or [`SendError::TooLarge`].
pub(crate) fn encode_packet<B: AsRef<[u8]>>(
    packet: &mcp_core::Packet<B>,
) -> Result<Bytes, SendError> {
    let mut buf = [0u8; mcp_core::MAX_PAYLOAD];
    let len = packet.encode(&mut buf).map_err(|_| SendError::TooLarge {
        len: packet.encoded_len(),
        max: mcp_core::MAX_PAYLOAD,
    })?;
    Ok(Bytes::copy_from_slice(&buf[..len]))
}

/// The payload of `command`: [`encode_packet`] of it as a packet.
fn encode_command<B: AsRef<[u8]>>(command: &mcp_core::Command<B>) -> Result<Bytes, SendError> {
    encode_packet(&mcp_core::Packet::Command(command.as_borrowed()))
}
