//! What machine and build a measurement ran on, for the head of a table of figures.

use std::fmt;

/// The processor, how many CPUs the process may use, and the SIMD level the build
/// targets: what a figure depends on beyond the code.
///
/// ```
/// let machine = perf::Machine::this();
/// assert!(machine.cpus >= 1);
/// println!("{machine}"); // e.g. "Intel(R) Xeon(R) Processor, 2 CPUs, x86_64 with SSE2 build"
/// ```
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Machine {
    /// The processor's model name (Linux's `/proc/cpuinfo`), or the architecture where
    /// it cannot be read.
    pub processor: String,
    /// CPUs available to this process.
    pub cpus: usize,
    /// The architecture and the widest SIMD the build may use, as compiled.
    pub build: &'static str,
}

impl Machine {
    /// This machine and this build.
    pub fn this() -> Self {
        let processor = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|info| model_name(&info).map(str::to_owned))
            .unwrap_or_else(|| std::env::consts::ARCH.to_owned());
        Self {
            processor,
            cpus: std::thread::available_parallelism().map_or(1, usize::from),
            build: build(),
        }
    }
}

impl fmt::Display for Machine {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let plural = if self.cpus == 1 { "" } else { "s" };
        write!(
            f,
            "{}, {} CPU{plural}, {} build",
            self.processor, self.cpus, self.build
        )
    }
}

/// The first `model name` of a `/proc/cpuinfo` text.
fn model_name(cpuinfo: &str) -> Option<&str> {
    cpuinfo.lines().find_map(|line| {
        let (key, value) = line.split_once(':')?;
        (key.trim() == "model name").then(|| value.trim())
    })
}

/// The build's architecture and widest SIMD, as compiled (`-C target-cpu` changes it).
const fn build() -> &'static str {
    if cfg!(all(target_arch = "x86_64", target_feature = "avx512bw")) {
        "x86_64 with AVX-512"
    } else if cfg!(all(target_arch = "x86_64", target_feature = "avx2")) {
        "x86_64 with AVX2"
    } else if cfg!(target_arch = "x86_64") {
        "x86_64 with SSE2"
    } else if cfg!(target_arch = "aarch64") {
        "aarch64 with NEON"
    } else {
        std::env::consts::ARCH
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn model_name_is_the_first_processors() {
        let info = "processor\t: 0\nvendor_id\t: GenuineIntel\nmodel name\t: Intel(R) Xeon(R) Processor\n\
                    \nprocessor\t: 1\nmodel name\t: Other\n";
        assert_eq!(model_name(info), Some("Intel(R) Xeon(R) Processor"));
        assert_eq!(model_name("processor\t: 0\nHardware\t: BCM2835\n"), None);
    }

    #[test]
    fn shows_processor_cpus_and_build() {
        let machine = Machine {
            processor: "AMD EPYC".into(),
            cpus: 2,
            build: "x86_64 with SSE2",
        };
        assert_eq!(
            machine.to_string(),
            "AMD EPYC, 2 CPUs, x86_64 with SSE2 build"
        );
        let one = Machine { cpus: 1, ..machine };
        assert_eq!(one.to_string(), "AMD EPYC, 1 CPU, x86_64 with SSE2 build");
    }
}
