//! Opening Zenoh sessions: the coordinator's router, listening on an endpoint, and the
//! clients (relays and agents) connecting to it. Explicit endpoints only: no multicast
//! or gossip scouting, which many networks (and CI) block.

use std::path::Path;
use std::time::Duration;

use zenoh::{Session, Wait};

use crate::endpoint::Endpoint;
use crate::security::{Role, Security, SessionError};

/// A link's lease: a peer silent this long (its process gone, its link down) is dropped
/// and its liveliness tokens with it. Zenoh's default is 10 s; a lease of 1 s drops healthy
/// agents on a loaded 2-core machine (keep-alives are sent every quarter lease). A silent agent
/// is caught sooner anyway, by the turn deadline.
pub const LINK_LEASE: Duration = Duration::from_millis(3000);

/// How long a client tries to reach the router before giving up.
pub const CONNECT_TIMEOUT: Duration = Duration::from_secs(10);

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
