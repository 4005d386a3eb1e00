//! Waiting for a state that no descriptor signals (a process gone from a control group,
//! a child reaped), by looking again with growing pauses: quick when the state comes at
//! once, and cheap when a thousand processes of a run wait at the same time.

use std::time::{Duration, Instant};

/// The first pause between two looks.
pub const FIRST_PAUSE: Duration = Duration::from_millis(1);

/// The longest pause between two looks.
pub const LONGEST_PAUSE: Duration = Duration::from_millis(50);

/// Call `done` until it returns true or `timeout` passes; whether it did. The pauses
/// between the calls double from [`FIRST_PAUSE`] up to [`LONGEST_PAUSE`], and the last
/// one ends at the deadline, where `done` is asked once more.
///
/// ```
/// use std::time::Duration;
/// let mut looks = 0;
/// assert!(wire::poll_until(Duration::from_secs(1), || {
///     looks += 1;
///     looks == 3
/// }));
/// assert!(!wire::poll_until(Duration::from_millis(5), || false));
/// ```
pub fn poll_until(timeout: Duration, mut done: impl FnMut() -> bool) -> bool {
    let deadline = Instant::now() + timeout;
    let mut pause = FIRST_PAUSE;
    loop {
        if done() {
            return true;
        }
        let now = Instant::now();
        if now >= deadline {
            return false;
        }
        std::thread::sleep(pause.min(deadline - now));
        pause = (pause * 2).min(LONGEST_PAUSE);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_state_never_reached_is_looked_at_a_few_times_and_at_the_deadline() {
        let started = Instant::now();
        let mut looks = 0;
        let reached = poll_until(Duration::from_millis(200), || {
            looks += 1;
            false
        });
        assert!(!reached);
        assert!(started.elapsed() >= Duration::from_millis(200));
        // 1 + 2 + 4 + ... + 32 + 50 + 50 + ... reaches 200 ms in at most 10 pauses: about
        // 11 looks, not the 100 of a fixed 2 ms pause.
        assert!((2..=12).contains(&looks), "{looks} looks");
    }

    #[test]
    fn a_state_reached_at_once_costs_one_look_and_no_pause() {
        let mut looks = 0;
        assert!(poll_until(Duration::ZERO, || {
            looks += 1;
            true
        }));
        assert_eq!(looks, 1);
    }
}
