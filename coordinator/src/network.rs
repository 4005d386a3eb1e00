//! Agents on other machines (`--transport zenoh`): the coordinator's Zenoh router and
//! what a relay is started with (see the `net` crate for the design).

use std::path::PathBuf;

use anyhow::Context;
use net::zenoh::Wait;
use net::zenoh::liveliness::LivelinessToken;
use net::{Endpoint, Security, TlsFiles};

/// How agents reach the coordinator over Zenoh.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NetworkOptions {
    /// Where the router listens.
    pub listen: Endpoint,
    /// The agents the user starts (on other machines, `agent --connect`); the coordinator
    /// starts the others itself, on this host.
    pub remote: Vec<usize>,
    /// The folder of TLS files (`ca.pem`, `coordinator.pem`, `coordinator-key.pem`; the
    /// relays use `agent.pem` and `agent-key.pem`) for a `tls/` endpoint.
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
    pub fn check(&self) -> Result<(), String> {
        for role in ["coordinator", "agent"] {
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

    fn security(&self, role: &str) -> Security {
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
pub struct Router {
    _token: LivelinessToken,
    session: net::zenoh::Session,
}

impl Router {
    /// Open the router on `options.listen`.
    pub fn open(options: &NetworkOptions) -> anyhow::Result<Self> {
        let security = options.security("coordinator");
        net::check_security(&options.listen, &security, options.allow_plain_tcp)?;
        let session = net::open_router(&options.listen, &security)
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
        drop(self._token);
        if let Err(e) = self.session.close().wait() {
            tracing::warn!("closing the zenoh router: {e}");
        }
    }
}
