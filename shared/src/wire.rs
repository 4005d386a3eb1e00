//! Messages between the coordinator and the agents over iceoryx2 shared memory.
//!
//! Every type is `#[repr(C)]`, [`ZeroCopySend`] with an explicit type name, of fixed
//! capacity and without pointers: a sample is written in place in shared memory and read
//! in place by the other process, with no serialization.
//!
//! Every agent has a channel of its own: five services below the run's prefix (set in the
//! iceoryx2 config), named by [`AgentServiceNames`] after the agent and the generation of
//! its process (0 for the first, one more for every replacement):
//! - `mission`: publish-subscribe, history 1: the static scenario;
//! - `world`: publish-subscribe, coordinator to agent: the world of its turn, with the
//!   turn's token;
//! - `turn`: event, coordinator to agent: "your turn" / "quit" / "echo";
//! - `state`: publish-subscribe, agent to coordinator: its handshake and its moves;
//! - `done`: event, agent to coordinator: "my state is published".
//!
//! One channel per agent, not services shared by all: every service then has exactly one
//! port on each side, so an agent that opens extra ports can starve no one but itself, a
//! turn reads one connection instead of N, and a replacement process never shares a
//! service with its predecessor.
//!
//! Everything an agent writes is untrusted: the coordinator reads a state sample only
//! through [`AgentState::read_checked`], which copies it out of shared memory and checks
//! every field before anything uses it.

use iceoryx2::prelude::*;
use iceoryx2_bb_container::vector::{StaticVec, Vector};

use crate::formation::Slot;
use crate::geometry::{Disk, Field, Point, Pose};
use crate::scenario::Scenario;
use crate::vocabulary::{
    AgentSpec, Body, CbfSettings, MAX_AGENTS, MAX_OBSTACLES, MAX_WAYPOINTS, MoveStatus,
    PlannerKind, PlannerSpec,
};

/// The names of the five services of one agent's channel (see the module documentation).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct AgentServiceNames {
    /// Coordinator to agent, history 1: the [`Mission`].
    pub mission: String,
    /// Coordinator to agent: the [`World`] of each turn.
    pub world: String,
    /// Event, coordinator to agent: [`EVENT_TURN`], [`EVENT_QUIT`], [`EVENT_ECHO`].
    pub turn: String,
    /// Agent to coordinator: its [`AgentState`] (handshake, moves, echoes).
    pub state: String,
    /// Event, agent to coordinator: a state is published.
    pub done: String,
}

impl AgentServiceNames {
    /// The services of agent `agent` served by its `generation`-th process (0 for the
    /// first; a replacement gets the next generation and so services of its own).
    pub fn new(agent: usize, generation: u32) -> Self {
        let base = format!("formation/agent/{agent}/{generation}");
        Self {
            mission: format!("{base}/mission"),
            world: format!("{base}/world"),
            turn: format!("{base}/turn"),
            state: format!("{base}/state"),
            done: format!("{base}/done"),
        }
    }
}

/// Event id on a turn service: take your turn (the world is published).
pub const EVENT_TURN: usize = 1;
/// Event id on a turn service: leave cleanly now.
pub const EVENT_QUIT: usize = 2;
/// Event id on a turn service: answer at once with an empty [`StateKind::Echo`] state,
/// without reading the world or planning (`coordinator bench`: the wake-up alone).
pub const EVENT_ECHO: usize = 3;

/// A point on the wire.
#[repr(C)]
#[derive(Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault)]
#[type_name("formation::WirePoint")]
pub struct WirePoint {
    /// x, in metres.
    pub x_m: f64,
    /// y, in metres.
    pub y_m: f64,
}

impl From<Point> for WirePoint {
    fn from(p: Point) -> Self {
        Self { x_m: p.x, y_m: p.y }
    }
}

impl From<WirePoint> for Point {
    fn from(p: WirePoint) -> Self {
        Point::new(p.x_m, p.y_m)
    }
}

/// A pose on the wire.
#[repr(C)]
#[derive(Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault)]
#[type_name("formation::WirePose")]
pub struct WirePose {
    /// x, in metres.
    pub x_m: f64,
    /// y, in metres.
    pub y_m: f64,
    /// Heading, in radians.
    pub heading_rad: f64,
}

impl From<Pose> for WirePose {
    fn from(p: Pose) -> Self {
        Self {
            x_m: p.x_m,
            y_m: p.y_m,
            heading_rad: p.heading_rad,
        }
    }
}

impl From<WirePose> for Pose {
    fn from(p: WirePose) -> Self {
        Pose::new(p.x_m, p.y_m, p.heading_rad)
    }
}

/// An obstacle on the wire (true radius).
#[repr(C)]
#[derive(Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault)]
#[type_name("formation::WireDisk")]
pub struct WireDisk {
    /// Centre x, in metres.
    pub x_m: f64,
    /// Centre y, in metres.
    pub y_m: f64,
    /// Radius, in metres.
    pub radius_m: f64,
}

/// An agent's formation slot and radius on the wire.
#[repr(C)]
#[derive(Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault)]
#[type_name("formation::WireAgent")]
pub struct WireAgent {
    /// Slot distance from the centre, in metres.
    pub slot_r_m: f64,
    /// Slot angle from the heading, in radians.
    pub slot_theta_rad: f64,
    /// Body radius, in metres.
    pub radius_m: f64,
}

/// The static scenario, published once (history 1) for every agent.
#[repr(C)]
#[derive(Debug, Default, ZeroCopySend, PlacementDefault)]
#[type_name("formation::Mission")]
pub struct Mission {
    /// Field width, in metres.
    pub field_width_m: f64,
    /// Field height, in metres.
    pub field_height_m: f64,
    /// Every obstacle, true radii.
    pub obstacles: StaticVec<WireDisk, MAX_OBSTACLES>,
    /// Every agent, in agent order.
    pub agents: StaticVec<WireAgent, MAX_AGENTS>,
    /// The controller: a [`PlannerKind`] code.
    pub planner: u32,
    /// Padding, always 0.
    pub reserved: u32,
    /// Barrier-function settings (see [`CbfSettings`]).
    pub cbf_gamma_per_s: f64,
    /// Duration of one barrier-function move, in seconds.
    pub cbf_dt_s: f64,
    /// Gain of the nominal control, in 1/s.
    pub cbf_gain_per_s: f64,
    /// Speed limit, in m/s.
    pub cbf_max_speed_m_per_s: f64,
    /// Sensing radius, in metres.
    pub cbf_sensing_radius_m: f64,
    /// LogSumExp sharpness, in 1/m.
    pub lse_sharpness_per_m: f64,
}

/// Why a scenario does not fit the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum CapacityError {
    /// More obstacles than [`MAX_OBSTACLES`].
    #[error("{0} obstacles exceed the wire capacity of {MAX_OBSTACLES}")]
    Obstacles(usize),
    /// More agents than [`MAX_AGENTS`].
    #[error("{0} agents exceed the wire capacity of {MAX_AGENTS}")]
    Agents(usize),
    /// More waypoints than [`MAX_WAYPOINTS`].
    #[error("{0} waypoints exceed the wire capacity of {MAX_WAYPOINTS}")]
    Waypoints(usize),
}

impl Mission {
    /// Fill the mission in place from `scenario`.
    pub fn fill(&mut self, scenario: &Scenario) -> Result<(), CapacityError> {
        let (field, obstacles, agents) = (&scenario.field, &scenario.obstacles, &scenario.agents);
        let p = &scenario.planner;
        self.planner = p.kind.code();
        self.cbf_gamma_per_s = p.cbf.gamma_per_s;
        self.cbf_dt_s = p.cbf.dt_s;
        self.cbf_gain_per_s = p.cbf.gain_per_s;
        self.cbf_max_speed_m_per_s = p.cbf.max_speed_m_per_s;
        self.cbf_sensing_radius_m = p.cbf.sensing_radius_m;
        self.lse_sharpness_per_m = p.lse_sharpness_per_m;
        self.field_width_m = field.width_m;
        self.field_height_m = field.height_m;
        self.obstacles.clear();
        self.agents.clear();
        for o in obstacles {
            self.obstacles
                .push(WireDisk {
                    x_m: o.center.x,
                    y_m: o.center.y,
                    radius_m: o.radius_m,
                })
                .map_err(|_| CapacityError::Obstacles(obstacles.len()))?;
        }
        for a in agents {
            self.agents
                .push(WireAgent {
                    slot_r_m: a.slot.r_m,
                    slot_theta_rad: a.slot.theta_rad,
                    radius_m: a.radius_m,
                })
                .map_err(|_| CapacityError::Agents(agents.len()))?;
        }
        Ok(())
    }

    /// The controller and its settings (`None` for an unknown planner code).
    pub fn planner(&self) -> Option<PlannerSpec> {
        Some(PlannerSpec {
            kind: PlannerKind::from_code(self.planner)?,
            cbf: CbfSettings {
                gamma_per_s: self.cbf_gamma_per_s,
                dt_s: self.cbf_dt_s,
                gain_per_s: self.cbf_gain_per_s,
                max_speed_m_per_s: self.cbf_max_speed_m_per_s,
                sensing_radius_m: self.cbf_sensing_radius_m,
            },
            lse_sharpness_per_m: self.lse_sharpness_per_m,
        })
    }

    /// The field.
    pub fn field(&self) -> Field {
        Field::new(self.field_width_m, self.field_height_m)
    }

    /// The obstacles, true radii.
    pub fn obstacles(&self) -> Vec<Disk> {
        self.obstacles
            .iter()
            .map(|o| Disk::new(o.x_m, o.y_m, o.radius_m))
            .collect()
    }

    /// The agents, in agent order.
    pub fn agents(&self) -> Vec<AgentSpec> {
        self.agents
            .iter()
            .map(|a| AgentSpec {
                slot: Slot::new(a.slot_r_m, a.slot_theta_rad),
                radius_m: a.radius_m,
            })
            .collect()
    }
}

/// One agent's body in the world message.
#[repr(C)]
#[derive(Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault)]
#[type_name("formation::WireBody")]
pub struct WireBody {
    /// Where the agent stands.
    pub position: WirePoint,
    /// 1 while the agent belongs to the formation, 0 once it is frozen as an obstacle.
    pub alive: u32,
    /// Padding, always 0.
    pub reserved: u32,
}

/// The world before a turn: published by the coordinator, read by the agent whose turn it
/// is.
#[repr(C)]
#[derive(Debug, Default, ZeroCopySend, PlacementDefault)]
#[type_name("formation::World")]
pub struct World {
    /// Increases with every world published; a state answering it echoes it.
    pub seq: u64,
    /// The step (centre pose index).
    pub step: u64,
    /// The turn's token: drawn for this turn alone from a generator seeded by the OS
    /// random source, so no process can answer a turn before it is granted; the move
    /// answering it carries it back.
    pub token: u64,
    /// Whose turn it is.
    pub turn_agent: u32,
    /// Padding, always 0.
    pub reserved: u32,
    /// The formation centre at this step.
    pub centre: WirePose,
    /// Every agent, in agent order, dead ones included (they are obstacles).
    pub bodies: StaticVec<WireBody, MAX_AGENTS>,
}

impl World {
    /// Replace the bodies with `bodies` (positions) and their `alive` flags.
    pub fn set_bodies(&mut self, bodies: &[Body], alive: &[bool]) -> Result<(), CapacityError> {
        self.bodies.clear();
        for (b, &a) in bodies.iter().zip(alive) {
            self.bodies
                .push(WireBody {
                    position: b.position.into(),
                    alive: u32::from(a),
                    reserved: 0,
                })
                .map_err(|_| CapacityError::Agents(bodies.len()))?;
        }
        Ok(())
    }
}

/// What an agent's state message is.
#[repr(u32)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StateKind {
    /// The agent has opened every service and waits for turns.
    Ready = 0,
    /// The agent's move for the turn with sequence number `seq`.
    Move = 1,
    /// The answer to an [`EVENT_ECHO`]: timestamps only.
    Echo = 2,
}

/// An agent's message to the coordinator: its ready handshake or its move.
///
/// Written by another process: read it only through [`AgentState::read_checked`].
#[repr(C)]
#[derive(Debug, Default, ZeroCopySend, PlacementDefault)]
#[type_name("formation::AgentState")]
pub struct AgentState {
    /// The world's `seq` this answers (0 for the handshake).
    pub seq: u64,
    /// The step this answers.
    pub step: u64,
    /// The world's `token` this answers (0 for the handshake and echoes).
    pub token: u64,
    /// Time the agent spent computing the move, in nanoseconds.
    pub compute_ns: u64,
    /// When the agent woke for this turn, on the machine's monotonic clock
    /// ([`monotonic_ns`]); 0 if unknown.
    pub woke_ns: u64,
    /// When the agent sent this state, on the machine's monotonic clock; 0 if unknown.
    pub sent_ns: u64,
    /// The agent's index.
    pub agent: u32,
    /// A [`StateKind`] code.
    pub kind: u32,
    /// A [`MoveStatus`] code.
    pub status: u32,
    /// The agent's process id.
    pub pid: u32,
    /// The ideal slot at this step.
    pub slot: WirePoint,
    /// The point the agent moves to.
    pub best: WirePoint,
    /// The polyline it follows, from its position to `best`.
    pub waypoints: StaticVec<WirePoint, MAX_WAYPOINTS>,
}

/// A state message copied out of shared memory and checked field by field
/// ([`AgentState::read_checked`]): plain values no other process can change any more.
#[derive(Clone, Debug, PartialEq)]
pub struct StateMsg {
    /// What the message is.
    pub kind: StateKind,
    /// The world's `seq` it answers.
    pub seq: u64,
    /// The step it answers.
    pub step: u64,
    /// The world's token it answers.
    pub token: u64,
    /// The agent's compute time for the move, in nanoseconds, as the agent reports it
    /// (bounded by [`MAX_COMPUTE_NS`]; the coordinator also bounds it by the turn).
    pub compute_ns: u64,
    /// When the agent woke, on the monotonic clock (0: unknown).
    pub woke_ns: u64,
    /// When the agent sent it, on the monotonic clock (0: unknown).
    pub sent_ns: u64,
    /// The process id the agent claims.
    pub pid: u32,
    /// The move status code, as sent (checked against [`MoveStatus`] by the monitor's
    /// caller, which refuses unknown codes as unsafe moves).
    pub status: u32,
    /// The ideal slot the agent computed.
    pub slot: Point,
    /// The point it moves to.
    pub best: Point,
    /// Its path, from where it stands to `best`.
    pub waypoints: Vec<Point>,
}

impl StateMsg {
    /// The move status, if the code is known.
    pub fn move_status(&self) -> Option<MoveStatus> {
        u8::try_from(self.status)
            .ok()
            .and_then(MoveStatus::from_code)
    }
}

/// Largest compute time an agent may report for one move: an hour, in nanoseconds.
/// Anything above is a corrupt value, not a slow planner.
pub const MAX_COMPUTE_NS: u64 = 3_600 * 1_000_000_000;

/// Why a state sample was refused before anything used it.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum MalformedState {
    /// The message kind code is none of [`StateKind`]'s.
    #[error("unknown message kind code {0}")]
    Kind(u32),
    /// The sample names another agent than the one whose channel carried it.
    #[error("the message claims to be from agent {claimed}, on agent {channel}'s channel")]
    Agent {
        /// The agent index written in the sample.
        claimed: u32,
        /// The agent whose channel it came on.
        channel: usize,
    },
    /// The waypoint count is beyond the message's capacity.
    #[error("waypoint count {0} exceeds the capacity of {MAX_WAYPOINTS}")]
    WaypointCount(u64),
    /// The reported compute time is beyond [`MAX_COMPUTE_NS`].
    #[error("compute time {0} ns is beyond any turn")]
    ComputeTime(u64),
    /// The agent's two timestamps are out of order.
    #[error("woke at {woke_ns} ns but sent at {sent_ns} ns")]
    Timestamps {
        /// When it claims it woke.
        woke_ns: u64,
        /// When it claims it sent.
        sent_ns: u64,
    },
    /// The sample could not be taken from the channel at all (the publisher's memory
    /// could not be mapped, for instance).
    #[error("the sample could not be received: {0}")]
    Unreadable(String),
    /// A handshake or echo carries a move (waypoints).
    #[error("a {kind:?} message carries {count} waypoints")]
    UnexpectedWaypoints {
        /// The message kind.
        kind: StateKind,
        /// How many waypoints it carries.
        count: usize,
    },
}

impl AgentState {
    /// Copy this sample out of shared memory and check it, as the message of agent
    /// `channel_agent` (the agent whose channel carried it). Every field is read once;
    /// the waypoint count is checked against the capacity before any waypoint is read,
    /// so no value written by another process can make the reader panic or read out of
    /// bounds. The values themselves (finite, in the field, safe) are the safety
    /// monitor's to judge.
    pub fn read_checked(&self, channel_agent: usize) -> Result<StateMsg, MalformedState> {
        let kind = match self.kind {
            0 => StateKind::Ready,
            1 => StateKind::Move,
            2 => StateKind::Echo,
            other => return Err(MalformedState::Kind(other)),
        };
        let claimed = self.agent;
        if usize::try_from(claimed).ok() != Some(channel_agent) {
            return Err(MalformedState::Agent {
                claimed,
                channel: channel_agent,
            });
        }
        let count = self.raw_waypoint_count();
        let len = match usize::try_from(count) {
            Ok(len) if len <= MAX_WAYPOINTS => len,
            _ => return Err(MalformedState::WaypointCount(count)),
        };
        if kind != StateKind::Move && len > 0 {
            return Err(MalformedState::UnexpectedWaypoints { kind, count: len });
        }
        let compute_ns = self.compute_ns;
        if compute_ns > MAX_COMPUTE_NS {
            return Err(MalformedState::ComputeTime(compute_ns));
        }
        let (woke_ns, sent_ns) = (self.woke_ns, self.sent_ns);
        if woke_ns != 0 && sent_ns != 0 && woke_ns > sent_ns {
            return Err(MalformedState::Timestamps { woke_ns, sent_ns });
        }
        let base = std::ptr::addr_of!(self.waypoints).cast::<WirePoint>();
        let waypoints = (0..len)
            .map(|i| {
                // SAFETY: `StaticVec` is `repr(C)` with its element array first (checked
                // by a test below), so `base` points at element 0 of an array of
                // MAX_WAYPOINTS points, and `i < len <= MAX_WAYPOINTS`. Every bit
                // pattern is a valid pair of f64. A volatile read: another process may
                // write this memory while it is read.
                Point::from(unsafe { std::ptr::read_volatile(base.add(i)) })
            })
            .collect();
        Ok(StateMsg {
            kind,
            seq: self.seq,
            step: self.step,
            token: self.token,
            compute_ns,
            woke_ns,
            sent_ns,
            pid: self.pid,
            status: self.status,
            slot: self.slot.into(),
            best: self.best.into(),
            waypoints,
        })
    }

    /// The waypoint count field as written, which may exceed the capacity.
    fn raw_waypoint_count(&self) -> u64 {
        // `len()` only reads the field; it is the slicing methods that trust it.
        self.waypoints.len() as u64
    }

    /// Replace the waypoints.
    pub fn set_waypoints(&mut self, points: &[Point]) -> Result<(), CapacityError> {
        self.waypoints.clear();
        for &p in points {
            self.waypoints
                .push(p.into())
                .map_err(|_| CapacityError::Waypoints(points.len()))?;
        }
        Ok(())
    }
}

/// Loan a sample from `publisher` and initialise its payload in place to its default
/// value: a large message (the 400 kB mission) is never built on the stack and copied.
/// The only in-place initialisation of the protocol; every sender loans through it.
pub fn loan_default<T>(
    publisher: &iceoryx2::port::publisher::Publisher<ipc::Service, T, ()>,
) -> Result<iceoryx2::sample_mut::SampleMut<ipc::Service, T, ()>, iceoryx2::port::LoanError>
where
    T: std::fmt::Debug + ZeroCopySend + PlacementDefault,
{
    let mut sample = publisher.loan_uninit()?;
    // SAFETY: the pointer is the sample's own payload slot, valid, aligned and exclusive;
    // `placement_default` writes every field of a `T` there.
    unsafe { T::placement_default(sample.payload_mut().as_mut_ptr()) };
    // SAFETY: the payload was initialised just above.
    Ok(unsafe { sample.assume_init() })
}

/// Which side of the protocol a process is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Role {
    /// The coordinator: creates the services and cleans up after dead nodes.
    Coordinator,
    /// An agent: opens the services and never cleans up after other nodes (cleanup racing
    /// a starting node can abort the cleaner, iceoryx2 issue 1880).
    Agent,
}

/// Why a run prefix cannot name iceoryx2 resources.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PrefixError {
    /// The prefix is not a valid file name, or longer than [`MAX_PREFIX_LEN`].
    #[error("run prefix {0:?} must be 1 to 24 characters of [A-Za-z0-9_-]")]
    Invalid(String),
    /// The OS random source failed to give the random part of a new prefix.
    #[error("no random run prefix: the OS random source failed: {0}")]
    Random(String),
}

/// Longest run prefix accepted: socket paths built from it must fit in 108 bytes.
pub const MAX_PREFIX_LEN: usize = 24;

/// The iceoryx2 configuration of one run: every resource name starts with `prefix`, so
/// runs never see each other, and listing or cleaning nodes only touches this run.
pub fn ipc_config(prefix: &str, role: Role) -> Result<Config, PrefixError> {
    if !is_valid_prefix(prefix) {
        return Err(PrefixError::Invalid(prefix.to_string()));
    }
    let mut config = Config::default();
    config.global.prefix =
        FileName::new(prefix.as_bytes()).map_err(|_| PrefixError::Invalid(prefix.to_string()))?;
    if let Some(root) = run_root(prefix) {
        let root = format!("{}/", root.display());
        let root =
            Path::new(root.as_bytes()).map_err(|_| PrefixError::Invalid(prefix.to_string()))?;
        config.global.set_root_path(&root);
    }
    if role == Role::Agent {
        config.global.node.cleanup_dead_nodes_on_creation = false;
        config.global.node.cleanup_dead_nodes_on_destruction = false;
        config.global.service.cleanup_dead_nodes_on_open = false;
    }
    Ok(config)
}

/// The folder where run `prefix` keeps iceoryx2's files (node and service descriptions,
/// event sockets): `/dev/shm/<prefix>iox2`, on the RAM file system, or `None` (iceoryx2's
/// default, `/tmp/iceoryx2`) where there is no `/dev/shm`. iceoryx2 syncs every such file
/// to disk as it creates it, about 5 N of them per run: on a disk that makes start-up
/// several times slower (6 s instead of 1.8 s for 200 agents here). A folder per run
/// also means that removing the run removes the folder ([`remove_run_root`]).
/// An invalid prefix ([`ipc_config`] refuses it) has no folder.
pub fn run_root(prefix: &str) -> Option<std::path::PathBuf> {
    let shm = std::path::Path::new("/dev/shm");
    (is_valid_prefix(prefix) && shm.is_dir()).then(|| shm.join(format!("{prefix}iox2")))
}

/// A prefix is 1 to [`MAX_PREFIX_LEN`] ASCII letters, digits, `_` or `-` (a file name
/// that cannot leave its folder).
fn is_valid_prefix(prefix: &str) -> bool {
    !prefix.is_empty()
        && prefix.len() <= MAX_PREFIX_LEN
        && prefix
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-')
}

/// Remove run `prefix`'s folder ([`run_root`]) once nothing of the run is left in it but
/// empty folders; a no-op where there is no such folder.
pub fn remove_run_root(prefix: &str) -> std::io::Result<()> {
    match run_root(prefix) {
        Some(root) if root.exists() => std::fs::remove_dir_all(root),
        _ => Ok(()),
    }
}

/// Environment variable the coordinator sets on every agent process: the run's prefix.
/// Whatever an agent starts inherits it (unless it clears its environment), so at the end
/// of the run the coordinator finds, kills and reaps every process the run left behind.
pub const RUN_ENV: &str = "FORMATION_RUN";

/// A run prefix: `fc<coordinator pid>x<random hex>_`, the one place that writes and reads
/// the format. The pid tells a crashed run's leftovers (its coordinator is gone) from a
/// live run's; the random part, from the OS random source, makes the names of a run's
/// files unpredictable, so no other local user can make them first (squat the run folder
/// or the management segment before the coordinator does).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct RunPrefix {
    text: String,
    pid: u32,
}

impl RunPrefix {
    /// Start of every run prefix.
    pub const STEM: &'static str = "fc";
    /// Most hex digits in the random part (64 bits); fewer when the pid is long, so that
    /// the prefix fits in [`MAX_PREFIX_LEN`]: at least 10 (40 bits) for any `u32` pid,
    /// 13 or more for the usual pids of up to 7 digits.
    const MAX_RANDOM_DIGITS: usize = 16;
    /// Most digits of a `u32` pid.
    const MAX_PID_DIGITS: usize = 10;

    /// A new prefix for a run coordinated by this process.
    pub fn new_random() -> Result<Self, PrefixError> {
        use rand::TryRngCore;
        let mut bytes = [0u8; 8];
        rand::rngs::OsRng
            .try_fill_bytes(&mut bytes)
            .map_err(|e| PrefixError::Random(e.to_string()))?;
        Ok(Self::with_random(
            std::process::id(),
            u64::from_le_bytes(bytes),
        ))
    }

    fn with_random(pid: u32, random: u64) -> Self {
        let head = format!("{}{pid}x", Self::STEM);
        let digits = (MAX_PREFIX_LEN - 1 - head.len()).min(Self::MAX_RANDOM_DIGITS);
        let hex = format!("{random:016x}");
        Self {
            text: format!("{head}{}_", &hex[..digits]),
            pid,
        }
    }

    /// The run prefix that `name` (a file or folder of a run, `<prefix><anything>`) starts
    /// with, if any. Also reads the prefixes of earlier versions, whose random part was a
    /// decimal counter, so their leftovers are still cleaned.
    pub fn parse(name: &str) -> Option<Self> {
        let rest = name.strip_prefix(Self::STEM)?;
        let pid_digits = rest.bytes().take_while(u8::is_ascii_digit).count();
        let (pid, rest) = rest.split_at(pid_digits);
        let rest = rest.strip_prefix('x')?;
        let hex_digits = rest
            .bytes()
            .take_while(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(b))
            .count();
        if !(1..=Self::MAX_PID_DIGITS).contains(&pid_digits)
            || !(1..=Self::MAX_RANDOM_DIGITS).contains(&hex_digits)
            || rest.as_bytes().get(hex_digits) != Some(&b'_')
        {
            return None;
        }
        let pid = pid.parse::<u32>().ok().filter(|&p| p > 0)?;
        // Every byte counted is ASCII, so `len` is a character boundary.
        let len = Self::STEM.len() + pid_digits + 1 + hex_digits + 1;
        (len <= MAX_PREFIX_LEN).then(|| Self {
            text: name[..len].to_string(),
            pid,
        })
    }

    /// The process id of the run's coordinator.
    pub fn pid(&self) -> u32 {
        self.pid
    }

    /// The prefix itself.
    pub fn as_str(&self) -> &str {
        &self.text
    }
}

impl std::fmt::Display for RunPrefix {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.text)
    }
}

/// Why a run's folder or one of its files in /dev/shm cannot be trusted.
#[derive(Debug, thiserror::Error)]
pub enum RunFilesError {
    /// The run folder does not exist.
    #[error("{} does not exist (no such run; the coordinator starts agents)", .0.display())]
    Missing(std::path::PathBuf),
    /// The coordinator found the folder of its new run already there.
    #[error(
        "{} already exists: this run did not make it, so it will not use it (nor delete it)",
        .0.display()
    )]
    Exists(std::path::PathBuf),
    /// Not a directory, or a file that is not a regular file (e.g. a symbolic link).
    #[error("{} is not what the run made (a symbolic link?): refusing it", .0.display())]
    WrongType(std::path::PathBuf),
    /// Owned by another user than this process's effective user.
    #[error(
        "{} belongs to user {owner}, not to this process's user {euid}: refusing it",
        path.display()
    )]
    Owner {
        /// The folder or file.
        path: std::path::PathBuf,
        /// Its owner.
        owner: u32,
        /// This process's effective user id.
        euid: u32,
    },
    /// A run folder whose mode is not exactly 0700.
    #[error(
        "{} has mode {mode:04o}, not 0700 (other users could reach the run's files): refusing it",
        path.display()
    )]
    Mode {
        /// The folder.
        path: std::path::PathBuf,
        /// Its permission bits.
        mode: u32,
    },
    /// The file system refused an operation.
    #[error("{}: {source}", path.display())]
    Io {
        /// The folder or file.
        path: std::path::PathBuf,
        /// What failed.
        source: std::io::Error,
    },
}

/// This process's effective user id.
pub fn effective_uid() -> u32 {
    // SAFETY: geteuid has no preconditions and cannot fail.
    unsafe { libc::geteuid() }
}

/// Check that `path` is a run folder no other user can reach: a directory, not a symbolic
/// link (lstat), owned by this process's effective user, mode exactly 0700. Every agent
/// checks it before it opens anything. Checking the path and then using it is safe here:
/// /dev/shm is sticky, so only the folder's owner (this user) can rename or remove it.
pub fn check_run_root(path: &std::path::Path) -> Result<(), RunFilesError> {
    use std::os::unix::fs::MetadataExt;
    let meta = match std::fs::symlink_metadata(path) {
        Ok(meta) => meta,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(RunFilesError::Missing(path.to_path_buf()));
        }
        Err(source) => {
            return Err(RunFilesError::Io {
                path: path.to_path_buf(),
                source,
            });
        }
    };
    if !meta.file_type().is_dir() {
        return Err(RunFilesError::WrongType(path.to_path_buf()));
    }
    let euid = effective_uid();
    if meta.uid() != euid {
        return Err(RunFilesError::Owner {
            path: path.to_path_buf(),
            owner: meta.uid(),
            euid,
        });
    }
    let mode = meta.mode() & 0o7777;
    if mode != 0o700 {
        return Err(RunFilesError::Mode {
            path: path.to_path_buf(),
            mode,
        });
    }
    Ok(())
}

/// The run folder ([`run_root`]) as the coordinator makes it, before anything else of the
/// run (before its iceoryx2 node): exclusively, so a folder that is already there (made by
/// someone else, or a leftover) is refused and left alone; mode 0700; then checked
/// ([`check_run_root`]). Dropping it removes the folder and everything in it (removing
/// it earlier with [`remove_run_root`] is fine). Where there is no /dev/shm there is no
/// folder (iceoryx2's default root is used, shared with other users).
#[derive(Debug)]
pub struct RunRoot {
    path: Option<std::path::PathBuf>,
}

impl RunRoot {
    /// Make run `prefix`'s folder.
    pub fn create(prefix: &str) -> Result<Self, RunFilesError> {
        use std::os::unix::fs::{DirBuilderExt, PermissionsExt};
        let Some(path) = run_root(prefix) else {
            return Ok(Self { path: None });
        };
        if let Err(source) = std::fs::DirBuilder::new().mode(0o700).create(&path) {
            return Err(if source.kind() == std::io::ErrorKind::AlreadyExists {
                RunFilesError::Exists(path)
            } else {
                RunFilesError::Io { path, source }
            });
        }
        // Ours from here on: dropping `root` removes it, whatever fails below.
        let root = Self {
            path: Some(path.clone()),
        };
        // The umask may have taken bits off 0700.
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o700)).map_err(
            |source| RunFilesError::Io {
                path: path.clone(),
                source,
            },
        )?;
        check_run_root(&path)?;
        Ok(root)
    }

    /// The folder (`None` where there is no /dev/shm).
    pub fn path(&self) -> Option<&std::path::Path> {
        self.path.as_deref()
    }
}

impl Drop for RunRoot {
    fn drop(&mut self) {
        if let Some(path) = &self.path
            && let Err(e) = std::fs::remove_dir_all(path)
            && e.kind() != std::io::ErrorKind::NotFound
        {
            tracing::warn!("removing the run folder {}: {e}", path.display());
        }
    }
}

/// The files of run `prefix` directly in /dev/shm (not in its folder), with their
/// metadata (lstat): iceoryx2's shared-memory segments, which `shm_open` puts there
/// whatever the configured root.
pub fn run_files_in_shm(prefix: &str) -> Vec<(std::path::PathBuf, std::fs::Metadata)> {
    let root = run_root(prefix);
    let Ok(entries) = std::fs::read_dir("/dev/shm") else {
        return Vec::new();
    };
    entries
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with(prefix))
        .filter(|e| Some(e.path()) != root)
        .filter_map(|e| Some((e.path(), std::fs::symlink_metadata(e.path()).ok()?)))
        .collect()
}

/// Take group and other permissions off every file of run `prefix` in /dev/shm
/// ([`run_files_in_shm`]); returns how many were changed. iceoryx2 0.10 makes the
/// management segment (`<prefix>node.<version>.global_mgmt`) there readable and writable
/// by everyone (`enable_global_access`, 0666); its other segments are 0600 already. Call
/// it right after the coordinator's node is made (that makes the segment), before any
/// agent starts. A file of the run that is not this user's, or not a regular file, is an
/// error: someone else made it.
///
/// Limit: between iceoryx2's `fchmod(0666)` and this call, a process of another user that
/// watches /dev/shm could open the segment and keep it open. It could then change the
/// counter iceoryx2 numbers the run's nodes with (so that an agent's node might fail to
/// start: a denial of service), but not read or write the run's data: the services'
/// segments are 0600 from their creation.
pub fn make_run_files_private(prefix: &str) -> Result<usize, RunFilesError> {
    use std::os::unix::fs::{MetadataExt, PermissionsExt};
    let euid = effective_uid();
    let mut changed = 0;
    for (path, meta) in run_files_in_shm(prefix) {
        if meta.uid() != euid {
            return Err(RunFilesError::Owner {
                path,
                owner: meta.uid(),
                euid,
            });
        }
        if !meta.file_type().is_file() {
            return Err(RunFilesError::WrongType(path));
        }
        let mode = meta.mode() & 0o7777;
        if mode & 0o077 != 0 {
            // By path, not by descriptor: the file is this user's in the sticky /dev/shm,
            // so no one else can swap it meanwhile.
            std::fs::set_permissions(&path, std::fs::Permissions::from_mode(mode & 0o700))
                .map_err(|source| RunFilesError::Io {
                    path: path.clone(),
                    source,
                })?;
            changed += 1;
        }
    }
    Ok(changed)
}

/// Benchmark floor (`coordinator bench`): coordinator to ping-pong process, one small
/// sample per round trip.
pub const BENCH_PING_SERVICE: &str = "bench/ping";
/// Benchmark floor: ping-pong process to coordinator (the ready handshake has `seq` 0).
pub const BENCH_PONG_SERVICE: &str = "bench/pong";
/// Benchmark floor: event "a ping is published" (or [`EVENT_QUIT`]).
pub const BENCH_PING_EVENT: &str = "bench/ping-event";
/// Benchmark floor: event "the pong is published".
pub const BENCH_PONG_EVENT: &str = "bench/pong-event";
/// Event id on [`BENCH_PING_EVENT`]: answer framed requests on the Unix socket now,
/// until the coordinator sends the frame header [`BENCH_SOCKET_DONE`].
pub const BENCH_EVENT_SOCKET: usize = 3;
/// Request length in a socket frame header meaning "back to the iceoryx2 ping-pong".
pub const BENCH_SOCKET_DONE: u32 = u32::MAX;

/// The small sample of the benchmark floor's ping-pong, each way.
#[repr(C)]
#[derive(Debug, Default, Clone, Copy, PartialEq, ZeroCopySend, PlacementDefault)]
#[type_name("formation::BenchPing")]
pub struct BenchPing {
    /// Round trip number (0: the ping-pong process's ready handshake).
    pub seq: u64,
    /// Filler, so the sample is as small as a turn's header.
    pub payload: [u64; 3],
}

/// The machine's monotonic clock (`CLOCK_MONOTONIC`, the clock of `std::time::Instant`
/// on Linux) in nanoseconds: the same in every process, so the coordinator can place an
/// agent's timestamps on its own time line. 0 if the clock cannot be read.
pub fn monotonic_ns() -> u64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid, writable timespec; the call only writes it.
    if unsafe { libc::clock_gettime(libc::CLOCK_MONOTONIC, &mut t) } != 0 {
        return 0;
    }
    let (Ok(s), Ok(ns)) = (u64::try_from(t.tv_sec), u64::try_from(t.tv_nsec)) else {
        return 0;
    };
    s.saturating_mul(1_000_000_000).saturating_add(ns)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prefixes_that_could_escape_or_overflow_are_refused() {
        assert!(ipc_config("fc123_4_", Role::Coordinator).is_ok());
        for bad in [
            "",
            "a/b",
            "../x",
            "with space",
            &"x".repeat(MAX_PREFIX_LEN + 1),
        ] {
            assert!(ipc_config(bad, Role::Agent).is_err(), "{bad:?}");
            assert_eq!(run_root(bad), None, "{bad:?}");
            // Nothing outside /dev/shm can be removed through a prefix.
            assert!(remove_run_root(bad).is_ok());
        }
        if let Some(root) = run_root("fc123_4_") {
            assert_eq!(root, std::path::Path::new("/dev/shm/fc123_4_iox2"));
        }
    }

    #[test]
    fn two_run_prefixes_differ_in_their_random_part_and_parse_back_to_the_pid() {
        let a = RunPrefix::new_random().expect("OS random source");
        let b = RunPrefix::new_random().expect("OS random source");
        let head = format!("fc{}x", std::process::id());
        let random_part = |p: &RunPrefix| {
            let s = p.as_str();
            s[head.len()..s.len() - 1].to_string()
        };
        for p in [&a, &b] {
            assert!(p.as_str().starts_with(&head), "{p}");
            assert!(p.as_str().ends_with('_'), "{p}");
            assert!(p.as_str().len() <= MAX_PREFIX_LEN, "{p}");
            assert!(ipc_config(p.as_str(), Role::Coordinator).is_ok(), "{p}");
            assert_eq!(p.pid(), std::process::id());
            assert_eq!(RunPrefix::parse(p.as_str()).as_ref(), Some(p));
            let file = format!("{p}node.0_10_0.global_mgmt");
            assert_eq!(RunPrefix::parse(&file).as_ref(), Some(p), "{file}");
            // At least 10 hex digits (40 bits), 13 for the usual pids of up to 7 digits.
            assert!(random_part(p).len() >= 10, "{p}");
        }
        assert_ne!(random_part(&a), random_part(&b));
        // The longest pid still leaves 10 random digits within the limit.
        let long = RunPrefix::with_random(u32::MAX, 0x0123_4567_89ab_cdef);
        assert_eq!(long.as_str(), "fc4294967295x0123456789_");
        assert_eq!(RunPrefix::parse(long.as_str()), Some(long));
        // A prefix of an earlier version (a decimal counter) is still recognised.
        let old = RunPrefix::parse("fc123x4_iox2").expect("old format");
        assert_eq!((old.as_str(), old.pid()), ("fc123x4_", 123));
        for bad in [
            "",
            "fc",
            "fcx1_",
            "fc12x_",
            "fc12x12",
            "fc0x1_",
            "fc12xg_",
            "fc12X1_",
            "fc12x0123456789abcdef0_",
            "fc12345678901x1_",
            "xfc12x1_",
            "fc4294967296x1_",
        ] {
            assert_eq!(RunPrefix::parse(bad), None, "{bad:?}");
        }
    }

    /// A fresh prefix whose folder and files no run uses, for the file tests below.
    fn test_prefix() -> Option<RunPrefix> {
        let p = RunPrefix::new_random().expect("OS random source");
        run_root(p.as_str()).map(|_| p)
    }

    #[test]
    fn a_new_run_folder_is_private_and_goes_with_its_guard() {
        use std::os::unix::fs::MetadataExt;
        let Some(prefix) = test_prefix() else { return };
        let root = RunRoot::create(prefix.as_str()).expect("run folder");
        let path = root.path().expect("a folder on /dev/shm").to_path_buf();
        let meta = std::fs::symlink_metadata(&path).expect("made");
        assert!(meta.is_dir());
        assert_eq!(meta.mode() & 0o7777, 0o700);
        assert_eq!(meta.uid(), effective_uid());
        check_run_root(&path).expect("passes its own check");
        std::fs::write(path.join("inside"), b"x").expect("usable");
        drop(root);
        assert!(!path.exists(), "the guard removes the folder");
    }

    #[test]
    fn a_run_folder_that_already_exists_is_refused_and_left_alone() {
        use std::os::unix::fs::DirBuilderExt;
        let Some(prefix) = test_prefix() else { return };
        let path = run_root(prefix.as_str()).expect("a folder on /dev/shm");
        std::fs::DirBuilder::new()
            .mode(0o700)
            .create(&path)
            .expect("squat");
        std::fs::write(path.join("theirs"), b"x").expect("a file in it");
        let err = RunRoot::create(prefix.as_str()).expect_err("an existing folder");
        assert!(matches!(err, RunFilesError::Exists(_)), "{err:?}");
        assert!(
            err.to_string().contains(&path.display().to_string()),
            "{err}"
        );
        assert!(path.join("theirs").exists(), "nothing of it deleted");
        std::fs::remove_dir_all(&path).expect("clean up");
    }

    #[test]
    fn a_run_folder_others_could_reach_or_that_is_a_link_is_refused() {
        use std::os::unix::fs::{DirBuilderExt, PermissionsExt};
        let Some(prefix) = test_prefix() else { return };
        let path = run_root(prefix.as_str()).expect("a folder on /dev/shm");
        assert!(matches!(
            check_run_root(&path),
            Err(RunFilesError::Missing(_))
        ));
        std::fs::DirBuilder::new()
            .mode(0o700)
            .create(&path)
            .expect("folder");
        for mode in [0o777, 0o750, 0o701, 0o1700, 0o500] {
            std::fs::set_permissions(&path, std::fs::Permissions::from_mode(mode)).expect("chmod");
            let err = check_run_root(&path).expect_err("not 0700");
            assert!(
                matches!(err, RunFilesError::Mode { mode: m, .. } if m == mode),
                "{err:?}"
            );
            assert!(err.to_string().contains(&path.display().to_string()));
        }
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o700)).expect("chmod");
        check_run_root(&path).expect("0700");
        // Another user's folder, 0700 or not, is refused (only root can make one here).
        if effective_uid() == 0 {
            std::os::unix::fs::chown(&path, Some(65534), None).expect("chown");
            let err = check_run_root(&path).expect_err("not ours");
            assert!(
                matches!(
                    err,
                    RunFilesError::Owner {
                        owner: 65534,
                        euid: 0,
                        ..
                    }
                ),
                "{err:?}"
            );
            std::os::unix::fs::chown(&path, Some(0), None).expect("chown back");
        }
        // A link to a good folder is still refused: it is not the folder.
        let link = std::path::PathBuf::from(format!("{}link", path.display()));
        std::os::unix::fs::symlink(&path, &link).expect("symlink");
        assert!(matches!(
            check_run_root(&link),
            Err(RunFilesError::WrongType(_))
        ));
        std::fs::remove_file(&link).expect("clean up");
        std::fs::remove_dir_all(&path).expect("clean up");
    }

    #[test]
    fn the_run_files_in_dev_shm_are_made_private_and_foreign_ones_refused() {
        use std::os::unix::fs::{MetadataExt, PermissionsExt};
        let Some(prefix) = test_prefix() else { return };
        let mgmt = std::path::PathBuf::from(format!("/dev/shm/{prefix}node.global_mgmt"));
        let data = std::path::PathBuf::from(format!("/dev/shm/{prefix}data"));
        for (file, mode) in [(&mgmt, 0o666), (&data, 0o600)] {
            std::fs::write(file, b"x").expect("file");
            std::fs::set_permissions(file, std::fs::Permissions::from_mode(mode)).expect("chmod");
        }
        assert_eq!(run_files_in_shm(prefix.as_str()).len(), 2);
        assert_eq!(make_run_files_private(prefix.as_str()).expect("private"), 1);
        for file in [&mgmt, &data] {
            let mode = std::fs::metadata(file).expect("file").mode();
            assert_eq!(mode & 0o777, 0o600, "{}", file.display());
        }
        // A symbolic link among them is not followed but refused.
        let link = std::path::PathBuf::from(format!("/dev/shm/{prefix}link"));
        std::os::unix::fs::symlink(&data, &link).expect("symlink");
        assert!(matches!(
            make_run_files_private(prefix.as_str()),
            Err(RunFilesError::WrongType(_))
        ));
        for file in [&mgmt, &data, &link] {
            std::fs::remove_file(file).expect("clean up");
        }
    }

    #[test]
    fn a_mission_round_trips_the_scenario_exactly() {
        let s = crate::scenario::Scenario::paper();
        let mut m = Mission::default();
        m.fill(&s).unwrap();
        assert_eq!(m.planner(), Some(s.planner));
        assert_eq!(m.field(), s.field);
        assert_eq!(m.obstacles(), s.obstacles);
        assert_eq!(m.agents(), s.agents);
    }

    /// Write the waypoint count field raw, as a hostile process can.
    fn write_raw_count(st: &mut AgentState, count: u64) {
        let vec = std::ptr::addr_of_mut!(st.waypoints).cast::<u8>();
        let len_offset = std::mem::size_of::<[WirePoint; MAX_WAYPOINTS]>();
        // SAFETY: `StaticVec` is `repr(C)` { data, len: u64 }: the count lies right after
        // the array, inside the struct.
        unsafe { std::ptr::write_unaligned(vec.add(len_offset).cast::<u64>(), count) };
    }

    fn a_move(agent: u32, points: &[Point]) -> AgentState {
        let mut st = AgentState {
            kind: StateKind::Move as u32,
            agent,
            seq: 7,
            token: 99,
            ..AgentState::default()
        };
        st.set_waypoints(points).unwrap();
        st
    }

    #[test]
    fn waypoints_beyond_capacity_are_an_error_not_a_truncation() {
        let mut st = AgentState::default();
        let many = vec![Point::new(1.0, 2.0); MAX_WAYPOINTS + 1];
        assert_eq!(
            st.set_waypoints(&many),
            Err(CapacityError::Waypoints(MAX_WAYPOINTS + 1))
        );
        st.set_waypoints(&many[..3]).unwrap();
        st.kind = StateKind::Move as u32;
        assert_eq!(st.read_checked(0).unwrap().waypoints, many[..3].to_vec());
    }

    #[test]
    fn a_checked_read_copies_every_field() {
        let points = [Point::new(1.0, 2.0), Point::new(3.5, -4.25)];
        let mut st = a_move(3, &points);
        st.step = 5;
        st.compute_ns = 1234;
        st.woke_ns = 10;
        st.sent_ns = 20;
        st.pid = 42;
        st.status = MoveStatus::AtSlot as u32;
        st.best = points[1].into();
        let m = st.read_checked(3).unwrap();
        assert_eq!(
            m,
            StateMsg {
                kind: StateKind::Move,
                seq: 7,
                step: 5,
                token: 99,
                compute_ns: 1234,
                woke_ns: 10,
                sent_ns: 20,
                pid: 42,
                status: MoveStatus::AtSlot as u32,
                slot: Point::new(0.0, 0.0),
                best: points[1],
                waypoints: points.to_vec(),
            }
        );
        assert_eq!(m.move_status(), Some(MoveStatus::AtSlot));
    }

    #[test]
    fn the_raw_count_writer_hits_the_count_field() {
        // The layout the checked read relies on: the count right after the array.
        let mut st = a_move(0, &[Point::new(1.0, 1.0); 5]);
        write_raw_count(&mut st, 2);
        assert_eq!(st.waypoints.len(), 2);
        assert_eq!(st.read_checked(0).unwrap().waypoints.len(), 2);
    }

    #[test]
    fn hostile_counts_kinds_and_agents_are_refused_not_panicked_on() {
        for count in [MAX_WAYPOINTS as u64 + 1, 1 << 40, u64::MAX] {
            let mut st = a_move(0, &[Point::new(1.0, 1.0)]);
            write_raw_count(&mut st, count);
            assert_eq!(
                st.read_checked(0),
                Err(MalformedState::WaypointCount(count))
            );
            // Leave a count the drop can walk.
            write_raw_count(&mut st, 0);
        }
        let mut st = a_move(0, &[]);
        st.kind = 7;
        assert_eq!(st.read_checked(0), Err(MalformedState::Kind(7)));
        let st = a_move(4, &[]);
        assert_eq!(
            st.read_checked(1),
            Err(MalformedState::Agent {
                claimed: 4,
                channel: 1
            })
        );
        let mut st = a_move(0, &[]);
        st.compute_ns = u64::MAX;
        assert_eq!(
            st.read_checked(0),
            Err(MalformedState::ComputeTime(u64::MAX))
        );
        let mut st = a_move(0, &[]);
        (st.woke_ns, st.sent_ns) = (20, 10);
        assert!(matches!(
            st.read_checked(0),
            Err(MalformedState::Timestamps { .. })
        ));
        let mut st = a_move(0, &[Point::new(0.0, 0.0)]);
        st.kind = StateKind::Ready as u32;
        assert!(matches!(
            st.read_checked(0),
            Err(MalformedState::UnexpectedWaypoints { .. })
        ));
    }

    #[test]
    fn every_agent_generation_has_services_of_its_own() {
        let a = AgentServiceNames::new(3, 0);
        let b = AgentServiceNames::new(3, 1);
        let c = AgentServiceNames::new(4, 0);
        let all = |n: &AgentServiceNames| {
            [
                n.mission.clone(),
                n.world.clone(),
                n.turn.clone(),
                n.state.clone(),
                n.done.clone(),
            ]
        };
        let mut names: Vec<String> = [all(&a), all(&b), all(&c)].concat();
        let count = names.len();
        names.sort();
        names.dedup();
        assert_eq!(names.len(), count);
    }

    #[test]
    fn monotonic_ns_is_the_clock_of_instant() {
        let a = monotonic_ns();
        let t = std::time::Instant::now();
        std::thread::sleep(std::time::Duration::from_millis(5));
        let elapsed_ns = t.elapsed().as_nanos() as u64;
        let b = monotonic_ns();
        assert!(a > 0);
        // b - a covers the sleep that `elapsed` measured, and little more.
        assert!(b - a >= elapsed_ns, "{} < {elapsed_ns}", b - a);
        assert!(b - a < elapsed_ns + 50_000_000, "{} vs {elapsed_ns}", b - a);
    }
}
