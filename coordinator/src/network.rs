//! Agents on other machines (`--transport zenoh`): the coordinator's Zenoh router and
//! what a relay is started with (see the `net` crate for the design).

use std::path::PathBuf;

use net::{Endpoint, Role, Security, TlsFiles};

/// How agents reach the coordinator over Zenoh.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NetworkOptions {
    /// Where the router listens.
    pub listen: Endpoint,
    /// The agents the user starts (on other machines, `agent --connect`); the coordinator
    /// starts the others itself, on this host.
    pub remote: Vec<usize>,
    /// The folder of TLS files for a `tls/` endpoint: `ca.pem`, `coordinator.pem`,
    /// `relay.pem`, `agent-I.pem` for every agent started here, each with its `-key.pem`
    /// (`scripts/make-tls-dir`).
    pub tls_dir: Option<PathBuf>,
    /// Allow plain TCP beyond the loopback.
    pub allow_plain_tcp: bool,
}

impl NetworkOptions {
    /// Plain TCP on `listen`, every agent started by the coordinator.
    pub fn plain(listen: Endpoint) -> Self {
        Self {
            listen,
            remote: Vec::new(),
            tls_dir: None,
            allow_plain_tcp: false,
        }
    }

    /// Check the options before anything runs: the endpoint against the security (TLS
    /// needs `tls/` and `--tls-dir`, plain TCP the loopback or `--allow-plain-tcp`) and
    /// that every TLS file is there.
    pub fn check(&self, agents: usize) -> Result<(), String> {
        // The agents started here need their own files; remote ones bring theirs.
        let local_agents = (0..agents)
            .filter(|i| !self.remote.contains(i))
            .map(Role::Agent);
        for role in [Role::Coordinator, Role::Relay]
            .into_iter()
            .chain(local_agents)
        {
            let security = self.security(role);
            net::check_security(&self.listen, &security, self.allow_plain_tcp)
                .map_err(|e| e.to_string())?;
            if let Security::Tls(files) = &security {
                for path in [&files.ca, &files.certificate, &files.private_key] {
                    if !path.is_file() {
                        return Err(format!(
                            "--tls-dir: {} is missing (scripts/make-tls-dir makes the files)",
                            path.display()
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    fn security(&self, role: Role) -> Security {
        match &self.tls_dir {
            Some(dir) => Security::Tls(TlsFiles::in_dir(dir, role)),
            None => Security::Plain,
        }
    }

    /// The arguments that make agent `agent`'s process a relay.
    pub fn relay_args(&self, agent: usize) -> Vec<String> {
        let mut args = vec![
            "--relay".to_string(),
            self.listen.local_connect().to_string(),
        ];
        if !self.remote.contains(&agent) {
            args.push("--spawn-agent".to_string());
        }
        if let Some(dir) = &self.tls_dir {
            args.extend(["--tls-dir".to_string(), dir.display().to_string()]);
        }
        if self.allow_plain_tcp {
            args.push("--allow-plain-tcp".to_string());
        }
        args
    }
}

/// The coordinator's router and its liveliness token, for the run's length.
#[cfg(feature = "zenoh")]
pub struct Router {
    _token: net::zenoh::liveliness::LivelinessToken,
    session: net::zenoh::Session,
}

#[cfg(feature = "zenoh")]
impl Router {
    /// Open the router on `options.listen` for a run of `agents` agents.
    pub fn open(options: &NetworkOptions, agents: usize) -> anyhow::Result<Self> {
        use anyhow::Context;
        use net::zenoh::Wait;
        let security = options.security(Role::Coordinator);
        net::check_security(&options.listen, &security, options.allow_plain_tcp)?;
        let session = net::open_router(&options.listen, &security, agents)
            .with_context(|| format!("listening on {}", options.listen))?;
        let token = session
            .liveliness()
            .declare_token(net::COORDINATOR_ALIVE_KEY)
            .wait()
            .map_err(|e| anyhow::anyhow!("zenoh: {e}"))?;
        Ok(Self {
            _token: token,
            session,
        })
    }

    /// Close the router: agents still connected see the coordinator go.
    pub fn close(self) {
        use net::zenoh::Wait;
        drop(self._token);
        if let Err(e) = self.session.close().wait() {
            tracing::warn!("closing the zenoh router: {e}");
        }
    }
}

/// Without Zenoh there is no router: a run asked to use one is refused.
#[cfg(not(feature = "zenoh"))]
pub struct Router;

#[cfg(not(feature = "zenoh"))]
impl Router {
    /// Refuse: this coordinator was built without Zenoh.
    pub fn open(_options: &NetworkOptions, _agents: usize) -> anyhow::Result<Self> {
        anyhow::bail!("{NO_ZENOH}")
    }

    /// Nothing to close.
    pub fn close(self) {}
}

/// What a coordinator built without Zenoh says when asked to use it.
#[cfg(not(feature = "zenoh"))]
pub const NO_ZENOH: &str = "this coordinator was built without Zenoh: build it with `cargo build --release --features zenoh -p agent -p coordinator`";
