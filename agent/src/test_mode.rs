//! The agent's test modes as the roles start them: the mode asked for (refused by an
//! agent built without them) and serving turns as it has it, the transport wrapped in
//! [`crate::misbehave::Misbehaving`].

use crate::args::Args;
use crate::serve::serve;
use crate::transport::Transport;
use wire::misbehave::Misbehave;

/// What an agent built without its test modes says when asked for one.
#[cfg(not(feature = "misbehave"))]
pub const NO_MISBEHAVE: &str = "this agent was built without its test modes: build it with `cargo build --release --features misbehave -p agent`";

/// The test mode asked for; an agent built without the test modes refuses any.
pub(crate) fn test_mode(args: &Args) -> anyhow::Result<Option<Misbehave>> {
    #[cfg(not(feature = "misbehave"))]
    if let Some(mode) = args.misbehave {
        anyhow::bail!("--misbehave {mode}: {NO_MISBEHAVE}");
    }
    Ok(args.misbehave)
}

/// Serve turns over `transport`, as test mode `mode` has it if one is given.
pub(crate) fn serve_as<T: Transport>(
    transport: T,
    agent: usize,
    mode: Option<Misbehave>,
) -> anyhow::Result<()> {
    #[cfg(feature = "misbehave")]
    if let Some(mode) = mode {
        return serve(
            &mut crate::misbehave::Misbehaving::new(transport, agent, mode),
            agent,
        );
    }
    #[cfg(not(feature = "misbehave"))]
    let _ = mode;
    let mut transport = transport;
    serve(&mut transport, agent)
}
