//! Where the answers to clients' requests go: the hub's frame ids, each routed to the
//! client that asked under it, and the ids held after a request not answered in time.

use std::cell::Cell;
use std::sync::Arc;

use tokio::sync::{OwnedSemaphorePermit, Semaphore};
use tokio::time::Instant;

use super::ANSWER_WINDOW;
use super::request::at_command;
use super::serve::AnswerQueue;
use crate::ids::IdTable;

/// Where the answers under each of the hub's frame ids go: ids handed out round-robin
/// (as the link's own), so that a late answer rarely meets a new request under its id.
pub(super) struct Routes(IdTable<Route>, Held);

/// The frame ids the hub's own requests went out under (its `AT AP`), until when they
/// are kept from clients (a late answer under one is no client's), and the permits of
/// the 255 ids they hold meanwhile.
#[derive(Default)]
pub(super) struct Held(Vec<(u8, Instant, Option<OwnedSemaphorePermit>)>);

impl Held {
    pub(super) fn expire(&mut self, now: Instant) {
        self.0.retain(|(_, until, _)| *until > now);
    }

    fn contains(&self, id: u8) -> bool {
        self.0.iter().any(|(held, ..)| *held == id)
    }
}

pub(super) struct Route {
    /// The client's number (see [`Serve::next_client`](super::serve::Serve::next_client)).
    pub(super) client: u64,
    /// The client's queue of answers.
    pub(super) queue: AnswerQueue,
    pub(super) own_id: u8,
    /// The frame type of the answers (see
    /// [`answer_type`](xbee_api::frame::frame_type::answer_type)): an answer of another
    /// type under the same id is not this request's.
    pub(super) answer_type: u8,
    /// The AT command of an AT or remote AT request ([`at_command`]): an answer that
    /// echoes another is not this request's either.
    pub(super) command: Option<[u8; 2]>,
    /// Until when answers are due: [`ANSWER_WINDOW`] from when the request was written
    /// to the radio; `None` while it waits its turn (no answer is due yet, and the route
    /// does not expire).
    pub(super) until: Cell<Option<Instant>>,
    /// Answers keep coming until `until` (node discovery, find neighbors, active scan,
    /// broadcast remote AT).
    pub(super) many: bool,
    /// Its client has gone since the request was written: its answers are dropped, and
    /// its id stays taken until they have come (or `until`), so that no late answer of
    /// its reaches a new request under the same id. An orphan holds one of the
    /// [`SHARED_IDS`](super::SHARED_IDS) (taken when it became one, if it had none):
    /// orphans never take the ids each client's first requests find.
    pub(super) orphan: Cell<bool>,
    /// One of the client's [`ROUTES_PER_CLIENT`](super::ROUTES_PER_CLIENT) permits, given
    /// back with the route.
    pub(super) _permit: OwnedSemaphorePermit,
    /// For a request answered many times, one of the client's
    /// [`MANY_ANSWER_PER_CLIENT`](super::MANY_ANSWER_PER_CLIENT) permits.
    pub(super) _many: Option<OwnedSemaphorePermit>,
    /// For a request beyond its client's first [`IDS_PER_CLIENT`](super::IDS_PER_CLIENT),
    /// one of the [`SHARED_IDS`](super::SHARED_IDS) permits.
    pub(super) _shared: Option<OwnedSemaphorePermit>,
    /// One of the 255 frame ids' permits: requests of all clients wait for a free id in
    /// the order they came.
    pub(super) _id: OwnedSemaphorePermit,
}

impl Routes {
    pub(super) fn new() -> Self {
        Routes(IdTable::new(), Held::default())
    }

    /// Ends the route under hub id `id` (its request not sent), and hands it back.
    pub(super) fn remove(&mut self, id: u8) -> Option<Route> {
        self.0.remove(id)
    }

    /// A hub id for `route`; `None` while all 255 wait for answers (or are held).
    pub(super) fn insert(&mut self, route: Route, now: Instant) -> Option<u8> {
        if !self.0.has_free() {
            self.expire(now);
        }
        let held = &self.1;
        self.0.insert_unless(route, |id| held.contains(id)).ok()
    }

    /// Keeps `ids`, which the hub's own requests went out under, from clients for
    /// [`ANSWER_WINDOW`]: their late answers then reach no client. Each holds one of
    /// the 255 ids of `permits`, so that clients wait for an id rather than find none
    /// free.
    pub(super) fn hold(&mut self, ids: &[u8], permits: &Arc<Semaphore>, now: Instant) {
        self.1.expire(now);
        let until = now + ANSWER_WINDOW;
        for &id in ids {
            let permit = permits.clone().try_acquire_owned().ok();
            self.1.0.push((id, until, permit));
        }
    }

    /// Ends the routes whose answers are no longer due, giving their clients' permits
    /// back.
    pub(super) fn expire(&mut self, now: Instant) {
        self.0.remove_where(
            |r| r.until.get().is_some_and(|until| until <= now),
            |_, _| {},
        );
        self.1.expire(now);
    }

    /// The request under hub id `id` goes to the radio at `now`: its answers are due
    /// for [`ANSWER_WINDOW`].
    pub(super) fn written(&mut self, id: u8, now: Instant) {
        if let Some(route) = self.0.get(id) {
            route.until.set(Some(now + ANSWER_WINDOW));
        }
    }

    /// Ends the routes of client `client` (gone) whose requests were not written: the
    /// others stay, orphans, until their answers have come or are no longer due, each
    /// on one of the `shared` ids. One that finds none free ends too (its late answer,
    /// if any comes, could then reach another request under its id, of the same type
    /// and, for an AT command, the same command: rare).
    pub(super) fn forget(&mut self, client: u64, shared: &Arc<Semaphore>) {
        for route in self.0.values_mut() {
            if route.client == client && route.until.get().is_some() {
                if route._shared.is_none() {
                    route._shared = shared.clone().try_acquire_owned().ok();
                }
                route.orphan.set(route._shared.is_some());
            }
        }
        self.0
            .remove_where(|r| r.client == client && !r.orphan.get(), |_, _| {});
    }

    /// Where `answer` (frame data) under hub id `id` goes, and the client's own id; the
    /// route ends with it unless more answers are due.
    pub(super) fn answer(
        &mut self,
        id: u8,
        answer: &[u8],
        now: Instant,
    ) -> Option<(AnswerQueue, u8)> {
        let route = self.0.get(id)?;
        // Not yet written: not its answer (a late one to an earlier request).
        let until = route.until.get()?;
        if Some(&route.answer_type) != answer.first() {
            return None;
        }
        if let (Some(asked), Some(echoed)) = (route.command, at_command(answer)) {
            if !asked.eq_ignore_ascii_case(&echoed) {
                return None;
            }
        }
        // An orphan's answer is taken, and goes nowhere.
        let to = (until > now && !route.orphan.get()).then(|| (route.queue.clone(), route.own_id));
        if until <= now || !route.many {
            self.0.remove(id);
        }
        to
    }
}
