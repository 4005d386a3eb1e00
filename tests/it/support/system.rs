//! The system tier's precondition: a test that needs root (a sandbox, a network
//! namespace, another user) says so in one line when it is started without it, instead
//! of failing somewhere inside.

/// Whether this process runs as root (effective user id 0).
pub fn is_root() -> bool {
    // SAFETY: geteuid(2) cannot fail and touches no memory.
    unsafe { libc::geteuid() == 0 }
}

/// Fails the calling test at once, in one line, unless it runs as root.
pub fn require_root() {
    assert!(
        is_root(),
        "this system-tier test needs root (sandboxes, network namespaces, other users): \
         run the system tier as root, as CI does"
    );
}
