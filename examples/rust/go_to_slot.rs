//! The naive controller as a Rust program: every turn, straight towards the agent's slot,
//! as far as its top speed allows, whatever stands in the way. The harness checks every
//! move, so an unsafe one is refused and recorded and the agent stays. The same controller
//! as `examples/python/go_to_slot.py`, through the Rust side of the protocol.
//!
//! `cargo run -p formation-shared --example go_to_slot` (it then waits for the agent's
//! hello on its standard input).

use std::io::{BufReader, stdin, stdout};
use std::process::ExitCode;

use shared::control::protocol::{MissionInfo, MoveReply, ProgramController, Turn, serve};

/// Straight to the slot.
#[derive(Default)]
struct GoToSlot {
    /// This agent's index.
    agent: usize,
    /// The mission, once the hello came.
    mission: Option<MissionInfo>,
}

impl ProgramController for GoToSlot {
    fn name(&self) -> &str {
        "go-to-slot"
    }

    fn start(&mut self, agent: usize, mission: &MissionInfo) {
        self.agent = agent;
        self.mission = Some(mission.clone());
    }

    fn turn(&mut self, turn: &Turn) -> Option<MoveReply> {
        let me = self.mission.as_ref()?.agents.get(self.agent)?;
        let [x, y] = turn.position_m;
        let [gx, gy] = turn.slot_position_m(me);
        let (dx, dy) = (gx - x, gy - y);
        let distance = dx.hypot(dy);
        if distance == 0.0 {
            return None; // at the slot: stay
        }
        let end = match me.max_step_m {
            Some(top) if distance > top => [x + dx * top / distance, y + dy * top / distance],
            _ => [gx, gy],
        };
        Some(MoveReply {
            waypoints_m: vec![end],
            end_heading_rad: None,
        })
    }
}

fn main() -> ExitCode {
    match serve(
        &mut GoToSlot::default(),
        BufReader::new(stdin().lock()),
        stdout().lock(),
    ) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("go_to_slot: {e}");
            ExitCode::FAILURE
        }
    }
}
