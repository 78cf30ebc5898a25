//! A simulated MAV (in progress).
