//! `perf::run::run_slice` in API mode 1.
#![no_std]
#![no_main]

perf_cortex_m::case!(run_slice, Unescaped);
