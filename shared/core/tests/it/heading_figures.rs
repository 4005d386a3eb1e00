//! The heading figures of a run (`Run::heading_summary`): absent for holonomic agents,
//! bounding every recorded heading error and turn for unicycles, and counting a turn there
//! and back as both ways.

use shared::geometry::Vector;
use shared::run::simulate::simulate;
use shared::world::scenario::Scenario;

fn scenario(name: &str) -> Scenario {
    let path = format!("{}/../../scenarios/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    Scenario::load(std::path::Path::new(&path)).expect("a valid shipped scenario")
}

#[test]
fn a_holonomic_run_has_no_heading_figures() {
    let s = scenario("paper");
    let run = simulate(&s).expect("runs");
    assert_eq!(run.heading_summary(&s), None);
}

#[test]
fn the_figures_bound_every_recorded_heading_and_turn() {
    let s = scenario("paper-unicycle");
    let run = simulate(&s).expect("runs");
    let f = run.heading_summary(&s).expect("unicycles");
    // Every agent starts facing the centre and the centre turns, so some error is seen.
    assert!(f.max_heading_error_rad > 0.0, "{f:?}");
    assert!(f.max_heading_error_rad <= std::f64::consts::PI + 1e-12);
    assert!(f.mean_heading_error_rad <= f.max_heading_error_rad);
    // Agents turn while the formation moves, never beyond their limit of 3 rad.
    assert!(
        f.max_turn_rad > 0.0 && f.max_turn_rad <= 3.0 + 1e-9,
        "{f:?}"
    );
    // The largest error is one of the recorded ones, computed independently here.
    let seen = run
        .steps
        .iter()
        .skip(1)
        .flat_map(|st| {
            st.agents.iter().filter(|a| a.alive).map(move |a| {
                let d = a.heading_rad.expect("a heading") - st.centre.heading_rad;
                d.sin().atan2(d.cos()).abs()
            })
        })
        .fold(0.0, f64::max);
    assert!((seen - f.max_heading_error_rad).abs() < 1e-12);
}

#[test]
fn a_turn_back_and_forth_counts_both_ways() {
    // One agent that turns a quarter left, drives, and ends facing where it started:
    // its net heading change is 0, its turning half a turn.
    let s = scenario("paper-unicycle");
    let mut run = simulate(&s).expect("runs");
    run.steps.truncate(2);
    for a in &mut run.steps[0].agents {
        a.heading_rad = Some(0.0);
    }
    for a in &mut run.steps[1].agents {
        a.heading_rad = Some(0.0);
        a.waypoints = vec![a.position];
    }
    let start = run.steps[0].agents[0].position;
    run.steps[1].agents[0].waypoints = vec![start, start + Vector::new(0.0, 0.1)];
    let f = run.heading_summary(&s).expect("unicycles");
    assert!(
        (f.max_turn_rad - std::f64::consts::PI).abs() < 1e-12,
        "{f:?}"
    );
}
