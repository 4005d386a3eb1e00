//! `coordinator render` of a changing world: moving and unknown obstacles, replans, and
//! the run folder's files named in `docs/outputs.md`.

use std::path::Path;

use tools::render::animation::Animation;
use tools::render::metrics;
use tools::render::{RunData, render_run_dir};

use crate::support::{decode_gif, px, scratch};

/// A changing world: one obstacle patrolling across the way near the goal, one unknown
/// obstacle on the straight line from start to goal, found only when an agent comes
/// within its sensing radius.
const CHANGING: &str = r#"
name = "changing"

[field]
width_m = 30.0
height_m = 12.0

[[obstacles.moving]]
radius_m = 0.8
waypoints_m = [[23.0, 1.5], [23.0, 10.5]]
speed_m_per_step = 0.2
route = "back-and-forth"

[[obstacles.unknown]]
x_m = 14.0
y_m = 6.0
radius_m = 1.0

[formation]
agent_radius_m = 0.3
max_step_m = 0.5
sensing_radius_m = 3.0
slots = [ { r_m = 0.0, theta_deg = 0.0 }, { r_m = 1.0, theta_deg = 90.0 } ]

[path]
start = { x_m = 2.0, y_m = 6.0, heading_deg = 0.0 }
goal = { x_m = 28.0, y_m = 6.0, heading_deg = 0.0 }
turning_radius_m = 2.0
step_m = 0.25
centre_clearance_m = 0.5
"#;

/// Reddish purple of the moving obstacles (drawn at 85 % over white or grey).
fn is_moving_obstacle(c: [u8; 3]) -> bool {
    let [r, g, b] = c.map(i32::from);
    r > 170 && (100..160).contains(&g) && b > 130 && r - g > 50
}

#[test]
fn a_changing_world_writes_its_obstacles_and_plans_and_renders_them() {
    use shared::geometry::Pose;
    let scenario =
        shared::world::scenario::Scenario::parse(CHANGING, "changing.toml").expect("scenario");
    let first_plan = shared::run::simulate::plan_centre_path(&scenario).expect("first plan");
    let run = shared::run::simulate::simulate_along(&scenario, &first_plan).expect("simulate");
    let dir = scratch("changing");
    runner::output::write_run(
        &dir,
        &scenario,
        "changing.toml",
        &run,
        &first_plan,
        &runner::output::Timing::default(),
    )
    .expect("write run");
    let found_at = run.course.found_at[0].expect("the unknown obstacle is found on the way");
    assert!(
        found_at > 1,
        "found by sensing, not at once: step {found_at}"
    );
    let taken: Vec<_> = run.course.replans.iter().filter(|r| r.found).collect();
    assert!(!taken.is_empty(), "the centre replans around what it finds");

    // obstacles.csv: one row per moving obstacle per step, exactly where its route puts
    // it; then the unknown obstacle with the step it became known.
    let mut reader = csv::Reader::from_path(dir.join("obstacles.csv")).expect("obstacles.csv");
    let header: Vec<String> = reader
        .headers()
        .expect("header")
        .iter()
        .map(str::to_string)
        .collect();
    assert_eq!(
        header,
        [
            "step",
            "kind",
            "index",
            "x_m",
            "y_m",
            "radius_m",
            "known_from_step"
        ]
    );
    let rows: Vec<csv::StringRecord> = reader.records().map(|r| r.expect("row")).collect();
    let f = |r: &csv::StringRecord, i: usize| -> f64 { r[i].parse().expect("number") };
    let moving: Vec<_> = rows.iter().filter(|r| &r[1] == "moving").collect();
    assert_eq!(moving.len(), run.steps.len() * scenario.moving.len());
    let mut far = false;
    for (row, st) in moving.iter().zip(&run.steps) {
        assert_eq!(row[0].parse::<usize>().expect("step"), st.step);
        assert_eq!(&row[2], "0");
        let p = scenario.moving[0].position_at(st.step);
        assert_eq!((f(row, 3), f(row, 4)), (p.x, p.y), "step {}", st.step);
        assert_eq!(f(row, 5), 0.8);
        assert_eq!(&row[6], "");
        far |= (p - scenario.moving[0].position_at(0)).norm() > 3.0;
    }
    assert!(far, "the obstacle moved");
    let unknown: Vec<_> = rows.iter().filter(|r| &r[1] == "unknown").collect();
    assert_eq!(unknown.len(), 1);
    assert_eq!((&unknown[0][0], &unknown[0][2]), ("", "0"));
    assert_eq!(
        (f(unknown[0], 3), f(unknown[0], 4), f(unknown[0], 5)),
        (14.0, 6.0, 1.0)
    );
    assert_eq!(unknown[0][6].parse::<usize>().expect("step"), found_at);
    assert_eq!(rows.len(), moving.len() + 1);

    // plans.csv: plan 0 is the first plan, pose for pose; then every replan taken, each
    // from where the centre stood when it was planned.
    let mut plans: Vec<(usize, usize, String, Vec<Pose>)> = Vec::new();
    let mut reader = csv::Reader::from_path(dir.join("plans.csv")).expect("plans.csv");
    for r in reader.records() {
        let r = r.expect("row");
        let plan: usize = r[0].parse().expect("plan");
        let pose = Pose::new(f(&r, 3), f(&r, 4), f(&r, 5));
        if plans.last().is_none_or(|p| p.0 != plan) {
            plans.push((
                plan,
                r[1].parse().expect("step"),
                r[2].to_string(),
                Vec::new(),
            ));
        }
        if let Some(last) = plans.last_mut() {
            last.3.push(pose);
        }
    }
    assert_eq!(plans.len(), 1 + taken.len());
    assert_eq!(
        (plans[0].0, plans[0].1, plans[0].2.as_str()),
        (0, 0, "first")
    );
    assert_eq!(plans[0].3, first_plan);
    for (k, (plan, replan)) in plans[1..].iter().zip(&taken).enumerate() {
        assert_eq!(plan.0, k + 1);
        assert_eq!(plan.1, replan.step);
        assert_eq!(plan.2, replan.reason.name());
        assert_eq!(plan.3, replan.path);
        assert_eq!(
            plan.3.first(),
            run.centre_path.get(replan.step - 1),
            "plan {} starts where the centre stood",
            plan.0
        );
    }
    // path.csv is the path followed, one pose per step, not the first plan.
    let followed = std::fs::read_to_string(dir.join("path.csv")).expect("path.csv");
    assert_eq!(followed.lines().count(), 1 + run.centre_path.len());
    assert_ne!(run.centre_path, first_plan);

    // The render reads them back and draws them.
    let written = render_run_dir(&dir).expect("render");
    assert_eq!(written.len(), 9);
    let data = RunData::load(&dir).expect("load");
    assert_eq!(data.plans.len(), plans.len());
    assert_eq!(data.plans[0].poses, first_plan);
    assert_eq!(data.moving.len(), run.steps.len());
    assert_eq!(data.unknown[0].known_from_step, Some(found_at));
    let svg = std::fs::read_to_string(dir.join("plots/field.svg")).expect("svg");
    for text in [
        format!("found at step {found_at}"),
        format!("plans (first + {} replan", taken.len()),
        "centre path followed".to_string(),
        "moving obstacle at step 0".to_string(),
    ] {
        assert!(svg.contains(&text), "field.svg lacks {text:?}");
    }

    // The animation: the moving obstacle where it is at each frame's step; the unknown
    // obstacle an outline (its centre background) before it was found, filled after.
    let m = metrics::per_step(&data);
    let animation = Animation::new(&data, &m);
    let l = animation.layout();
    let frames = decode_gif(&dir.join("plots/animation.gif"));
    assert_eq!(frames.len(), animation.frames().len());
    let shown = |k: usize| run.steps[animation.frames()[k]].step;
    let last = frames.len() - 1;
    for k in [0, last] {
        let p = scenario.moving[0].position_at(shown(k));
        let c = frames[k].at(px(l, p.x, p.y));
        assert!(is_moving_obstacle(c), "frame {k}: {c:?}");
    }
    let start = scenario.moving[0].position_at(0);
    let end = scenario.moving[0].position_at(shown(last));
    assert!(
        (start - end).norm() > 2.0,
        "it moved between the first and last frames"
    );
    let c = frames[last].at(px(l, start.x, start.y));
    assert!(
        !is_moving_obstacle(c),
        "not left behind at its start: {c:?}"
    );
    let before = (0..frames.len())
        .rfind(|&k| shown(k) < found_at)
        .expect("a frame before it was found");
    // A small patch round its centre: background (white, or a grid line's 225 grey) before
    // it was found; grey fill or black hatching after.
    let patch = |k: usize| -> Vec<[u8; 3]> {
        [(-0.3, 0.0), (0.3, 0.0), (0.0, -0.3), (0.0, 0.3), (0.0, 0.0)]
            .iter()
            .map(|(dx, dy)| frames[k].at(px(l, 14.0 + dx, 6.0 + dy)))
            .collect()
    };
    assert!(
        patch(before).iter().all(|c| c.iter().all(|&v| v >= 220)),
        "outline only before step {found_at}: {:?}",
        patch(before)
    );
    assert!(
        patch(last).iter().all(|c| c.iter().all(|&v| v < 200)),
        "filled once found: {:?}",
        patch(last)
    );

    // A folder written before these files is drawn from its scenario and summary.json.
    let loaded = (data.moving.clone(), data.unknown.clone());
    std::fs::remove_file(dir.join("obstacles.csv")).expect("remove");
    std::fs::remove_file(dir.join("plans.csv")).expect("remove");
    let older = RunData::load(&dir).expect("load without the new files");
    assert_eq!((older.moving, older.unknown), loaded);
    assert!(older.plans.is_empty());
    render_run_dir(&dir).expect("render without the new files");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The names in the first table after the line `heading` of `doc`: every backticked name
/// of each row's first cell, in order.
fn documented_names(doc: &str, heading: &str) -> Vec<String> {
    let mut lines = doc.lines().skip_while(|l| *l != heading).skip(1);
    let rows = lines
        .by_ref()
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .skip(2); // the header and the separator
    let mut names = Vec::new();
    for row in rows {
        let cell = row.split('|').nth(1).unwrap_or_default();
        names.extend(cell.split('`').skip(1).step_by(2).map(str::to_string));
    }
    assert!(!names.is_empty(), "no table after {heading}");
    names
}

#[test]
fn docs_outputs_md_names_every_summary_key_and_every_csv_column() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let doc = std::fs::read_to_string(repo.join("docs").join("outputs.md")).expect("outputs.md");
    let scenario =
        shared::world::scenario::Scenario::parse(CHANGING, "changing.toml").expect("scenario");
    let first_plan = shared::run::simulate::plan_centre_path(&scenario).expect("first plan");
    let run = shared::run::simulate::simulate_along(&scenario, &first_plan).expect("simulate");
    let dir = scratch("doc");
    let written = runner::output::write_run(
        &dir,
        &scenario,
        "changing.toml",
        &run,
        &first_plan,
        &runner::output::Timing::default(),
    )
    .expect("write run");
    let names: Vec<String> = written
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    // The run folder's table lists the log the run writes as it goes, then the files
    // made from it in the order written, summary.json last, then the plots.
    let mut listed = documented_names(&doc, "## `coordinator run`: the run folder");
    assert_eq!(listed.pop().as_deref(), Some("plots/"));
    assert_eq!(listed.first().map(String::as_str), Some("run.mcap"));
    assert_eq!(listed[1..], names[..]);

    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).expect("summary"))
            .expect("summary.json parses");
    let mut keys: Vec<String> = summary
        .as_object()
        .expect("an object")
        .keys()
        .cloned()
        .collect();
    // Agents with a heading add their figures: a run of unicycles has every key.
    const HEADING_KEYS: [&str; 3] = [
        "max_heading_error_rad",
        "max_turn_rad",
        "mean_heading_error_rad",
    ];
    assert!(HEADING_KEYS.iter().all(|k| summary.get(k).is_none()));
    let unicycles =
        shared::world::scenario::Scenario::load(&repo.join("scenarios/paper-unicycle.toml"))
            .expect("paper-unicycle.toml");
    let unicycle_plan = shared::run::simulate::plan_centre_path(&unicycles).expect("first plan");
    let unicycle_run =
        shared::run::simulate::simulate_along(&unicycles, &unicycle_plan).expect("simulate");
    let unicycle_dir = scratch("doc-unicycles");
    runner::output::write_run(
        &unicycle_dir,
        &unicycles,
        "paper-unicycle.toml",
        &unicycle_run,
        &unicycle_plan,
        &runner::output::Timing::default(),
    )
    .expect("write run");
    let unicycle_summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(unicycle_dir.join("summary.json")).expect("summary"))
            .expect("summary.json parses");
    for k in HEADING_KEYS {
        assert!(unicycle_summary[k].is_number(), "{k}: {unicycle_summary:#}");
        keys.push(k.to_string());
    }
    let _ = std::fs::remove_dir_all(&unicycle_dir);
    let mut documented = documented_names(&doc, "### `summary.json`");
    keys.sort();
    documented.sort();
    assert_eq!(documented, keys, "summary.json keys");
    let replan = &summary["replans"][0];
    let mut replan_keys: Vec<&String> = replan.as_object().expect("a replan").keys().collect();
    replan_keys.sort();
    assert_eq!(replan_keys, ["found", "planning_ms", "reason", "step"]);

    for file in [
        "trajectory.csv",
        "moves.csv",
        "path.csv",
        "plans.csv",
        "obstacles.csv",
    ] {
        let mut reader = csv::Reader::from_path(dir.join(file)).expect(file);
        let mut header: Vec<String> = reader
            .headers()
            .expect("header")
            .iter()
            .map(str::to_string)
            .collect();
        if file == "trajectory.csv" {
            // The heading columns, documented, come only in runs with agents that have
            // a heading; this run's agents are holonomic.
            assert!(
                !header.iter().any(|c| c.starts_with("heading")),
                "{header:?}"
            );
            header.extend(["heading_rad".to_string(), "heading_error_rad".to_string()]);
        }
        if file == "moves.csv" {
            // So do the primitives' columns.
            assert!(!header.iter().any(|c| c == "heading_rad"), "{header:?}");
            header.extend(["heading_rad", "drive_m", "curvature_per_m"].map(String::from));
        }
        assert_eq!(
            documented_names(&doc, &format!("### `{file}`")),
            header,
            "{file}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
