//! The agent's test mode as the roles meet it: one value, [`TestMode`], that opens the
//! transport and serves turns as the mode has it. Its attacks come before the transport
//! is opened (the mission forged, other agents' channels raced, strays started), its
//! misbehaviour in the decorated transport ([`crate::misbehave::Misbehaving`], the ports
//! [`crate::misbehave::Tampered`]). Without the `misbehave` feature the mode is always
//! none and each method opens and serves as an honest agent does: the roles read the
//! same either way.

use crate::args::Args;
use crate::ipc::{IpcTransport, Mission};
use crate::serve::serve;
use crate::transport::Transport;
use wire::misbehave::Misbehave;

/// What an agent built without its test modes says when asked for one.
#[cfg(not(feature = "misbehave"))]
pub const NO_MISBEHAVE: &str = "this agent was built without its test modes: build it with `cargo build --release --features misbehave -p agent`";

/// The test mode agent `agent` runs in, if any.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TestMode {
    /// The agent's index.
    agent: usize,
    /// The mode; always `None` in an agent built without the test modes.
    mode: Option<Misbehave>,
}

impl TestMode {
    /// The test mode `args` ask for; an agent built without the test modes refuses any.
    pub(crate) fn asked(args: &Args) -> anyhow::Result<Self> {
        #[cfg(not(feature = "misbehave"))]
        if let Some(mode) = args.misbehave {
            anyhow::bail!("--misbehave {mode}: {NO_MISBEHAVE}");
        }
        Ok(Self {
            agent: args.agent,
            mode: args.misbehave,
        })
    }

    /// No test mode: a relay has none of its own (it passes its agent's on to the agent
    /// it starts).
    pub(crate) fn none(self) -> Self {
        Self { mode: None, ..self }
    }

    /// Read run `prefix`'s mission (checked against `digest` when given); the
    /// `rewrite-mission` mode forges the file first, and then reads its own forgery as
    /// any agent that reads it after.
    pub(crate) fn read_mission(
        self,
        prefix: &str,
        digest: Option<wire::MissionDigest>,
    ) -> anyhow::Result<Mission> {
        #[cfg(feature = "misbehave")]
        if let Some(mode) = self.mode {
            crate::misbehave::before_reading(prefix, self.agent, mode);
        }
        Mission::read(prefix, digest)
    }

    /// Open the agent's iceoryx2 channel with `open` and serve turns over it: the mode's
    /// attacks on the run's shared memory first (what they hold stays open for the life of
    /// the process), then its ports tampered and its moves misbehaving.
    pub(crate) fn serve_ipc(
        self,
        prefix: &str,
        open: impl FnOnce() -> anyhow::Result<IpcTransport>,
    ) -> anyhow::Result<()> {
        #[cfg(feature = "misbehave")]
        if let Some(mode) = self.mode {
            let _held = crate::misbehave::before_opening(prefix, self.agent, mode)?;
            return crate::misbehave::serve_ipc(open()?, self.agent, mode);
        }
        let _ = prefix;
        self.serve(open()?)
    }

    /// Serve turns over the socket `open` takes from the relay, as a sandboxed agent: the
    /// mode's attacks on the run's shared memory are tried first, as any agent would (its
    /// user can open none of it), then its moves misbehave.
    pub(crate) fn serve_socket<T: Transport>(
        self,
        prefix: &str,
        open: impl FnOnce() -> T,
    ) -> anyhow::Result<()> {
        #[cfg(feature = "misbehave")]
        let _held = match self.mode {
            Some(mode) => crate::misbehave::before_opening(prefix, self.agent, mode)?,
            None => Vec::new(),
        };
        let _ = prefix;
        if self.mode == Some(Misbehave::ExitBeforeReady) {
            // Leave at once, without closing anything: the coordinator must cope.
            std::process::exit(3);
        }
        self.serve(open())
    }

    /// Serve turns over `transport`, its moves misbehaving as the mode has it.
    pub(crate) fn serve<T: Transport>(self, transport: T) -> anyhow::Result<()> {
        #[cfg(feature = "misbehave")]
        if let Some(mode) = self.mode {
            return serve(
                &mut crate::misbehave::Misbehaving::new(transport, self.agent, mode),
                self.agent,
            );
        }
        let mut transport = transport;
        serve(&mut transport, self.agent)
    }
}
