//! Sets `cfg(holds_port)` where a socket bound without listening can hold a TCP port
//! against other programs (`SO_REUSEPORT`): the hub keeps its port during an outage
//! there (`src/hub/port.rs`), and its tests check that.

fn main() {
    println!("cargo::rustc-check-cfg=cfg(holds_port)");
    println!("cargo::rerun-if-changed=build.rs");
    let unix = std::env::var_os("CARGO_CFG_UNIX").is_some();
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    // Tokio's `TcpSocket::set_reuseport` is there on these.
    if unix && !matches!(os.as_str(), "solaris" | "illumos" | "cygwin" | "nuttx") {
        println!("cargo::rustc-cfg=holds_port");
    }
}
