//! Locking a mutex that a panic may have poisoned.

use std::sync::{Mutex, MutexGuard, PoisonError};

/// The guard of `shared`, whether or not a thread panicked while holding it: every
/// mutex of this crate guards state that each holder leaves consistent at every step
/// (a table, a list, counters), so a panic elsewhere is no reason to fail here too.
pub(crate) fn lock<T>(shared: &Mutex<T>) -> MutexGuard<'_, T> {
    shared.lock().unwrap_or_else(PoisonError::into_inner)
}
