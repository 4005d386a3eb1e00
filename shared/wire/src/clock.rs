//! The machine's monotonic clock, the same in every process.

/// The machine's monotonic clock (`CLOCK_MONOTONIC`, the clock of `std::time::Instant`
/// on Linux) in nanoseconds: the same in every process, so the coordinator can place an
/// agent's timestamps on its own time line. 0 if the clock cannot be read.
pub fn monotonic_ns() -> u64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid, writable timespec; the call only writes it.
    if unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut t) } != 0 {
        return 0;
    }
    let (Ok(s), Ok(ns)) = (u64::try_from(t.tv_sec), u64::try_from(t.tv_nsec)) else {
        return 0;
    };
    s.saturating_mul(1_000_000_000).saturating_add(ns)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn monotonic_ns_is_the_clock_of_instant() {
        let a = monotonic_ns();
        let t = std::time::Instant::now();
        std::thread::sleep(std::time::Duration::from_millis(5));
        let elapsed_ns = t.elapsed().as_nanos() as u64;
        let b = monotonic_ns();
        assert!(a > 0);
        // b - a covers the sleep that `elapsed` measured, and little more.
        assert!(b - a >= elapsed_ns, "{} < {elapsed_ns}", b - a);
        assert!(b - a < elapsed_ns + 50_000_000, "{} vs {elapsed_ns}", b - a);
    }
}
