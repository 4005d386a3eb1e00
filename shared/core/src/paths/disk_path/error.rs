//! Why no path was returned.

/// Why no path was returned.
#[derive(Debug, thiserror::Error, Clone, Copy, PartialEq, Eq)]
pub enum PathError {
    /// The start is inside a disk or outside the field (beyond
    /// [`FREE_TOLERANCE_M`](super::FREE_TOLERANCE_M)).
    #[error("the start is not in free space")]
    StartNotFree,
    /// The goal is inside a disk or outside the field (beyond
    /// [`FREE_TOLERANCE_M`](super::FREE_TOLERANCE_M)).
    #[error("the goal is not in free space")]
    GoalNotFree,
    /// Start and goal are both free but lie in different components of free space.
    #[error("the goal cannot be reached from the start")]
    Unreachable,
}
