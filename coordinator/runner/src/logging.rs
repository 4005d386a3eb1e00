//! Logs go to stderr through `tracing`; `RUST_LOG` sets the level (default `warn`), and
//! other crates' lines are within a budget ([`wire::logging`]).

/// Install the stderr logger once.
pub fn init() {
    wire::logging::init("warn");
}
