//! [`TurnRequest`]: everything an agent knows when its turn comes, the one input of
//! [`TurnController::plan`](super::TurnController::plan).

use crate::control::vocabulary::Body;
use crate::geometry::{Point, Pose};

use super::{MateView, Velocities};

/// One agent's turn as its controller sees it: the world of the turn, from the agent's
/// side. World coordinates are metres, angles radians anticlockwise from the x axis, and
/// time is counted in steps.
///
/// The reference simulation and the agent process build one from the world they are
/// given and hand it to [`TurnController::plan`](super::TurnController::plan); a test or
/// a benchmark starts from [`TurnRequest::new`] and adds what it knows:
///
/// ```
/// use shared::geometry::{Point, Pose};
/// use shared::control::turn::TurnRequest;
/// use shared::control::vocabulary::Body;
///
/// let others = [Body { position: Point::new(2.0, 0.0), radius_m: 0.5 }];
/// let ahead = [Pose::new(0.1, 0.0, 0.0)];
/// let turn = TurnRequest::new(Pose::new(0.0, 0.0, 0.0), Point::new(-1.0, 0.0), &others)
///     .at_step(12)
///     .looking_ahead(&ahead)
///     .facing(0.0);
/// assert_eq!((turn.step, turn.ahead.len(), turn.heading_rad), (12, 1, Some(0.0)));
/// ```
#[derive(Clone, Copy, Debug)]
pub struct TurnRequest<'a> {
    /// The step this turn belongs to (0 is the start): where the moving obstacles stand
    /// ([`crate::world::moving_obstacle::MovingObstacle::position_at`]).
    pub step: usize,
    /// The formation centre's pose this step (metres, radians): with the agent's slot it
    /// gives the ideal position.
    pub centre: Pose,
    /// The centre's next poses along its current plan, the pose of `step + 1` first
    /// (fewer near the plan's end; none: the agent does not look ahead).
    pub ahead: &'a [Pose],
    /// Where the agent stands (metres).
    pub me: Point,
    /// Where the agent faces (radians), for an agent with a heading (a unicycle or a
    /// car); `None` for a holonomic one, which ignores it anyway.
    pub heading_rad: Option<f64>,
    /// The other bodies (the other agents, alive or frozen, with their true radii), which
    /// stand still while the agent moves. They may be more than it senses: a controller
    /// with a sensing radius sees only those within it.
    pub others: &'a [Body],
    /// The other agents as the world shows them (index, position, alive), any order: an
    /// agent that looks ahead gives way to a mate it senses far behind its slot
    /// ([`super::Aim::lagging`]). Empty: it knows of none.
    pub mates: &'a [MateView],
    /// When every agent moves at once: how every body moved over the last step (metres a
    /// step); the ORCA controller then plans in its reciprocal model, the others ignore it.
    pub velocities: Option<&'a Velocities>,
}

impl<'a> TurnRequest<'a> {
    /// A turn at step 0 for the agent at `me` with the centre at `centre` among `others`,
    /// knowing nothing more: no look-ahead, no heading, no mates, no velocities.
    pub fn new(centre: Pose, me: Point, others: &'a [Body]) -> Self {
        Self {
            step: 0,
            centre,
            ahead: &[],
            me,
            heading_rad: None,
            others,
            mates: &[],
            velocities: None,
        }
    }

    /// This turn at step `step`.
    pub fn at_step(self, step: usize) -> Self {
        Self { step, ..self }
    }

    /// This turn knowing the centre's next poses, `ahead` ([`Self::ahead`]).
    pub fn looking_ahead(self, ahead: &'a [Pose]) -> Self {
        Self { ahead, ..self }
    }

    /// This turn for an agent facing `heading_rad` ([`Self::heading_rad`]).
    pub fn facing(self, heading_rad: f64) -> Self {
        Self {
            heading_rad: Some(heading_rad),
            ..self
        }
    }

    /// This turn knowing the mates `mates` ([`Self::mates`]).
    pub fn with_mates(self, mates: &'a [MateView]) -> Self {
        Self { mates, ..self }
    }

    /// This turn with every agent moving at once, as `velocities` says they moved.
    pub fn with_velocities(self, velocities: Option<&'a Velocities>) -> Self {
        Self { velocities, ..self }
    }
}
