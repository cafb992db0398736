//! The server's connections: accepted with a cap on how many are open in all and from
//! one client address, served by hyper (HTTP/1) with a deadline for each request's head (which
//! also closes a kept-alive connection left idle that long), and finished gracefully on
//! shutdown. A client over a cap is closed at once, without a byte read; the body of a
//! request and its handling are bounded by the request timeout of [`super::app`]. A
//! trusted reverse proxy ([`super::client_address`]) is held to the total cap only: its
//! connections carry many clients, each of them known by the address it forwards.

use std::collections::HashMap;
use std::future::Future;
use std::net::IpAddr;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use axum::Router;
use axum::body::Body;
use hyper_util::rt::{TokioExecutor, TokioIo, TokioTimer};
use hyper_util::server::conn::auto;
use hyper_util::service::TowerToHyperService;
use tokio::net::TcpListener;
use tokio::sync::{OwnedSemaphorePermit, Semaphore};
use tower::ServiceExt;

use super::client_address::{ClientAddress, TrustedProxies};

/// Bounds on the server's connections.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ConnectionLimits {
    /// Most connections open at once, from every client together.
    pub max_connections: usize,
    /// Most connections open at once from one client address.
    pub max_per_address: usize,
    /// How long a client may take to send a request's head, from the moment the server
    /// waits for it: a new connection, or a kept-alive one between requests.
    pub head_timeout: Duration,
}

impl Default for ConnectionLimits {
    /// 4096 connections, 256 per address, 10 s for a request's head.
    fn default() -> Self {
        ConnectionLimits {
            max_connections: 4096,
            max_per_address: 256,
            head_timeout: Duration::from_secs(10),
        }
    }
}

/// Descriptors kept for everything but connections: the database, bots' pipes and
/// files, builds, logs.
const RESERVED_DESCRIPTORS: u64 = 1024;

impl ConnectionLimits {
    /// These limits fitted to the process's descriptors: the soft limit on open files is
    /// raised to the hard one, and the connection cap lowered (said in the log) when the
    /// connections would otherwise leave fewer than 1024 descriptors for the rest, so
    /// that open connections can never starve the database or the bots of descriptors.
    pub fn fitted_to_descriptors(mut self) -> ConnectionLimits {
        use nix::sys::resource::{Resource, getrlimit, setrlimit};
        let Ok((soft, hard)) = getrlimit(Resource::RLIMIT_NOFILE) else {
            return self;
        };
        let soft = if soft < hard && setrlimit(Resource::RLIMIT_NOFILE, hard, hard).is_ok() {
            hard
        } else {
            soft
        };
        let room = soft.saturating_sub(RESERVED_DESCRIPTORS).max(16);
        if (self.max_connections as u64) > room {
            tracing::warn!(
                asked = self.max_connections,
                allowed = room,
                open_files_limit = soft,
                "the connection cap is lowered to leave descriptors for the database and the bots"
            );
            self.max_connections = room as usize;
        }
        self.max_per_address = self.max_per_address.min(self.max_connections);
        self
    }
}

/// Open connections by client address.
#[derive(Debug, Default)]
struct PerAddress(Mutex<HashMap<IpAddr, usize>>);

/// One open connection's place under the caps; given back when dropped.
struct Held {
    _total: OwnedSemaphorePermit,
    addr: IpAddr,
    per_address: Arc<PerAddress>,
}

impl Drop for Held {
    fn drop(&mut self) {
        let mut open = self.per_address.0.lock().unwrap_or_else(|p| p.into_inner());
        if let Some(n) = open.get_mut(&self.addr) {
            *n -= 1;
            if *n == 0 {
                open.remove(&self.addr);
            }
        }
    }
}

impl PerAddress {
    /// Counts one more connection from `addr`, unless it has `max` open already.
    fn take(
        self: &Arc<Self>,
        addr: IpAddr,
        max: usize,
        total: OwnedSemaphorePermit,
    ) -> Option<Held> {
        let mut open = self.0.lock().unwrap_or_else(|p| p.into_inner());
        let n = open.entry(addr).or_insert(0);
        if *n >= max {
            return None;
        }
        *n += 1;
        Some(Held {
            _total: total,
            addr,
            per_address: self.clone(),
        })
    }
}

/// Serves `app` on `listener` within `limits` until `shutdown` completes, then lets
/// the requests in flight finish.
///
/// # Errors
/// None today: a failed accept (too many open files, a reset) is logged and retried.
pub async fn serve(
    listener: TcpListener,
    app: Router,
    limits: ConnectionLimits,
    trusted: Arc<TrustedProxies>,
    shutdown: impl Future<Output = ()> + Send + 'static,
) -> std::io::Result<()> {
    let total = Arc::new(Semaphore::new(limits.max_connections));
    let per_address = Arc::new(PerAddress::default());
    let graceful = hyper_util::server::graceful::GracefulShutdown::new();
    // HTTP/1 only: hyper's head timeout is HTTP/1's, and an HTTP/2 connection (h2c,
    // prior knowledge) could otherwise idle past it for good. (No upgrades are served:
    // `http1_only` holds only without them.)
    let mut builder = auto::Builder::new(TokioExecutor::new()).http1_only();
    builder
        .http1()
        .timer(TokioTimer::new())
        .header_read_timeout(limits.head_timeout);
    let builder = Arc::new(builder);
    tokio::pin!(shutdown);
    loop {
        let (stream, remote) = tokio::select! {
            accepted = listener.accept() => match accepted {
                Ok(pair) => pair,
                Err(e) => {
                    // Out of descriptors or a connection reset before it was taken:
                    // the listener itself is fine; wait a little on the first.
                    tracing::warn!(cause = %e, "cannot accept a connection");
                    if !matches!(e.kind(), std::io::ErrorKind::ConnectionAborted | std::io::ErrorKind::ConnectionReset) {
                        tokio::time::sleep(Duration::from_millis(50)).await;
                    }
                    continue;
                }
            },
            () = &mut shutdown => break,
        };
        let Ok(permit) = total.clone().try_acquire_owned() else {
            tracing::debug!(%remote, "connection refused: the server's connection cap is reached");
            continue;
        };
        // A trusted proxy carries many clients on its connections: it is held to the
        // total cap only.
        let most = if trusted.trusts(remote.ip()) {
            limits.max_connections
        } else {
            limits.max_per_address
        };
        let Some(held) = per_address.take(remote.ip(), most, permit) else {
            tracing::debug!(%remote, "connection refused: its address's connection cap is reached");
            continue;
        };
        let _ = stream.set_nodelay(true);
        // Each request carries its peer (`ConnectInfo`) and its client's address
        // (`ClientAddress`: behind a trusted proxy, the one it forwards), for the
        // budgets that count per address.
        let trusted = trusted.clone();
        let service = TowerToHyperService::new(app.clone().map_request(
            move |req: axum::http::Request<hyper::body::Incoming>| {
                let mut req = req.map(Body::new);
                let client = trusted.client(remote.ip(), req.headers());
                req.extensions_mut()
                    .insert(axum::extract::ConnectInfo(remote));
                req.extensions_mut().insert(ClientAddress(client));
                req
            },
        ));
        let connection = builder
            .serve_connection(TokioIo::new(stream), service)
            .into_owned();
        let connection = graceful.watch(connection);
        tokio::spawn(async move {
            if let Err(e) = connection.await {
                tracing::trace!(cause = %e, "a connection ended with an error");
            }
            drop(held);
        });
    }
    drop(listener);
    graceful.shutdown().await;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_address_is_held_to_its_cap_and_given_back() {
        let total = Arc::new(Semaphore::new(3));
        let per = Arc::new(PerAddress::default());
        let a: IpAddr = "10.0.0.1".parse().unwrap();
        let b: IpAddr = "10.0.0.2".parse().unwrap();
        let permit = || total.clone().try_acquire_owned().unwrap();
        let first = per.take(a, 2, permit()).unwrap();
        let _second = per.take(a, 2, permit()).unwrap();
        assert!(
            per.take(a, 2, permit()).is_none(),
            "a third from one address"
        );
        // The refused one's permit went back with it: b still gets in.
        let _other = per.take(b, 2, permit()).unwrap();
        assert_eq!(total.available_permits(), 0);
        drop(first);
        assert_eq!(total.available_permits(), 1);
        assert!(per.take(a, 2, permit()).is_some());
    }
}
