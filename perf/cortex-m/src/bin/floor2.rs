//! `perf::run::run_floor` (the least a byte-at-a-time decoder does) in API mode 2.
#![no_std]
#![no_main]

perf_cortex_m::case!(run_floor, Escaped);
