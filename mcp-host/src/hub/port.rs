//! The hub's TCP port: listened on while the radio is there, and held while it is not,
//! so that clients are refused then and no other program can take the port.
//!
//! A listening socket cannot stop listening without giving its port up. So where the
//! system allows it (Unix, but Solaris and illumos), the port is held by a second
//! socket, bound to the same address with `SO_REUSEPORT` and never listening: the
//! system refuses connections to a port nobody listens on, and other programs cannot
//! bind it (sharing a port takes `SO_REUSEPORT` on every socket, from the same user).
//! Elsewhere the port is given up during an outage, and listened on again once it is
//! free.

use std::io;
use std::net::SocketAddr;

use tokio::net::TcpListener;

/// The address the hub serves on, held between outages of the radio.
pub(super) struct Port {
    addr: SocketAddr,
    /// What keeps the port while no listener does.
    _held: system::Held,
}

impl Port {
    /// Binds `listen` (`ADDR:PORT`, a host name resolved) and listens there: the first
    /// of its addresses that can be had, as [`TcpListener::bind`] does.
    pub(super) async fn bind(listen: &str) -> io::Result<(Port, TcpListener)> {
        let mut last = None;
        for addr in tokio::net::lookup_host(listen).await? {
            match system::bind(addr).await {
                Ok((held, addr, listener)) => return Ok((Port { addr, _held: held }, listener)),
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

    /// Listens on the port again, after an outage. Where the port is held this fails
    /// only if another socket of this user shares it; elsewhere, if another program
    /// took it meanwhile.
    pub(super) async fn listen(&self) -> io::Result<TcpListener> {
        system::listen(self.addr).await
    }
}

/// Where the system lets a bound socket hold the port.
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

    pub(super) async fn bind(addr: SocketAddr) -> io::Result<(Held, SocketAddr, TcpListener)> {
        let held = new_socket(addr)?;
        // Not `SO_REUSEADDR`: with it, a socket of another program that sets it too
        // could bind the port while nobody listens there.
        held.set_reuseport(true)?;
        held.bind(addr)?;
        let addr = held.local_addr()?;
        let listener = listen(addr).await?;
        Ok((held, addr, listener))
    }

    pub(super) async fn listen(addr: SocketAddr) -> io::Result<TcpListener> {
        let socket = new_socket(addr)?;
        // Past connections in TIME_WAIT do not keep the port from being listened on.
        socket.set_reuseaddr(true)?;
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

    pub(super) type Held = ();

    pub(super) async fn bind(addr: SocketAddr) -> io::Result<(Held, SocketAddr, TcpListener)> {
        let listener = listen(addr).await?;
        Ok(((), listener.local_addr()?, listener))
    }

    pub(super) async fn listen(addr: SocketAddr) -> io::Result<TcpListener> {
        TcpListener::bind(addr).await
    }
}
