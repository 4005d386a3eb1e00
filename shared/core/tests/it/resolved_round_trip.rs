//! The resolved form of a scenario (`Scenario::to_resolved_toml`, the `scenario.toml` of
//! a run folder) and its JSON twin (`Scenario::to_mission_json`, the agents' mission
//! file) load back to the same scenario, bit for bit, whether validated whole or value by
//! value: every shipped scenario, every test scenario that loads, and random valid
//! scenarios with awkward numbers (`-0.0`, subnormals, full-precision values, long
//! decimals).

use std::path::{Path, PathBuf};

use proptest::prelude::*;
use shared::control::vocabulary::{ControllerKind, TurnMode};
use shared::world::scenario::{Checks, Scenario};

/// `a` and `b` equal with `==`, and bit for bit: Debug prints every float in its
/// shortest round-trip form, which tells `-0.0` from `0.0` and any two different finite
/// values apart, so equal Debug text means equal bits (a scenario holds no NaN: the
/// checks refuse it).
fn assert_same(a: &Scenario, b: &Scenario, what: &str) {
    assert_eq!(a, b, "{what}");
    assert_eq!(format!("{a:?}"), format!("{b:?}"), "{what}: bit for bit");
}

/// The resolved text of `s`, checked to load back to `s` bit for bit, to list every
/// obstacle explicitly (no `[obstacles.random]`, no `positions_m`) and to name `what` in
/// its comment header.
fn round_trip(s: &Scenario, what: &str) -> String {
    let text = s
        .to_resolved_toml(what)
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    let back = Scenario::parse(&text, "resolved.toml")
        .unwrap_or_else(|e| panic!("{what}: the resolved text does not load: {e}\n{text}"));
    assert_same(&back, s, what);
    let doc: toml::Table = toml::from_str(&text).expect("TOML");
    let obstacles = doc["obstacles"].as_table().expect("[obstacles]");
    assert!(!obstacles.contains_key("random"), "{what}\n{text}");
    assert!(!obstacles.contains_key("positions_m"), "{what}\n{text}");
    assert_eq!(
        obstacles["disk"].as_array().expect("disk").len(),
        s.obstacles.len(),
        "{what}: every obstacle listed\n{text}"
    );
    assert_eq!(
        doc["controller"].as_str(),
        Some(s.controller.kind.name()),
        "{what}"
    );
    assert_eq!(
        doc["turns"]["mode"].as_str(),
        Some(s.turns.name()),
        "{what}"
    );
    // The order is written out: left out, it would be chosen again from the agents.
    assert_eq!(
        doc["turns"]["order"].as_str(),
        Some(s.turn_order.name()),
        "{what}"
    );
    assert!(
        doc["cbf"].as_table().is_some_and(|c| c.len() == 8),
        "{what}"
    );
    assert!(text.starts_with("# Resolved form"), "{what}");
    // Resolving the resolved scenario gives the same text but for the source named.
    let again = back
        .to_resolved_toml(what)
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    assert_eq!(again, text, "{what}");
    // The mission file: the same scenario, however much is checked.
    let json = s
        .to_mission_json()
        .unwrap_or_else(|e| panic!("{what}: {e}"));
    for checks in [Checks::All, Checks::Values] {
        let back = Scenario::from_mission_json(&json, "mission.json", checks)
            .unwrap_or_else(|e| panic!("{what}: the mission does not load ({checks:?}): {e}"));
        assert_same(&back, s, &format!("{what}: mission, {checks:?}"));
    }
    text
}

fn toml_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    files.sort();
    files
}

fn repository(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(path)
}

#[test]
fn every_shipped_scenario_resolves_to_a_file_that_loads_to_the_same_scenario() {
    let files = toml_files(&repository("scenarios"));
    assert!(files.len() >= 10, "{files:?}");
    let mut generated = 0;
    for file in &files {
        let what = file.display().to_string();
        let s = Scenario::load(file).unwrap_or_else(|e| panic!("{e}"));
        let original = Scenario::read(file).expect("read");
        generated += usize::from(original.contains("[obstacles.random]"));
        // Beside polygons only the best-point controller is accepted.
        let kinds = ControllerKind::ALL
            .into_iter()
            .filter(|k| s.polygons.is_empty() || *k == ControllerKind::BestPoint);
        for kind in kinds {
            let text = round_trip(&s.with_controller(kind), &what);
            assert!(text.contains(&what), "{what}: the source is named");
        }
    }
    assert!(
        generated >= 3,
        "the shipped scenarios draw obstacles from a seed"
    );
}

#[test]
fn every_test_scenario_that_loads_resolves_to_a_file_that_loads_to_the_same_scenario() {
    let files = toml_files(&repository("tests/data"));
    let loaded: Vec<_> = files
        .iter()
        .filter_map(|f| Scenario::load(f).ok().map(|s| (f, s)))
        .collect();
    assert!(loaded.len() >= 5, "{files:?}");
    for (file, s) in &loaded {
        round_trip(s, &file.display().to_string());
    }
}

/// The older key `planner` still reads as `controller`, and the resolved file writes
/// `controller`.
#[test]
fn the_older_key_planner_reads_as_controller() {
    let paper = shared::world::scenario::PAPER_SCENARIO_TOML;
    assert!(
        paper.contains("\n[field]"),
        "the paper example changed shape"
    );
    for kind in ControllerKind::ALL {
        let with = |key: &str| {
            paper.replacen(
                "\n[field]",
                &format!("\n{key} = \"{}\"\n\n[field]", kind.name()),
                1,
            )
        };
        let old = Scenario::parse(&with("planner"), "old.toml").expect("older key");
        let new = Scenario::parse(&with("controller"), "new.toml").expect("key");
        assert_eq!(old.controller.kind, kind);
        assert_same(&old, &new, kind.name());
        let text = round_trip(&old, kind.name());
        assert!(
            text.contains(&format!("controller = \"{}\"", kind.name())),
            "{text}"
        );
        assert!(!text.contains("planner ="), "{text}");
    }
}

#[test]
fn every_shipped_scenario_with_a_moving_obstacle_lists_it_as_its_own_table() {
    let mut seen = 0;
    for file in toml_files(&repository("scenarios")) {
        let s = Scenario::load(&file).unwrap_or_else(|e| panic!("{e}"));
        let text = s.to_resolved_toml("x").expect("resolved");
        for m in &s.moving {
            let table = shared::world::scenario::moving_obstacle_table(m);
            assert!(text.contains(&table), "{}: {table}", file.display());
            seen += 1;
        }
    }
    assert!(seen > 0, "a shipped scenario has moving obstacles");
}

// ---------------------------------------------------------------------------------------
// Random valid scenarios.

/// A number as scenario text: Rust's Debug form, the shortest round-trip digits with a
/// fraction or an exponent (`1.0`, `1e-7`, `5e-324`, `-0.0`), all valid TOML floats.
fn num(v: f64) -> String {
    format!("{v:?}")
}

/// A disk `{ x_m, y_m[, radius_m] }` as an inline table.
fn disk((x, y, r): &(f64, f64, Option<f64>)) -> String {
    let radius = r.map_or(String::new(), |r| format!(", radius_m = {}", num(r)));
    format!("{{ x_m = {}, y_m = {}{radius} }}", num(*x), num(*y))
}

/// An angle in degrees anywhere in the format's range, or one of its awkward values.
fn degrees() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(0.0),
        Just(-0.0),
        Just(360.0),
        Just(-360.0),
        Just(-179.99999999999997),
        -360.0..=360.0f64,
    ]
}

/// A point in the middle band of a `w` x `h` field (fractions of it), clear of the start
/// and goal and of the formation around them.
fn middle() -> impl Strategy<Value = (f64, f64)> {
    (0.35..0.65f64, 0.02..0.98f64)
}

/// One slot on ring `k` (1 m apart, so no two slots overlap): its angle, an optional
/// radius, an optional top speed.
fn slot() -> impl Strategy<Value = (f64, f64, Option<f64>, Option<f64>)> {
    (
        0.0..0.2f64,
        degrees(),
        prop::option::of(0.1..0.3f64),
        prop::option::of(0.3..1.0f64),
    )
}

/// A moving obstacle: its radius (absent: the default), waypoints, speed, and whether
/// its route loops.
type MovingSpec = (Option<f64>, Vec<(f64, f64)>, f64, bool);

/// A random scenario, as the values its file is written from.
#[derive(Debug, Clone)]
struct Random {
    name: String,
    seed: u64,
    w: f64,
    h: f64,
    start: (f64, f64, f64),
    goal: (f64, f64, f64),
    turning_radius_m: f64,
    step_m: f64,
    centre_clearance_m: f64,
    allow_reverse: bool,
    max_lag_m: Option<f64>,
    obstacle_radius_m: Option<f64>,
    positions: Vec<(f64, f64)>,
    disks: Vec<(f64, f64, Option<f64>)>,
    random: Option<(usize, f64, Option<f64>)>,
    moving: Vec<MovingSpec>,
    unknown: Vec<(f64, f64, Option<f64>)>,
    agent_radius_m: Option<f64>,
    slot0_r_m: f64,
    slots: Vec<(f64, f64, Option<f64>, Option<f64>)>,
    max_step_m: Option<f64>,
    sensing_extra_m: Option<f64>,
    controller: Option<ControllerKind>,
    cbf: Option<(f64, f64, f64, f64, f64, f64)>,
    parallel: bool,
}

fn random_scenario() -> impl Strategy<Value = Random> {
    let head = (
        "[a-zA-Z0-9 \"'\\\\#é\\n\\t]{0,16}",
        0..=i64::MAX as u64,
        50.0..100.0f64,
        30.0..60.0f64,
        (-0.5..0.5f64, -0.5..0.5f64, degrees()),
        (-0.5..0.5f64, -0.5..0.5f64, degrees()),
        0.5..3.0f64,
        0.1..1.0f64,
        prop_oneof![Just(0.0), Just(-0.0), 0.1..0.5f64],
        any::<bool>(),
        prop::option::of(0.5..3.0f64),
    );
    let obstacles = (
        prop::option::of(0.3..1.5f64),
        prop::collection::vec(middle(), 0..3),
        prop::collection::vec((middle(), prop::option::of(0.3..1.5f64)), 0..6),
        prop::option::of((0..8usize, prop::option::of(0.3..1.2f64))),
        prop::collection::vec(
            (
                prop::option::of(0.3..1.0f64),
                prop::collection::vec(middle(), 2..4),
                0.01..0.3f64,
                any::<bool>(),
            ),
            0..3,
        ),
        prop::collection::vec((middle(), prop::option::of(0.3..1.5f64)), 0..3),
    );
    let formation = (
        prop::option::of(0.1..0.3f64),
        prop_oneof![Just(0.0), Just(-0.0), Just(5e-324), 0.0..0.2f64],
        prop::collection::vec(slot(), 0..5),
        prop::option::of(0.3..1.0f64),
        prop::option::of(0.0..2.0f64),
    );
    let controller = (
        prop::option::of(prop::sample::select(ControllerKind::ALL.to_vec())),
        prop::option::of((
            0.1..1.0f64,
            0.5..1.5f64,
            0.1..2.0f64,
            0.1..1.0f64,
            0.0..2.0f64,
            1.0..50.0f64,
        )),
        any::<bool>(),
    );
    (head, obstacles, formation, controller).prop_map(
        |(
            (
                name,
                seed,
                w,
                h,
                start,
                goal,
                turning_radius_m,
                step_m,
                centre_clearance_m,
                allow_reverse,
                max_lag_m,
            ),
            (obstacle_radius_m, positions, disks, random, moving, unknown),
            (agent_radius_m, slot0_r_m, slots, max_step_m, sensing_extra_m),
            (controller, cbf, parallel),
        )| {
            let at = |(fx, fy): (f64, f64)| (fx * w, fy * h);
            Random {
                name: format!("s{name}"),
                seed,
                w,
                h,
                start: (8.0 + start.0, 0.5 * h + start.1, start.2),
                goal: (w - 8.0 + goal.0, 0.5 * h + goal.1, goal.2),
                turning_radius_m,
                step_m,
                centre_clearance_m,
                allow_reverse,
                max_lag_m,
                obstacle_radius_m,
                positions: positions.into_iter().map(at).collect(),
                disks: disks
                    .into_iter()
                    .map(|(p, r)| {
                        let (x, y) = at(p);
                        (x, y, r)
                    })
                    .collect(),
                // Random obstacles keep 7 m clear of the start and goal: of the
                // formation around them too.
                random: random.map(|(count, r)| (count, 7.0, r)),
                moving: moving
                    .into_iter()
                    .map(|(r, ws, speed, looped)| {
                        (r, ws.into_iter().map(at).collect(), speed, looped)
                    })
                    .collect(),
                unknown: unknown
                    .into_iter()
                    .map(|(p, r)| {
                        let (x, y) = at(p);
                        (x, y, r)
                    })
                    .collect(),
                agent_radius_m,
                slot0_r_m,
                slots,
                max_step_m,
                sensing_extra_m,
                controller,
                cbf,
                parallel,
            }
        },
    )
}

impl Random {
    /// Whether every agent has a top speed (limited sensing and parallel turns need one).
    fn every_agent_has_a_top_speed(&self) -> bool {
        // Slot 0 has none of its own: it takes the formation's.
        self.max_step_m.is_some()
    }

    /// The scenario file.
    fn text(&self) -> String {
        use std::fmt::Write as _;
        let mut t = String::new();
        let _ = writeln!(t, "name = {}", toml::Value::String(self.name.clone()));
        let _ = writeln!(t, "seed = {}", self.seed);
        if let Some(kind) = self.controller {
            let _ = writeln!(t, "controller = \"{}\"", kind.name());
        }
        let _ = writeln!(
            t,
            "[field]\nwidth_m = {}\nheight_m = {}",
            num(self.w),
            num(self.h)
        );
        let _ = writeln!(t, "[obstacles]");
        if let Some(r) = self.obstacle_radius_m {
            let _ = writeln!(t, "radius_m = {}", num(r));
        }
        let positions: Vec<String> = self
            .positions
            .iter()
            .map(|(x, y)| format!("[{}, {}]", num(*x), num(*y)))
            .collect();
        let _ = writeln!(t, "positions_m = [{}]", positions.join(", "));
        let disks: Vec<String> = self.disks.iter().map(disk).collect();
        let _ = writeln!(t, "disk = [{}]", disks.join(", "));
        let unknown: Vec<String> = self.unknown.iter().map(disk).collect();
        let _ = writeln!(t, "unknown = [{}]", unknown.join(", "));
        let moving: Vec<String> = self
            .moving
            .iter()
            .map(|(r, ws, speed, looped)| {
                let ws: Vec<String> = ws
                    .iter()
                    .map(|(x, y)| format!("[{}, {}]", num(*x), num(*y)))
                    .collect();
                let radius = r.map_or(String::new(), |r| format!("radius_m = {}, ", num(r)));
                let route = if *looped { "loop" } else { "back-and-forth" };
                format!(
                    "{{ {radius}waypoints_m = [{}], speed_m_per_step = {}, route = \"{route}\" }}",
                    ws.join(", "),
                    num(*speed)
                )
            })
            .collect();
        let _ = writeln!(t, "moving = [{}]", moving.join(", "));
        if let Some((count, keep_clear_m, r)) = self.random {
            let _ = writeln!(
                t,
                "[obstacles.random]\ncount = {count}\nkeep_clear_m = {}",
                num(keep_clear_m)
            );
            if let Some(r) = r {
                let _ = writeln!(t, "radius_m = {}", num(r));
            }
        }
        let _ = writeln!(t, "[formation]");
        if let Some(r) = self.agent_radius_m {
            let _ = writeln!(t, "agent_radius_m = {}", num(r));
        }
        if let Some(v) = self.max_step_m {
            let _ = writeln!(t, "max_step_m = {}", num(v));
        }
        if let (Some(extra), Some(_)) = (self.sensing_extra_m, self.max_step_m) {
            // Covers a move (at most 1 m), the agent's radius (at most 0.3 m) and a
            // moving obstacle's step (at most 0.3 m).
            let _ = writeln!(t, "sensing_radius_m = {}", num(1.6 + extra));
        }
        let mut slots = vec![format!(
            "{{ r_m = {}, theta_deg = {} }}",
            num(self.slot0_r_m),
            num(self.start.2)
        )];
        for (k, (jitter, theta, radius, max_step)) in self.slots.iter().enumerate() {
            let mut s = format!(
                "{{ r_m = {}, theta_deg = {}",
                num((k + 1) as f64 + jitter),
                num(*theta)
            );
            if let Some(r) = radius {
                let _ = write!(s, ", radius_m = {}", num(*r));
            }
            if let Some(v) = max_step {
                let _ = write!(s, ", max_step_m = {}", num(*v));
            }
            s.push_str(" }");
            slots.push(s);
        }
        let _ = writeln!(t, "slots = [{}]", slots.join(", "));
        let pose = |(x, y, heading): (f64, f64, f64)| {
            format!(
                "{{ x_m = {}, y_m = {}, heading_deg = {} }}",
                num(x),
                num(y),
                num(heading)
            )
        };
        let _ = writeln!(
            t,
            "[path]\nstart = {}\ngoal = {}\nturning_radius_m = {}\nstep_m = {}\ncentre_clearance_m = {}\nallow_reverse = {}",
            pose(self.start),
            pose(self.goal),
            num(self.turning_radius_m),
            num(self.step_m),
            num(self.centre_clearance_m),
            self.allow_reverse
        );
        if let Some(v) = self.max_lag_m {
            let _ = writeln!(t, "max_lag_m = {}", num(v));
        }
        if let Some((gamma_dt, dt_s, gain_per_s, max_speed_m_per_s, sensing_extra_m, lse)) =
            self.cbf
        {
            // gamma * dt below 1; the sensing radius covers the agent (at most 0.3 m), a
            // move and the margin.
            let _ = writeln!(
                t,
                "[cbf]\ngamma_per_s = {}\ndt_s = {}\ngain_per_s = {}\nmax_speed_m_per_s = {}\nsensing_radius_m = {}\nlse_sharpness_per_m = {}",
                num(gamma_dt / dt_s),
                num(dt_s),
                num(gain_per_s),
                num(max_speed_m_per_s),
                num(0.3 + max_speed_m_per_s * dt_s + 1.0 + sensing_extra_m),
                num(lse)
            );
        }
        if self.parallel && self.every_agent_has_a_top_speed() {
            let _ = writeln!(t, "[turns]\nmode = \"{}\"", TurnMode::Parallel.name());
        }
        t
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Random valid scenarios, numbers at full precision and awkward values among them,
    /// load back from their resolved form bit for bit.
    #[test]
    fn random_scenarios_load_back_from_their_resolved_form(r in random_scenario()) {
        let text = r.text();
        let s = Scenario::parse(&text, "random.toml")
            .unwrap_or_else(|e| panic!("the generator made an invalid scenario: {e}\n{text}"));
        round_trip(&s, "random.toml");
    }
}

/// A mission checked value by value still refuses every bad value, naming the field, and
/// refuses text that is not a mission; only the rules relating the parts are left to the
/// coordinator (here two slots on top of each other, which `Checks::All` refuses).
#[test]
fn a_mission_checked_value_by_value_still_refuses_bad_values() {
    let json = Scenario::paper().to_mission_json().expect("json");
    let cases = [
        ("\"step_m\":0.25", "\"step_m\":-1.0", "path.step_m"),
        ("\"width_m\":", "\"width_m\":1e999,\"x\":", "(top level)"),
        (
            "\"turning_radius_m\":",
            "\"turning_radius_m\":\"far\",\"x\":",
            "path.turning_radius_m",
        ),
        ("\"name\":", "\"speed\":1,\"name\":", "(top level)"),
    ];
    for (from, to, field) in cases {
        assert!(json.contains(from), "{from}");
        let bad = json.replacen(from, to, 1);
        let e = Scenario::from_mission_json(&bad, "mission.json", Checks::Values).expect_err(&bad);
        assert!(e.to_string().starts_with("mission.json: "), "{e}");
        assert!(!e.to_string().contains('\n'), "one line: {e}");
        if field != "(top level)" {
            assert_eq!(e.field(), field, "{e}");
        }
    }
    assert!(Scenario::from_mission_json("{}", "m", Checks::Values).is_err());
    assert!(Scenario::from_mission_json(&format!("{json} {{}}"), "m", Checks::Values).is_err());
    // Two slots on one spot: only the whole check sees it.
    let mut crowded = Scenario::paper();
    crowded.agents[1].slot = crowded.agents[0].slot;
    let json = crowded.to_mission_json().expect("json");
    assert!(Scenario::from_mission_json(&json, "m", Checks::All).is_err());
    assert!(Scenario::from_mission_json(&json, "m", Checks::Values).is_ok());
}
