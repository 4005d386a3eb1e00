//! `coordinator render`: every file is written, decodes at its stated size, and agents are
//! drawn where they are. The run directories are small synthetic ones written here (plus
//! one real, in-process simulation of the paper's example).

use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

use coordinator::CliError;
use coordinator::cli::RenderArgs;
use coordinator::render::animation::Animation;
use coordinator::render::canvas::Figure;
use coordinator::render::field::FieldFigure;
use coordinator::render::formation::FormationFigure;
use coordinator::render::layout::MapLayout;
use coordinator::render::metrics;
use coordinator::render::series::SeriesFigure;
use coordinator::render::{RunData, render_run_dir};

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

/// A fresh, empty directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("render-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch dir");
    dir
}

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

/// An RGB image decoded from a PNG file.
struct Rgb {
    width: u32,
    height: u32,
    pixels: Vec<u8>,
}

impl Rgb {
    fn at(&self, (x, y): (i32, i32)) -> [u8; 3] {
        assert!(x >= 0 && y >= 0 && (x as u32) < self.width && (y as u32) < self.height);
        let i = (y as usize * self.width as usize + x as usize) * 3;
        [self.pixels[i], self.pixels[i + 1], self.pixels[i + 2]]
    }
}

fn decode_png(path: &Path) -> Rgb {
    let file = BufReader::new(File::open(path).expect("open png"));
    let mut reader = png::Decoder::new(file).read_info().expect("png header");
    let mut buf = vec![0; reader.output_buffer_size().expect("png buffer size")];
    let info = reader.next_frame(&mut buf).expect("png data");
    assert_eq!(info.color_type, png::ColorType::Rgb, "{}", path.display());
    assert_eq!(info.bit_depth, png::BitDepth::Eight, "{}", path.display());
    buf.truncate(info.buffer_size());
    Rgb {
        width: info.width,
        height: info.height,
        pixels: buf,
    }
}

/// Every frame of a GIF composed onto the canvas, as RGB images.
fn decode_gif(path: &Path) -> Vec<Rgb> {
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options
        .read_info(BufReader::new(File::open(path).expect("open gif")))
        .expect("gif header");
    let (w, h) = (usize::from(decoder.width()), usize::from(decoder.height()));
    let mut canvas = vec![0u8; w * h * 3];
    let mut frames = Vec::new();
    while let Some(frame) = decoder.read_next_frame().expect("gif frame") {
        let (fw, fh) = (usize::from(frame.width), usize::from(frame.height));
        for y in 0..fh {
            for x in 0..fw {
                let src = (y * fw + x) * 4;
                if frame.buffer[src + 3] == 0 {
                    continue; // transparent: the previous frame shows through
                }
                let dst = ((usize::from(frame.top) + y) * w + usize::from(frame.left) + x) * 3;
                canvas[dst..dst + 3].copy_from_slice(&frame.buffer[src..src + 3]);
            }
        }
        frames.push(Rgb {
            width: w as u32,
            height: h as u32,
            pixels: canvas.clone(),
        });
    }
    frames
}

fn assert_svg(path: &Path, (w, h): (u32, u32)) {
    let text = std::fs::read_to_string(path).expect("read svg");
    let doc = roxmltree::Document::parse(&text).expect("svg is XML");
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "svg", "{}", path.display());
    assert_eq!(root.attribute("width"), Some(w.to_string().as_str()));
    assert_eq!(root.attribute("height"), Some(h.to_string().as_str()));
}

/// Orange of the agents' safety circles, translucent over white.
fn is_agent(c: [u8; 3]) -> bool {
    let [r, g, b] = c.map(i32::from);
    r > 215 && (150..235).contains(&g) && b < 175 && r - b > 60
}

fn px(layout: &MapLayout, x: f64, y: f64) -> (i32, i32) {
    layout.to_px(x, y)
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

#[test]
fn a_bad_run_dir_is_a_usage_error_naming_the_file() {
    let dir = scratch("bad");
    write_tiny_run(&dir);
    std::fs::remove_file(dir.join("trajectory.csv")).expect("remove");
    let err = coordinator::render::execute(&RenderArgs {
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
    let msg = coordinator::render::execute(&RenderArgs {
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
    let err = coordinator::render::execute(&RenderArgs {
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
    let scenario = shared::scenario::Scenario::paper();
    let run = shared::simulate::simulate(&scenario).expect("simulate the paper example");
    let dir = scratch("paper");
    coordinator::output::write_run(
        &dir,
        &scenario,
        shared::scenario::PAPER_SCENARIO_NAME,
        &run,
        &shared::simulate::plan_centre_path(&scenario).expect("the paper's centre path"),
        &coordinator::output::Timing::default(),
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
    coordinator::render::execute(&RenderArgs {
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
    let scenario = shared::scenario::Scenario::parse(CHANGING, "changing.toml").expect("scenario");
    let first_plan = shared::simulate::plan_centre_path(&scenario).expect("first plan");
    let run = shared::simulate::simulate_along(&scenario, &first_plan).expect("simulate");
    let dir = scratch("changing");
    coordinator::output::write_run(
        &dir,
        &scenario,
        "changing.toml",
        &run,
        &first_plan,
        &coordinator::output::Timing::default(),
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
    let repo = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the repository holds the coordinator crate");
    let doc = std::fs::read_to_string(repo.join("docs").join("outputs.md")).expect("outputs.md");
    let scenario = shared::scenario::Scenario::parse(CHANGING, "changing.toml").expect("scenario");
    let first_plan = shared::simulate::plan_centre_path(&scenario).expect("first plan");
    let run = shared::simulate::simulate_along(&scenario, &first_plan).expect("simulate");
    let dir = scratch("doc");
    let written = coordinator::output::write_run(
        &dir,
        &scenario,
        "changing.toml",
        &run,
        &first_plan,
        &coordinator::output::Timing::default(),
    )
    .expect("write run");
    let names: Vec<String> = written
        .iter()
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    // The run folder's table lists the files in the order written, summary.json last.
    let mut listed = documented_names(&doc, "## `coordinator run`: the run folder");
    assert_eq!(listed.pop().as_deref(), Some("plots/"));
    assert_eq!(listed, names);

    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("summary.json")).expect("summary"))
            .expect("summary.json parses");
    let mut keys: Vec<String> = summary
        .as_object()
        .expect("an object")
        .keys()
        .cloned()
        .collect();
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
        let header: Vec<String> = reader
            .headers()
            .expect("header")
            .iter()
            .map(str::to_string)
            .collect();
        assert_eq!(
            documented_names(&doc, &format!("### `{file}`")),
            header,
            "{file}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
