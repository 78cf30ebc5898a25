//! `perf::run::run_slice_calls` in API mode 2.
#![no_std]
#![no_main]

perf_cortex_m::case!(run_slice_calls, Escaped);
