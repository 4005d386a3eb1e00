//! `coordinator bound`: the physical limit of tracking under a top speed among the static
//! obstacles, against the reference simulation's deviation. No controller can beat the
//! bound.

use crate::support;

use std::collections::BTreeMap;
use std::process::Command;
use std::sync::{Arc, Mutex, OnceLock, PoisonError};

fn bound(scenario: Option<&str>) -> serde_json::Value {
    bound_with(scenario, &[])
}

/// The report of `coordinator bound FLAGS [SCENARIO]`, computed once per scenario and
/// flags in this test process however many tests read it (the searches take seconds).
fn bound_with(scenario: Option<&str>, flags: &[&str]) -> serde_json::Value {
    type Reports = BTreeMap<String, Arc<OnceLock<serde_json::Value>>>;
    static REPORTS: Mutex<Reports> = Mutex::new(BTreeMap::new());
    let key = format!("{scenario:?} {flags:?}");
    let report = Arc::clone(
        REPORTS
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .entry(key)
            .or_default(),
    );
    report.get_or_init(|| run_bound(scenario, flags)).clone()
}

/// Runs `coordinator bound FLAGS [SCENARIO]` (which must succeed): its JSON report.
fn run_bound(scenario: Option<&str>, flags: &[&str]) -> serde_json::Value {
    let mut cmd = Command::new(support::coordinator_bin());
    cmd.arg("bound").args(flags);
    if let Some(s) = scenario {
        cmd.arg(support::repo_root().join(s));
    }
    let out = cmd.output().expect("coordinator bound");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON on stdout")
}

#[test]
fn the_bound_is_below_the_run_and_zero_for_a_slot_that_can_be_followed() {
    let r = bound(Some("tests/data/sweeping-turn.toml"));
    let f = |k: &str| r[k].as_f64().unwrap_or_else(|| panic!("{k}: {r}"));
    assert_eq!(r["agents"], 4);
    assert_eq!(r["collisions"], 0);
    // The outer slots sweep faster than the top speed: the bound is positive, and the
    // run, which meets obstacles of nobody, stays above it.
    assert!(f("bound_mean_deviation_m") > 0.1, "{r}");
    assert!(f("mean_deviation_m") >= f("bound_mean_deviation_m") * (1.0 - 1e-6));
    assert!(f("max_deviation_m") >= f("bound_max_deviation_m") * (1.0 - 1e-6));
    assert!(f("mean_ratio") >= 1.0 - 1e-6);
    let per = r["per_agent"].as_array().expect("per_agent");
    assert_eq!(per.len(), 4);
    // Agent 0 sits at the centre, which moves slower than its top speed; agent 2, on
    // the outside of the turn, sweeps faster.
    let mean = |i: usize| per[i]["mean_deviation_m"].as_f64().expect("mean");
    assert!(mean(0) < 1e-4);
    assert!(mean(2) > 0.1, "{r}");
    let mean_of_agents = per
        .iter()
        .map(|a| a["mean_deviation_m"].as_f64().expect("mean"))
        .sum::<f64>()
        / 4.0;
    assert!((mean_of_agents - f("bound_mean_deviation_m")).abs() < 1e-12);
}

#[test]
fn without_a_top_speed_only_the_obstacles_bound_and_the_run_stays_above() {
    // The paper's example: no top speed, so the top speed forces nothing; its slots pass
    // through obstacles, which force a deviation wherever an agent is.
    let r = bound(None);
    let f = |k: &str| r[k].as_f64().unwrap_or_else(|| panic!("{k}: {r}"));
    assert_eq!(f("speed_bound_mean_deviation_m"), 0.0);
    assert!(f("obstacle_bound_mean_deviation_m") > 0.0, "{r}");
    assert_eq!(
        f("bound_mean_deviation_m"),
        f("obstacle_bound_mean_deviation_m")
    );
    assert!(f("mean_deviation_m") >= f("bound_mean_deviation_m") * (1.0 - 1e-9));
    assert!(f("max_deviation_m") >= f("bound_max_deviation_m") * (1.0 - 1e-9));
    assert!(f("mean_ratio") >= 1.0 - 1e-9);
    assert!(r["per_agent"][0]["max_step_m"].is_null());
}

#[test]
fn the_run_stays_above_the_bound_with_a_top_speed_among_obstacles() {
    // Top speed and obstacles both bound the capped paper example; neither alone is as
    // high as both, and the reference simulation stays above it.
    let r = bound(Some("scenarios/paper-top-speed.toml"));
    let f = |k: &str| r[k].as_f64().unwrap_or_else(|| panic!("{k}: {r}"));
    assert_eq!(r["collisions"], 0);
    // Never below a part (the parts are exact, the whole is the solver's to a tolerance,
    // and the report keeps the larger).
    assert!(f("bound_mean_deviation_m") >= f("speed_bound_mean_deviation_m"));
    assert!(f("bound_mean_deviation_m") >= f("obstacle_bound_mean_deviation_m"));
    assert!(f("mean_deviation_m") >= f("bound_mean_deviation_m") * (1.0 - 1e-6));
    assert!(f("max_deviation_m") >= f("bound_max_deviation_m") * (1.0 - 1e-6));
}

/// Each agent alone (`--alone`): the method alone and the best track the lattice search
/// finds are both achievable, so neither is below the agent's bound; the mates' share is
/// the formation's deviation less the agents' alone. Without the flag there is no such
/// report.
#[test]
fn each_agent_alone_stays_above_its_bound_and_the_mates_make_the_difference() {
    let plain = bound(Some("scenarios/paper-top-speed.toml"));
    assert!(plain["alone"].is_null(), "{plain}");
    let r = bound_with(Some("scenarios/paper-top-speed.toml"), &["--alone"]);
    let alone = &r["alone"];
    let f = |v: &serde_json::Value, k: &str| v[k].as_f64().unwrap_or_else(|| panic!("{k}: {v}"));
    let agents = r["per_agent"].as_array().expect("per_agent");
    let each = alone["per_agent"].as_array().expect("alone per_agent");
    assert_eq!(each.len(), agents.len());
    for (a, b) in each.iter().zip(agents) {
        assert_eq!(a["agent"], b["agent"]);
        let bound_m = f(b, "mean_deviation_m");
        assert!(
            f(a, "mean_deviation_m") >= bound_m * (1.0 - 1e-6),
            "{a} {b}"
        );
        assert!(
            f(a, "searched_mean_deviation_m") >= bound_m * (1.0 - 1e-6),
            "{a} {b}"
        );
    }
    let n = each.len() as f64;
    let mean_alone = each.iter().map(|a| f(a, "mean_deviation_m")).sum::<f64>() / n;
    assert!((f(alone, "mean_deviation_m") - mean_alone).abs() < 1e-12);
    assert!((f(alone, "mates_m") - (f(&r, "mean_deviation_m") - mean_alone)).abs() < 1e-12);
    // On this field the obstacles keep some agents off their slots: the best track found
    // alone is above 0.
    assert!(f(alone, "searched_mean_deviation_m") > 0.0, "{alone}");
}

/// The way round: where an agent's slot enters an obstacle, the bound keeps the agent's
/// every position out of it (`way_round_mean_deviation_m`), which costs at least the
/// floors and, on the capped paper example, more for some agent (it cannot stand inside
/// an obstacle and wait there); where the slot never enters one it is not computed. The
/// agent's bound is never below it.
#[test]
fn the_bound_goes_round_the_obstacles_the_slots_cross() {
    let r = bound(Some("scenarios/paper-top-speed.toml"));
    let f = |v: &serde_json::Value, k: &str| v[k].as_f64().unwrap_or_else(|| panic!("{k}: {v}"));
    let mut above_floors = 0;
    for a in r["per_agent"].as_array().expect("per_agent") {
        let floors_m = f(a, "obstacle_mean_deviation_m");
        match a["way_round_mean_deviation_m"].as_f64() {
            None => assert_eq!(floors_m, 0.0, "{a}"),
            Some(round_m) => {
                assert!(floors_m > 0.0, "{a}");
                assert!(round_m >= floors_m * (1.0 - 1e-9), "{a}");
                assert!(f(a, "mean_deviation_m") >= round_m, "{a}");
                if round_m > floors_m * 1.01 {
                    above_floors += 1;
                }
            }
        }
    }
    assert!(above_floors >= 1, "{r}");
}

/// In a changing world the centre's plan is mended on the way (here round a wall found
/// late), and the run's deviation is measured from the slots of the centre it followed:
/// the bound is taken along that same centre, so the run stays above it. (Along the
/// first plan, which runs through the wall, the floors alone were three times the run's
/// mean.)
#[test]
fn in_a_changing_world_the_bound_follows_the_mended_plan() {
    let r = bound(Some("scenarios/discovered-wall.toml"));
    let f = |k: &str| r[k].as_f64().unwrap_or_else(|| panic!("{k}: {r}"));
    assert!(f("bound_mean_deviation_m") > 0.0, "{r}");
    assert!(
        f("mean_deviation_m") >= f("bound_mean_deviation_m") * (1.0 - 1e-6),
        "{r}"
    );
    assert!(
        f("max_deviation_m") >= f("bound_max_deviation_m") * (1.0 - 1e-6),
        "{r}"
    );
}

/// The formation searched together (`--together`): an achievable formation, mates
/// included, so it is no better than the bound, nor (each agent) than the best track found
/// for it alone; its tracks (`--together-csv`) keep the top speed, and at every step the
/// bodies stand apart. Without the flag there is no such report.
#[test]
fn the_formation_searched_together_stays_above_the_bound_and_apart() {
    let plain = bound(Some("scenarios/paper-top-speed.toml"));
    assert!(plain["together"].is_null(), "{plain}");
    assert!(plain["lattice_per_move"].is_null(), "{plain}");
    let dir = tempfile::tempdir().expect("a scratch folder");
    let csv_path = dir.path().join("together.csv");
    let csv_arg = csv_path.to_str().expect("a UTF-8 path");
    let r = bound_with(
        Some("scenarios/paper-top-speed.toml"),
        &["--alone", "--together", "--together-csv", csv_arg],
    );
    let f = |v: &serde_json::Value, k: &str| v[k].as_f64().unwrap_or_else(|| panic!("{k}: {v}"));
    let together = &r["together"];
    assert!(
        f(together, "mean_deviation_m") >= f(&r, "bound_mean_deviation_m") * (1.0 - 1e-6),
        "{r}"
    );
    let each = together["per_agent_mean_deviation_m"]
        .as_array()
        .expect("per agent");
    let alone = r["alone"]["per_agent"].as_array().expect("alone per agent");
    assert_eq!(each.len(), alone.len());
    for (t, a) in each.iter().zip(alone) {
        let t = t.as_f64().expect("a number");
        assert!(t >= f(a, "searched_mean_deviation_m") - 1e-12, "{t} {a}");
    }
    // The tracks: (step, agent, x, y), every agent at every step.
    let text = std::fs::read_to_string(&csv_path).expect("the tracks' CSV");
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("step,agent,x_m,y_m"));
    let rows: Vec<(usize, usize, f64, f64)> = lines
        .map(|l| {
            let v: Vec<&str> = l.split(',').collect();
            (
                v[0].parse().expect("step"),
                v[1].parse().expect("agent"),
                v[2].parse().expect("x"),
                v[3].parse().expect("y"),
            )
        })
        .collect();
    let agents = each.len();
    let steps = r["steps"].as_u64().expect("steps") as usize;
    assert_eq!(rows.len(), agents * (steps + 1));
    let at = |step: usize, agent: usize| {
        let (s, a, x, y) = rows[step * agents + agent];
        assert_eq!((s, a), (step, agent));
        (x, y)
    };
    // The scenario's top speed and agent radius: 0.5 m a step, 0.25 m.
    for step in 1..=steps {
        for a in 0..agents {
            let ((x0, y0), (x1, y1)) = (at(step - 1, a), at(step, a));
            assert!(
                (x1 - x0).hypot(y1 - y0) <= 0.5 + 1e-9,
                "agent {a} step {step}"
            );
            for b in a + 1..agents {
                let (xb, yb) = at(step, b);
                assert!(
                    (x1 - xb).hypot(y1 - yb) >= 0.5,
                    "agents {a} {b} step {step}"
                );
            }
        }
    }
}

/// A lattice twice as fine (`--lattice-per-move 10`, every point of the default's
/// among its own) finds each agent alone a track no worse than the default lattice, and
/// still no better than its bound; the report says which lattice it searched.
#[test]
fn a_finer_lattice_finds_each_agent_alone_no_worse_a_track() {
    let scenario = Some("scenarios/paper-top-speed.toml");
    let coarse = bound_with(scenario, &["--alone"]);
    let fine = bound_with(scenario, &["--alone", "--lattice-per-move", "10"]);
    assert_eq!(coarse["lattice_per_move"], 5, "{coarse}");
    // Without a search to run, the flag is refused, not ignored.
    let alone_flag = Command::new(support::coordinator_bin())
        .args(["bound", "--lattice-per-move", "10"])
        .output()
        .expect("coordinator bound");
    assert!(!alone_flag.status.success());
    let stderr = String::from_utf8_lossy(&alone_flag.stderr);
    assert!(stderr.contains("--alone"), "{stderr}");
    assert_eq!(fine["lattice_per_move"], 10, "{fine}");
    let searched = |r: &serde_json::Value| -> Vec<f64> {
        r["alone"]["per_agent"]
            .as_array()
            .expect("alone per agent")
            .iter()
            .map(|a| a["searched_mean_deviation_m"].as_f64().expect("a track"))
            .collect()
    };
    let bounds: Vec<f64> = fine["per_agent"]
        .as_array()
        .expect("per agent")
        .iter()
        .map(|a| a["mean_deviation_m"].as_f64().expect("a bound"))
        .collect();
    let (coarse, fine) = (searched(&coarse), searched(&fine));
    assert!(
        fine.iter().zip(&coarse).any(|(f, c)| f < &(c - 1e-6)),
        "the finer lattice found nothing better: {fine:?} {coarse:?}"
    );
    for ((f, c), b) in fine.iter().zip(&coarse).zip(&bounds) {
        assert!(*f <= c + 1e-12, "finer {f} against {c}");
        assert!(*f >= b * (1.0 - 1e-6), "finer {f} below the bound {b}");
    }
}
