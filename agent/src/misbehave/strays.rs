//! [`Misbehave::Fork`](wire::misbehave::Misbehave::Fork): processes that try to outlive
//! the run.

/// `argv[0]` of the children [`Misbehave::Fork`](wire::misbehave::Misbehave::Fork) starts for run `prefix`, so that tests
/// can find them: `formation-stray-<prefix>`.
pub fn stray_marker(prefix: &str) -> String {
    format!("formation-stray-{prefix}")
}

/// [`Misbehave::Fork`](wire::misbehave::Misbehave::Fork): start two `sleep` processes named [`stray_marker`] that ignore
/// SIGTERM and SIGHUP, the second in a new session (out of the agent's process group);
/// returns their pids. They are never waited for.
pub fn start_strays(prefix: &str) -> anyhow::Result<[u32; 2]> {
    use std::os::unix::process::CommandExt;

    use anyhow::Context;
    use nix::sys::signal::{SigHandler, Signal, signal};

    let start = |escape: bool| -> anyhow::Result<u32> {
        let mut command = std::process::Command::new("sleep");
        command
            .arg0(stray_marker(prefix))
            .arg("2147483647")
            .stdin(std::process::Stdio::null())
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null());
        // SAFETY: between fork and exec the closure only calls async-signal-safe
        // functions (sigaction, setsid) and allocates nothing.
        unsafe {
            command.pre_exec(move || {
                // Ignored dispositions survive exec.
                signal(Signal::SIGTERM, SigHandler::SigIgn)?;
                signal(Signal::SIGHUP, SigHandler::SigIgn)?;
                if escape {
                    nix::unistd::setsid()?;
                }
                Ok(())
            });
        }
        let child = command
            .spawn()
            .with_context(|| format!("starting a stray process (escape: {escape})"))?;
        Ok(child.id())
    };
    Ok([start(false)?, start(true)?])
}
