//! Agents on other machines (`--transport zenoh`): the coordinator's Zenoh router and
//! what a relay is started with (see the `net` crate for the design).

use std::path::PathBuf;

use net::{Endpoint, Role, Security, TlsFiles};

/// How agents reach the coordinator.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum TransportKind {
    /// iceoryx2 shared memory: every agent on this host.
    #[default]
    Ipc,
    /// Zenoh: each agent over the network, through a relay on this host; agents may run
    /// on other machines (`--remote`).
    Zenoh,
}

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
    /// (`scripts/make-tls-dir`). Without it the run makes its own authority
    /// ([`NetworkOptions::with_run_authority`]).
    pub tls_dir: Option<PathBuf>,
    /// Allow plain TCP (a `tcp/` endpoint), on the loopback too: anyone who reaches the
    /// port could join.
    pub allow_plain_tcp: bool,
}

impl NetworkOptions {
    /// The default: TLS on `listen` (a `tls/` endpoint) with the run's own authority,
    /// every agent started by the coordinator.
    pub fn new(listen: Endpoint) -> Self {
        Self {
            listen,
            remote: Vec::new(),
            tls_dir: None,
            allow_plain_tcp: false,
        }
    }

    /// Plain TCP on `listen` (a `tcp/` endpoint), consented to, every agent started by
    /// the coordinator.
    pub fn plain(listen: Endpoint) -> Self {
        Self {
            allow_plain_tcp: true,
            ..Self::new(listen)
        }
    }

    /// Check the options for a run of `agents` agents before anything runs: every
    /// `--remote` agent one of them, the endpoint against the security (TLS needs `tls/`,
    /// plain TCP `--allow-plain-tcp`), that agents the user starts elsewhere have an
    /// authority they can get files of before the run (`--tls-dir`), and that every TLS
    /// file the user named is there.
    pub fn check(&self, agents: usize) -> Result<(), String> {
        if let Some(a) = self.remote.iter().find(|&&a| a >= agents) {
            return Err(format!(
                "--remote {a}: the scenario has {agents} agents (0 to {})",
                agents.saturating_sub(1)
            ));
        }
        if self.makes_own_authority() {
            if !self.remote.is_empty() {
                return Err(
                    "--remote: agents started elsewhere need their certificates before the run: make them with scripts/make-tls-dir and pass --tls-dir".into(),
                );
            }
            // The run makes its own authority for exactly the roles it starts.
            return Ok(());
        }
        // The agents started here need their own files; remote ones bring theirs.
        for role in self.local_roles(agents) {
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

    /// Whether the run makes its own authority: a `tls/` endpoint and no `--tls-dir`.
    fn makes_own_authority(&self) -> bool {
        self.tls_dir.is_none() && self.listen.protocol == net::LinkProtocol::Tls
    }

    /// Whether the coordinator starts agent `agent` on this host (it is not `--remote`).
    pub fn starts_here(&self, agent: usize) -> bool {
        !self.remote.contains(&agent)
    }

    /// The agents of `agents` the coordinator starts on this host.
    pub fn agents_started_here(&self, agents: usize) -> impl Iterator<Item = usize> + '_ {
        (0..agents).filter(|&i| self.starts_here(i))
    }

    /// The roles that take part from this host: the coordinator, the relays, and every
    /// agent the coordinator starts.
    fn local_roles(&self, agents: usize) -> Vec<Role> {
        [Role::Coordinator, Role::Relay]
            .into_iter()
            .chain(self.agents_started_here(agents).map(Role::Agent))
            .collect()
    }

    /// These options for a run of `agents` agents whose private folder is `run_folder`:
    /// with a `tls/` endpoint and no `--tls-dir`, the run's own authority is made in
    /// `run_folder/tls` (certificates for the coordinator, the relays and the agents it
    /// starts; the authority's key is never written) and named as the TLS folder.
    #[cfg(feature = "zenoh")]
    pub fn with_run_authority(
        &self,
        run_folder: &std::path::Path,
        agents: usize,
    ) -> Result<Self, net::AuthorityError> {
        if !self.makes_own_authority() {
            return Ok(self.clone());
        }
        let dir = run_folder.join("tls");
        net::make_run_authority(&dir, &self.listen, &self.local_roles(agents))?;
        Ok(Self {
            tls_dir: Some(dir),
            ..self.clone()
        })
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
        if self.starts_here(agent) {
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
    options: NetworkOptions,
}

#[cfg(feature = "zenoh")]
impl Router {
    /// Open the router on `options.listen` for a run of `agents` agents whose private
    /// folder is `run_folder` (where the run's own authority is made, if it needs one).
    pub fn open(
        options: &NetworkOptions,
        agents: usize,
        run_folder: Option<&std::path::Path>,
    ) -> anyhow::Result<Self> {
        use anyhow::Context;
        use net::zenoh::Wait;
        let options = match run_folder {
            Some(folder) => options.with_run_authority(folder, agents)?,
            None => options.clone(),
        };
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
            options,
        })
    }

    /// The options the run goes on with: the TLS folder of its own authority named.
    pub fn options(&self) -> &NetworkOptions {
        &self.options
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
    pub fn open(
        _options: &NetworkOptions,
        _agents: usize,
        _run_folder: Option<&std::path::Path>,
    ) -> anyhow::Result<Self> {
        anyhow::bail!("{NO_ZENOH}")
    }

    /// Never reached: there is no router.
    pub fn options(&self) -> &NetworkOptions {
        unreachable!("{NO_ZENOH}")
    }

    /// Nothing to close.
    pub fn close(self) {}
}

/// What a coordinator built without Zenoh says when asked to use it.
#[cfg(not(feature = "zenoh"))]
pub const NO_ZENOH: &str = "this coordinator was built without Zenoh: build it with `cargo build --release --features zenoh -p agent -p coordinator`";
