//! Test modes in which an agent publishes bad results on purpose, so users can check that
//! the coordinator's safety monitor refuses every one of them.

use shared::geometry::{Disk, Point, Vector};
pub use shared::misbehave::Misbehave;
use shared::turn::{Move, MoveStatus};

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
                .min_by(|a, b| (a.center - me).norm().total_cmp(&(b.center - me).norm()))?;
            let across = nearest.center + (nearest.center - me);
            Some((
                Move {
                    best: across,
                    waypoints: vec![*me, nearest.center, across],
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
        | Misbehave::ExitBeforeReady => Some((honest, status)),
        Misbehave::Garbage => {
            // Deterministic nonsense, different at every step.
            let s = (step as f64 * 12.9898).sin() * 43_758.545;
            let junk = Point::new(s.fract() * 1e6, -s.fract() * 3e5);
            Some((
                Move {
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
