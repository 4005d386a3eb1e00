//! What an agent process started by a coordinator does before anything else: tie its
//! life to the coordinator's, and wait at the start gate until the run's channels exist.

use anyhow::{Context, bail};

/// Started by a coordinator ([`wire::PARENT_ENV`] names its process): be killed with it,
/// and leave at once if it is gone already (this process's parent is then another).
pub(crate) fn die_with_the_coordinator() -> anyhow::Result<()> {
    let Ok(text) = std::env::var(wire::PARENT_ENV) else {
        return Ok(());
    };
    let coordinator: u32 = text
        .parse()
        .with_context(|| format!("{}: {text:?} is not a process id", wire::PARENT_ENV))?;
    #[cfg(target_os = "linux")]
    nix::sys::prctl::set_pdeathsig(nix::sys::signal::Signal::SIGKILL)
        .context("asking to die with the coordinator")?;
    let parent = std::os::unix::process::parent_id();
    if parent != coordinator {
        bail!("the coordinator (process {coordinator}) is gone: the parent is {parent}");
    }
    Ok(())
}

/// Wait until standard input ends: the coordinator closes the other end once the run's
/// channels exist (or dies, which closes it too: then opening them fails).
pub(crate) fn pass_the_gate() -> anyhow::Result<()> {
    use std::io::Read as _;
    let mut sink = [0u8; 64];
    let mut stdin = std::io::stdin().lock();
    loop {
        match stdin.read(&mut sink) {
            Ok(0) => return Ok(()),
            Ok(_) => {}
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e).context("waiting for the run's channels (standard input)"),
        }
    }
}
