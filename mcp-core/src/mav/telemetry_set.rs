//! A set of telemetry ids: a 256-bit bitmap.

use core::iter::FusedIterator;

use crate::id::TelemetryId;

/// A set of telemetry ids, all 256 of them possible (a 32-byte bitmap).
///
/// ```
/// use mcp_core::{mav::TelemetrySet, TelemetryId};
/// let mut set = TelemetrySet::new();
/// set.insert(TelemetryId::PitchAngle);
/// set.insert(TelemetryId::from(0xF0));
/// set.insert(TelemetryId::Altitude);
/// let ids: Vec<u8> = set.iter().map(u8::from).collect();
/// assert_eq!(ids, [0x01, 0x19, 0xF0]);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct TelemetrySet {
    bits: [u32; 8],
}

impl TelemetrySet {
    /// The empty set.
    pub const fn new() -> Self {
        TelemetrySet { bits: [0; 8] }
    }

    fn word_bit(id: TelemetryId) -> (usize, u32) {
        let n = u8::from(id);
        (usize::from(n / 32), 1 << (n % 32))
    }

    /// Adds or removes `id`.
    pub fn set(&mut self, id: TelemetryId, on: bool) {
        let (word, bit) = Self::word_bit(id);
        if let Some(w) = self.bits.get_mut(word) {
            if on {
                *w |= bit;
            } else {
                *w &= !bit;
            }
        }
    }

    /// Adds `id`.
    pub fn insert(&mut self, id: TelemetryId) {
        self.set(id, true);
    }

    /// Removes `id`.
    pub fn remove(&mut self, id: TelemetryId) {
        self.set(id, false);
    }

    /// Removes every id.
    pub fn clear(&mut self) {
        self.bits = [0; 8];
    }

    /// `true` if `id` is in the set.
    pub fn contains(&self, id: TelemetryId) -> bool {
        let (word, bit) = Self::word_bit(id);
        self.bits.get(word).is_some_and(|w| w & bit != 0)
    }

    /// The number of ids in the set.
    pub fn len(&self) -> usize {
        self.bits.iter().map(|w| w.count_ones() as usize).sum()
    }

    /// `true` if the set is empty.
    pub fn is_empty(&self) -> bool {
        self.bits.iter().all(|&w| w == 0)
    }

    /// The ids in ascending order.
    pub fn iter(&self) -> TelemetrySetIter<'_> {
        TelemetrySetIter {
            set: self,
            next: Some(0),
        }
    }
}

impl<'s> IntoIterator for &'s TelemetrySet {
    type Item = TelemetryId;
    type IntoIter = TelemetrySetIter<'s>;

    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

impl FromIterator<TelemetryId> for TelemetrySet {
    fn from_iter<I: IntoIterator<Item = TelemetryId>>(iter: I) -> Self {
        let mut set = TelemetrySet::new();
        iter.into_iter().for_each(|id| set.insert(id));
        set
    }
}

/// Iterator over a [`TelemetrySet`] in ascending id order.
#[derive(Debug, Clone)]
pub struct TelemetrySetIter<'s> {
    set: &'s TelemetrySet,
    next: Option<u8>,
}

impl Iterator for TelemetrySetIter<'_> {
    type Item = TelemetryId;

    fn next(&mut self) -> Option<TelemetryId> {
        while let Some(n) = self.next {
            self.next = n.checked_add(1);
            let id = TelemetryId::from(n);
            if self.set.contains(id) {
                return Some(id);
            }
        }
        None
    }
}

impl FusedIterator for TelemetrySetIter<'_> {}
