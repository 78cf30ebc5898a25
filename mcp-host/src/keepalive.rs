//! TCP keepalive: how a connection whose peer is gone without a word is found out, for
//! a link's connection and a hub's clients.

use std::time::Duration;

use tokio::net::TcpStream;

/// How a TCP connection whose peer is gone without a word (a bridge powered off, a
/// laptop asleep, a cable pulled) is found out: probed by TCP keepalive once quiet for
/// `idle`, every `interval`, given up after `probes` unanswered (where the system lets
/// the number be set: Linux, Android, macOS, iOS, FreeBSD, NetBSD, Windows 10 and
/// later; else its own); and, on Linux, given up as well once data written has gone
/// unacknowledged for `unacknowledged`, if given, as keepalive probes only go out while
/// nothing written waits. (Linux counts a peer that takes nothing, its receive window
/// closed, as unacknowledged too: a connection to a program that stopped reading is
/// given up then.)
#[derive(Debug, Clone, Copy)]
pub(crate) struct KeepAlive {
    pub(crate) idle: Duration,
    pub(crate) interval: Duration,
    /// Read where the system takes it ([`keep_alive`] says where).
    #[allow(dead_code)]
    pub(crate) probes: u32,
    /// Linux alone takes it.
    #[cfg_attr(not(target_os = "linux"), allow(dead_code))]
    pub(crate) unacknowledged: Option<Duration>,
}

/// A `tcp:` or `tcp-listen:` link's connection: a peer gone is found out within about
/// half a minute (a minute on Windows before 10), and the link reconnects, even on a quiet
/// network where nothing is written.
pub(crate) const LINK_KEEPALIVE: KeepAlive = KeepAlive {
    idle: Duration::from_secs(10),
    interval: Duration::from_secs(5),
    probes: 4,
    unacknowledged: Some(Duration::from_secs(30)),
};

/// Sets `socket` to find out a peer gone as `keep` says. A setting the system refuses
/// is left as it was.
pub(crate) fn keep_alive(socket: &TcpStream, keep: &KeepAlive) {
    let sock = socket2::SockRef::from(socket);
    let keepalive = socket2::TcpKeepalive::new()
        .with_time(keep.idle)
        .with_interval(keep.interval);
    let counted = keepalive.clone();
    #[cfg(any(
        target_os = "linux",
        target_os = "android",
        target_os = "macos",
        target_os = "ios",
        target_os = "freebsd",
        target_os = "netbsd",
        windows
    ))]
    let counted = counted.with_retries(keep.probes);
    // A system that takes no number of probes (Windows before 10) keeps its own.
    if sock.set_tcp_keepalive(&counted).is_err() {
        let _ = sock.set_tcp_keepalive(&keepalive);
    }
    #[cfg(target_os = "linux")]
    let _ = sock.set_tcp_user_timeout(keep.unacknowledged);
}

/// Asserts that `stream` is probed when quiet, as `keep` says.
#[cfg(all(test, any(target_os = "linux", target_os = "macos")))]
pub(crate) fn assert_kept_alive(stream: &TcpStream, keep: &KeepAlive) {
    let sock = socket2::SockRef::from(stream);
    assert!(sock.keepalive().unwrap());
    assert_eq!(sock.tcp_keepalive_time().unwrap(), keep.idle);
    assert_eq!(sock.tcp_keepalive_interval().unwrap(), keep.interval);
    assert_eq!(sock.tcp_keepalive_retries().unwrap(), keep.probes);
    #[cfg(target_os = "linux")]
    assert_eq!(sock.tcp_user_timeout().unwrap(), keep.unacknowledged);
}
