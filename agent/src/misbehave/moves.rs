//! The test modes that change what moves an agent publishes: bad moves the coordinator's
//! safety monitor must refuse (`nan`, `teleport`, ...) and honest moves sent out of turn
//! (`replay`, `early`, `flood`). [`Misbehaving`] is the [`Transport`] decorator that
//! publishes them in place of the honest move the turn loop hands it.

use anyhow::Context;
use shared::control::vocabulary::{MAX_WAYPOINTS, Move, MoveStatus};
use shared::geometry::{Disk, Point, Vector};
use wire::misbehave::Misbehave;

use crate::transport::{Command, MissionView, Reply, Transport, TurnInput};

/// A [`Transport`] decorator: agent `agent`'s moves go out as mode `mode` has them, the
/// rest passes through `T` untouched.
pub struct Misbehaving<T> {
    inner: T,
    agent: usize,
    mode: Misbehave,
    /// The mission's static obstacles (`through-obstacle` crosses the nearest), taken
    /// from the first [`Transport::mission`] that passes through.
    obstacles: Option<Vec<Disk>>,
    /// The last honest move handed over, with its turn (`replay` sends it again).
    previous: Option<(TurnInput, Move)>,
}

impl<T: Transport> Misbehaving<T> {
    /// Agent `agent` over `inner`, misbehaving as `mode` says.
    pub fn new(inner: T, agent: usize, mode: Misbehave) -> Self {
        Self {
            inner,
            agent,
            mode,
            obstacles: None,
            previous: None,
        }
    }

    /// The transport inside.
    pub fn into_inner(self) -> T {
        self.inner
    }
}

impl<T: Transport> Transport for Misbehaving<T> {
    fn announce_ready(&mut self) -> anyhow::Result<()> {
        self.inner.announce_ready()
    }

    fn next_command(&mut self) -> anyhow::Result<Command> {
        self.inner.next_command()
    }

    fn mission(&mut self) -> anyhow::Result<MissionView> {
        let mission = self.inner.mission()?;
        self.obstacles = Some(mission.obstacles.clone());
        Ok(mission)
    }

    fn publish_move(&mut self, reply: Reply<'_>) -> anyhow::Result<()> {
        let Reply { turn, mv, .. } = reply;
        match self.mode {
            Misbehave::Replay => {
                if let Some((old_turn, old_move)) = &self.previous {
                    self.inner
                        .publish_move(Reply::new(old_turn, old_move, reply.compute))?;
                }
                self.inner.publish_move(reply)?;
            }
            Misbehave::Early => {
                self.inner.publish_move(reply)?;
                let guess = TurnInput {
                    seq: turn.seq + 1,
                    step: turn.step + 1,
                    token: turn.token.wrapping_add(1),
                    ..turn.clone()
                };
                self.inner.publish_move(Reply {
                    turn: &guess,
                    ..reply
                })?;
            }
            Misbehave::Flood => {
                for _ in 0..4 {
                    self.inner.publish_move(reply)?;
                }
            }
            Misbehave::LateSome => {
                if turn.step % 3 != 0 {
                    std::thread::sleep(LATE_SOME_DELAY);
                }
                self.inner.publish_move(reply)?;
            }
            Misbehave::Sluggish => {
                std::thread::sleep(SLUGGISH_DELAY);
                self.inner.publish_move(reply)?;
            }
            mode => {
                let me = turn
                    .bodies
                    .iter()
                    .find(|(j, _)| *j == self.agent)
                    .map(|&(_, p)| p)
                    .with_context(|| format!("the world does not list agent {}", self.agent))?;
                if self.obstacles.is_none() {
                    self.obstacles = Some(self.inner.mission()?.obstacles);
                }
                let obstacles = self.obstacles.as_deref().unwrap_or_default();
                if let Some((bad, status)) = corrupt(mode, mv.clone(), &me, obstacles, turn.step) {
                    self.inner.publish_move(Reply {
                        mv: &bad,
                        status,
                        ..reply
                    })?;
                }
            }
        }
        self.previous = Some((turn.clone(), mv.clone()));
        Ok(())
    }
}

/// Turn an honest move into this mode's bad one (`None`: publish nothing). Modes that do
/// not corrupt moves return the honest move unchanged.
pub fn corrupt(
    mode: Misbehave,
    honest: Move,
    me: &Point,
    obstacles: &[Disk],
    step: u64,
) -> Option<(Move, u32)> {
    let status = honest.status as u32;
    match mode {
        Misbehave::Silent => None,
        Misbehave::Nan => {
            let bad = Point::new(f64::NAN, me.y);
            Some((
                Move {
                    end_heading_rad: None,
                    best: bad,
                    waypoints: vec![*me, bad],
                    ..honest
                },
                status,
            ))
        }
        Misbehave::Teleport => {
            let far = me + Vector::new(7.5, -3.25);
            Some((
                Move {
                    end_heading_rad: None,
                    best: far,
                    waypoints: vec![far],
                    ..honest
                },
                status,
            ))
        }
        Misbehave::ThroughObstacle => {
            let nearest = obstacles
                .iter()
                .min_by(|a, b| (a.centre - me).norm().total_cmp(&(b.centre - me).norm()))?;
            let across = nearest.centre + (nearest.centre - me);
            Some((
                Move {
                    end_heading_rad: None,
                    best: across,
                    waypoints: vec![*me, nearest.centre, across],
                    ..honest
                },
                status,
            ))
        }
        Misbehave::Overspeed => {
            let waypoints = overspeed(&honest.waypoints);
            Some((
                Move {
                    end_heading_rad: None,
                    waypoints,
                    ..honest
                },
                status,
            ))
        }
        Misbehave::OverTurn => {
            let honest_end_rad = honest.end_heading_rad.unwrap_or(0.0);
            Some((
                Move {
                    end_heading_rad: Some(shared::geometry::wrap_angle_rad(
                        honest_end_rad + std::f64::consts::PI,
                    )),
                    ..honest
                },
                status,
            ))
        }
        Misbehave::RawLength
        | Misbehave::RawLengthReady
        | Misbehave::Replay
        | Misbehave::Early
        | Misbehave::Flood
        | Misbehave::Impersonate { .. }
        | Misbehave::SpoofReady { .. }
        | Misbehave::Hoard
        | Misbehave::Fork
        | Misbehave::ExitBeforeReady
        | Misbehave::KilledConnecting
        | Misbehave::DeafToPrepare
        | Misbehave::Scribble
        | Misbehave::StopOthers
        | Misbehave::RewriteMission
        | Misbehave::ForkBomb
        | Misbehave::LateSome
        | Misbehave::Sluggish
        | Misbehave::LogFlood
        | Misbehave::TtyPush
        | Misbehave::FillTmp
        | Misbehave::KillTwin => Some((honest, status)),
        Misbehave::Garbage => {
            // Deterministic nonsense, different at every step.
            let s = (step as f64 * 12.9898).sin() * 43_758.545;
            let junk = Point::new(s.fract() * 1e6, -s.fract() * 3e5);
            Some((
                Move {
                    end_heading_rad: None,
                    best: junk,
                    waypoints: vec![*me, junk, *me],
                    status: MoveStatus::AtSlot,
                    ..honest
                },
                0xBAD,
            ))
        }
    }
}

/// How late [`Misbehave::LateSome`] answers two turns of three: past a 1 s deadline.
const LATE_SOME_DELAY: std::time::Duration = std::time::Duration::from_millis(1300);

/// How late [`Misbehave::Sluggish`] answers every turn: within the default deadline, past
/// the default slow bound (50 ms).
const SLUGGISH_DELAY: std::time::Duration = std::time::Duration::from_millis(200);

/// Most passes [`Misbehave::Overspeed`] makes over the honest path.
const OVERSPEED_PASSES: usize = 9;

/// [`Misbehave::Overspeed`]: `path` followed forth, back, forth... an odd number of
/// times (at most [`OVERSPEED_PASSES`], as many as [`MAX_WAYPOINTS`] holds), so it ends
/// where `path` ends; a path of one point is left as it is.
fn overspeed(path: &[Point]) -> Vec<Point> {
    let segments = path.len().saturating_sub(1);
    if segments == 0 {
        return path.to_vec();
    }
    let fit = (MAX_WAYPOINTS - 1) / segments;
    let passes = OVERSPEED_PASSES.min(fit);
    let passes = if passes.is_multiple_of(2) {
        passes - 1
    } else {
        passes
    };
    let mut out = vec![path[0]];
    for pass in 0..passes {
        if pass.is_multiple_of(2) {
            out.extend_from_slice(&path[1..]);
        } else {
            out.extend(path[..segments].iter().rev());
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fork_mode_publishes_the_honest_move() {
        let me = Point::new(1.0, 2.0);
        let honest = Move {
            end_heading_rad: None,
            slot: Point::new(3.0, 4.0),
            best: Point::new(2.0, 3.0),
            status: MoveStatus::AtSlot,
            waypoints: vec![me, Point::new(2.0, 3.0)],
        };
        let got = corrupt(Misbehave::Fork, honest.clone(), &me, &[], 7);
        assert_eq!(got, Some((honest.clone(), honest.status as u32)));
    }

    #[test]
    fn the_over_turn_mode_keeps_the_ground_and_ends_facing_the_other_way() {
        let me = Point::new(1.0, 2.0);
        let honest = Move {
            end_heading_rad: Some(0.25),
            slot: Point::new(3.0, 4.0),
            best: Point::new(2.0, 3.0),
            status: MoveStatus::Deviated,
            waypoints: vec![me, Point::new(2.0, 3.0)],
        };
        let (spun, status) =
            corrupt(Misbehave::OverTurn, honest.clone(), &me, &[], 7).expect("a move");
        assert_eq!(status, honest.status as u32);
        assert_eq!(spun.waypoints, honest.waypoints);
        let end = spun.end_heading_rad.expect("a heading");
        assert!((end - (0.25 - std::f64::consts::PI)).abs() < 1e-12, "{end}");
        // A holonomic agent's honest move has no heading: the rogue one has one.
        let holonomic = Move {
            end_heading_rad: None,
            ..honest
        };
        let (spun, _) = corrupt(Misbehave::OverTurn, holonomic, &me, &[], 7).expect("a move");
        assert!(spun.end_heading_rad.is_some());
    }

    #[test]
    fn the_overspeed_mode_retraces_the_honest_path_and_ends_where_it_ends() {
        let me = Point::new(1.0, 2.0);
        let path = vec![me, Point::new(1.3, 2.4), Point::new(1.6, 2.4)];
        let honest = Move {
            end_heading_rad: None,
            slot: Point::new(3.0, 4.0),
            best: Point::new(1.6, 2.4),
            status: MoveStatus::AtSlot,
            waypoints: path.clone(),
        };
        let (fast, status) =
            corrupt(Misbehave::Overspeed, honest.clone(), &me, &[], 7).expect("a move");
        assert_eq!(status, honest.status as u32);
        assert_eq!(
            (fast.slot, fast.best, fast.status),
            (honest.slot, honest.best, honest.status)
        );
        let length = |p: &[Point]| -> f64 { p.windows(2).map(|w| (w[1] - w[0]).norm()).sum() };
        assert!((length(&fast.waypoints) - 9.0 * length(&path)).abs() < 1e-12);
        assert_eq!(fast.waypoints.first(), Some(&me));
        assert_eq!(fast.waypoints.last(), path.last());
        // Only the honest path's points, and every step between two neighbours of it.
        for w in fast.waypoints.windows(2) {
            assert!(
                path.windows(2).any(|p| p == w || p == [w[1], w[0]]),
                "{w:?}"
            );
        }
        // Within the waypoint capacity, an odd number of passes.
        let long: Vec<Point> = (0..200)
            .map(|i| Point::new(f64::from(i) * 0.01, 0.0))
            .collect();
        let stretched = overspeed(&long);
        assert!(stretched.len() <= MAX_WAYPOINTS);
        assert_eq!(stretched.len(), 200, "one pass: no room for three");
        let mid: Vec<Point> = (0..100)
            .map(|i| Point::new(f64::from(i) * 0.01, 0.0))
            .collect();
        let stretched = overspeed(&mid);
        assert_eq!(stretched.len(), 1 + 99 * 5);
        assert_eq!(stretched.last(), mid.last());
        // Standing still stays standing still.
        assert_eq!(overspeed(&[me]), vec![me]);
    }
}
