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
    /// [`MAX_WAYPOINTS`](crate::vocabulary::MAX_WAYPOINTS) waypoints: stayed.
    PathTooLong = 4,
    /// The safety monitor rejected the published move: the agent stayed where it was.
    Rejected = 5,
    /// The agent missed its turn deadline (dead or hung): frozen where it was.
    Missed = 6,
    /// The agent is out of the formation (its process died): a static obstacle.
    Dead = 7,
}

impl MoveStatus {
    /// Every status, in code order.
    pub const ALL: [MoveStatus; 8] = [
        Self::AtSlot,
        Self::Deviated,
        Self::Stayed,
        Self::NoFreePoint,
        Self::PathTooLong,
        Self::Rejected,
        Self::Missed,
        Self::Dead,
    ];

    /// The status with wire code `code`, if any.
    ///
    /// ```
    /// use shared::vocabulary::MoveStatus;
    /// assert_eq!(MoveStatus::from_code(MoveStatus::Rejected as u8), Some(MoveStatus::Rejected));
    /// assert_eq!(MoveStatus::from_code(8), None);
    /// ```
    pub fn from_code(code: u8) -> Option<Self> {
        Self::ALL.get(code as usize).copied()
    }

    /// A short lowercase name for tables and CSV files.
    pub fn name(&self) -> &'static str {
        match self {
            Self::AtSlot => "at_slot",
            Self::Deviated => "deviated",
            Self::Stayed => "stayed",
            Self::NoFreePoint => "no_free_point",
            Self::PathTooLong => "path_too_long",
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
    /// The point the agent goes to (its current position when it stays).
    pub best: Point,
    /// What happened.
    pub status: MoveStatus,
    /// The polyline followed, from the current position to `best` (a single point when
    /// the agent stays).
    pub waypoints: Vec<Point>,
}
