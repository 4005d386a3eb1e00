//! The fixed capacities: how many agents, obstacles and waypoints every part of the
//! system holds at most. The wire messages are sized by them, and the scenario checks and
//! the controllers refuse anything larger, so nothing is ever cut short in transit.

/// Most agents a scenario may hold (the wire types' fixed capacity).
pub const MAX_AGENTS: usize = 1024;

/// Most obstacles a scenario may hold (the wire types' fixed capacity).
pub const MAX_OBSTACLES: usize = 16_384;

/// Most waypoints one move may have (the wire message's capacity).
pub const MAX_WAYPOINTS: usize = 512;
