//! `coordinator render`: every file is written, decodes at its stated size, and agents are
//! drawn where they are. The run directories are small synthetic ones written here (plus
//! one real, in-process simulation of the paper's example).

use std::path::Path;

use runner::CliError;
use tools::render::RenderArgs;
use tools::render::animation::Animation;
use tools::render::canvas::Figure;
use tools::render::field::FieldFigure;
use tools::render::formation::FormationFigure;
use tools::render::metrics;
use tools::render::series::SeriesFigure;
use tools::render::{RunData, render_run_dir};

use crate::support::{Rgb, assert_svg, decode_gif, decode_png, is_agent, px, scratch};

const SCENARIO: &str = r#"
name = "tiny"
seed = 1

[field]
width_m = 12.0
height_m = 8.0

[obstacles]
radius_m = 0.5
positions_m = [[9.0, 6.5]]

[formation]
agent_radius_m = 0.4
slots = [ { r_m = 0.0, theta_deg = 0.0 }, { r_m = 1.2, theta_deg = 90.0 } ]

[path]
start = { x_m = 2.0, y_m = 3.0, heading_deg = 0.0 }
goal = { x_m = 10.0, y_m = 3.0, heading_deg = 0.0 }
turning_radius_m = 1.0
step_m = 1.0
centre_clearance_m = 0.3
allow_reverse = false
"#;

/// A four-step run: the centre moves 1 m a step along +x; agent 0 sits on the centre,
/// agent 1 1.2 m to its left until it dies in step 2 and stays frozen at (3, 4.2).
fn write_tiny_run(dir: &Path) {
    std::fs::write(dir.join("scenario.toml"), SCENARIO).expect("write scenario");
    let mut path = String::from("step,x_m,y_m,heading_rad\n");
    let mut trajectory = String::from(
        "step,agent,x,y,slot_x,slot_y,best_x,best_y,deviation_m,clearance_m,status,alive\n",
    );
    let mut moves = String::from("step,agent,index,x,y\n");
    for step in 0..4 {
        let cx = 2.0 + step as f64;
        path.push_str(&format!("{step},{cx},3,0\n"));
        trajectory.push_str(&format!("{step},0,{cx},3,{cx},3,{cx},3,0,0.4,at_slot,1\n"));
        let (x1, alive, status) = if step < 2 {
            (cx, 1, "at_slot")
        } else {
            (3.0, 0, "dead")
        };
        let dev = cx - x1;
        trajectory.push_str(&format!(
            "{step},1,{x1},4.2,{cx},4.2,{x1},4.2,{dev},0.4,{status},{alive}\n"
        ));
        match step {
            0 => moves.push_str("0,0,0,2,3\n0,1,0,2,4.2\n"),
            1 => moves.push_str("1,0,0,2,3\n1,0,1,2.5,2.8\n1,0,2,3,3\n1,1,0,2,4.2\n1,1,1,3,4.2\n"),
            _ => moves.push_str(&format!(
                "{step},0,0,{},3\n{step},0,1,{cx},3\n{step},1,0,3,4.2\n",
                cx - 1.0
            )),
        }
    }
    std::fs::write(dir.join("path.csv"), path).expect("write path");
    std::fs::write(dir.join("trajectory.csv"), trajectory).expect("write trajectory");
    std::fs::write(dir.join("moves.csv"), moves).expect("write moves");
    std::fs::write(
        dir.join("summary.json"),
        r#"{"scenario": "tiny", "completed": true,
            "faults": [{"agent": 1, "step": 2, "kind": "dead", "detail": "killed"}]}"#,
    )
    .expect("write summary");
}

#[test]
fn every_file_is_written_and_decodes_at_its_stated_size() {
    let dir = scratch("sizes");
    write_tiny_run(&dir);
    let written = render_run_dir(&dir).expect("render");
    let plots = dir.join("plots");
    let names: Vec<String> = written
        .iter()
        .map(|p| {
            assert_eq!(p.parent(), Some(plots.as_path()));
            assert!(p.is_file(), "{}", p.display());
            p.file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default()
        })
        .collect();
    let mut expected: Vec<String> = ["field", "formation", "deviation", "clearance"]
        .iter()
        .flat_map(|s| [format!("{s}.png"), format!("{s}.svg")])
        .collect();
    expected.push("animation.gif".into());
    assert_eq!(names, expected);

    let data = RunData::load(&dir).expect("load");
    let m = metrics::per_step(&data);
    let sizes = [
        ("field", FieldFigure::new(&data).size_px()),
        ("formation", FormationFigure::new(&data).size_px()),
        ("deviation", SeriesFigure::deviation(&data, &m).size_px()),
        ("clearance", SeriesFigure::clearance(&data, &m).size_px()),
    ];
    for (stem, (w, h)) in sizes {
        let png = decode_png(&plots.join(format!("{stem}.png")));
        assert_eq!((png.width, png.height), (w, h), "{stem}.png");
        assert_svg(&plots.join(format!("{stem}.svg")), (w, h));
    }
    let animation = Animation::new(&data, &m);
    let frames = decode_gif(&plots.join("animation.gif"));
    assert_eq!(frames.len(), animation.frames().len());
    assert_eq!(frames.len(), 4);
    assert_eq!((frames[0].width, frames[0].height), animation.size_px());
    assert!(
        animation.size_px().0 > animation.layout().width_px,
        "close-up panel"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn agents_are_drawn_where_they_are() {
    let dir = scratch("pixels");
    write_tiny_run(&dir);
    render_run_dir(&dir).expect("render");
    let data = RunData::load(&dir).expect("load");

    // Formation at the start pose: agent 0 on the centre (2, 3), agent 1 at (2, 4.2).
    let formation = FormationFigure::new(&data);
    let l = formation.layout();
    let png = decode_png(&dir.join("plots/formation.png"));
    assert!(
        is_agent(png.at(px(l, 1.8, 2.8))),
        "{:?}",
        png.at(px(l, 1.8, 2.8))
    );
    assert!(
        is_agent(png.at(px(l, 2.2, 4.4))),
        "{:?}",
        png.at(px(l, 2.2, 4.4))
    );
    assert!(!is_agent(png.at(px(l, 1.3, 2.7))), "outside every agent");

    // Animation: agent 0 starts at (2, 3) and ends at (5, 3); agent 1 dies at (3, 4.2).
    let m = metrics::per_step(&data);
    let animation = Animation::new(&data, &m);
    let l = animation.layout();
    let frames = decode_gif(&dir.join("plots/animation.gif"));
    let (first, last) = (&frames[0], &frames[frames.len() - 1]);
    assert!(
        is_agent(first.at(px(l, 1.9, 3.2))),
        "{:?}",
        first.at(px(l, 1.9, 3.2))
    );
    assert!(
        is_agent(last.at(px(l, 4.9, 3.2))),
        "{:?}",
        last.at(px(l, 4.9, 3.2))
    );
    assert!(
        !is_agent(last.at(px(l, 1.9, 3.2))),
        "agent 0 has left its start"
    );
    let dead = last.at(px(l, 3.1, 4.3));
    assert!(
        dead.iter().all(|&c| c < 110),
        "dead agent drawn dark: {dead:?}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A pixel of an agent's edge colour (dark brown), not of its fill or the background.
fn is_edge(c: [u8; 3]) -> bool {
    let [r, g, b] = c.map(i32::from);
    r < 180 && g < 130 && b < 80 && r > b
}

/// Whether a pixel of the edge colour lies within one pixel of `(x, y)`.
fn edge_near(img: &Rgb, (x, y): (i32, i32)) -> bool {
    (-1..=1).any(|dx| (-1..=1).any(|dy| is_edge(img.at((x + dx, y + dy)))))
}

#[test]
fn an_agent_with_a_heading_shows_where_it_faces() {
    let dir = scratch("headings");
    write_tiny_run(&dir);
    // The same run with unicycles: every agent starts facing +x (the centre's heading);
    // in the run agent 0 faces +y at every step.
    let scenario = SCENARIO.replace(
        "agent_radius_m = 0.4",
        "agent_radius_m = 0.4\nmax_step_m = 1.5\nkinematics = \"unicycle\"\nmax_turn_rad = 3.0",
    );
    std::fs::write(dir.join("scenario.toml"), scenario).expect("write scenario");
    let old = std::fs::read_to_string(dir.join("trajectory.csv")).expect("read trajectory");
    let mut lines = old.lines();
    let mut trajectory = format!("{},heading_rad,heading_error_rad\n", lines.next().unwrap());
    for line in lines {
        let h = if line.split(',').nth(1) == Some("0") {
            std::f64::consts::FRAC_PI_2
        } else {
            0.0
        };
        trajectory.push_str(&format!("{line},{h},{h}\n"));
    }
    std::fs::write(dir.join("trajectory.csv"), trajectory).expect("write trajectory");
    render_run_dir(&dir).expect("render");
    let data = RunData::load(&dir).expect("load");

    // Formation: agent 0 at (2, 3), radius 0.4, faces +x: a tick on its +x side, fill on
    // its -y side at the same distance.
    let formation = FormationFigure::new(&data);
    let l = formation.layout();
    let png = decode_png(&dir.join("plots/formation.png"));
    assert!(
        edge_near(&png, px(l, 2.3, 3.0)),
        "{:?}",
        png.at(px(l, 2.3, 3.0))
    );
    assert!(
        is_agent(png.at(px(l, 2.0, 2.7))),
        "{:?}",
        png.at(px(l, 2.0, 2.7))
    );

    // Animation, first frame: agent 0 faces +y, so the line is above its centre and
    // nothing of it below.
    let m = metrics::per_step(&data);
    let animation = Animation::new(&data, &m);
    let l = animation.layout();
    let frames = decode_gif(&dir.join("plots/animation.gif"));
    let first = &frames[0];
    assert!(
        edge_near(first, px(l, 2.0, 3.3)),
        "{:?}",
        first.at(px(l, 2.0, 3.3))
    );
    assert!(
        !edge_near(first, px(l, 2.0, 2.7)),
        "{:?}",
        first.at(px(l, 2.0, 2.7))
    );
    assert!(
        is_agent(first.at(px(l, 2.0, 2.7))),
        "{:?}",
        first.at(px(l, 2.0, 2.7))
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_bad_run_dir_is_a_usage_error_naming_the_file() {
    let dir = scratch("bad");
    write_tiny_run(&dir);
    std::fs::remove_file(dir.join("trajectory.csv")).expect("remove");
    let err = tools::render::execute(&RenderArgs {
        run_dir: dir.clone(),
        sensing_circles: false,
    })
    .expect_err("missing file");
    assert!(matches!(err, CliError::Usage(_)), "{err:?}");
    assert_eq!(err.exit_code(), 2);
    let msg = err.to_string();
    assert!(
        msg.contains("trajectory.csv") && !msg.contains('\n'),
        "{msg}"
    );

    std::fs::write(
        dir.join("trajectory.csv"),
        "step,agent,x,y,slot_x,slot_y,best_x,best_y,deviation_m,clearance_m,status,alive\n\
         0,0,2,3,2,3,2,3,0,0.4,at_slot,1\n0,1,oops,4.2,2,4.2,2,4.2,0,0.4,at_slot,1\n",
    )
    .expect("write");
    let msg = tools::render::execute(&RenderArgs {
        run_dir: dir.clone(),
        sensing_circles: false,
    })
    .expect_err("malformed file")
    .to_string();
    assert!(
        msg.contains("trajectory.csv") && msg.contains("line 3"),
        "{msg}"
    );

    let missing = dir.join("no-such-run");
    let err = tools::render::execute(&RenderArgs {
        run_dir: missing,
        sensing_circles: false,
    })
    .expect_err("no directory");
    assert_eq!(err.exit_code(), 2);
    assert!(
        !dir.join("plots").exists(),
        "nothing written for a bad run dir"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_simulated_paper_run_renders() {
    let scenario = shared::world::scenario::Scenario::paper();
    let run = shared::run::simulate::simulate(&scenario).expect("simulate the paper example");
    let dir = scratch("paper");
    runner::output::write_run(
        &dir,
        &scenario,
        shared::world::scenario::PAPER_SCENARIO_NAME,
        &run,
        &shared::run::simulate::plan_centre_path(&scenario).expect("the paper's centre path"),
        &runner::output::Timing::default(),
    )
    .expect("write run");
    let written = render_run_dir(&dir).expect("render");
    assert_eq!(written.len(), 9);
    // A static world: no plan but the first, nothing moving, nothing unknown, the field
    // figure as before.
    let data = RunData::load(&dir).expect("load");
    assert_eq!(data.plans.len(), 1);
    assert!(data.moving.is_empty() && data.unknown.is_empty());
    let svg = std::fs::read_to_string(dir.join("plots/field.svg")).expect("svg");
    assert!(svg.contains("centre path (Hybrid A*)"));
    assert!(!svg.contains("plans (") && !svg.contains("moving obstacle"));
    for p in &written {
        let len = std::fs::metadata(p).map(|m| m.len()).unwrap_or(0);
        assert!(len > 1000, "{} is {len} bytes", p.display());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The tiny run's scenario with a top speed, limited sensing and parallel turns.
fn timed_scenario() -> String {
    SCENARIO
        .replace(
            "agent_radius_m = 0.4\n",
            "agent_radius_m = 0.4\nmax_step_m = 0.5\nsensing_radius_m = 2.5\n",
        )
        .replace(
            "allow_reverse = false\n",
            "allow_reverse = false\n\n[turns]\nmode = \"parallel\"\n",
        )
}

#[test]
fn titles_name_the_top_speed_the_sensing_and_parallel_turns() {
    let dir = scratch("timed");
    write_tiny_run(&dir);
    std::fs::write(dir.join("scenario.toml"), timed_scenario()).expect("write scenario");
    let written = render_run_dir(&dir).expect("render");
    assert_eq!(written.len(), 9);
    for stem in ["field", "formation", "deviation", "clearance"] {
        let svg = std::fs::read_to_string(dir.join(format!("plots/{stem}.svg"))).expect("svg");
        assert!(
            svg.contains("top speed 0.5 m/step, sensing 2.5 m, parallel turns"),
            "{stem}.svg"
        );
    }
    // The paper's model has no such note.
    let plain = scratch("untimed");
    write_tiny_run(&plain);
    render_run_dir(&plain).expect("render");
    let svg = std::fs::read_to_string(plain.join("plots/field.svg")).expect("svg");
    assert!(!svg.contains("top speed") && !svg.contains("parallel"));
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&plain);
}

#[test]
fn sensing_circles_are_drawn_only_when_asked_and_the_scenario_has_a_radius() {
    let dir = scratch("sensing");
    write_tiny_run(&dir);
    std::fs::write(dir.join("scenario.toml"), timed_scenario()).expect("write scenario");
    let data = RunData::load(&dir).expect("load");
    let m = metrics::per_step(&data);
    let plain = Animation::new(&data, &m);
    let circles = Animation::with_sensing_circles(&data, &m, true);
    assert!(!plain.draws_sensing_circles());
    assert!(circles.draws_sensing_circles());
    let a = plain.write_gif(Vec::new()).expect("gif");
    let b = circles.write_gif(Vec::new()).expect("gif");
    assert_ne!(a, b, "the circles change the frames");

    // Through the command: the flag draws them, the GIF decodes at its size.
    tools::render::execute(&RenderArgs {
        run_dir: dir.clone(),
        sensing_circles: true,
    })
    .expect("render --sensing-circles");
    let frames = decode_gif(&dir.join("plots/animation.gif"));
    assert_eq!((frames[0].width, frames[0].height), circles.size_px());

    // Without a sensing radius in the scenario the flag changes nothing.
    let untimed = scratch("sensing-none");
    write_tiny_run(&untimed);
    let data = RunData::load(&untimed).expect("load");
    let m = metrics::per_step(&data);
    assert!(!Animation::with_sensing_circles(&data, &m, true).draws_sensing_circles());
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&untimed);
}
