//! A turn and a move as they cross a relay's link (Zenoh to another machine, or the
//! socket to a sandboxed agent): [`net`]'s plain messages, converted both ways and
//! checked on the way in like any input from another process.

use std::time::Duration;

use anyhow::{Context, bail};
use net::{NetMove, NetTurn};
use shared::control::vocabulary::{MAX_AGENTS, MAX_WAYPOINTS, Move, MoveStatus};
use shared::geometry::{Point, Pose, Vector};
use shared::world::scenario::{Checks, Scenario};

use crate::transport::{MissionView, Reply, TurnInput};

/// The mission of agent `agent` from the mission file's text, as a relay sends it,
/// checked as `checks` says: [`Checks::Values`] for a sandboxed agent, whose own relay
/// read the file by the digest the coordinator handed over; [`Checks::All`] over a
/// network.
pub fn mission_view(json: &str, agent: usize, checks: Checks) -> anyhow::Result<MissionView> {
    let scenario = Scenario::from_mission_json(json, "the mission from the coordinator", checks)
        .context("the mission")?;
    if agent >= scenario.agents.len() {
        bail!(
            "agent {agent} is not in the mission's {} agents",
            scenario.agents.len()
        );
    }
    Ok(MissionView::of(scenario))
}

/// A turn as the link carries it.
pub fn net_turn(t: &TurnInput) -> NetTurn {
    NetTurn {
        seq: t.seq,
        step: t.step,
        token: t.token,
        centre: [t.centre.x_m, t.centre.y_m, t.centre.heading_rad],
        heading_rad: t.heading_rad,
        ahead: t
            .ahead
            .iter()
            .map(|p| [p.x_m, p.y_m, p.heading_rad])
            .collect(),
        bodies: t
            .bodies
            .iter()
            .map(|&(j, p)| (u32::try_from(j).unwrap_or(u32::MAX), [p.x, p.y]))
            .collect(),
        velocities: t.velocities.iter().map(|v| [v.x, v.y]).collect(),
        frozen: t
            .frozen
            .iter()
            .map(|&j| u32::try_from(j).unwrap_or(u32::MAX))
            .collect(),
    }
}

/// A turn from the link, checked like any input from another process.
pub fn turn_input(t: NetTurn) -> anyhow::Result<TurnInput> {
    if t.bodies.len() > MAX_AGENTS {
        bail!("a turn with {} bodies, beyond the capacity", t.bodies.len());
    }
    if t.velocities.len() > t.bodies.len() {
        bail!(
            "a turn with {} velocities for {} bodies",
            t.velocities.len(),
            t.bodies.len()
        );
    }
    if t.frozen.len() > t.bodies.len() {
        bail!(
            "a turn with {} frozen agents for {} bodies",
            t.frozen.len(),
            t.bodies.len()
        );
    }
    if t.ahead.len() > shared::control::tracking::MAX_HORIZON_STEPS {
        bail!(
            "a turn with {} poses ahead, beyond the capacity",
            t.ahead.len()
        );
    }
    let finite = t.centre.iter().all(|v| v.is_finite())
        && t.ahead.iter().flatten().all(|v| v.is_finite())
        && t.velocities.iter().flatten().all(|v| v.is_finite())
        && t.heading_rad.is_none_or(f64::is_finite)
        && t.bodies
            .iter()
            .all(|(_, p)| p.iter().all(|v| v.is_finite()));
    if !finite {
        bail!("a turn with a coordinate that is not a finite number");
    }
    Ok(TurnInput {
        seq: t.seq,
        step: t.step,
        token: t.token,
        centre: Pose::new(t.centre[0], t.centre[1], t.centre[2]),
        heading_rad: t.heading_rad,
        ahead: t
            .ahead
            .iter()
            .map(|p| Pose::new(p[0], p[1], p[2]))
            .collect(),
        bodies: t
            .bodies
            .into_iter()
            .map(|(j, p)| (j as usize, Point::new(p[0], p[1])))
            .collect(),
        velocities: t
            .velocities
            .iter()
            .map(|v| Vector::new(v[0], v[1]))
            .collect(),
        frozen: t.frozen.into_iter().map(|j| j as usize).collect(),
    })
}

/// Agent `agent`'s reply as the link carries it.
pub fn net_move(agent: usize, reply: Reply<'_>) -> anyhow::Result<NetMove> {
    let xy = |p: &Point| [p.x, p.y];
    Ok(NetMove {
        agent: u32::try_from(agent).context("the agent's index")?,
        seq: reply.turn.seq,
        step: reply.turn.step,
        token: reply.turn.token,
        status: reply.status,
        compute_ns: u64::try_from(reply.compute.as_nanos()).unwrap_or(u64::MAX),
        slot: xy(&reply.mv.slot),
        best: xy(&reply.mv.best),
        end_heading_rad: reply.mv.end_heading_rad,
        waypoints: reply.mv.waypoints.iter().map(xy).collect(),
    })
}

/// A move from the link as the iceoryx2 channel takes it (with its status code and
/// compute time); `None` (logged) if it cannot be written there. Its values are checked
/// by the coordinator like any move.
pub fn move_of(agent: usize, m: NetMove) -> Option<(Move, u32, Duration)> {
    if m.waypoints.len() > MAX_WAYPOINTS {
        tracing::warn!(
            "relay of agent {agent}: a move of {} waypoints, beyond the capacity: dropped",
            m.waypoints.len()
        );
        return None;
    }
    let p = |xy: [f64; 2]| Point::new(xy[0], xy[1]);
    Some((
        Move {
            end_heading_rad: m.end_heading_rad,
            slot: p(m.slot),
            best: p(m.best),
            // Only the code below is sent; this field is not read.
            status: MoveStatus::Stayed,
            waypoints: m.waypoints.into_iter().map(p).collect(),
        },
        m.status,
        Duration::from_nanos(m.compute_ns),
    ))
}
