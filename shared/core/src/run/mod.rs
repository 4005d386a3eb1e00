//! The run: the step engine and what it keeps. Built on every layer before it.
//!
//! - [`step_loop`]: the step, written once for the reference simulation and the run over
//!   agent processes;
//! - [`turn_world`]: the world a turn reads ([`World`]): where every agent stands and
//!   faces, who is alive;
//! - [`record`]: the record of a run and its figures, and its referee (the recorder);
//! - [`simulate`]: the in-process reference simulation.

pub mod record;
pub mod simulate;
pub mod step_loop;
pub mod turn_world;

pub use turn_world::World;
