//! What the bench shares with the callgrind example and the tests.

pub(crate) mod mavlink_run;
