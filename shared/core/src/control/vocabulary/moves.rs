//! The outcome of one agent's turn: where it goes, along which polyline, and why.

use crate::geometry::Point;

/// What an agent did in its turn.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum MoveStatus {
    /// Reached its ideal slot.
    AtSlot = 0,
    /// The slot is blocked or unreachable: moved to the nearest reachable free point.
    Deviated = 1,
    /// Nothing nearer the slot is reachable: stayed where it was.
    Stayed = 2,
    /// No point of the field is free for this agent: stayed where it was.
    NoFreePoint = 3,
    /// The path to the best point needs more than
    /// [`MAX_WAYPOINTS`](crate::control::vocabulary::MAX_WAYPOINTS) waypoints: stayed.
    PathTooLong = 4,
    /// The path to the best point is longer than the agent's top speed allows in one
    /// step: it followed the path that far and stopped (it plans again next step).
    UnderWay = 5,
    /// The safety monitor rejected the published move: the agent stayed where it was.
    Rejected = 6,
    /// The agent missed its turn deadline (dead or hung): frozen where it was.
    Missed = 7,
    /// The agent is out of the formation (its process died): a static obstacle.
    Dead = 8,
}

impl MoveStatus {
    /// Every status, in code order.
    pub const ALL: [MoveStatus; 9] = [
        Self::AtSlot,
        Self::Deviated,
        Self::Stayed,
        Self::NoFreePoint,
        Self::PathTooLong,
        Self::UnderWay,
        Self::Rejected,
        Self::Missed,
        Self::Dead,
    ];

    /// The status with wire code `code`, if any.
    ///
    /// ```
    /// use shared::control::vocabulary::MoveStatus;
    /// assert_eq!(MoveStatus::from_code(MoveStatus::Rejected as u8), Some(MoveStatus::Rejected));
    /// assert_eq!(MoveStatus::from_code(9), None);
    /// ```
    pub fn from_code(code: u8) -> Option<Self> {
        Self::ALL.get(code as usize).copied()
    }

    /// Whether an agent may report this status itself (the others are the
    /// coordinator's verdicts).
    pub fn set_by_agent(&self) -> bool {
        (*self as u8) <= Self::UnderWay as u8
    }

    /// A short lowercase name for tables and CSV files.
    pub fn name(&self) -> &'static str {
        match self {
            Self::AtSlot => "at_slot",
            Self::Deviated => "deviated",
            Self::Stayed => "stayed",
            Self::NoFreePoint => "no_free_point",
            Self::PathTooLong => "path_too_long",
            Self::UnderWay => "under_way",
            Self::Rejected => "rejected",
            Self::Missed => "missed",
            Self::Dead => "dead",
        }
    }
}

/// The outcome of a turn.
#[derive(Clone, Debug, PartialEq)]
pub struct Move {
    /// The ideal slot at this step.
    pub slot: Point,
    /// The best point the agent aims for (its current position when it stays). With a
    /// top speed the move may stop short of it ([`MoveStatus::UnderWay`]).
    pub best: Point,
    /// What happened.
    pub status: MoveStatus,
    /// The polyline followed, from the current position to where the agent stops: `best`,
    /// or short of it when under way (a single point when the agent stays).
    pub waypoints: Vec<Point>,
    /// The agent's heading where the move ends, radians, for an agent with a heading
    /// (a unicycle or a car, [`Kinematics`](crate::control::vocabulary::Kinematics)); `None` for a holonomic
    /// agent.
    pub end_heading_rad: Option<f64>,
}

impl Move {
    /// Where the agent stands after the move: its last waypoint (`best` for a move
    /// without one, which the safety checks refuse anyway).
    pub fn end(&self) -> Point {
        self.waypoints.last().copied().unwrap_or(self.best)
    }
}

impl super::Named for MoveStatus {
    const ALL: &'static [Self] = &Self::ALL;
    const WHAT: &'static str = "move status";

    fn name(&self) -> &'static str {
        MoveStatus::name(self)
    }
}
