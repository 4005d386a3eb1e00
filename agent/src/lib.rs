//! One formation agent: it waits for its turn, reads the world, computes its slot, best
//! point and path with [`shared::turn::AgentPlanner`], and publishes its move.
//!
//! The turn loop, [`serve`], talks to the world only through the [`Transport`] trait, so
//! it runs the same over iceoryx2 ([`ipc::IpcTransport`]) and in-process in tests.

pub mod ipc;
pub mod misbehave;
pub mod pingpong;
pub mod transport;

use std::time::{Duration, Instant};

use anyhow::Context;
use clap::Parser;
use shared::turn::{Body, TurnPlanner};

use crate::misbehave::Misbehave;

pub use transport::{Command, Transport, TurnInput};

/// Command line of the agent process (normally started by the coordinator).
#[derive(Debug, Parser)]
#[command(name = "agent", version, about = "One formation agent process")]
pub struct Args {
    /// The run's iceoryx2 prefix (given by the coordinator).
    #[arg(long)]
    pub run: String,
    /// This agent's index in the formation.
    #[arg(long)]
    pub agent: usize,
    /// How often to check that the coordinator is still there while waiting, in ms.
    #[arg(long, default_value_t = 200)]
    pub liveness_ms: u64,
    /// Test mode: publish bad results on purpose (the safety monitor must refuse them).
    #[arg(long, value_enum)]
    pub misbehave: Option<Misbehave>,
    /// Benchmark mode (`coordinator bench`): answer the latency floor's iceoryx2
    /// ping-pong, then the Unix-socket one on `--uds`, instead of taking turns.
    #[arg(long)]
    pub pingpong: bool,
    /// Benchmark mode: the coordinator's Unix socket for the socket ping-pong.
    #[arg(long, requires = "pingpong")]
    pub uds: Option<std::path::PathBuf>,
}

/// Install the stderr logger (`RUST_LOG`, default `warn`) and route iceoryx2's own log
/// through it.
pub fn init_logging() {
    use iceoryx2::prelude::{LogLevel, set_log_level_from_env_or};
    set_log_level_from_env_or(LogLevel::Warn);
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn"));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_target(false)
        .try_init();
}

/// Open the run's services and serve turns until told to stop or the coordinator is gone.
pub fn run(args: &Args) -> anyhow::Result<()> {
    if args.pingpong {
        let liveness = Duration::from_millis(args.liveness_ms.max(1));
        return pingpong::run(&args.run, args.uds.as_deref(), liveness);
    }
    let mut transport = ipc::IpcTransport::open(
        &args.run,
        args.agent,
        Duration::from_millis(args.liveness_ms.max(1)),
    )
    .with_context(|| format!("opening run {}", args.run))?;
    serve(&mut transport, args.agent, args.misbehave)
}

/// The agent's turn loop: announce readiness, then for every turn plan and publish a
/// move, until [`Command::Quit`]. `misbehave` is a test mode that publishes bad moves.
pub fn serve<T: Transport>(
    transport: &mut T,
    agent: usize,
    misbehave: Option<Misbehave>,
) -> anyhow::Result<()> {
    transport.announce_ready()?;
    let mut planner: Option<TurnPlanner> = None;
    let mut obstacles = Vec::new();
    loop {
        let turn = match transport.next_command()? {
            Command::Quit => return Ok(()),
            Command::Turn(turn) => turn,
        };
        if planner.is_none() {
            let mission = transport.mission()?;
            let spec = mission.agents.get(agent).with_context(|| {
                format!(
                    "agent {agent} is not in the mission's {} agents",
                    mission.agents.len()
                )
            })?;
            planner = Some(
                TurnPlanner::new(&mission.planner, mission.field, &mission.obstacles, spec)
                    .context("the mission's planner settings")?,
            );
            obstacles = mission.obstacles.clone();
        }
        let Some(planner) = planner.as_ref() else {
            continue;
        };
        let started = Instant::now();
        let me = turn.positions.get(agent).copied().with_context(|| {
            format!(
                "the world has {} agents, not agent {agent}",
                turn.positions.len()
            )
        })?;
        let others: Vec<Body> = turn
            .positions
            .iter()
            .zip(&turn.radii_m)
            .enumerate()
            .filter(|(j, _)| *j != agent)
            .map(|(_, (&position, &radius_m))| Body { position, radius_m })
            .collect();
        let mv = planner.plan_move(&turn.centre, &me, &others);
        let compute = started.elapsed();
        match misbehave {
            None => transport.publish_move(&turn, &mv, mv.status as u32, compute)?,
            Some(mode) => {
                if let Some((bad, status)) =
                    misbehave::corrupt(mode, mv, &me, &obstacles, turn.step)
                {
                    transport.publish_move(&turn, &bad, status, compute)?;
                }
            }
        }
    }
}
