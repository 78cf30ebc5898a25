//! A virtual XBee network (in progress).
