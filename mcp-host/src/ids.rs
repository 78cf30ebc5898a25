//! Frame ids in flight: 1..=255, handed out round-robin, skipping ids still in use.

/// A table of values keyed by XBee frame id (1..=255).
///
/// Ids are handed out round-robin from the id after the last one given, skipping ids
/// still in flight (the link keeps the id of a request that timed out after its frame
/// went out until its late answer comes or can no longer be expected), so a late status
/// is unlikely to meet a new request with the same id. Freed ids are reused; the table
/// never runs out as long as entries are removed.
#[derive(Debug)]
pub(crate) struct IdTable<T> {
    slots: Vec<Option<T>>,
    /// Index (id - 1) to try first.
    cursor: usize,
    len: usize,
}

impl<T> IdTable<T> {
    pub(crate) fn new() -> Self {
        IdTable {
            slots: (0..255).map(|_| None).collect(),
            cursor: 0,
            len: 0,
        }
    }

    /// Number of ids in flight.
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// Whether an id is free.
    pub(crate) fn has_free(&self) -> bool {
        self.len < self.slots.len()
    }

    /// Stores `value` under a free id and returns the id, or gives the value back when
    /// all 255 ids are in flight.
    pub(crate) fn insert(&mut self, value: T) -> Result<u8, T> {
        self.insert_unless(value, |_| false)
    }

    /// [`insert`](Self::insert), passing over the free ids for which `held` is true.
    pub(crate) fn insert_unless(&mut self, value: T, held: impl Fn(u8) -> bool) -> Result<u8, T> {
        let n = self.slots.len();
        for step in 0..n {
            let index = (self.cursor + step) % n;
            if self.slots[index].is_none() && !held(id_of(index)) {
                self.slots[index] = Some(value);
                self.cursor = (index + 1) % n;
                self.len += 1;
                return Ok(id_of(index));
            }
        }
        Err(value)
    }

    /// Removes and returns the value under `id` (None for id 0 or a free id).
    pub(crate) fn remove(&mut self, id: u8) -> Option<T> {
        let slot = self.slots.get_mut(usize::from(id).checked_sub(1)?)?;
        let value = slot.take();
        if value.is_some() {
            self.len -= 1;
        }
        value
    }

    /// The value under `id`, if in flight.
    pub(crate) fn get(&self, id: u8) -> Option<&T> {
        self.slots.get(usize::from(id).checked_sub(1)?)?.as_ref()
    }

    /// The value under `id`, if in flight, to change.
    pub(crate) fn get_mut(&mut self, id: u8) -> Option<&mut T> {
        self.slots
            .get_mut(usize::from(id).checked_sub(1)?)?
            .as_mut()
    }

    /// Removes every entry for which `expired` is true, passing each to `on_removed`.
    pub(crate) fn remove_where(
        &mut self,
        expired: impl FnMut(&T) -> bool,
        mut on_removed: impl FnMut(u8, T),
    ) {
        self.replace_where(expired, |id, value| {
            on_removed(id, value);
            None
        });
    }

    /// Takes every entry for which `expired` is true to `replace`, which gives back
    /// what stays under its id (`None` frees the id).
    pub(crate) fn replace_where(
        &mut self,
        mut expired: impl FnMut(&T) -> bool,
        mut replace: impl FnMut(u8, T) -> Option<T>,
    ) {
        for (index, slot) in self.slots.iter_mut().enumerate() {
            if slot.as_ref().is_some_and(&mut expired) {
                if let Some(value) = slot.take() {
                    *slot = replace(id_of(index), value);
                    if slot.is_none() {
                        self.len -= 1;
                    }
                }
            }
        }
    }

    /// The values in flight.
    pub(crate) fn values(&self) -> impl Iterator<Item = &T> {
        self.slots.iter().flatten()
    }

    /// The values in flight, to change.
    pub(crate) fn values_mut(&mut self) -> impl Iterator<Item = &mut T> {
        self.slots.iter_mut().flatten()
    }
}

fn id_of(index: usize) -> u8 {
    // index < 255 by construction.
    u8::try_from(index + 1).unwrap_or(u8::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hands_out_every_id_once_then_is_full() {
        let mut table = IdTable::new();
        let ids: Vec<u8> = (0..255).map(|i| table.insert(i).unwrap()).collect();
        assert_eq!(ids, (1..=255).collect::<Vec<u8>>());
        assert!(!table.has_free());
        assert_eq!(table.insert(999), Err(999));
        assert_eq!(table.remove(0), None);
        assert_eq!(table.remove(7), Some(6));
        assert_eq!(table.remove(7), None);
        assert_eq!(table.insert(1000), Ok(7));
        assert_eq!(table.get(7), Some(&1000));
    }

    #[test]
    fn round_robin_skips_ids_in_flight_and_never_runs_out() {
        let mut table = IdTable::new();
        // Keep ids 1..=10 in flight forever; churn through thousands of others.
        const FOREVER: usize = 1 << 40;
        for i in 0..10 {
            assert_eq!(table.insert(FOREVER + i), Ok(i as u8 + 1));
        }
        let mut last = 10u8;
        for i in 0..10_000 {
            let id = table.insert(i).unwrap();
            assert!(id > 10, "id {id} still in flight");
            assert_ne!(id, last, "an id is not reused at once");
            last = id;
            if i % 3 != 0 {
                table.remove(id);
            } else {
                // Some are never answered and expire later.
                table.remove_where(|v| *v < FOREVER && *v + 100 < i, |_, _| {});
            }
        }
        assert!(table.len() < 255);
        let mut expired = vec![];
        table.remove_where(|v| *v < FOREVER, |id, v| expired.push((id, v)));
        assert!(expired.iter().all(|(id, _)| *id > 10));
        assert_eq!(table.len(), 10);
        table.remove_where(|_| true, |_, _| {});
        assert_eq!(table.len(), 0);
        assert_eq!(table.values().count(), 0);
    }
}
