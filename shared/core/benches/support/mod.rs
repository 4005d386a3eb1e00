//! What the benches share: per-item timings where criterion's mean would hide the spread.

/// Time `run(i)` for each `i` in `0..count` alone, best of five, and print the p50, p90
/// and largest of those times (microseconds) under `what`. The cost of a turn varies with
/// the turn (a direct path, or a search when none is clear), which criterion's mean over
/// a cycle of turns hides.
pub fn print_best_of_five_percentiles(what: &str, count: usize, mut run: impl FnMut(usize)) {
    let mut times_us: Vec<f64> = (0..count)
        .map(|i| {
            (0..5)
                .map(|_| {
                    let start = std::time::Instant::now();
                    run(i);
                    start.elapsed().as_secs_f64() * 1e6
                })
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    if times_us.is_empty() {
        eprintln!("{what}: nothing to time");
        return;
    }
    times_us.sort_by(f64::total_cmp);
    let at = |q: f64| times_us[((times_us.len() - 1) as f64 * q).round() as usize];
    eprintln!(
        "{what} ({count} items, each best of 5): p50 {:.1} us, p90 {:.1} us, max {:.1} us",
        at(0.5),
        at(0.9),
        at(1.0)
    );
}
