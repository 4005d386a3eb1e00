//! Tracking under a top speed with the look-ahead (`[formation] horizon_steps`): an agent
//! that cannot follow its slot aims where the slot is going. Checked against the same
//! scenario without the look-ahead, and with the safety properties unchanged.

use std::path::PathBuf;

use shared::control::vocabulary::TurnOrder;
use shared::geometry::polyline_length_m;
use shared::run::record::Run;
use shared::run::simulate::simulate;
use shared::world::scenario::Scenario;

fn data(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/data")).join(name)
}

/// The scenario of `file` with every agent looking `horizon_steps` ahead, in the turn
/// order a file saying so would get ([`TurnOrder::default_for`]; the file names none).
fn with_horizon(file: &str, horizon_steps: usize) -> Scenario {
    let mut s = Scenario::load(&data(file)).expect("scenario");
    for a in &mut s.agents {
        a.horizon_steps = horizon_steps;
    }
    s.turn_order = TurnOrder::default_for(&s.agents);
    s
}

/// The longest move of the run, and that no move is longer than its agent's top speed.
fn check_moves(s: &Scenario, run: &Run) {
    for step in &run.steps[1..] {
        for (i, a) in step.agents.iter().enumerate() {
            let cap = s.agents[i].max_step_m.expect("a top speed");
            let len = polyline_length_m(&a.waypoints);
            assert!(len <= cap + 1e-9, "agent {i}: a move of {len} m, cap {cap}");
        }
    }
}

/// The formation turns round and its outer slots sweep faster than the agents' top
/// speed: looking ahead lowers both the mean and the largest deviation, safely.
#[test]
fn looking_ahead_tracks_a_sweeping_slot_closer() {
    let (chase, ahead) = (
        with_horizon("sweeping-turn.toml", 0),
        with_horizon("sweeping-turn.toml", 10),
    );
    look_ahead_does_better("sweeping-turn", &chase, &ahead, 0.95);
}

/// Both scenarios run safely (complete, no collision, every move within its top speed),
/// and `ahead` has a mean deviation below `ratio` times `chase`'s and a lower largest.
fn look_ahead_does_better(name: &str, chase: &Scenario, ahead: &Scenario, ratio: f64) {
    let (a, b) = (simulate(chase).expect("run"), simulate(ahead).expect("run"));
    for (s, run) in [(chase, &a), (ahead, &b)] {
        let summary = run.summary();
        assert!(summary.completed, "{name}");
        assert_eq!(summary.collisions, 0, "{name}");
        check_moves(s, run);
    }
    let (sa, sb) = (a.summary(), b.summary());
    assert!(
        sb.mean_deviation_m < ratio * sa.mean_deviation_m,
        "{name}: mean {} with the look-ahead, {} without",
        sb.mean_deviation_m,
        sa.mean_deviation_m
    );
    assert!(
        sb.max_deviation_m < sa.max_deviation_m,
        "{name}: max {} with the look-ahead, {} without",
        sb.max_deviation_m,
        sa.max_deviation_m
    );
}

/// The scenario `scenarios/NAME.toml` with every agent capped at `max_step_m` a step and
/// looking `horizon_steps` ahead.
fn capped(name: &str, max_step_m: f64, horizon_steps: usize) -> Scenario {
    let path = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenarios"))
        .join(format!("{name}.toml"));
    let text = std::fs::read_to_string(&path).expect("scenario file");
    let text = text.replacen(
        "[formation]\n",
        &format!("[formation]\nmax_step_m = {max_step_m}\nhorizon_steps = {horizon_steps}\n"),
        1,
    );
    let s = Scenario::parse(&text, &path.display().to_string()).expect("scenario");
    assert!(s.agents.iter().all(|a| a.max_step_m == Some(max_step_m)));
    s
}

/// Slots whose way crosses obstacles (dense and narrow, capped at twice the centre's
/// step): looking ahead, an agent goes round an obstacle on the side its slot comes out
/// of, early, and both the mean and the largest deviation come out lower than without
/// the look-ahead, safely.
#[test]
fn looking_ahead_goes_round_the_obstacles_on_the_slots_way() {
    for name in ["dense", "narrow"] {
        let (chase, ahead) = (capped(name, 0.5, 0), capped(name, 0.5, 10));
        look_ahead_does_better(name, &chase, &ahead, 0.9);
    }
}

/// Where every agent can follow its slot (an open field, slots moving slower than the
/// top speed), the look-ahead changes nothing, to the bit.
#[test]
fn a_followable_slot_is_planned_as_without_a_look_ahead() {
    let a = simulate(&with_horizon("open-field.toml", 0)).expect("run");
    let b = simulate(&with_horizon("open-field.toml", 32)).expect("run");
    assert_eq!(a.steps.len(), b.steps.len());
    for (x, y) in a.steps.iter().zip(&b.steps) {
        for (p, q) in x.agents.iter().zip(&y.agents) {
            assert_eq!(p.waypoints, q.waypoints);
            assert_eq!(p.status, q.status);
        }
    }
}

/// A scenario file's `horizon_steps` is read, defaults to 10 and is refused beyond 32,
/// naming the key.
#[test]
fn the_horizon_is_read_and_bounded() {
    let text = std::fs::read_to_string(data("sweeping-turn.toml")).expect("file");
    let s = Scenario::parse(&text, "sweeping-turn.toml").expect("scenario");
    assert!(s.agents.iter().all(|a| a.horizon_steps == 10));
    let set = |h: &str| {
        text.replacen(
            "max_step_m = 0.4",
            &format!("max_step_m = 0.4\nhorizon_steps = {h}"),
            1,
        )
    };
    let s = Scenario::parse(&set("3"), "x.toml").expect("scenario");
    assert!(s.agents.iter().all(|a| a.horizon_steps == 3));
    let err = Scenario::parse(&set("33"), "x.toml").expect_err("33 steps");
    assert_eq!(err.field(), "formation.horizon_steps");
}
