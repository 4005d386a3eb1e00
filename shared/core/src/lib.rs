//! The formation controller's library: every algorithm, no I/O loop and no transport
//! (the messages between processes are in the `wire` crate, `shared/wire`).
//!
//! One concept per module:
//! - [`geometry`]: points, poses, disks, the field, the disk grid index, free space;
//! - [`formation`]: ideal slots (the paper's equation 2);
//! - [`vocabulary`]: the words every other part speaks (bodies, moves, agents, controllers
//!   and their settings, capacities); a leaf, so the modules form no import cycle;
//! - [`best_point`]: the exact best point (Theorem 1) with reachability;
//! - [`disk_path`]: shortest collision-free path for a point among disks;
//! - [`curve`]: curvature-bounded paths (arcs and lines) between poses;
//! - [`reeds_shepp`] and [`dubins`]: the shortest such paths;
//! - [`hybrid_astar`]: the formation centre's planner;
//! - [`kinematics`]: moves a robot with a heading can drive (a unicycle's), and their checks;
//! - [`cbf`]: the control-barrier-function controllers and their exact 2-D QP;
//! - [`orca`]: the reactive baseline ORCA (RVO2, on `dodgy_2d`), cut to stay safe;
//! - [`moving_obstacle`]: obstacles driven along routes, and when they move;
//! - [`maps`]: occupancy-grid maps (ROS map_server YAML with a PGM or PNG image) and
//!   their blocked cells merged into exact polygon outlines;
//! - [`course`]: the centre's course in a changing world (obstacles found on the way,
//!   online replanning, waits);
//! - [`scenario`]: the TOML scenario model and its validation;
//! - [`tracking`]: where an agent with a top speed aims, knowing where its slot will be;
//! - [`turn`]: one agent's turn: the paper's best-point controller, and every controller behind
//!   one interface, shared by simulation and agents;
//! - [`groups`]: parallel turns: which agents may move at once;
//! - [`sensing`]: which agents an agent senses (limited sensing);
//! - [`safety`]: the safety invariant checked with plain geometry;
//! - [`world`]: the world a turn reads: where every agent stands and faces, who is alive;
//! - [`record`]: the record of a run and its figures, and its referee (the recorder);
//! - [`step_loop`]: the step, written once for the reference simulation and the run over
//!   agent processes;
//! - [`simulate`]: the in-process reference simulation;
//! - [`input_file`]: reading a file handed in, with a size bound that holds for devices,
//!   FIFOs and sparse files;
//! - [`output_file`]: writing into a folder that may hold someone else's links.
#![warn(missing_docs)]

pub mod control;
pub mod course;
pub mod geometry;
pub mod groups;
pub mod input_file;
pub mod maps;
pub mod moving_obstacle;
mod ordered;
pub mod output_file;
pub mod paths;
pub mod record;
pub mod scenario;
pub mod sensing;
pub mod simulate;
pub mod step_loop;
pub mod world;
