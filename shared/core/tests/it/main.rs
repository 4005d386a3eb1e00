//! The integration tests of the shared library (`formation-shared`), in one test binary:
//! its algorithms against independent oracles, their properties on random inputs
//! (proptest), and the reference simulation on scenarios. One module per concept;
//! `support` holds the helpers the modules share.
//!
//! One binary rather than one per file: the library and the helpers are compiled once and
//! the test build links once. Run a single module with
//! `cargo test -p formation-shared --test it -- MODULE::`.
//!
//! proptest's regressions of a module `it/NAME.rs` are in
//! `shared/core/tests/proptest-regressions/NAME.txt`, not beside the module: proptest finds
//! this `main.rs` above the module and keeps them in a `proptest-regressions` folder beside
//! `it/`.

mod support;

mod car_scenarios;
mod cbf;
mod changing_world;
mod changing_world_random;
mod escape_among_polygons;
mod heading_figures;
mod hybrid_astar;
mod look_ahead_tracking;
mod module_graph;
mod oracle_best_point;
mod oracle_reeds_shepp;
mod orca;
mod prop_best_point;
mod prop_car;
mod prop_cbf;
mod prop_check_move;
mod prop_curves;
mod prop_disk_path;
mod prop_hybrid_astar;
mod prop_maps;
mod prop_polygons;
mod prop_simultaneous;
mod prop_survival_grid;
mod prop_time_model;
mod prop_unicycle;
mod replan;
mod resolved_round_trip;
mod scenario_doc;
mod simulate_scenarios;
mod step_loop;
mod turn_order;
mod unicycle_scenarios;
