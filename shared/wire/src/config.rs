//! The iceoryx2 configuration of one run, by side of the protocol.

use iceoryx2::prelude::*;

use crate::prefix::{PrefixError, is_valid_prefix};
use crate::run_folder::run_root;

/// Which side of the protocol a process is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// The coordinator: creates the services and cleans up after dead nodes.
    Coordinator,
    /// An agent: opens the services and never cleans up after other nodes (cleanup racing
    /// a starting node can abort the cleaner, iceoryx2 issue 1880).
    Agent,
}

/// The iceoryx2 configuration of one run: every resource name starts with `prefix`, so
/// runs never see each other, and listing or cleaning nodes only touches this run.
pub fn ipc_config(prefix: &str, role: Role) -> Result<Config, PrefixError> {
    if !is_valid_prefix(prefix) {
        return Err(PrefixError::Invalid(prefix.to_string()));
    }
    let mut config = Config::default();
    config.global.prefix =
        FileName::new(prefix.as_bytes()).map_err(|_| PrefixError::Invalid(prefix.to_string()))?;
    if let Some(root) = run_root(prefix) {
        let root = format!("{}/", root.display());
        let root =
            Path::new(root.as_bytes()).map_err(|_| PrefixError::Invalid(prefix.to_string()))?;
        config.global.set_root_path(&root);
    }
    // A subscriber keeps the connections of publishers that went away while they still
    // hold undelivered or borrowed samples: by default 128 of them, each slot a few kB
    // allocated up front, so 460 kB of heap per subscriber (measured: 93 MB of the
    // coordinator's 135 MB with 200 agents, one state subscriber each, and twice that in
    // every agent). Every service of the protocol admits one publisher and one borrowed
    // sample, so one expired connection at a time is all a subscriber can need (iceoryx2
    // requires at least `subscriber_max_borrowed_samples`, 1 here); a process that keeps
    // replacing its own publisher only loses its own undelivered samples.
    config
        .defaults
        .publish_subscribe
        .subscriber_expired_connection_buffer = 1;
    if role == Role::Agent {
        config.global.node.cleanup_dead_nodes_on_creation = false;
        config.global.node.cleanup_dead_nodes_on_destruction = false;
        config.global.service.cleanup_dead_nodes_on_open = false;
    }
    Ok(config)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::MAX_PREFIX_LEN;
    use crate::run_folder::remove_run_root;

    #[test]
    fn prefixes_that_could_escape_or_overflow_are_refused() {
        assert!(ipc_config("fc123_4_", Role::Coordinator).is_ok());
        for bad in [
            "",
            "a/b",
            "../x",
            "with space",
            &"x".repeat(MAX_PREFIX_LEN + 1),
        ] {
            assert!(ipc_config(bad, Role::Agent).is_err(), "{bad:?}");
            assert_eq!(run_root(bad), None, "{bad:?}");
            // Nothing outside /dev/shm can be removed through a prefix.
            assert!(remove_run_root(bad).is_ok());
        }
        if let Some(root) = run_root("fc123_4_") {
            assert_eq!(root, std::path::Path::new("/dev/shm/fc123_4_iox2"));
        }
    }
}
