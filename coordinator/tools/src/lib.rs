//! The tools round a run, apart from running a formation (the `runner` crate) so that
//! running one does not build the plotting stack:
//! - [`render`]: a run folder's plots and animation;
//! - [`bench`](mod@bench): what a turn costs, and where the time goes (latency, start-up, scale);
//! - [`bound`]: a lower bound on the deviation any controller can reach, and tracks that
//!   come near it;
//! - [`compare`]: controllers side by side on the same scenarios.

pub mod bench;
pub mod bound;
pub mod compare;
pub mod render;
