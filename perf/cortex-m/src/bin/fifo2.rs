//! `perf::run::run_fifo` in API mode 2.
#![no_std]
#![no_main]

perf_cortex_m::case!(run_fifo, Escaped, perf_cortex_m::CHUNK);
