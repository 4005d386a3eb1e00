//! Control: what one agent decides in its turn. Built on [`geometry`](crate::geometry)
//! and [`paths`](crate::paths); the turn also reads what the world puts round it (the
//! scenario's map and the moving obstacles, [`world`](crate::world)).
//!
//! - [`vocabulary`]: the words every other part speaks (bodies, moves, agents,
//!   controllers and their settings, capacities);
//! - [`formation`]: ideal slots (the paper's equation 2);
//! - [`best_point`]: the exact best point (Theorem 1) with reachability;
//! - [`tracking`]: where an agent with a top speed aims, knowing where its slot will be;
//! - [`kinematics`]: moves a robot with a heading can drive (a unicycle's, a car's), and
//!   their checks;
//! - [`safety`]: the safety invariant checked with plain geometry (the controllers check
//!   their own moves with it, the record checks every move with it);
//! - [`cbf`]: the control-barrier-function controllers and their exact 2-D QP;
//! - [`orca`]: the reactive baseline ORCA (RVO2, on `dodgy_2d`), cut to stay safe;
//! - [`survival_grid`]: for how many turns an agent can keep out of the moving obstacles'
//!   reach;
//! - [`protocol`]: how an agent talks to a controller that is a program of the user's
//!   (one JSON object a line over its standard input and output);
//! - [`turn`]: one agent's turn: the turn request and every controller behind one
//!   interface, shared by the reference simulation and the agents.

pub mod best_point;
pub mod cbf;
pub mod formation;
pub mod kinematics;
pub mod orca;
pub mod protocol;
pub mod safety;
pub mod survival_grid;
pub mod tracking;
pub mod turn;
pub mod vocabulary;
