//! The program's side of the protocol, in Rust: a controller is a type with one method to
//! write ([`ProgramController::turn`]), and [`serve`] speaks the protocol for it over the
//! program's standard input and output.
//!
//! ```
//! use shared::control::protocol::{MoveReply, ProgramController, Turn, serve};
//!
//! /// Straight to the slot, whatever stands in the way (the harness checks every move).
//! struct GoToSlot {
//!     agent: usize,
//!     mission: Option<shared::control::protocol::MissionInfo>,
//! }
//!
//! impl ProgramController for GoToSlot {
//!     fn name(&self) -> &str {
//!         "go-to-slot"
//!     }
//!     fn start(&mut self, agent: usize, mission: &shared::control::protocol::MissionInfo) {
//!         (self.agent, self.mission) = (agent, Some(mission.clone()));
//!     }
//!     fn turn(&mut self, turn: &Turn) -> Option<MoveReply> {
//!         let me = &self.mission.as_ref()?.agents[self.agent];
//!         Some(MoveReply { waypoints_m: vec![turn.slot_position_m(me)], end_heading_rad: None })
//!     }
//! }
//!
//! // What the agent would send, and what the program answers.
//! let hello = r#"{"type": "hello", "protocol": 1, "agent": 0, "mission": {"field_m": [10, 10],
//!   "obstacles": [], "polygons_m": [], "turns": "sequential", "agents": [{"slot_r_m": 1,
//!   "slot_theta_rad": 0, "radius_m": 0.3, "max_step_m": null, "sensing_radius_m": null,
//!   "kinematics": {"model": "holonomic"}}]}}"#.replace('\n', " ");
//! let turn = r#"{"type": "turn", "step": 1, "centre": {"position_m": [2, 2], "heading_rad": 0},
//!   "ahead": [], "position_m": [0, 0], "heading_rad": null, "others": [], "mates": [],
//!   "moving": [], "velocities": null}"#.replace('\n', " ");
//! let input = format!("{hello}\n{turn}\n");
//! let mut output = Vec::new();
//! serve(&mut GoToSlot { agent: 0, mission: None }, input.as_bytes(), &mut output).unwrap();
//! let output = String::from_utf8(output).unwrap();
//! let lines: Vec<&str> = output.lines().collect();
//! assert_eq!(lines[0], r#"{"type":"ready","protocol":1,"name":"go-to-slot"}"#);
//! assert_eq!(lines[1], r#"{"type":"move","waypoints_m":[[3.0,2.0]]}"#);
//! ```

use std::io::{BufRead, Read, Write};

use super::messages::{Message, MissionInfo, Ready, Turn};
use super::reply::{MoveReply, Reply};
use super::{MAX_LINE_BYTES, PROTOCOL_VERSION};

/// A controller written as a program in Rust: the contract of the Python SDK's
/// `Controller`, as a trait.
pub trait ProgramController {
    /// The name the reports give the controller (at most 64 printable characters).
    fn name(&self) -> &str;

    /// Called once, before the first turn, with this agent's index and the mission.
    fn start(&mut self, agent: usize, mission: &MissionInfo) {
        let _ = (agent, mission);
    }

    /// The move for `turn`; `None` stays where the agent stands.
    fn turn(&mut self, turn: &Turn) -> Option<MoveReply>;
}

/// Why [`serve`] stopped before the agent closed the input.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// Reading from the agent failed.
    #[error("reading from the agent: {0}")]
    Read(std::io::Error),
    /// Writing to the agent failed (it is gone).
    #[error("writing to the agent: {0}")]
    Write(std::io::Error),
    /// A line from the agent over [`MAX_LINE_BYTES`].
    #[error("a line of more than {MAX_LINE_BYTES} bytes from the agent")]
    TooLong,
    /// A line that is no message of the protocol.
    #[error("not a message of the protocol: {reason}")]
    Malformed {
        /// What the JSON reader found wrong.
        reason: String,
    },
    /// The agent speaks another version of the protocol.
    #[error("the agent speaks protocol {agent}, this program {PROTOCOL_VERSION}")]
    Version {
        /// The agent's version.
        agent: u32,
    },
    /// A turn before the hello, or a second hello.
    #[error("the hello must come first, and once")]
    OutOfOrder,
}

/// Answer the agent on `input` and `output` (the program's standard input and output)
/// until it closes the input: the hello with ready, each turn with `controller`'s move.
pub fn serve<C: ProgramController + ?Sized>(
    controller: &mut C,
    mut input: impl BufRead,
    mut output: impl Write,
) -> Result<(), ServeError> {
    let mut started = false;
    let mut line = Vec::new();
    loop {
        line.clear();
        let read = (&mut input)
            .take(MAX_LINE_BYTES as u64 + 1)
            .read_until(b'\n', &mut line)
            .map_err(ServeError::Read)?;
        if read == 0 {
            return Ok(());
        }
        if line.len() > MAX_LINE_BYTES {
            return Err(ServeError::TooLong);
        }
        if line.iter().all(u8::is_ascii_whitespace) {
            continue;
        }
        let message: Message =
            serde_json::from_slice(&line).map_err(|e| ServeError::Malformed {
                reason: e.to_string(),
            })?;
        let reply = match (message, started) {
            (Message::Hello(hello), false) => {
                if hello.protocol != PROTOCOL_VERSION {
                    return Err(ServeError::Version {
                        agent: hello.protocol,
                    });
                }
                controller.start(hello.agent, &hello.mission);
                started = true;
                Reply::Ready(Ready {
                    protocol: PROTOCOL_VERSION,
                    name: Some(controller.name().chars().take(64).collect()),
                })
            }
            (Message::Turn(turn), true) => match controller.turn(&turn) {
                Some(m) => Reply::Move(m),
                None => Reply::Stay,
            },
            _ => return Err(ServeError::OutOfOrder),
        };
        output
            .write_all(reply.to_line().as_bytes())
            .and_then(|()| output.flush())
            .map_err(ServeError::Write)?;
    }
}
