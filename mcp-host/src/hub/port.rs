//! The hub's TCP port: listened on while the radio is there, and held while it is not,
//! so that clients are refused then and no other program can take the port.
//!
//! A listening socket cannot stop listening without giving its port up. So on Linux
//! the port is held during an outage by a second socket, bound to the same address
//! with `SO_REUSEPORT` (the listener has it too) and never listening: the system
//! refuses connections to a port nobody listens on, and other programs cannot bind it.
//! Only a socket that sets `SO_REUSEPORT` too, of the same user, could share it: no
//! other hub, which first makes sure that the port is free with a socket that does not.
//! If the port cannot be held (connections of an earlier server on it still in
//! TIME_WAIT, say), or elsewhere (on macOS and the BSDs such a socket may swallow
//! connections rather than refuse them), the port is given up during the outage, and
//! listened on again once it is free.

use std::io;
use std::net::SocketAddr;

use tokio::net::TcpListener;

/// The address the hub serves on, held between outages of the radio.
pub(super) struct Port {
    addr: SocketAddr,
    /// What keeps the port while no listener does, once taken.
    held: Option<system::Held>,
}

impl Port {
    /// Binds `listen` (`ADDR:PORT`, a host name resolved) and listens there: the first
    /// of its addresses that can be had, as [`TcpListener::bind`] does. Fails if a
    /// socket listens there already, or holds the port (another hub's).
    pub(super) async fn bind(listen: &str) -> io::Result<(Port, TcpListener)> {
        let mut last = None;
        for addr in tokio::net::lookup_host(listen).await? {
            match system::bind(addr).await {
                Ok((addr, listener)) => return Ok((Port { addr, held: None }, listener)),
                Err(error) => last = Some(error),
            }
        }
        Err(last.unwrap_or_else(|| {
            io::Error::new(
                io::ErrorKind::InvalidInput,
                "could not resolve to any address",
            )
        }))
    }

    /// The address clients connect to (with the port the system chose, for `:0`).
    pub(super) fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// Holds the port before its listener is dropped at an outage (or from the start,
    /// for a radio not there yet), where the system allows it; logged at debug level
    /// if it cannot be (the port is then given up until the radio is back).
    pub(super) fn hold(&mut self) {
        if self.held.is_some() {
            return;
        }
        match system::hold(self.addr) {
            Ok(held) => self.held = held,
            Err(error) => {
                tracing::debug!(addr = %self.addr, %error, "hub: cannot hold the port during the outage");
            }
        }
    }

    /// Listens on the port again, after an outage; fails if another program took it
    /// meanwhile (where it was not held).
    pub(super) async fn listen(&self) -> io::Result<TcpListener> {
        system::listen(self.addr).await
    }
}

/// Where a bound socket holds the port, and the system refuses connections to it.
#[cfg(holds_port)]
mod system {
    use std::io;
    use std::net::SocketAddr;

    use tokio::net::{TcpListener, TcpSocket};

    /// Bound to the port, never listening.
    pub(super) type Held = TcpSocket;

    /// As many connections as the system queues for a listener before they are
    /// accepted (tokio's own choice).
    const BACKLOG: u32 = 1024;

    pub(super) async fn bind(addr: SocketAddr) -> io::Result<(SocketAddr, TcpListener)> {
        // A socket without `SO_REUSEPORT` first, as any other server's: it cannot be
        // bound where a listener is, or where another hub holds the port.
        let probe = new_socket(addr)?;
        probe.set_reuseaddr(true)?;
        probe.bind(addr)?;
        let addr = probe.local_addr()?;
        drop(probe);
        let listener = listen(addr).await?;
        Ok((addr, listener))
    }

    pub(super) fn hold(addr: SocketAddr) -> io::Result<Option<Held>> {
        let held = new_socket(addr)?;
        // Not `SO_REUSEADDR`: with it, a socket of another program that sets it too
        // could bind the port while nobody listens there.
        held.set_reuseport(true)?;
        held.bind(addr)?;
        Ok(Some(held))
    }

    pub(super) async fn listen(addr: SocketAddr) -> io::Result<TcpListener> {
        let socket = new_socket(addr)?;
        // Past connections in TIME_WAIT do not keep the port from being listened on.
        socket.set_reuseaddr(true)?;
        // Beside the socket that holds the port.
        socket.set_reuseport(true)?;
        socket.bind(addr)?;
        socket.listen(BACKLOG)
    }

    fn new_socket(addr: SocketAddr) -> io::Result<TcpSocket> {
        match addr {
            SocketAddr::V4(_) => TcpSocket::new_v4(),
            SocketAddr::V6(_) => TcpSocket::new_v6(),
        }
    }
}

/// Where it does not: the port is given up during an outage.
#[cfg(not(holds_port))]
mod system {
    use std::io;
    use std::net::SocketAddr;

    use tokio::net::TcpListener;

    /// Nothing holds the port.
    pub(super) type Held = ();

    pub(super) async fn bind(addr: SocketAddr) -> io::Result<(SocketAddr, TcpListener)> {
        let listener = listen(addr).await?;
        Ok((listener.local_addr()?, listener))
    }

    pub(super) fn hold(_addr: SocketAddr) -> io::Result<Option<Held>> {
        Ok(None)
    }

    pub(super) async fn listen(addr: SocketAddr) -> io::Result<TcpListener> {
        TcpListener::bind(addr).await
    }
}
