//! Who the client is, by address: the peer of the connection, or, when the peer is a
//! reverse proxy the operator trusts (`serve --trusted-proxies`), the address that proxy
//! forwards in `X-Forwarded-For` (or `Forwarded`, RFC 7239).
//!
//! A forwarding header is a list that each proxy appends its own peer to. Anything left
//! of the entry the nearest trusted proxy wrote came from the client or from proxies
//! nobody vouches for, so the list is walked from the right, skipping trusted proxies:
//! the first address that is not one is the client. The leftmost entry is never taken
//! as such (a client can put anything there). From a peer that is not a trusted proxy
//! the headers are ignored. Only the header the operator's proxy writes is read: a
//! proxy that appends to `X-Forwarded-For` passes a client's own `Forwarded` header on
//! untouched, and reading it would let the client choose its address.

use std::net::{IpAddr, SocketAddr};
use std::str::FromStr;

use axum::http::HeaderMap;
use ipnet::IpNet;

/// The client's address of a request ([`TrustedProxies::client`]), put in the request's
/// extensions by the connection that received it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ClientAddress(pub IpAddr);

/// Which header a trusted proxy writes the client's address in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum ProxyHeader {
    /// `X-Forwarded-For: client, proxy1, ...` (nginx's `$proxy_add_x_forwarded_for`,
    /// the Kubernetes ingress-nginx, most load balancers).
    #[default]
    XForwardedFor,
    /// `Forwarded: for=client, for=proxy1` (RFC 7239).
    Forwarded,
}

/// The reverse proxies whose forwarding header is believed.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct TrustedProxies {
    nets: Vec<IpNet>,
    header: ProxyHeader,
}

impl TrustedProxies {
    /// No proxy is trusted: every client is its connection's peer.
    pub fn none() -> TrustedProxies {
        TrustedProxies::default()
    }

    /// The proxies in `list` (addresses or networks, `10.0.0.0/8,192.168.1.7,::1`,
    /// separated by commas or spaces), whose client address is read from `header`.
    ///
    /// # Errors
    /// An entry that is neither an address nor a network, named.
    pub fn parse(list: &str, header: ProxyHeader) -> Result<TrustedProxies, String> {
        let mut nets = Vec::new();
        for entry in list
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|e| !e.is_empty())
        {
            let net = IpNet::from_str(entry)
                .or_else(|_| IpAddr::from_str(entry).map(IpNet::from))
                .map_err(|_| {
                    format!(
                        "trusted proxy {entry:?} is not an address or a network (such as 10.0.0.0/8 or 127.0.0.1)"
                    )
                })?;
            nets.push(net.trunc());
        }
        Ok(TrustedProxies { nets, header })
    }

    /// Whether any proxy is trusted.
    pub fn is_empty(&self) -> bool {
        self.nets.is_empty()
    }

    /// Whether `addr` is a trusted proxy.
    pub fn trusts(&self, addr: IpAddr) -> bool {
        let addr = addr.to_canonical();
        self.nets.iter().any(|n| n.contains(&addr))
    }

    /// The client of a request that came from `peer` with `headers`: `peer` unless it is
    /// a trusted proxy; else the rightmost address of the forwarding header that is not
    /// a trusted proxy. Where the walk meets an entry that names no address (`unknown`,
    /// an obfuscated name, garbage) or runs out, the last trusted hop is the client: it
    /// is the nearest address anyone vouches for.
    pub fn client(&self, peer: IpAddr, headers: &HeaderMap) -> IpAddr {
        let mut client = peer.to_canonical();
        if !self.trusts(client) {
            return client;
        }
        let name = match self.header {
            ProxyHeader::XForwardedFor => "x-forwarded-for",
            ProxyHeader::Forwarded => "forwarded",
        };
        // Several header lines are one list, in order.
        let lines: Vec<&str> = headers
            .get_all(name)
            .iter()
            .filter_map(|v| v.to_str().ok())
            .collect();
        for entry in lines.iter().rev().flat_map(|line| line.rsplit(',')) {
            let entry = entry.trim();
            if entry.is_empty() {
                continue;
            }
            let Some(addr) = self.entry_address(entry) else {
                break;
            };
            client = addr.to_canonical();
            if !self.trusts(client) {
                break;
            }
        }
        client
    }

    /// The address one entry of the forwarding header names, if it names one.
    fn entry_address(&self, entry: &str) -> Option<IpAddr> {
        match self.header {
            ProxyHeader::XForwardedFor => IpAddr::from_str(entry)
                .ok()
                .or_else(|| SocketAddr::from_str(entry).ok().map(|s| s.ip())),
            ProxyHeader::Forwarded => forwarded_header_value::ForwardedStanza::from_str(entry)
                .ok()?
                .forwarded_for_ip(),
        }
    }
}

/// The client's address of a request, by the connection's [`ClientAddress`] (its peer
/// when no connection put one there: a request made inside the process).
pub fn of_request<B>(request: &axum::http::Request<B>) -> Option<IpAddr> {
    of_extensions(request.extensions())
}

/// [`of_request`] from a request's extensions.
pub fn of_extensions(extensions: &axum::http::Extensions) -> Option<IpAddr> {
    extensions.get::<ClientAddress>().map(|c| c.0).or_else(|| {
        extensions
            .get::<axum::extract::ConnectInfo<SocketAddr>>()
            .map(|c| c.0.ip().to_canonical())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn headers(name: &str, values: &[&str]) -> HeaderMap {
        let mut h = HeaderMap::new();
        for v in values {
            h.append(
                axum::http::HeaderName::from_str(name).unwrap(),
                v.parse().unwrap(),
            );
        }
        h
    }

    fn ip(s: &str) -> IpAddr {
        s.parse().unwrap()
    }

    #[test]
    fn a_peer_that_is_not_trusted_is_the_client_whatever_it_sends() {
        let t = TrustedProxies::parse("10.0.0.0/8", ProxyHeader::XForwardedFor).unwrap();
        let h = headers("x-forwarded-for", &["1.1.1.1"]);
        assert_eq!(t.client(ip("203.0.113.9"), &h), ip("203.0.113.9"));
        // Nothing trusted: the same.
        assert_eq!(
            TrustedProxies::none().client(ip("10.1.1.1"), &h),
            ip("10.1.1.1")
        );
    }

    #[test]
    fn the_walk_from_the_right_skips_trusted_proxies_and_ignores_what_the_client_prepended() {
        let t = TrustedProxies::parse("10.0.0.0/8, 127.0.0.1", ProxyHeader::XForwardedFor).unwrap();
        // The client forged "6.6.6.6" on the left; the proxy appended its real peer.
        let h = headers("x-forwarded-for", &["6.6.6.6, 198.51.100.7"]);
        assert_eq!(t.client(ip("127.0.0.1"), &h), ip("198.51.100.7"));
        // Two trusted proxies in a row: both skipped.
        let h = headers("x-forwarded-for", &["6.6.6.6, 198.51.100.7, 10.2.3.4"]);
        assert_eq!(t.client(ip("10.9.9.9"), &h), ip("198.51.100.7"));
        // Several header lines are one list.
        let h = headers("x-forwarded-for", &["6.6.6.6", "198.51.100.7, 10.2.3.4"]);
        assert_eq!(t.client(ip("10.9.9.9"), &h), ip("198.51.100.7"));
        // Garbage right of the client's entry stops the walk at the last trusted hop.
        let h = headers("x-forwarded-for", &["198.51.100.7, unknown, 10.2.3.4"]);
        assert_eq!(t.client(ip("10.9.9.9"), &h), ip("10.2.3.4"));
        // Garbage left of it changes nothing.
        let h = headers("x-forwarded-for", &["not an address, 198.51.100.7"]);
        assert_eq!(t.client(ip("10.9.9.9"), &h), ip("198.51.100.7"));
        // No header: the proxy itself.
        assert_eq!(t.client(ip("10.9.9.9"), &HeaderMap::new()), ip("10.9.9.9"));
        // Entries with a port, and IPv4-mapped addresses.
        let h = headers("x-forwarded-for", &["198.51.100.7:5555"]);
        assert_eq!(t.client(ip("::ffff:127.0.0.1"), &h), ip("198.51.100.7"));
    }

    #[test]
    fn forwarded_is_read_only_when_it_is_the_proxys_header() {
        let xff = TrustedProxies::parse("127.0.0.1", ProxyHeader::XForwardedFor).unwrap();
        let fwd = TrustedProxies::parse("127.0.0.1", ProxyHeader::Forwarded).unwrap();
        let mut h = headers(
            "forwarded",
            &["for=6.6.6.6, for=\"[2001:db8::1]:4711\";proto=https"],
        );
        h.append("x-forwarded-for", "198.51.100.7".parse().unwrap());
        assert_eq!(fwd.client(ip("127.0.0.1"), &h), ip("2001:db8::1"));
        assert_eq!(xff.client(ip("127.0.0.1"), &h), ip("198.51.100.7"));
    }

    #[test]
    fn bad_entries_are_named() {
        let e = TrustedProxies::parse("10.0.0.0/8,proxy.local", ProxyHeader::XForwardedFor)
            .unwrap_err();
        assert!(e.contains("proxy.local"), "{e}");
        let t = TrustedProxies::parse("192.168.1.7/24", ProxyHeader::XForwardedFor).unwrap();
        assert!(t.trusts(ip("192.168.1.200")));
        assert!(!t.trusts(ip("192.168.2.1")));
    }
}
