//! `perf::run::run_fifo` in API mode 1.
#![no_std]
#![no_main]

perf_cortex_m::case!(run_fifo, Unescaped, perf_cortex_m::CHUNK);
