//! The stderr log of every process of a run, with a budget for other crates' lines.
//!
//! A stranger can make a library log: every junk connection to the Zenoh router, every
//! failed TLS handshake is a warning of `zenoh_*` or `rustls`. Unbounded, a flood of them
//! fills the disk (4.6 million lines in one measured attack). So the lines of every crate
//! but this project's own share a budget per crate ([`LogBudget`]): a burst of
//! [`BURST_LINES`], then [`LINES_PER_S`] a second. What the budget drops is counted
//! ([`suppressed_log_lines`]; the coordinator writes it in `summary.json`) and the first
//! drop of each crate says so in one line. This project's own lines are never dropped:
//! each names a fault, and faults are bounded per agent.

use std::collections::HashMap;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// Lines a crate may log at once before its budget applies.
pub const BURST_LINES: f64 = 50.0;

/// Lines a second a crate may log once its burst is spent.
pub const LINES_PER_S: f64 = 2.0;

/// The crates whose lines are never dropped: this project's.
const OWN_CRATES: [&str; 8] = [
    "coordinator",
    "runner",
    "tools",
    "agent",
    "shared",
    "wire",
    "net",
    "bench_peer",
];

/// Lines dropped by the budget in this process so far.
static SUPPRESSED: AtomicU64 = AtomicU64::new(0);

/// The process's budget (one for all threads).
static BUDGET: Mutex<Option<LogBudget>> = Mutex::new(None);

/// How many log lines of other crates the budget dropped in this process.
pub fn suppressed_log_lines() -> u64 {
    SUPPRESSED.load(Ordering::Relaxed)
}

/// Install the stderr logger once: `RUST_LOG` sets the levels (default `default_level`,
/// e.g. `"warn"`), other crates' lines within their budget.
pub fn init(default_level: &str) {
    use tracing_subscriber::Layer;
    use tracing_subscriber::filter::{EnvFilter, FilterExt, dynamic_filter_fn};
    use tracing_subscriber::layer::SubscriberExt;
    use tracing_subscriber::util::SubscriberInitExt;
    let levels =
        EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(default_level));
    // Dynamic: asked at every event (a plain filter's answer is cached per call site).
    let within_budget =
        dynamic_filter_fn(|meta, _| !meta.is_event() || within_budget(meta.target()));
    let layer = tracing_subscriber::fmt::layer()
        .with_writer(std::io::stderr)
        .with_target(false)
        .with_filter(levels.and(within_budget));
    let _ = tracing_subscriber::registry().with(layer).try_init();
}

/// Whether a line of `target` may be written now (counted if not).
fn within_budget(target: &str) -> bool {
    let krate = target.split("::").next().unwrap_or(target);
    if OWN_CRATES.contains(&krate) {
        return true;
    }
    let Ok(mut budget) = BUDGET.lock() else {
        return true;
    };
    let budget = budget.get_or_insert_with(|| LogBudget::new(BURST_LINES, LINES_PER_S));
    match budget.take(krate, Instant::now()) {
        Take::Allowed => true,
        Take::FirstDrop => {
            SUPPRESSED.fetch_add(1, Ordering::Relaxed);
            // Written directly: a tracing event from inside the filter would come back here.
            eprintln!(
                "log lines of {krate} beyond {BURST_LINES} at once and {LINES_PER_S} a second are dropped from here on and counted"
            );
            false
        }
        Take::Dropped => {
            SUPPRESSED.fetch_add(1, Ordering::Relaxed);
            false
        }
    }
}

/// What [`LogBudget::take`] decided.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Take {
    /// The line may be written.
    Allowed,
    /// The line is dropped, the first of its crate to be.
    FirstDrop,
    /// The line is dropped.
    Dropped,
}

/// A token bucket per crate: `burst` lines at once, refilled at `per_s` lines a second.
#[derive(Debug)]
pub struct LogBudget {
    burst: f64,
    per_s: f64,
    crates: HashMap<String, Bucket>,
}

#[derive(Debug)]
struct Bucket {
    tokens: f64,
    at: Instant,
    dropped_before: bool,
}

impl LogBudget {
    /// A budget of `burst` lines at once and `per_s` a second for each crate.
    pub fn new(burst: f64, per_s: f64) -> Self {
        Self {
            burst,
            per_s,
            crates: HashMap::new(),
        }
    }

    /// Take one line of `krate` at `now`.
    ///
    /// ```
    /// use std::time::{Duration, Instant};
    /// use wire::logging::{LogBudget, Take};
    /// let mut budget = LogBudget::new(2.0, 1.0);
    /// let t = Instant::now();
    /// assert_eq!(budget.take("zenoh", t), Take::Allowed);
    /// assert_eq!(budget.take("zenoh", t), Take::Allowed);
    /// assert_eq!(budget.take("zenoh", t), Take::FirstDrop);
    /// assert_eq!(budget.take("zenoh", t), Take::Dropped);
    /// assert_eq!(budget.take("rustls", t), Take::Allowed);
    /// assert_eq!(budget.take("zenoh", t + Duration::from_secs(1)), Take::Allowed);
    /// ```
    pub fn take(&mut self, krate: &str, now: Instant) -> Take {
        let bucket = self
            .crates
            .entry(krate.to_string())
            .or_insert_with(|| Bucket {
                tokens: self.burst,
                at: now,
                dropped_before: false,
            });
        let elapsed_s = now.saturating_duration_since(bucket.at).as_secs_f64();
        bucket.tokens = (bucket.tokens + elapsed_s * self.per_s).min(self.burst);
        bucket.at = now;
        if bucket.tokens >= 1.0 {
            bucket.tokens -= 1.0;
            Take::Allowed
        } else if bucket.dropped_before {
            Take::Dropped
        } else {
            bucket.dropped_before = true;
            Take::FirstDrop
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;

    #[test]
    fn a_flood_is_cut_to_the_burst_and_the_rate() {
        let mut budget = LogBudget::new(BURST_LINES, LINES_PER_S);
        let start = Instant::now();
        // 100 000 lines in 10 s: a burst, then two a second.
        let allowed = (0..100_000u32)
            .filter(|i| {
                let at = start + Duration::from_micros(u64::from(*i) * 100);
                budget.take("zenoh_transport", at) == Take::Allowed
            })
            .count();
        let most = BURST_LINES + 10.0 * LINES_PER_S;
        assert!(allowed as f64 <= most + 1.0, "{allowed} lines passed");
        assert!(allowed as f64 >= BURST_LINES, "{allowed} lines passed");
    }

    #[test]
    fn own_crates_are_never_dropped() {
        for _ in 0..10_000 {
            assert!(within_budget("coordinator::cli"));
            assert!(within_budget("runner::turns::driver"));
            assert!(within_budget("tools::bench"));
            assert!(within_budget("wire"));
        }
    }
}
