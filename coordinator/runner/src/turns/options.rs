//! How a run is carried out: the options, the wait mode of the hand-over, the time
//! limits.

use std::path::PathBuf;
use std::time::Duration;

use super::fault_injection::FaultInjection;
use shared::control::vocabulary::Kinematics;

use crate::network::NetworkOptions;

/// How often the coordinator checks an agent's process while it waits for its move.
pub(super) const LIVENESS_SLICE: Duration = Duration::from_millis(10);

/// How the coordinator waits for a move, and how an agent waits for its turn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum WaitMode {
    /// Sleep in a blocking event wait on both sides: no CPU spent waiting, two wake-ups
    /// per turn (the agent's and the coordinator's).
    Block,
    /// The coordinator spins (yielding) on the agent's state for up to a millisecond
    /// before sleeping, and the agent whose turn comes next is told so and polls its
    /// world meanwhile; its turn is then granted by publishing the world alone, without a
    /// ring: no wake-up and no event on the turn's path, at the price of up to two busy
    /// cores while turns go on. Agents not next in line still sleep.
    Spin,
    /// `Spin` on a machine with two cores or more, `Block` on one core (where a spinning
    /// process would take the core from the one it waits for).
    #[default]
    Auto,
}

impl WaitMode {
    /// Whether to spin on this machine.
    pub fn spins(&self) -> bool {
        match self {
            Self::Block => false,
            Self::Spin => true,
            Self::Auto => std::thread::available_parallelism().is_ok_and(|n| n.get() >= 2),
        }
    }
}

/// How the coordinator and the agents wake each other (a ring: "your turn", "my state is
/// published").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum WakeMode {
    /// The run's doorbells: a futex word per agent and one answer counter, in a file of
    /// the run's private folder; a ring is a store and at most one system call on each
    /// side (`wire::Doorbells`).
    #[default]
    Doorbell,
    /// iceoryx2 events: each agent's `turn` service, and the run's `done` service rung
    /// with the agent's index (a datagram socket per listener).
    Event,
}

impl WakeMode {
    /// The mode's name on the command line (`doorbell`, `event`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Doorbell => "doorbell",
            Self::Event => "event",
        }
    }
}

/// How long the coordinator spins on an agent's state before it sleeps (`--wait spin`):
/// a turn computes in tens of microseconds; a longer one then sleeps on the `done` event like `--wait block`.
pub const SPIN_BUDGET: Duration = Duration::from_millis(1);

/// How a run is carried out.
#[derive(Clone, Debug)]
pub struct RunOptions {
    /// The agent executable (default: beside the coordinator).
    pub agent_bin: Option<PathBuf>,
    /// How long an agent has for its turn.
    pub turn_deadline: Duration,
    /// How long every agent together has to start and shake hands, plus
    /// [`STARTUP_PER_AGENT`] for each agent ([`RunOptions::startup_timeout_for`]).
    pub startup_timeout: Duration,
    /// Missed turns, of the agent's last [`Self::late_window_turns`], after which a live
    /// but silent agent is declared hung, killed and frozen; as many answers later than
    /// the slow bound make it slow, killed and frozen alike.
    pub max_missed_turns: u32,
    /// The window of the hung and slow rules, in the agent's turns.
    pub late_window_turns: u32,
    /// The slow bound: an answer later than this after its grant is late (default:
    /// [`RunOptions::slow_bound_for`]).
    pub slow_turn: Option<Duration>,
    /// Start a replacement process for every agent that dies.
    pub respawn: bool,
    /// The faults injected on purpose (none by default).
    pub faults: FaultInjection,
    /// Show a progress bar on stderr (only drawn on a terminal).
    pub progress: bool,
    /// How turns are handed over: sleeping, spinning, or chosen by the core count.
    pub wait: WaitMode,
    /// How the coordinator and the agents wake each other.
    pub wake: WakeMode,
    /// Benchmark hook: after the ready handshake, hold every agent idle this long (no
    /// turn) and measure the CPU time they used meanwhile (the outcome's idle CPU, for `bench`).
    pub idle_probe: Option<Duration>,
    /// Agents over Zenoh: each agent's process is a relay to the agent itself, which runs
    /// here or on another machine ([`NetworkOptions`]); `None`: every agent on iceoryx2.
    pub network: Option<NetworkOptions>,
    /// Each agent in a sandbox behind a relay ([`SandboxOptions`]); `None`: every agent
    /// as this process's user, on the run's channels itself (it is trusted).
    pub sandbox: Option<SandboxOptions>,
    /// Where the run writes its log as it goes (`run.mcap`), if anywhere.
    pub log: Option<crate::run_log::LogOptions>,
    /// Go on with a killed run from the last step of its log (`run --resume DIR`): the
    /// world at that step rebuilt from it, the log written again and continued.
    pub resume: Option<std::sync::Arc<crate::run_log::LoggedRun>>,
}

/// How agents are sandboxed: agent `i` runs as user and group `first_uid + i`, in a
/// control group of its own with `limits` (when the machine's cgroups can be used),
/// behind a relay of this process's user that alone opens the run's shared memory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SandboxOptions {
    /// The first agent's user id.
    pub first_uid: u32,
    /// The limits of each agent's control group.
    pub limits: wire::cgroup::Limits,
}

impl RunOptions {
    /// The options that change the run's record, as its log keeps them.
    pub fn logged(&self) -> crate::run_log::LoggedOptions {
        crate::run_log::LoggedOptions {
            turn_deadline_ms: u64::try_from(self.turn_deadline.as_millis()).unwrap_or(u64::MAX),
            slow_turn_ms: self
                .slow_turn
                .map(|d| u64::try_from(d.as_millis()).unwrap_or(u64::MAX)),
            respawn: self.respawn,
            kills: self.faults.kills.clone(),
            deaths: self.faults.deaths.clone(),
            misbehave: self
                .faults
                .misbehave
                .iter()
                .map(|(agent, mode)| format!("{agent}={mode}"))
                .collect(),
        }
    }

    /// The slow bound in force for an agent that moves as `kinematics`:
    /// [`Self::slow_turn`], or by default a fifth of the turn deadline, and half of it for
    /// a car. A boxed-in car's turn runs a Hybrid A* search to its end
    /// ([`shared::control::turn::SEARCH_EXPANSIONS`]), about 65 ms in one process on the project's
    /// 2-core machine and up to 83 ms among agent processes on `paper-car`: honest, and
    /// over a fifth of the default deadline.
    ///
    /// ```
    /// use std::time::Duration;
    ///
    /// use runner::turns::RunOptions;
    /// use shared::control::vocabulary::Kinematics;
    ///
    /// let options = RunOptions::default();
    /// let car = Kinematics::Car { turning_radius_m: 0.5, reverse: true };
    /// assert_eq!(options.slow_bound_for(&Kinematics::Holonomic), options.turn_deadline / 5);
    /// assert_eq!(options.slow_bound_for(&car), options.turn_deadline / 2);
    /// let set = RunOptions { slow_turn: Some(Duration::from_millis(30)), ..options };
    /// assert_eq!(set.slow_bound_for(&car), Duration::from_millis(30));
    /// ```
    pub fn slow_bound_for(&self, kinematics: &Kinematics) -> Duration {
        self.slow_turn.unwrap_or(match kinematics {
            Kinematics::Car { .. } => self.turn_deadline / 2,
            Kinematics::Holonomic | Kinematics::Unicycle { .. } => self.turn_deadline / 5,
        })
    }
}

/// Whether this process runs as root (effective user id 0): the sandbox needs it.
pub fn running_as_root() -> bool {
    // SAFETY: geteuid(2) reads this process's effective user id; it cannot fail.
    unsafe { libc::geteuid() == 0 }
}

impl SandboxOptions {
    /// The default first user id: high, so that it names no account of a usual system.
    pub const DEFAULT_FIRST_UID: u32 = 200_000;

    /// The default sandbox.
    pub fn new() -> Self {
        Self {
            first_uid: Self::DEFAULT_FIRST_UID,
            limits: wire::cgroup::Limits::default(),
        }
    }

    /// The relay's arguments for agent `agent`, with `cgroup` if the run has one.
    pub fn relay_args(&self, agent: usize, cgroup: bool) -> Vec<String> {
        let uid = self.first_uid.saturating_add(agent as u32);
        let mut args = vec![
            "--sandbox-uid".to_string(),
            uid.to_string(),
            "--pids-max".to_string(),
            self.limits.pids_max.to_string(),
            "--memory-mib".to_string(),
            self.limits.memory_mib.to_string(),
            "--cpu-percent".to_string(),
            self.limits.cpu_percent.to_string(),
        ];
        if cgroup {
            args.push("--cgroup".to_string());
        }
        args
    }
}

impl Default for SandboxOptions {
    fn default() -> Self {
        Self::new()
    }
}

/// Start-up time allowed per agent on top of [`RunOptions::startup_timeout`]: the agents
/// start on the machine's few cores at once, so their handshakes take time in proportion
/// to their number (measured on 2 vCPUs: 780 agents ready 6.6 s after the run began, 8.5
/// ms per agent; this leaves room for a machine that is busy with other work).
pub const STARTUP_PER_AGENT: Duration = Duration::from_millis(25);

impl RunOptions {
    /// How long `agents` agents together have to start and shake hands.
    pub fn startup_timeout_for(&self, agents: usize) -> Duration {
        self.startup_timeout + STARTUP_PER_AGENT * u32::try_from(agents).unwrap_or(u32::MAX)
    }
}

impl Default for RunOptions {
    fn default() -> Self {
        Self {
            agent_bin: None,
            turn_deadline: Duration::from_millis(250),
            startup_timeout: Duration::from_secs(30),
            max_missed_turns: 3,
            late_window_turns: 10,
            slow_turn: None,
            respawn: false,
            faults: FaultInjection::default(),
            progress: true,
            wait: WaitMode::default(),
            wake: WakeMode::default(),
            idle_probe: None,
            network: None,
            sandbox: None,
            log: None,
            resume: None,
        }
    }
}
