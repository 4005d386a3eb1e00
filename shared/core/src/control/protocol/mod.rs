//! The controller protocol: how an agent talks to a controller that is a program of the
//! user's, in any language, over the program's standard input and output.
//!
//! One JSON object a line, UTF-8, each line at most [`MAX_LINE_BYTES`]; every object has
//! a `"type"`. The agent speaks first:
//!
//! 1. the agent sends [`Hello`] (the protocol version and the mission as the agent sees
//!    it); the program answers [`Ready`];
//! 2. at every turn the agent sends [`Turn`] (the turn request: the step, the centre and
//!    its poses ahead, where the agent stands and faces, what it knows of the others);
//!    the program answers with a move ([`Reply::Move`]: waypoints, from where the agent
//!    stands, and the heading it ends with where its model has one) or
//!    [`Reply::Stay`];
//! 3. when the run ends the agent closes the program's standard input.
//!
//! What a program answers is input from another process: [`read_reply`] reads one line
//! into a [`Reply`] with every number checked finite and every list bounded, and refuses
//! anything else with a [`ReplyError`] that names what was wrong. The move then goes
//! through the same checks as any controller's (the recorder's and the monitor's).
//!
//! `docs/controllers.md` is the reference a user writes a controller from; the Python
//! SDK (`shared/python`) and the Rust one ([`ProgramController`] and [`serve`]) speak
//! this protocol.

mod messages;
mod program;
mod reply;

pub use messages::{
    AgentInfo, Circle, Hello, KinematicsInfo, MateInfo, Message, MissionInfo, PoseInfo, Ready,
    Turn, VelocitiesInfo, XY,
};
pub use program::{ProgramController, ServeError, serve};
pub use reply::{MAX_NAME_CHARS, MoveReply, Reply, ReplyError, read_reply};

/// The version of the protocol the agent speaks: a program answers [`Ready`] with the
/// same number, or the agent stops it.
pub const PROTOCOL_VERSION: u32 = 1;

/// The longest line either side may send, in bytes, its newline included: a mission with
/// thousands of polygon corners fits, a flood does not.
pub const MAX_LINE_BYTES: usize = 4 << 20;

/// `value` as one line of JSON, its newline included. Serialising the protocol's plain
/// numbers, strings and lists cannot fail; a non-finite number would be written `null`.
fn json_line(value: &impl serde::Serialize) -> String {
    let mut line = serde_json::to_string(value).unwrap_or_else(|_| String::from("{}"));
    line.push('\n');
    line
}
