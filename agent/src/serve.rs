//! The agent's turn loop ([`serve`]): announce readiness, then for every turn read the
//! world it carries (checked: it comes from another process), plan with the mission's
//! controller and publish the move, over any [`Transport`].

use std::time::Instant;

use anyhow::{Context, bail};
use shared::control::turn::{TurnController, TurnRequest, Velocities};
use shared::control::vocabulary::{Body, TurnMode};
use shared::geometry::Point;

use crate::transport::{Command, Reply, Transport, TurnInput};

/// The step of `turn` as an index (moving obstacles stand where this step puts them; a
/// step beyond the platform's indices cannot come from a run, and saturates).
fn turn_step(turn: &TurnInput) -> usize {
    usize::try_from(turn.step).unwrap_or(usize::MAX)
}

/// Read the turn's bodies into `others` (every listed agent but `agent`, with its radius
/// from `radii_m`) and return `agent`'s own position. A list that is not in increasing
/// agent order, names an agent the mission does not have, or lacks `agent` is an error:
/// the world comes from another process.
fn read_bodies(
    turn: &TurnInput,
    agent: usize,
    radii_m: &[f64],
    others: &mut Vec<Body>,
) -> anyhow::Result<Point> {
    others.clear();
    let mut me = None;
    let mut previous: Option<usize> = None;
    for &(j, position) in &turn.bodies {
        if previous.is_some_and(|p| p >= j) {
            bail!("the world lists agent {j} after agent {previous:?}: not in increasing order");
        }
        previous = Some(j);
        let Some(&radius_m) = radii_m.get(j) else {
            bail!(
                "the world lists agent {j} but the mission has {} agents",
                radii_m.len()
            );
        };
        if j == agent {
            me = Some(position);
        } else {
            others.push(Body { position, radius_m });
        }
    }
    me.with_context(|| format!("the world does not list agent {agent} itself"))
}

/// How the bodies of `turn` moved over the last step, as agent `agent` plans with them:
/// its own, then the others' in the order [`read_bodies`] lists them (zero where the
/// world gives none).
fn velocities_of(turn: &TurnInput, agent: usize) -> Velocities {
    let mut v = Velocities::default();
    for (k, &(j, _)) in turn.bodies.iter().enumerate() {
        let velocity = turn.velocities.get(k).copied().unwrap_or_default();
        if j == agent {
            v.me = velocity;
        } else {
            v.others.push(velocity);
        }
    }
    v
}

/// The agent's turn loop: announce readiness, then for every turn plan and publish a
/// move, until [`Command::Quit`].
pub fn serve<T: Transport>(transport: &mut T, agent: usize) -> anyhow::Result<()> {
    transport.announce_ready()?;
    let mut controller: Option<TurnController> = None;
    // Every agent's radius, from the mission (the world carries positions only).
    let mut radii_m: Vec<f64> = Vec::new();
    // The other agents as bodies; the buffer is kept from turn to turn.
    let mut others: Vec<Body> = Vec::new();
    // Whether every agent moves at once (the world then says how each body moved).
    let mut simultaneous = false;
    loop {
        let turn = match transport.next_command()? {
            Command::Quit => return Ok(()),
            Command::Turn(turn) => turn,
        };
        if controller.is_none() {
            let mission = transport.mission()?;
            let spec = mission.agents.get(agent).with_context(|| {
                format!(
                    "agent {agent} is not in the mission's {} agents",
                    mission.agents.len()
                )
            })?;
            // Every real obstacle it may sense, known to the centre or not.
            let obstacles = &mission.obstacles;
            controller = Some(
                TurnController::new(&mission.controller, mission.field, obstacles, spec)
                    .context("the mission's controller settings")?
                    .with_moving(&mission.moving, obstacles)
                    .with_polygons(&mission.polygons)
                    .with_map(mission.map.as_ref())
                    .with_formation(&mission.agents),
            );
            radii_m = mission.agents.iter().map(|a| a.radius_m).collect();
            simultaneous = mission.turns == TurnMode::Simultaneous;
        }
        let Some(controller) = controller.as_ref() else {
            continue;
        };
        let started = Instant::now();
        let me = read_bodies(&turn, agent, &radii_m, &mut others)?;
        let step = turn_step(&turn);
        let velocities = simultaneous.then(|| velocities_of(&turn, agent));
        let mates = turn.mates_for(agent, controller);
        let mv = controller.plan(&TurnRequest {
            step,
            centre: turn.centre,
            ahead: &turn.ahead,
            me,
            heading_rad: turn.heading_rad,
            others: &others,
            mates: &mates,
            velocities: velocities.as_ref(),
        });
        let compute = started.elapsed();
        transport.publish_move(Reply::new(&turn, &mv, compute))?;
    }
}

#[cfg(test)]
mod tests {
    use std::collections::VecDeque;

    use shared::control::vocabulary::Move;
    use shared::run::simulate::{agent_controllers, plan_centre_path};
    use shared::world::scenario::Scenario;

    use super::*;
    use crate::transport::MissionView;
    #[cfg(feature = "misbehave")]
    use wire::misbehave::Misbehave;

    /// A scripted coordinator: hands out commands, keeps what the agent publishes.
    struct Scripted {
        mission: MissionView,
        commands: VecDeque<Command>,
        ready: bool,
        published: Vec<(u64, Move, u32)>,
    }

    impl Transport for Scripted {
        fn announce_ready(&mut self) -> anyhow::Result<()> {
            self.ready = true;
            Ok(())
        }
        fn next_command(&mut self) -> anyhow::Result<Command> {
            Ok(self.commands.pop_front().unwrap_or(Command::Quit))
        }
        fn mission(&mut self) -> anyhow::Result<MissionView> {
            Ok(self.mission.clone())
        }
        fn publish_move(&mut self, reply: Reply<'_>) -> anyhow::Result<()> {
            self.published
                .push((reply.turn.seq, reply.mv.clone(), reply.status));
            Ok(())
        }
    }

    fn scripted(scenario: &Scenario, turns: Vec<TurnInput>) -> Scripted {
        Scripted {
            mission: MissionView::of(scenario.clone()),
            commands: turns.into_iter().map(Command::Turn).collect(),
            ready: false,
            published: Vec::new(),
        }
    }

    fn first_turns(scenario: &Scenario, agent: usize) -> Vec<TurnInput> {
        let path = plan_centre_path(scenario).expect("path");
        let positions: Vec<_> = scenario
            .agents
            .iter()
            .map(|a| a.slot.ideal_position(&path[0]))
            .collect();
        (1..4)
            .map(|step| TurnInput {
                seq: step as u64 * 10 + agent as u64,
                step: step as u64,
                token: 1000 + step as u64,
                centre: path[step],
                heading_rad: None,
                ahead: path[step + 1..].iter().take(10).copied().collect(),
                bodies: positions.iter().copied().enumerate().collect(),
                velocities: Vec::new(),
                frozen: Vec::new(),
            })
            .collect()
    }

    #[test]
    fn the_turn_loop_publishes_exactly_the_controllers_move_for_every_turn() {
        let scenario = Scenario::paper();
        let agent = 2;
        let turns = first_turns(&scenario, agent);
        let mut t = scripted(&scenario, turns.clone());
        serve(&mut t, agent).expect("serve");
        assert!(t.ready);
        assert_eq!(t.published.len(), turns.len());
        let controller = &agent_controllers(&scenario).expect("controllers")[agent];
        for ((seq, mv, status), turn) in t.published.iter().zip(&turns) {
            let others: Vec<Body> = turn
                .bodies
                .iter()
                .filter(|(j, _)| *j != agent)
                .map(|&(j, position)| Body {
                    position,
                    radius_m: scenario.agents[j].radius_m,
                })
                .collect();
            let want = controller.plan(&TurnRequest {
                step: turn_step(turn),
                centre: turn.centre,
                ahead: &turn.ahead,
                me: turn.bodies[agent].1,
                heading_rad: None,
                others: &others,
                mates: &turn.mates_for(agent, controller),
                velocities: None,
            });
            assert_eq!(*seq, turn.seq);
            assert_eq!(*mv, want);
            assert_eq!(*status, want.status as u32);
        }
    }

    /// What agent `agent` publishes over [`Scripted`] in mode `mode`.
    #[cfg(feature = "misbehave")]
    fn published_in_mode(
        scenario: &Scenario,
        turns: &[TurnInput],
        agent: usize,
        mode: Misbehave,
    ) -> Vec<(u64, Move, u32)> {
        let mut t =
            crate::misbehave::Misbehaving::new(scripted(scenario, turns.to_vec()), agent, mode);
        serve(&mut t, agent).expect("serve");
        let inner = t.into_inner();
        assert!(inner.ready);
        inner.published
    }

    #[cfg(feature = "misbehave")]
    #[test]
    fn a_silent_agent_publishes_nothing_and_a_nan_agent_publishes_nan() {
        let scenario = Scenario::paper();
        let turns = first_turns(&scenario, 0);
        assert!(published_in_mode(&scenario, &turns, 0, Misbehave::Silent).is_empty());
        let nan = published_in_mode(&scenario, &turns, 0, Misbehave::Nan);
        assert_eq!(nan.len(), turns.len());
        assert!(nan.iter().all(|(_, mv, _)| mv.best.x.is_nan()));
    }

    #[cfg(feature = "misbehave")]
    #[test]
    fn replay_early_and_flood_send_the_honest_moves_out_of_turn() {
        let scenario = Scenario::paper();
        let agent = 1;
        let turns = first_turns(&scenario, agent);
        let mut plain = scripted(&scenario, turns.clone());
        serve(&mut plain, agent).expect("serve");
        let honest = plain.published;
        assert_eq!(honest.len(), turns.len());

        let replay = published_in_mode(&scenario, &turns, agent, Misbehave::Replay);
        // The first turn's move alone, then every later turn's after the one before.
        let mut want = vec![honest[0].clone()];
        for w in honest.windows(2) {
            want.extend([w[0].clone(), w[1].clone()]);
        }
        assert_eq!(replay, want);

        let early = published_in_mode(&scenario, &turns, agent, Misbehave::Early);
        let want: Vec<_> = honest
            .iter()
            .flat_map(|(seq, mv, status)| {
                [(*seq, mv.clone(), *status), (seq + 1, mv.clone(), *status)]
            })
            .collect();
        assert_eq!(early, want);

        let flood = published_in_mode(&scenario, &turns, agent, Misbehave::Flood);
        let want: Vec<_> = honest
            .iter()
            .flat_map(|m| std::iter::repeat_n(m.clone(), 4))
            .collect();
        assert_eq!(flood, want);

        // Modes that act outside the moves publish the honest moves.
        for mode in [
            Misbehave::Fork,
            Misbehave::RawLength,
            Misbehave::DeafToPrepare,
        ] {
            assert_eq!(
                published_in_mode(&scenario, &turns, agent, mode),
                honest,
                "{mode}"
            );
        }
    }

    #[test]
    fn a_world_that_disagrees_with_the_mission_is_an_error_not_a_panic() {
        let scenario = Scenario::paper();
        let mut turns = first_turns(&scenario, 0);
        turns[0].bodies.push((6, Point::new(1.0, 1.0)));
        let mut t = scripted(&scenario, turns.clone());
        let err = serve(&mut t, 0).expect_err("a world with a seventh agent");
        assert!(
            format!("{err:#}").contains("the world lists agent 6 but the mission has 6 agents"),
            "{err:#}"
        );
        assert!(t.published.is_empty());
        turns[0].bodies.pop();
        turns[0].bodies.swap(1, 2);
        let mut t = scripted(&scenario, turns.clone());
        let err = serve(&mut t, 0).expect_err("out of order");
        assert!(
            format!("{err:#}").contains("not in increasing order"),
            "{err:#}"
        );
        turns[0].bodies.remove(0);
        turns[0].bodies.sort_by_key(|b| b.0);
        let mut t = scripted(&scenario, turns);
        let err = serve(&mut t, 0).expect_err("without itself");
        assert!(
            format!("{err:#}").contains("does not list agent 0 itself"),
            "{err:#}"
        );
    }

    #[test]
    fn an_agent_missing_from_the_mission_is_an_error_not_a_panic() {
        let scenario = Scenario::paper();
        let mut t = scripted(&scenario, first_turns(&scenario, 0));
        assert!(serve(&mut t, 99).is_err());
    }
}
