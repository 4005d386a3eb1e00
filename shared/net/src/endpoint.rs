//! Where a Zenoh session listens or connects: `tcp/HOST:PORT` or `tls/HOST:PORT`.

use std::fmt;
use std::net::IpAddr;

/// The link protocol of an [`Endpoint`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LinkProtocol {
    /// Plain TCP: nothing is encrypted or authenticated.
    Tcp,
    /// TLS over TCP, with certificates on both sides ([`crate::Security::Tls`]).
    Tls,
}

/// A Zenoh endpoint, checked: a protocol, a host (name or address) and a port.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Endpoint {
    /// The link protocol.
    pub protocol: LinkProtocol,
    /// The host: an IP address (IPv6 in brackets) or a name.
    pub host: String,
    /// The port.
    pub port: u16,
}

/// Why a text is not an endpoint.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum EndpointError {
    /// The text does not start with `tcp/` or `tls/`.
    #[error("endpoint {0:?}: expected tcp/HOST:PORT or tls/HOST:PORT")]
    Protocol(String),
    /// There is no `:PORT`, or the port is not a number from 1 to 65535.
    #[error("endpoint {0:?}: expected a port from 1 to 65535 after the host")]
    Port(String),
    /// The host is empty or holds characters no host name or address has.
    #[error("endpoint {0:?}: the host is not a name or an address")]
    Host(String),
}

impl Endpoint {
    /// Parse `tcp/HOST:PORT` or `tls/HOST:PORT`.
    ///
    /// ```
    /// use net::{Endpoint, LinkProtocol};
    /// let e = Endpoint::parse("tcp/127.0.0.1:7447").unwrap();
    /// assert_eq!((e.protocol, e.port), (LinkProtocol::Tcp, 7447));
    /// assert!(e.is_loopback());
    /// assert!(Endpoint::parse("udp/127.0.0.1:7447").is_err());
    /// ```
    pub fn parse(text: &str) -> Result<Self, EndpointError> {
        let (protocol, rest) = if let Some(rest) = text.strip_prefix("tcp/") {
            (LinkProtocol::Tcp, rest)
        } else if let Some(rest) = text.strip_prefix("tls/") {
            (LinkProtocol::Tls, rest)
        } else {
            return Err(EndpointError::Protocol(text.to_string()));
        };
        let (host, port) = rest
            .rsplit_once(':')
            .ok_or_else(|| EndpointError::Port(text.to_string()))?;
        let port: u16 = port
            .parse()
            .ok()
            .filter(|&p| p > 0)
            .ok_or_else(|| EndpointError::Port(text.to_string()))?;
        let bare = host
            .strip_prefix('[')
            .and_then(|h| h.strip_suffix(']'))
            .unwrap_or(host);
        let host_ok = !bare.is_empty()
            && bare
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | ':'));
        if !host_ok || (bare.contains(':') && bare == host) {
            return Err(EndpointError::Host(text.to_string()));
        }
        Ok(Self {
            protocol,
            host: host.to_string(),
            port,
        })
    }

    /// The host without the brackets of an IPv6 address (`::1` for `[::1]`): the name a
    /// certificate gives it.
    pub fn bare_host(&self) -> &str {
        self.host
            .strip_prefix('[')
            .and_then(|h| h.strip_suffix(']'))
            .unwrap_or(&self.host)
    }

    /// The host as an address, if it is one.
    fn address(&self) -> Option<IpAddr> {
        self.bare_host().parse().ok()
    }

    /// Whether the host is this machine's loopback (`127.0.0.0/8`, `::1` or
    /// `localhost`): traffic that never leaves the machine.
    pub fn is_loopback(&self) -> bool {
        self.host == "localhost" || self.address().is_some_and(|a| a.is_loopback())
    }

    /// Whether the host is the unspecified address (`0.0.0.0` or `::`): every interface.
    pub fn is_unspecified(&self) -> bool {
        self.address().is_some_and(|a| a.is_unspecified())
    }

    /// Where a process on this machine connects to reach a session listening here: the
    /// same endpoint, with the unspecified address replaced by the loopback.
    pub fn local_connect(&self) -> Self {
        let mut e = self.clone();
        match self.address() {
            Some(IpAddr::V4(a)) if a.is_unspecified() => e.host = "127.0.0.1".into(),
            Some(IpAddr::V6(a)) if a.is_unspecified() => e.host = "[::1]".into(),
            _ => {}
        }
        e
    }
}

impl fmt::Display for Endpoint {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let protocol = match self.protocol {
            LinkProtocol::Tcp => "tcp",
            LinkProtocol::Tls => "tls",
        };
        write!(f, "{protocol}/{}:{}", self.host, self.port)
    }
}

impl std::str::FromStr for Endpoint {
    type Err = EndpointError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::parse(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_prints_back() {
        for text in [
            "tcp/127.0.0.1:7447",
            "tls/10.0.0.1:1",
            "tcp/[::1]:65535",
            "tcp/robot-3.local:7447",
        ] {
            assert_eq!(Endpoint::parse(text).unwrap().to_string(), text);
        }
    }

    #[test]
    fn refuses_what_is_not_an_endpoint() {
        for text in [
            "",
            "127.0.0.1:7447",
            "udp/127.0.0.1:7447",
            "tcp/127.0.0.1",
            "tcp/127.0.0.1:0",
            "tcp/127.0.0.1:70000",
            "tcp/:7447",
            "tcp/a b:7447",
            "tcp/::1:7447",
            "tcp/host/x:7447",
        ] {
            assert!(Endpoint::parse(text).is_err(), "{text:?} accepted");
        }
    }

    #[test]
    fn loopback_and_unspecified() {
        let e = |t: &str| Endpoint::parse(t).unwrap();
        assert!(e("tcp/127.0.0.2:1").is_loopback());
        assert!(e("tcp/[::1]:1").is_loopback());
        assert!(e("tcp/localhost:1").is_loopback());
        assert!(!e("tcp/10.0.0.1:1").is_loopback());
        assert!(!e("tcp/0.0.0.0:1").is_loopback());
        assert_eq!(e("tcp/0.0.0.0:9").local_connect(), e("tcp/127.0.0.1:9"));
        assert_eq!(e("tls/[::]:9").local_connect(), e("tls/[::1]:9"));
        assert_eq!(e("tcp/10.0.0.1:9").local_connect(), e("tcp/10.0.0.1:9"));
    }
}
