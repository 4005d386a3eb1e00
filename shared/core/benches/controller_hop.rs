//! What a turn costs when the controller is a program (the controller protocol, JSON
//! lines over pipes), measured before the agent starts programs, to choose the encoding:
//!
//! - `encode_turn`: a turn of the paper (agent 2 of six, three poses ahead, about 1.2 KB)
//!   written as its line;
//! - `read_reply`: a move line read back and checked;
//! - `python_echo`: a round trip of that turn line through a python3 process that only
//!   echoes lines (the pipes and the interpreter's own loop: the floor of any Python
//!   controller);
//! - `python_go_to_slot`: the same turn through the naive controller of
//!   `examples/python/go_to_slot.py` with the SDK (JSON decoded into dataclasses, the
//!   move encoded): what a Python controller costs a turn beyond its own compute.
//!
//! `cargo bench -p formation-shared --features bench --bench controller_hop`; python3 on
//! the PATH (standard library only).

use std::hint::black_box;
use std::io::{BufRead, BufReader, Write};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, ChildStdout, Command, Stdio};

use criterion::{Criterion, criterion_group, criterion_main};
use shared::control::protocol::{Hello, Message, MissionInfo, PROTOCOL_VERSION, Turn, read_reply};
use shared::control::turn::TurnRequest;
use shared::control::vocabulary::Body;
use shared::geometry::Pose;
use shared::run::simulate::plan_centre_path;
use shared::world::scenario::Scenario;

fn repo_root() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

/// The paper's hello and a turn of agent 2 at step 10, every other agent in its slot.
fn paper_lines() -> (String, String) {
    let scenario = Scenario::paper();
    let path = plan_centre_path(&scenario).expect("the paper's centre path");
    let agent = 2;
    let step = 10;
    let others: Vec<Body> = (0..scenario.agents.len())
        .filter(|&a| a != agent)
        .map(|a| Body {
            position: scenario.agents[a].slot.ideal_position(&path[step - 1]),
            radius_m: scenario.agents[a].radius_m,
        })
        .collect();
    let ahead: Vec<Pose> = path[step + 1..].iter().take(3).copied().collect();
    let me = scenario.agents[agent].slot.ideal_position(&path[step - 1]);
    let request = TurnRequest::new(path[step], me, &others)
        .at_step(step)
        .looking_ahead(&ahead);
    let hello = Message::Hello(Hello {
        protocol: PROTOCOL_VERSION,
        agent,
        mission: MissionInfo::new(
            scenario.field,
            &scenario.static_obstacles(),
            &scenario.polygons,
            &scenario.agents,
            scenario.turns,
        ),
    });
    let turn = Message::Turn(Turn::of(&request, &[]));
    (hello.to_line(), turn.to_line())
}

/// A program on pipes: one line in, one line out.
struct Program {
    child: Child,
    stdin: ChildStdin,
    stdout: BufReader<ChildStdout>,
    line: String,
}

impl Program {
    fn start(args: &[&str]) -> Self {
        let mut child = Command::new("python3")
            .args(args)
            .env("PYTHONPATH", repo_root().join("shared/python"))
            .env("PYTHONDONTWRITEBYTECODE", "1")
            .current_dir(repo_root())
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .spawn()
            .expect("start python3");
        let stdin = child.stdin.take().expect("stdin");
        let stdout = BufReader::new(child.stdout.take().expect("stdout"));
        Self {
            child,
            stdin,
            stdout,
            line: String::new(),
        }
    }

    fn round_trip(&mut self, line: &str) -> usize {
        self.stdin.write_all(line.as_bytes()).expect("write");
        self.stdin.flush().expect("flush");
        self.line.clear();
        self.stdout.read_line(&mut self.line).expect("read")
    }
}

impl Drop for Program {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

const ECHO: &str =
    "import sys\nfor line in sys.stdin:\n    sys.stdout.write(line)\n    sys.stdout.flush()\n";

fn controller_hop(c: &mut Criterion) {
    let (hello, turn) = paper_lines();
    let reply = r#"{"type": "move", "waypoints_m": [[3.25, 2.5]]}"#;
    let mut group = c.benchmark_group("controller_hop");
    group.bench_function("encode_turn", |b| {
        let message: Message = serde_json::from_str(&turn).expect("a turn");
        b.iter(|| black_box(&message).to_line())
    });
    group.bench_function("read_reply", |b| {
        b.iter(|| read_reply(black_box(reply.as_bytes())))
    });
    let mut echo = Program::start(&["-c", ECHO]);
    group.bench_function("python_echo", |b| b.iter(|| echo.round_trip(&turn)));
    drop(echo);
    let mut controller = Program::start(&["examples/python/go_to_slot.py"]);
    controller.round_trip(&hello);
    assert!(controller.line.contains("ready"), "{}", controller.line);
    group.bench_function("python_go_to_slot", |b| {
        b.iter(|| controller.round_trip(&turn))
    });
    group.finish();
}

criterion_group!(benches, controller_hop);
criterion_main!(benches);
