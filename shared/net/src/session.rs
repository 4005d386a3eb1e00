//! Opening Zenoh sessions: the coordinator's router, listening on an endpoint, and the
//! clients (relays and agents) connecting to it. Explicit endpoints only: no multicast
//! or gossip scouting, which many networks (and CI) block.

use std::path::{Path, PathBuf};
use std::time::Duration;

use zenoh::{Session, Wait};

use crate::endpoint::{Endpoint, LinkProtocol};

/// A link's lease: a peer silent this long (its process gone, its link down) is dropped
/// and its liveliness tokens with it. Zenoh's default is 10 s; 1 s dropped healthy agents
/// on a loaded 2-core machine (keep-alives are sent every quarter lease). A silent agent
/// is caught sooner anyway, by the turn deadline.
pub const LINK_LEASE: Duration = Duration::from_millis(3000);

/// How long a client tries to reach the router before giving up.
pub const CONNECT_TIMEOUT: Duration = Duration::from_secs(10);

/// Who may talk to whom.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Security {
    /// Plain TCP: anyone who reaches the port may join. Loopback only, unless the user
    /// says otherwise ([`check_security`]).
    Plain,
    /// TLS with certificates on both sides, signed by one certificate authority.
    Tls(TlsFiles),
}

/// Who a TLS certificate names (its common name, `formation ROLE`): the router lets each
/// do only its part ([`open_router`]).
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
    /// Plain TCP on an endpoint beyond the loopback without the user's consent.
    #[error(
        "{0}: plain TCP beyond the loopback lets anyone on the network join; use tls/ with --tls-dir, or pass --allow-plain-tcp"
    )]
    PlainBeyondLoopback(Endpoint),
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
/// `tcp/` and, unless `allow_plain_beyond_loopback`, a loopback host.
pub fn check_security(
    endpoint: &Endpoint,
    security: &Security,
    allow_plain_beyond_loopback: bool,
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
            if endpoint.is_loopback() || allow_plain_beyond_loopback {
                Ok(())
            } else {
                Err(SessionError::PlainBeyondLoopback(endpoint.clone()))
            }
        }
    }
}

fn zenoh_err(e: impl std::fmt::Display) -> SessionError {
    SessionError::Zenoh(e.to_string())
}

fn insert(config: &mut zenoh::Config, key: &str, value: &str) -> Result<(), SessionError> {
    config
        .insert_json5(key, value)
        .map_err(|e| SessionError::Zenoh(format!("{key} = {value}: {e}")))
}

/// A JSON string literal.
fn json_string(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            c if c.is_control() => out.push_str(&format!("\\u{:04x}", c as u32)),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

fn base_config(
    mode: &str,
    security: &Security,
    listening: bool,
) -> Result<zenoh::Config, SessionError> {
    let mut config = zenoh::Config::default();
    insert(&mut config, "mode", &json_string(mode))?;
    insert(&mut config, "scouting/multicast/enabled", "false")?;
    insert(&mut config, "scouting/gossip/enabled", "false")?;
    insert(
        &mut config,
        "transport/link/tx/lease",
        &LINK_LEASE.as_millis().to_string(),
    )?;
    if let Security::Tls(files) = security {
        for path in [&files.ca, &files.certificate, &files.private_key] {
            std::fs::metadata(path).map_err(|source| SessionError::TlsFile {
                path: path.clone(),
                source,
            })?;
        }
        let path = |p: &Path| json_string(&p.display().to_string());
        insert(
            &mut config,
            "transport/link/tls/root_ca_certificate",
            &path(&files.ca),
        )?;
        insert(&mut config, "transport/link/tls/enable_mtls", "true")?;
        let (cert_key, key_key) = if listening {
            ("listen_certificate", "listen_private_key")
        } else {
            ("connect_certificate", "connect_private_key")
        };
        insert(
            &mut config,
            &format!("transport/link/tls/{cert_key}"),
            &path(&files.certificate),
        )?;
        insert(
            &mut config,
            &format!("transport/link/tls/{key_key}"),
            &path(&files.private_key),
        )?;
    }
    Ok(config)
}

/// The router's access control for `agents` agents (TLS only: it names clients by their
/// certificate). Denied unless allowed: a relay may use every key of the run; agent I
/// only its own keys (`formation/agent/I/...`), and may watch the coordinator's
/// liveliness token but not declare it. So a certified agent can neither read another's
/// turns (and their tokens) nor answer them.
fn access_control(agents: usize) -> String {
    let name = |role: Role| json_string(&format!("formation {}", role.stem()));
    let mut rules = vec![
        r#"{ id: "relay", permission: "allow", flows: ["ingress", "egress"],
            messages: ["put", "delete", "declare_subscriber", "query", "reply", "declare_queryable",
                       "liveliness_token", "liveliness_query", "declare_liveliness_subscriber"],
            key_exprs: ["formation/**"] }"#
            .to_string(),
        format!(
            r#"{{ id: "watch-coordinator-in", permission: "allow", flows: ["ingress"],
                messages: ["declare_liveliness_subscriber", "liveliness_query"],
                key_exprs: [{key}] }}"#,
            key = json_string(crate::COORDINATOR_ALIVE_KEY)
        ),
        format!(
            r#"{{ id: "watch-coordinator-out", permission: "allow", flows: ["egress"],
                messages: ["liveliness_token", "reply"],
                key_exprs: [{key}] }}"#,
            key = json_string(crate::COORDINATOR_ALIVE_KEY)
        ),
    ];
    let mut subjects = vec![format!(
        r#"{{ id: "relay", cert_common_names: [{}] }}"#,
        name(Role::Relay)
    )];
    let mut policies = vec![r#"{ rules: ["relay"], subjects: ["relay"] }"#.to_string()];
    for i in 0..agents {
        rules.push(format!(
            r#"{{ id: "agent-{i}", permission: "allow", flows: ["ingress", "egress"],
                messages: ["put", "declare_subscriber", "liveliness_token",
                           "declare_liveliness_subscriber", "liveliness_query", "reply"],
                key_exprs: ["formation/agent/{i}/**"] }}"#
        ));
        subjects.push(format!(
            r#"{{ id: "agent-{i}", cert_common_names: [{}] }}"#,
            name(Role::Agent(i))
        ));
        policies.push(format!(
            r#"{{ rules: ["agent-{i}", "watch-coordinator-in", "watch-coordinator-out"], subjects: ["agent-{i}"] }}"#
        ));
    }
    format!(
        "{{ enabled: true, default_permission: \"deny\", rules: [{}], subjects: [{}], policies: [{}] }}",
        rules.join(", "),
        subjects.join(", "),
        policies.join(", ")
    )
}

/// Open the coordinator's router for `agents` agents, listening on `listen`. Over TLS,
/// each client may do only its part ([`Role`]).
pub fn open_router(
    listen: &Endpoint,
    security: &Security,
    agents: usize,
) -> Result<Session, SessionError> {
    let mut config = base_config("router", security, true)?;
    if matches!(security, Security::Tls(_)) {
        insert(&mut config, "access_control", &access_control(agents))?;
    }
    insert(
        &mut config,
        "listen/endpoints",
        &format!("[{}]", json_string(&listen.to_string())),
    )?;
    zenoh::open(config).wait().map_err(zenoh_err)
}

/// Open a client session connected to the router at `connect` (tried for
/// [`CONNECT_TIMEOUT`]).
pub fn open_client(connect: &Endpoint, security: &Security) -> Result<Session, SessionError> {
    let mut config = base_config("client", security, false)?;
    insert(
        &mut config,
        "connect/endpoints",
        &format!("[{}]", json_string(&connect.to_string())),
    )?;
    insert(
        &mut config,
        "connect/timeout_ms",
        &CONNECT_TIMEOUT.as_millis().to_string(),
    )?;
    zenoh::open(config).wait().map_err(zenoh_err)
}
