//! Descriptors a started process must not inherit.

/// Marks every descriptor from `first_fd` up close-on-exec with one
/// `close_range(first_fd, ~0, CLOSE_RANGE_CLOEXEC)` call (Linux 5.11). Returns false when
/// the kernel refused (`ENOSYS` on an older kernel): the caller falls back or accepts it.
///
/// One system call and nothing allocated, so it may run between `fork` and `exec`.
pub fn mark_cloexec_from(first_fd: libc::c_int) -> bool {
    let Ok(first) = libc::c_uint::try_from(first_fd) else {
        return false;
    };
    // SAFETY: a plain system call on descriptor numbers; it changes only their flags.
    let marked = unsafe {
        libc::syscall(
            libc::SYS_close_range,
            first,
            libc::c_uint::MAX,
            libc::CLOSE_RANGE_CLOEXEC as libc::c_uint,
        )
    };
    marked == 0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn descriptors_from_the_first_are_marked_and_those_below_are_not() {
        // SAFETY: dup of stderr makes a new descriptor this test owns.
        let below = unsafe { libc::dup(2) };
        // SAFETY: as above.
        let above = unsafe { libc::dup(2) };
        assert!(below > 2 && above > below);
        // SAFETY: reads the flags of a descriptor this test owns.
        let flags = |fd| unsafe { libc::fcntl(fd, libc::F_GETFD) } & libc::FD_CLOEXEC;
        // dup() clears the flag on both.
        assert_eq!((flags(below), flags(above)), (0, 0));
        assert!(mark_cloexec_from(above));
        assert_eq!(flags(below), 0);
        assert_eq!(flags(above), libc::FD_CLOEXEC);
        assert!(!mark_cloexec_from(-1));
        // SAFETY: closes the two descriptors this test made, nothing else uses them.
        unsafe {
            libc::close(below);
            libc::close(above);
        }
    }
}
