//! The task that writes the clients' frames to the radio, taking them from each
//! client's queue in turn.

use std::sync::{Arc, Mutex};
use std::time::Duration;

use tokio::sync::{Notify, mpsc};
use tokio::time::Instant;
use tokio_util::sync::CancellationToken;
use xbee_api::ApiMode;

use super::client::Client;
use super::routes::Routes;
use super::{Counters, RADIO_BACKLOG, encode, settled};
use crate::CommandSender;
use crate::mutex::lock;

/// A client's queue of frames to the radio, and the client (kept until the queue is
/// drained, so that the routes of its last frames stay until these are written).
type ClientFrames = (mpsc::Receiver<Queued>, Arc<Client>);

/// A client's frame on its way to the radio.
pub(super) struct Queued {
    /// Its frame data, a request's under its hub id.
    pub(super) data: Vec<u8>,
    /// For a request: when it must have gone to the radio
    /// ([`REQUEST_WAIT`](super::REQUEST_WAIT) after the hub could first have read it);
    /// one still waiting its turn then is not sent.
    pub(super) deadline: Option<Instant>,
}

/// The clients' queues of frames to the radio, taken by the [`RadioWriter`].
#[derive(Default)]
pub(super) struct ToRadio {
    /// Queues of new clients, not yet taken by the writer.
    pub(super) new: Mutex<Vec<ClientFrames>>,
    /// A frame waits in a queue, or a new queue.
    pub(super) ready: Notify,
}

/// The task that writes the clients' frames to the radio: one frame of each client in
/// turn (round-robin), at the pace the radio takes them (see [`RADIO_BACKLOG`]), so that
/// a client writing nonstop slows itself alone.
pub(super) struct RadioWriter {
    pub(super) mode: ApiMode,
    pub(super) sender: CommandSender,
    pub(super) counters: Arc<Counters>,
    /// The routes of the requests it writes: their answer windows start then.
    pub(super) routes: Arc<Mutex<Routes>>,
    pub(super) to_radio: Arc<ToRadio>,
    /// The radio UART's pace.
    pub(super) bytes_per_second: f64,
}

impl RadioWriter {
    pub(super) async fn run(self, stop: CancellationToken) {
        let mut queues: Vec<ClientFrames> = Vec::new();
        // The queue to look at first.
        let mut next = 0;
        // When the bytes written so far are through the radio's UART, as reckoned.
        let mut through = Instant::now();
        loop {
            let ahead = through.saturating_duration_since(Instant::now());
            if ahead > RADIO_BACKLOG {
                tokio::select! {
                    () = stop.cancelled() => return,
                    () = tokio::time::sleep(ahead - RADIO_BACKLOG) => {}
                }
            }
            let (Queued { data, deadline }, client) = tokio::select! {
                () = stop.cancelled() => return,
                queued = self.next_frame(&mut queues, &mut next) => queued,
            };
            let hub_id = match data[..] {
                [_, id, ..] if id != 0 => Some(id),
                _ => None,
            };
            // A request that waited its turn too long: not sent, answered as failed.
            if let (Some(deadline), Some(id)) = (deadline, hub_id) {
                if Instant::now() >= deadline {
                    self.give_up(&client, &data, id, "its turn to the radio");
                    continue;
                }
            }
            // A request's answers are due from now on (the window does not start while
            // the request waits its turn), and not before: the route is marked before the
            // radio can answer.
            if let Some(id) = hub_id {
                lock(&self.routes).written(id, Instant::now());
            }
            // A request is taken by the link by its deadline, or not written.
            let written = match deadline {
                Some(deadline) => self.sender.write_frame_until(&data, deadline).await,
                None => self.sender.write_frame(&data).await,
            };
            match written {
                Ok(()) => {
                    settled(&self.counters.frames_from_clients);
                    let len = encode(&data, self.mode).map_or(data.len(), |bytes| bytes.len());
                    let time = Duration::from_secs_f64(len as f64 / self.bytes_per_second);
                    through = through.max(Instant::now()) + time;
                }
                Err(error) => {
                    // Not written: no pacing time spent, and no answer due.
                    tracing::debug!(%error, "hub: a client's frame not written");
                    // The link did not take it in time: answered as failed.
                    let answered = matches!(error, crate::SendError::NotSent { .. })
                        && hub_id.is_some_and(|id| {
                            self.give_up(&client, &data, id, "the radio's link to take it")
                        });
                    if !answered {
                        if let Some(id) = hub_id {
                            lock(&self.routes).remove(id);
                        }
                        settled(&self.counters.frames_refused);
                    }
                }
            }
        }
    }

    /// Ends the route of `client`'s request `data`, under hub id `hub_id`, which waited
    /// for `what` in vain: answered as failed under the client's own id, not sent
    /// ([`Client::not_sent`]). Whether it had a route still.
    fn give_up(&self, client: &Client, data: &[u8], hub_id: u8, what: &str) -> bool {
        let Some(route) = lock(&self.routes).remove(hub_id) else {
            return false;
        };
        let mut request = data.to_vec();
        request[1] = route.own_id;
        client.not_sent(&request, what);
        true
    }

    /// The next client's next frame, in turn.
    async fn next_frame(
        &self,
        queues: &mut Vec<ClientFrames>,
        next: &mut usize,
    ) -> (Queued, Arc<Client>) {
        loop {
            queues.append(&mut lock(&self.to_radio.new));
            // Whatever the other queues hold: the queues of clients ended (their frames
            // not yet written are dropped: a client's commands are not carried out after
            // it was disconnected), and of clients that closed their connection once
            // their frames are all written. Each client then goes, and its routes with
            // it (see `Client`'s `Drop`).
            queues.retain_mut(|(queue, client)| {
                if client.end.is_cancelled() {
                    queue.close();
                    while queue.try_recv().is_ok() {
                        settled(&self.counters.frames_refused);
                    }
                    return false;
                }
                !(queue.is_closed() && queue.is_empty())
            });
            let n = queues.len();
            for step in 0..n {
                let index = (*next + step) % n;
                if let Ok(queued) = queues[index].0.try_recv() {
                    *next = index + 1;
                    return (queued, queues[index].1.clone());
                }
            }
            // A frame queued (or a queue added) since the look above has left a permit.
            self.to_radio.ready.notified().await;
        }
    }
}
