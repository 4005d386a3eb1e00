//! The process's logger drops other crates' lines beyond their budget and counts them;
//! this project's own lines all pass. (A process of its own: the logger is global.)

#[test]
fn a_flood_of_another_crates_warnings_is_cut_and_counted() {
    wire::logging::init("warn");
    for i in 0..1000 {
        tracing::warn!(target: "zenoh_link_tls::unicast", "junk connection {i}");
    }
    let dropped = wire::logging::suppressed_log_lines();
    let most_passed = wire::logging::BURST_LINES as u64 + 10;
    assert!(
        dropped >= 1000 - most_passed,
        "only {dropped} of 1000 lines dropped"
    );
    for i in 0..1000 {
        tracing::warn!(target: "coordinator::turns", "a fault {i}");
    }
    assert_eq!(wire::logging::suppressed_log_lines(), dropped);
}
