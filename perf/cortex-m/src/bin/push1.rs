//! `perf::run::run_push` in API mode 1.
#![no_std]
#![no_main]

perf_cortex_m::case!(run_push, Unescaped);
