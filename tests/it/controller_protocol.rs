//! The controller protocol between its two ends: the lines the agent side writes
//! (`shared::control::protocol`) fit the documented schema
//! (`docs/controller-protocol.schema.json`); a real Python process running the SDK
//! (`shared/python/formation_controller.py`) and the naive example
//! (`examples/python/go_to_slot.py`) answers them; its answers fit the schema and read
//! back as moves to the agent's slot, as the formation itself places it. The SDK's own
//! unit tests run here too, in python3 (standard library only).

use std::io::{BufRead, BufReader, Write};
use std::process::{Command, Stdio};

use serde_json::Value;
use shared::control::protocol::{Message, MissionInfo, PROTOCOL_VERSION, Reply, Turn, read_reply};
use shared::control::turn::{MateView, TurnRequest, Velocities};
use shared::control::vocabulary::Body;
use shared::geometry::{Point, Pose, Vector};
use shared::run::simulate::plan_centre_path;
use shared::world::scenario::Scenario;

use crate::support::{json_schema, repo_root};

fn python() -> Command {
    let mut c = Command::new("python3");
    c.env("PYTHONPATH", repo_root().join("shared/python"))
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .env_remove("PYTHONHOME")
        .current_dir(repo_root());
    c
}

fn schema() -> Value {
    let text = std::fs::read_to_string(repo_root().join("docs/controller-protocol.schema.json"))
        .expect("the protocol's schema");
    serde_json::from_str(&text).expect("the schema is JSON")
}

/// Check one protocol line against the schema of its `type`.
fn fits_schema(schema: &Value, line: &str) {
    let value: Value = serde_json::from_str(line).unwrap_or_else(|e| panic!("{line}: {e}"));
    let kind = value["type"]
        .as_str()
        .unwrap_or_else(|| panic!("no type: {line}"));
    let message = &schema["messages"][kind];
    assert!(message.is_object(), "the schema has no message {kind}");
    json_schema::check(message, &value).unwrap_or_else(|e| panic!("{e}\nin {line}"));
}

fn hello(scenario: &Scenario, agent: usize) -> Message {
    Message::Hello(shared::control::protocol::Hello {
        protocol: PROTOCOL_VERSION,
        agent,
        mission: MissionInfo::new(
            scenario.field,
            &scenario.static_obstacles(),
            &scenario.polygons,
            &scenario.agents,
            scenario.turns,
        ),
    })
}

/// Agent `agent`'s turns along the first `steps` steps of the paper's centre path, each
/// agent standing in its slot of the step before; and where its slot is at each step.
fn paper_turns(agent: usize, steps: usize) -> (Scenario, Vec<Message>, Vec<Point>) {
    turns_of(Scenario::paper(), agent, steps)
}

/// Agent `agent`'s turns along the first `steps` steps of `scenario`'s centre path, as
/// [`paper_turns`].
fn turns_of(
    scenario: Scenario,
    agent: usize,
    steps: usize,
) -> (Scenario, Vec<Message>, Vec<Point>) {
    let path = plan_centre_path(&scenario).expect("the paper's centre path");
    let slot_at = |a: usize, step: usize| scenario.agents[a].slot.ideal_position(&path[step]);
    let mut turns = Vec::new();
    let mut slots = Vec::new();
    for step in 1..=steps {
        let others: Vec<Body> = (0..scenario.agents.len())
            .filter(|&a| a != agent)
            .map(|a| Body {
                position: slot_at(a, step - 1),
                radius_m: scenario.agents[a].radius_m,
            })
            .collect();
        let mates: Vec<MateView> = (0..scenario.agents.len())
            .filter(|&a| a != agent)
            .map(|a| MateView {
                agent: a,
                position: slot_at(a, step - 1),
                alive: true,
            })
            .collect();
        let ahead: Vec<Pose> = path[step + 1..].iter().take(3).copied().collect();
        let request = TurnRequest::new(path[step], slot_at(agent, step - 1), &others)
            .at_step(step)
            .looking_ahead(&ahead)
            .with_mates(&mates);
        turns.push(Message::Turn(Turn::of(&request, &[])));
        slots.push(slot_at(agent, step));
    }
    (scenario, turns, slots)
}

#[test]
fn the_agent_sides_lines_fit_the_schema() {
    let schema = schema();
    let (scenario, turns, _) = paper_turns(0, 3);
    fits_schema(&schema, &hello(&scenario, 0).to_line());
    for turn in &turns {
        fits_schema(&schema, &turn.to_line());
    }
    // A unicycle's mission, and a turn with a heading and velocities.
    let unicycle = Scenario::load(&repo_root().join("scenarios/paper-unicycle.toml"))
        .expect("paper-unicycle.toml");
    fits_schema(&schema, &hello(&unicycle, 2).to_line());
    let others = [Body {
        position: Point::new(3.0, 1.0),
        radius_m: 0.4,
    }];
    let velocities = Velocities {
        me: Vector::new(0.1, 0.0),
        others: vec![Vector::new(0.0, -0.2)],
    };
    let request = TurnRequest::new(Pose::new(1.0, 1.0, 0.3), Point::new(2.0, 2.0), &others)
        .at_step(7)
        .facing(1.2)
        .with_velocities(Some(&velocities));
    let moving = [shared::geometry::Disk::new(5.0, 5.0, 0.5)];
    fits_schema(
        &schema,
        &Message::Turn(Turn::of(&request, &moving)).to_line(),
    );
}

/// Start `program`, send it `hello` and `turns` one line at a time, and return its
/// answers (the ready first); it must leave cleanly when its input closes.
fn converse(mut program: Command, hello: &Message, turns: &[Message]) -> Vec<String> {
    let mut child = program
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .expect("start the controller program");
    let mut stdin = child.stdin.take().expect("stdin");
    let mut stdout = BufReader::new(child.stdout.take().expect("stdout"));
    let mut answers = Vec::new();
    for message in std::iter::once(hello).chain(turns) {
        stdin
            .write_all(message.to_line().as_bytes())
            .expect("write a line");
        let mut line = String::new();
        stdout
            .read_line(&mut line)
            .expect("a line from the program");
        assert!(line.ends_with('\n'), "an unfinished line: {line:?}");
        answers.push(line);
    }
    drop(stdin); // the run ends: the program leaves
    let status = child.wait().expect("the program ends");
    assert!(status.success(), "the program exited with {status}");
    answers
}

fn python_go_to_slot() -> Command {
    let mut c = python();
    c.arg("examples/python/go_to_slot.py");
    c
}

fn rust_go_to_slot() -> Command {
    let program = crate::support::target_dir().join("examples/go_to_slot");
    assert!(
        program.is_file(),
        "{} is missing: `cargo test --workspace` builds the examples",
        program.display()
    );
    Command::new(program)
}

#[test]
fn a_python_controller_answers_the_agent_with_moves_to_its_slot() {
    let schema = schema();
    let agent = 2;
    let (scenario, turns, slots) = paper_turns(agent, 5);
    let answers = converse(python_go_to_slot(), &hello(&scenario, agent), &turns);
    for line in &answers {
        fits_schema(&schema, line);
    }
    match read_reply(answers[0].trim_end().as_bytes()) {
        Ok(Reply::Ready(r)) => {
            assert_eq!(r.protocol, PROTOCOL_VERSION);
            assert_eq!(r.name.as_deref(), Some("go-to-slot"));
        }
        other => panic!("expected ready, got {other:?}"),
    }
    // No top speed in the paper: the naive move ends at the slot.
    assert!(scenario.agents[agent].max_step_m.is_none());
    for (line, slot) in answers[1..].iter().zip(&slots) {
        match read_reply(line.trim_end().as_bytes()) {
            Ok(Reply::Move(m)) => {
                let [x, y] = *m.waypoints_m.last().expect("a waypoint");
                assert!(
                    (x - slot.x).abs() < 1e-9 && (y - slot.y).abs() < 1e-9,
                    "ended at ({x}, {y}), the slot is {slot:?}"
                );
            }
            other => panic!("expected a move, got {other:?}"),
        }
    }
}

#[test]
fn the_rust_and_the_python_sdks_answer_alike() {
    // A top speed short of the slot, so that both cut the move.
    let mut scenario = Scenario::paper();
    for a in &mut scenario.agents {
        a.max_step_m = Some(0.05);
    }
    let agent = 4;
    let (scenario, turns, _) = turns_of(scenario, agent, 6);
    let hello = hello(&scenario, agent);
    let python = converse(python_go_to_slot(), &hello, &turns);
    let rust = converse(rust_go_to_slot(), &hello, &turns);
    assert_eq!(python.len(), rust.len());
    let replies = |lines: &[String]| -> Vec<Reply> {
        lines
            .iter()
            .map(|l| read_reply(l.trim_end().as_bytes()).unwrap_or_else(|e| panic!("{l}: {e}")))
            .collect()
    };
    let (python, rust) = (replies(&python), replies(&rust));
    assert_eq!(python[0], rust[0], "the ready lines differ");
    for (step, (p, r)) in python[1..].iter().zip(&rust[1..]).enumerate() {
        let (Reply::Move(p), Reply::Move(r)) = (p, r) else {
            panic!("turn {step}: {p:?} and {r:?}");
        };
        assert_eq!(p.waypoints_m.len(), r.waypoints_m.len());
        for (a, b) in p.waypoints_m.iter().zip(&r.waypoints_m) {
            assert!(
                (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12,
                "turn {step}: python {a:?}, rust {b:?}"
            );
        }
        let [x, y] = *r.waypoints_m.last().expect("a waypoint");
        let Message::Turn(turn) = &turns[step] else {
            unreachable!("turns_of makes turns")
        };
        let [x0, y0] = turn.position_m;
        assert!(
            ((x - x0).hypot(y - y0) - 0.05).abs() < 1e-9,
            "turn {step}: a move of {} m, not the top speed",
            (x - x0).hypot(y - y0)
        );
    }
}

#[test]
fn the_python_sdk_passes_its_own_tests() {
    let out = python()
        .args([
            "-m",
            "unittest",
            "discover",
            "-s",
            "shared/python",
            "-p",
            "test_*.py",
        ])
        .output()
        .expect("start python3");
    assert!(
        out.status.success(),
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let report = String::from_utf8_lossy(&out.stderr);
    assert!(report.contains("OK"), "{report}");
    assert!(!report.contains("Ran 0 tests"), "{report}");
}
