//! A set of telemetry ids: a 256-bit bitmap.

use core::iter::FusedIterator;

use crate::id::TelemetryId;

/// A set of telemetry ids, all 256 of them possible (a 32-byte bitmap). [`Mav`](super::Mav)
/// keeps the enabled ids in one; a firmware without `Mav` can too (it is also at the
/// crate root, `mcp_core::TelemetrySet`).
///
/// ```
/// use mcp_core::{TelemetryId, TelemetrySet};
/// let mut set = TelemetrySet::new();
/// set.insert(TelemetryId::PitchAngle);
/// set.insert(TelemetryId::from(0xF0));
/// set.insert(TelemetryId::Altitude);
/// let ids: Vec<u8> = set.iter().map(u8::from).collect();
/// assert_eq!(ids, [0x01, 0x19, 0xF0]);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TelemetrySet {
    bits: [u32; 8],
}

impl TelemetrySet {
    /// The empty set.
    pub const fn new() -> Self {
        TelemetrySet { bits: [0; 8] }
    }

    const fn word_bit(id: TelemetryId) -> (usize, u32) {
        let n = id.to_u8();
        ((n / 32) as usize, 1 << (n % 32))
    }

    /// Adds or removes `id`.
    // Indexing in a `const fn` (`get_mut` is not `const`), behind a bounds test.
    #[allow(clippy::indexing_slicing)]
    pub const fn set(&mut self, id: TelemetryId, on: bool) {
        let (word, bit) = Self::word_bit(id);
        // Always true (`word` is a `u8` over 32); tested so that indexing cannot panic.
        if word < self.bits.len() {
            if on {
                self.bits[word] |= bit;
            } else {
                self.bits[word] &= !bit;
            }
        }
    }

    /// Adds `id`.
    pub const fn insert(&mut self, id: TelemetryId) {
        self.set(id, true);
    }

    /// Removes `id`.
    pub const fn remove(&mut self, id: TelemetryId) {
        self.set(id, false);
    }

    /// The set with `id` added, for sets built in a `const` context.
    ///
    /// ```
    /// use mcp_core::{mav::TelemetrySet, TelemetryId};
    /// const DEFAULT: TelemetrySet = TelemetrySet::new()
    ///     .with(TelemetryId::Altitude)
    ///     .with(TelemetryId::PitchAngle);
    /// assert_eq!(DEFAULT.len(), 2);
    /// ```
    #[must_use]
    pub const fn with(mut self, id: TelemetryId) -> Self {
        self.insert(id);
        self
    }

    /// Removes every id.
    pub fn clear(&mut self) {
        self.bits = [0; 8];
    }

    /// `true` if `id` is in the set.
    #[allow(clippy::indexing_slicing)]
    pub const fn contains(&self, id: TelemetryId) -> bool {
        let (word, bit) = Self::word_bit(id);
        word < self.bits.len() && self.bits[word] & bit != 0
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
        self.iter_from(0)
    }

    /// The ids from `first` on, in ascending order.
    pub(crate) fn iter_from(&self, first: u8) -> TelemetrySetIter<'_> {
        TelemetrySetIter {
            set: self,
            next: Some(first),
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
