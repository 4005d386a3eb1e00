//! Who may talk to whom over the network: plain TCP or TLS, the TLS files of each side
//! and the names in their certificates ([`Role`]), and the check of an endpoint against
//! them.

use std::path::{Path, PathBuf};

use crate::endpoint::{Endpoint, LinkProtocol};

/// Who may talk to whom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Security {
    /// Plain TCP: anyone who reaches the port may join, another user of this machine
    /// too. Only with the user's explicit consent ([`check_security`]).
    Plain,
    /// TLS with certificates on both sides, signed by one certificate authority.
    Tls(TlsFiles),
}

/// Who a TLS certificate names (its common name, `formation ROLE`): the router lets each
/// do only its part (`open_router`, with the feature `zenoh`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// The coordinator's router.
    Coordinator,
    /// A relay, on the coordinator's host: any key of the run.
    Relay,
    /// Agent I: its own keys, and the coordinator's liveliness.
    Agent(usize),
}

impl Role {
    /// The file stem (`coordinator`, `relay`, `agent-I`); the certificate's common name is
    /// `formation ` and this.
    pub fn stem(self) -> String {
        match self {
            Self::Coordinator => "coordinator".into(),
            Self::Relay => "relay".into(),
            Self::Agent(i) => format!("agent-{i}"),
        }
    }
}

/// The PEM files of one side of a TLS link, in a folder (`--tls-dir`): `ca.pem` (the
/// authority every side trusts), `STEM.pem` and `STEM-key.pem` (this side's certificate
/// and private key, [`Role::stem`]); `scripts/make-tls-dir` makes them.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TlsFiles {
    /// The certificate authority.
    pub ca: PathBuf,
    /// This side's certificate.
    pub certificate: PathBuf,
    /// This side's private key.
    pub private_key: PathBuf,
}

impl TlsFiles {
    /// The files of `role` in `dir`.
    pub fn in_dir(dir: &Path, role: Role) -> Self {
        let stem = role.stem();
        Self {
            ca: dir.join("ca.pem"),
            certificate: dir.join(format!("{stem}.pem")),
            private_key: dir.join(format!("{stem}-key.pem")),
        }
    }
}

/// Why a session cannot be opened.
#[derive(Debug, thiserror::Error)]
pub enum SessionError {
    /// Plain TCP without the user's consent (`--allow-plain-tcp`), on the loopback too.
    #[error(
        "{0}: plain TCP lets anyone who reaches the port join (on the loopback, any other user of this machine); use tls/ (with no --tls-dir the run makes its own authority), or pass --allow-plain-tcp"
    )]
    PlainWithoutConsent(Endpoint),
    /// The endpoint's protocol and the security disagree.
    #[error("{0}: {1}")]
    Mismatch(Endpoint, &'static str),
    /// A TLS file is missing or unreadable.
    #[error("{}: {source}", path.display())]
    TlsFile {
        /// The file.
        path: PathBuf,
        /// Why it cannot be read.
        source: std::io::Error,
    },
    /// Zenoh refused the configuration or could not open the session.
    #[error("zenoh: {0}")]
    Zenoh(String),
}

/// Check that `endpoint` may be used with `security`: TLS needs `tls/`, plain needs
/// `tcp/` and the user's consent (`allow_plain_tcp`), wherever the host is.
///
/// ```
/// use net::{Endpoint, Security, check_security};
/// let loopback = Endpoint::parse("tcp/127.0.0.1:7447").unwrap();
/// assert!(check_security(&loopback, &Security::Plain, false).is_err());
/// assert!(check_security(&loopback, &Security::Plain, true).is_ok());
/// ```
pub fn check_security(
    endpoint: &Endpoint,
    security: &Security,
    allow_plain_tcp: bool,
) -> Result<(), SessionError> {
    match (security, endpoint.protocol) {
        (Security::Tls(_), LinkProtocol::Tls) => Ok(()),
        (Security::Tls(_), LinkProtocol::Tcp) => Err(SessionError::Mismatch(
            endpoint.clone(),
            "certificates given (--tls-dir) for a tcp/ endpoint: use tls/",
        )),
        (Security::Plain, LinkProtocol::Tls) => Err(SessionError::Mismatch(
            endpoint.clone(),
            "a tls/ endpoint needs certificates (--tls-dir)",
        )),
        (Security::Plain, LinkProtocol::Tcp) => {
            if allow_plain_tcp {
                Ok(())
            } else {
                Err(SessionError::PlainWithoutConsent(endpoint.clone()))
            }
        }
    }
}
