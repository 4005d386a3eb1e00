//! The messages of the controller protocol, as JSON objects. Points are `[x, y]` pairs,
//! in metres; angles are radians, anticlockwise from the x axis; time is counted in steps.

use serde::{Deserialize, Serialize};

use crate::control::formation::Slot;
use crate::control::turn::Velocities;
use crate::control::turn::{MateView, TurnRequest};
use crate::control::vocabulary::{AgentSpec, Body, Kinematics, TurnMode};
use crate::geometry::{Disk, Field, Point, Polygon, Pose};

/// A point in metres, `[x, y]`.
pub type XY = [f64; 2];

fn xy(p: Point) -> XY {
    [p.x, p.y]
}

/// A disk: an obstacle, or another agent's body.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Circle {
    /// Its centre, metres.
    pub centre_m: XY,
    /// Its radius, metres.
    pub radius_m: f64,
}

impl Circle {
    fn of_disk(d: &Disk) -> Self {
        Self {
            centre_m: xy(d.centre),
            radius_m: d.radius_m,
        }
    }

    fn of_body(b: &Body) -> Self {
        Self {
            centre_m: xy(b.position),
            radius_m: b.radius_m,
        }
    }
}

/// A pose: where, and which way it faces.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PoseInfo {
    /// Where, metres.
    pub position_m: XY,
    /// Which way it faces, radians.
    pub heading_rad: f64,
}

impl From<Pose> for PoseInfo {
    fn from(p: Pose) -> Self {
        Self {
            position_m: [p.x_m, p.y_m],
            heading_rad: p.heading_rad,
        }
    }
}

/// How an agent can move.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "model", rename_all = "snake_case")]
pub enum KinematicsInfo {
    /// In any direction at once: a move is any polyline.
    Holonomic,
    /// A differential drive: it turns in place (at most `max_turn_rad` a step) and drives
    /// along its heading; turning and driving share a step's time.
    Unicycle {
        /// The largest heading change in one step, radians.
        max_turn_rad: f64,
        /// Whether it may drive backwards.
        reverse: bool,
    },
    /// A car: its path bends no tighter than `turning_radius_m`; it cannot turn in place.
    Car {
        /// The smallest radius its path may bend with, metres.
        turning_radius_m: f64,
        /// Whether it may drive backwards.
        reverse: bool,
    },
}

impl From<Kinematics> for KinematicsInfo {
    fn from(k: Kinematics) -> Self {
        match k {
            Kinematics::Holonomic => Self::Holonomic,
            Kinematics::Unicycle {
                max_turn_rad,
                reverse,
            } => Self::Unicycle {
                max_turn_rad,
                reverse,
            },
            Kinematics::Car {
                turning_radius_m,
                reverse,
            } => Self::Car {
                turning_radius_m,
                reverse,
            },
        }
    }
}

/// One agent of the formation as every agent knows it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AgentInfo {
    /// Its slot: the distance from the formation centre, metres.
    pub slot_r_m: f64,
    /// Its slot: the angle from the formation's heading, radians.
    pub slot_theta_rad: f64,
    /// The radius of its body, metres.
    pub radius_m: f64,
    /// Its top speed, the longest move it makes in one step, metres; `null`: no limit.
    pub max_step_m: Option<f64>,
    /// How far it senses, metres; `null`: it knows every body.
    pub sensing_radius_m: Option<f64>,
    /// How it can move.
    pub kinematics: KinematicsInfo,
}

impl From<&AgentSpec> for AgentInfo {
    fn from(a: &AgentSpec) -> Self {
        let Slot { r_m, theta_rad } = a.slot;
        Self {
            slot_r_m: r_m,
            slot_theta_rad: theta_rad,
            radius_m: a.radius_m,
            max_step_m: a.max_step_m,
            sensing_radius_m: a.sensing_radius_m,
            kinematics: a.kinematics.into(),
        }
    }
}

/// The mission as an agent sees it: what stays the same for the whole run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MissionInfo {
    /// The field's width and height, metres: it spans `[0, width] x [0, height]`.
    pub field_m: XY,
    /// Every static disk obstacle, with its true radius.
    pub obstacles: Vec<Circle>,
    /// Every static polygon obstacle (a map's blocked cells among them), each a list of
    /// corners, anticlockwise.
    pub polygons_m: Vec<Vec<XY>>,
    /// Every agent, in agent order (this one at [`Hello::agent`]).
    pub agents: Vec<AgentInfo>,
    /// How the agents take their turns: `sequential`, `parallel` or `simultaneous`.
    pub turns: String,
}

impl MissionInfo {
    /// The mission of the agents `agents` taking turns as `turns` says, on `field` among
    /// the static `obstacles` (true radii, known or to be found) and `polygons`.
    pub fn new(
        field: Field,
        obstacles: &[Disk],
        polygons: &[Polygon],
        agents: &[AgentSpec],
        turns: TurnMode,
    ) -> Self {
        Self {
            field_m: [field.width_m, field.height_m],
            obstacles: obstacles.iter().map(Circle::of_disk).collect(),
            polygons_m: polygons.iter().map(corners).collect(),
            agents: agents.iter().map(AgentInfo::from).collect(),
            turns: turns.name().to_string(),
        }
    }
}

fn corners(p: &Polygon) -> Vec<XY> {
    p.vertices().iter().copied().map(xy).collect()
}

/// The first line an agent sends its program.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Hello {
    /// The protocol version the agent speaks ([`super::PROTOCOL_VERSION`]).
    pub protocol: u32,
    /// This agent's index into [`MissionInfo::agents`].
    pub agent: usize,
    /// The mission.
    pub mission: MissionInfo,
}

/// The program's answer to [`Hello`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Ready {
    /// The protocol version the program speaks: the agent's, or the agent stops it.
    pub protocol: u32,
    /// The controller's name, for the logs and the reports (at most 64 characters).
    #[serde(default)]
    pub name: Option<String>,
}

/// Another agent as this one knows it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MateInfo {
    /// Its index.
    pub index: usize,
    /// Where it stands, metres.
    pub position_m: XY,
    /// Whether it belongs to the formation (false: frozen, an obstacle).
    pub alive: bool,
}

/// One turn, as the agent's program sees it: the turn request.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Turn {
    /// The step (0 is the start).
    pub step: usize,
    /// The formation centre's pose this step.
    pub centre: PoseInfo,
    /// The centre's next poses along its plan, the pose of `step + 1` first (empty when
    /// the agent does not look ahead).
    pub ahead: Vec<PoseInfo>,
    /// Where this agent stands, metres.
    pub position_m: XY,
    /// Where this agent faces, radians, for a unicycle or a car; `null` for a holonomic
    /// agent.
    pub heading_rad: Option<f64>,
    /// The other agents' bodies, which stand still while this one moves (all of them:
    /// an agent with a sensing radius is to use only those within it).
    pub others: Vec<Circle>,
    /// The other agents by index, and whether they still belong to the formation (false:
    /// frozen where they stopped, an obstacle).
    pub mates: Vec<MateInfo>,
    /// The moving obstacles where they stand this step.
    pub moving: Vec<Circle>,
    /// When every agent moves at once: how the bodies moved over the last step; `null`
    /// otherwise.
    pub velocities: Option<VelocitiesInfo>,
}

/// How the bodies moved over the last step, metres a step.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VelocitiesInfo {
    /// This agent's.
    pub me_m_per_step: XY,
    /// Each other body's, in the order of [`Turn::others`].
    pub others_m_per_step: Vec<XY>,
}

impl From<&Velocities> for VelocitiesInfo {
    fn from(v: &Velocities) -> Self {
        Self {
            me_m_per_step: [v.me.x, v.me.y],
            others_m_per_step: v.others.iter().map(|d| [d.x, d.y]).collect(),
        }
    }
}

impl Turn {
    /// The turn of `request`, the moving obstacles standing at `moving`.
    pub fn of(request: &TurnRequest<'_>, moving: &[Disk]) -> Self {
        Self {
            step: request.step,
            centre: request.centre.into(),
            ahead: request.ahead.iter().copied().map(PoseInfo::from).collect(),
            position_m: xy(request.me),
            heading_rad: request.heading_rad,
            others: request.others.iter().map(Circle::of_body).collect(),
            mates: request.mates.iter().map(mate_info).collect(),
            moving: moving.iter().map(Circle::of_disk).collect(),
            velocities: request.velocities.map(VelocitiesInfo::from),
        }
    }
}

impl Turn {
    /// Where `agent`'s slot is this turn: the paper's ideal position, the slot turned by
    /// the centre's heading (`x + r cos(h + theta)`, `y + r sin(h + theta)`, as the Python
    /// SDK's `Turn.slot_position_m`).
    pub fn slot_position_m(&self, agent: &AgentInfo) -> XY {
        let [x, y] = self.centre.position_m;
        let centre = Pose::new(x, y, self.centre.heading_rad);
        xy(Slot::new(agent.slot_r_m, agent.slot_theta_rad).ideal_position(&centre))
    }
}

fn mate_info(m: &MateView) -> MateInfo {
    MateInfo {
        index: m.agent,
        position_m: xy(m.position),
        alive: m.alive,
    }
}

/// A line the agent sends its program.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Message {
    /// The first line: the protocol version and the mission.
    Hello(Hello),
    /// A turn: the program answers with a move or stays.
    Turn(Turn),
}

impl Message {
    /// The message as one line of JSON, its newline included.
    pub fn to_line(&self) -> String {
        super::json_line(self)
    }
}
