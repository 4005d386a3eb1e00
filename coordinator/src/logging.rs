//! Logs go to stderr through `tracing`; `RUST_LOG` sets the level (default `warn`).

use tracing_subscriber::EnvFilter;

/// Install the stderr logger once.
pub fn init() {
    let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new("warn"));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_target(false)
        .try_init();
}
