//! Sets `cfg(holds_port)` on Linux and Android, where a socket bound without listening
//! holds a TCP port against other programs (`SO_REUSEPORT`) and connections to it are
//! refused: the hub keeps its port during an outage there (`src/hub/port.rs`), and its
//! tests check that. (On macOS and the BSDs such a socket may swallow connections rather
//! than refuse them: not used there.)

fn main() {
    println!("cargo::rustc-check-cfg=cfg(holds_port)");
    println!("cargo::rerun-if-changed=build.rs");
    let os = std::env::var("CARGO_CFG_TARGET_OS").unwrap_or_default();
    if matches!(os.as_str(), "linux" | "android") {
        println!("cargo::rustc-cfg=holds_port");
    }
}
