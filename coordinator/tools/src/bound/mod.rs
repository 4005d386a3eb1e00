//! `coordinator bound [SCENARIO]`: the physical limit of tracking under a top speed and
//! among the static obstacles.
//!
//! Each agent alone (no mate), starting at its slot and knowing the whole centre path,
//! can do no better than the track that solves
//!
//! ```text
//! minimise   sum_k t_k                  k = 1 .. T (s_k: its slot at step k)
//! subject to |x_k - s_k| <= t_k
//!            f_k <= t_k                  f_k: how far s_k lies from where the agent fits
//!            |x_k - x_(k-1)| <= c        x_0: its slot at step 0, c: its top speed
//! ```
//!
//! a second-order cone programme, solved by Clarabel (an interior-point solver, pure
//! Rust; `cone.rs`). The floor `f_k` is the distance from the slot to the nearest point
//! where the agent's disk lies inside the field and clear of every static obstacle
//! (disks, known or found on the way, and polygons, true sizes): wherever the agent is
//! at step `k`, its deviation is at least that. (Keeping `x_k` itself out of the
//! obstacles would not be convex; the floor is its convex part.) Where a slot enters an
//! obstacle, a second bound keeps every `x_k` out of the obstacles, on a grid of cells
//! (`grid.rs`: dynamic programming whose every relaxation only lowers it), and the
//! greater of the two counts. The optimum over `T` and the agents is a
//! lower bound of the mean deviation any controller can reach, mates (and moving
//! obstacles) only adding to it. The same constraints with one `t` for every `k`,
//! minimising `t`, bound the largest deviation from below. The bound with the top speed
//! alone (no floor) and with the obstacles alone (the floors' mean) are reported too, to
//! say which dominates. The reference simulation is run first, and its figures are
//! reported against the bounds; the bounds are taken along the centre it followed (the
//! plan, or in a changing world the plan as it was mended on the way), whose slots its
//! deviation is measured from.
//!
//! With `--alone` each agent is also run alone (`alone.rs`: the method with no mate) and
//! its best track searched on a lattice (`shared::control::tracking::best_track_on_lattice`): an achievable track, so the least
//! deviation an agent alone can have lies between its bound and that track, and the
//! formation's excess over the agents alone is what the mates cost.
//!
//! With `--together` the formation's tracks are searched together (`together.rs`: each
//! agent in turn on the same lattice, clear of the tracks before it): an achievable
//! formation, mates included, so the least deviation any method can give the formation
//! lies between the bound and it.

use anyhow::Context;
use serde::Serialize;
use shared::control::best_point::nearest_free_point;
use shared::geometry::{FreeSpace, Point, Pose, Vector};
use shared::run::simulate::simulate_along;
use shared::world::scenario::Scenario;

mod alone;
mod args;
mod cone;
mod grid;
mod together;
pub use args::BoundArgs;

pub use alone::{AgentAlone, DEFAULT_POINTS_PER_MOVE, StaticSpace, agent_alone};
pub use cone::{Objective, optimal_track};
pub use grid::{Grid, least_deviation_round_obstacles};
pub use together::{ORDERS, Together, best_formation_together, tracks_csv};

use runner::CliError;
use runner::loaded::load_and_plan;

/// Why a bound could not be computed.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum BoundError {
    /// The solver did not reach an optimum.
    #[error("the cone programme was not solved: {0}")]
    NotSolved(String),
    /// The top speed is not a positive finite number.
    #[error("top speed {0} m is not a positive finite number")]
    BadSpeed(f64),
}

/// How far `slot` (in the scenario's frame) lies from the nearest point where the agent
/// fits, `space` being the free space of its centre in a frame offset by `offset` (the
/// field inset by its radius, the obstacles grown by it): 0 where it fits there already,
/// 0 too where it fits nowhere (no bound to give).
fn floor_in_m(space: &FreeSpace, offset: &Vector, slot: &Point) -> f64 {
    let query = slot - offset;
    nearest_free_point(space, &query).map_or(0.0, |free| (free - query).norm())
}

/// The floors at `slots` in one agent's static `world` ([`floor_in_m`]).
fn obstacle_floors_m(world: &StaticSpace, slots: &[Point]) -> Vec<f64> {
    world.with_free_space(|space| {
        slots
            .iter()
            .map(|s| floor_in_m(space, &world.offset, s))
            .collect()
    })
}

/// The least summed deviation (metres) of an agent in its static `world` with every
/// position out of the obstacles, bounded on a grid ([`least_deviation_round_obstacles`]);
/// the other arguments as [`optimal_track`]'s. The grid's relaxations only lower it, and
/// an agent that can follow no track (every cell in reach blocked) gives no bound: 0.
fn way_round_m(
    world: &StaticSpace,
    start: &Point,
    slots: &[Point],
    floors_m: &[f64],
    max_step_m: f64,
) -> f64 {
    let to_frame = |p: &Point| p - world.offset;
    let slots: Vec<Point> = slots.iter().map(to_frame).collect();
    let bound_m = world.with_free_space(|space| {
        least_deviation_round_obstacles(
            &to_frame(start),
            &slots,
            floors_m,
            max_step_m,
            Grid::for_speed(max_step_m),
            |p, radius_m| space.is_free(p, radius_m),
        )
    });
    if bound_m.is_finite() { bound_m } else { 0.0 }
}

/// One agent's bounds.
#[derive(Clone, Debug, Serialize)]
pub struct AgentBound {
    /// The agent.
    pub agent: usize,
    /// Its top speed (`null`: none: only the obstacles bound it).
    pub max_step_m: Option<f64>,
    /// The least mean deviation over the steps, in metres.
    pub mean_deviation_m: f64,
    /// The least largest deviation, in metres.
    pub max_deviation_m: f64,
    /// The least mean deviation the top speed alone forces (no obstacle), in metres.
    pub speed_mean_deviation_m: f64,
    /// The least mean deviation the obstacles alone force (the floors' mean), in metres.
    pub obstacle_mean_deviation_m: f64,
    /// The least mean deviation with every position kept out of the obstacles (the way
    /// round them, bounded on a grid: `least_deviation_on_grid`), in metres; `null`
    /// where it is not computed: without a top speed, or where the slot never enters an
    /// obstacle.
    pub way_round_mean_deviation_m: Option<f64>,
}

/// What `bound` prints.
#[derive(Clone, Debug, Serialize)]
pub struct BoundReport {
    /// Scenario name.
    pub scenario: String,
    /// Agents.
    pub agents: usize,
    /// Steps of the centre path (after step 0).
    pub steps: usize,
    /// The least mean deviation any controller can reach (every agent alone), in metres.
    pub bound_mean_deviation_m: f64,
    /// The least largest deviation any controller can reach, in metres.
    pub bound_max_deviation_m: f64,
    /// The least mean deviation the top speeds alone force (no obstacle), in metres.
    pub speed_bound_mean_deviation_m: f64,
    /// The least mean deviation the static obstacles alone force, in metres.
    pub obstacle_bound_mean_deviation_m: f64,
    /// The reference simulation's mean deviation (the multi-process run's, to the bit).
    pub mean_deviation_m: f64,
    /// The reference simulation's largest deviation.
    pub max_deviation_m: f64,
    /// `mean_deviation_m / bound_mean_deviation_m` (`null` when the bound is 0).
    pub mean_ratio: Option<f64>,
    /// `max_deviation_m / bound_max_deviation_m` (`null` when the bound is 0).
    pub max_ratio: Option<f64>,
    /// Collisions of the reference simulation (0 in a safe run).
    pub collisions: usize,
    /// Each agent's bounds.
    pub per_agent: Vec<AgentBound>,
    /// With `--alone`: each agent alone; `null` without.
    pub alone: Option<AloneReport>,
    /// With `--together`: the formation's tracks searched together (each agent in turn,
    /// clear of those before it: achievable with the mates); `null` without, or when no
    /// order of the search gave every agent a track (or an agent has no top speed).
    pub together: Option<Together>,
    /// With `--alone` or `--together`: the searches' lattice points per top-speed move
    /// (`--lattice-per-move`); `null` without.
    pub lattice_per_move: Option<u32>,
}

/// Each agent alone (`bound --alone`), over the agents.
#[derive(Clone, Debug, Serialize)]
pub struct AloneReport {
    /// The method's mean deviation with each agent alone, in metres.
    pub mean_deviation_m: f64,
    /// The mean deviation of the best tracks found alone (an agent without a top speed
    /// reaches its bound), in metres; `null` if the search found no track for an agent.
    pub searched_mean_deviation_m: Option<f64>,
    /// What the mates add: the formation's mean deviation minus the agents' alone, in
    /// metres.
    pub mates_m: f64,
    /// Each agent alone.
    pub per_agent: Vec<AgentAlone>,
}

/// The bounds of every agent of `scenario` along `centre_path`, the agents shared among
/// the cores (round-robin: the costly ones, whose slots enter obstacles, often come
/// together); `done` is called as each agent's are ready (a progress bar).
pub fn agent_bounds(
    scenario: &Scenario,
    centre_path: &[Pose],
    done: impl Fn() + Sync,
) -> Result<Vec<AgentBound>, BoundError> {
    let done = &done;
    let agents = scenario.agents.len();
    let workers = std::thread::available_parallelism()
        .map_or(1, |n| n.get())
        .clamp(1, agents.max(1));
    let mut bounds: Vec<(usize, Result<AgentBound, BoundError>)> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..workers)
            .map(|worker| {
                s.spawn(move || {
                    (worker..agents)
                        .step_by(workers)
                        .map(|agent| {
                            let bound = agent_bound(scenario, centre_path, agent);
                            done();
                            (agent, bound)
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        handles
            .into_iter()
            .flat_map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect()
    });
    bounds.sort_by_key(|(agent, _)| *agent);
    bounds.into_iter().map(|(_, bound)| bound).collect()
}

/// The bounds of agent `agent` of `scenario` along `centre_path`.
fn agent_bound(
    scenario: &Scenario,
    centre_path: &[Pose],
    agent: usize,
) -> Result<AgentBound, BoundError> {
    let spec = &scenario.agents[agent];
    let (start, slots) = match centre_path.split_first() {
        Some((first, rest)) => (
            spec.slot.ideal_position(first),
            rest.iter().map(|c| spec.slot.ideal_position(c)).collect(),
        ),
        None => (Point::origin(), Vec::new()),
    };
    let world = StaticSpace::new(scenario, spec);
    let floors_m = obstacle_floors_m(&world, &slots);
    let steps = slots.len().max(1) as f64;
    let obstacle_mean_m = floors_m.iter().sum::<f64>() / steps;
    let Some(cap) = spec.max_step_m else {
        // It can be anywhere each step: the nearest point where it fits.
        return Ok(AgentBound {
            agent,
            max_step_m: None,
            mean_deviation_m: obstacle_mean_m,
            max_deviation_m: floors_m.iter().copied().fold(0.0, f64::max),
            speed_mean_deviation_m: 0.0,
            obstacle_mean_deviation_m: obstacle_mean_m,
            way_round_mean_deviation_m: None,
        });
    };
    let (sum_m, _) = optimal_track(&start, &slots, &floors_m, cap, Objective::Sum)?;
    let (max_m, _) = optimal_track(&start, &slots, &floors_m, cap, Objective::Max)?;
    let (speed_sum_m, _) = optimal_track(&start, &slots, &[], cap, Objective::Sum)?;
    // The way round costs nothing more where the slot never enters an obstacle
    // (and its grid is the costly part): only where it does.
    let way_round_sum_m = floors_m
        .iter()
        .any(|f| *f > 0.0)
        .then(|| way_round_m(&world, &start, &slots, &floors_m, cap));
    // Each part is a lower bound too; the solver's answers are exact only to its
    // tolerance, so the whole is never reported below a part.
    let floors_sum_m: f64 = floors_m.iter().sum();
    let largest_floor_m = floors_m.iter().copied().fold(0.0, f64::max);
    let sum_m = sum_m
        .max(speed_sum_m)
        .max(floors_sum_m)
        .max(way_round_sum_m.unwrap_or(0.0));
    Ok(AgentBound {
        agent,
        max_step_m: Some(cap),
        mean_deviation_m: sum_m / steps,
        max_deviation_m: max_m.max(largest_floor_m),
        speed_mean_deviation_m: speed_sum_m / steps,
        obstacle_mean_deviation_m: obstacle_mean_m,
        way_round_mean_deviation_m: way_round_sum_m.map(|m| m / steps),
    })
}

/// Carry out `bound`: one JSON object on stdout, one line on stderr.
pub fn execute(args: &BoundArgs) -> Result<(), CliError> {
    let loaded = load_and_plan(args.scenario.as_deref())?;
    let scenario = &loaded.scenario;
    let run = simulate_along(scenario, &loaded.centre_path).context("the reference simulation")?;
    let summary = run.summary();
    // The centre the run followed: the plan, or in a changing world the plan as it was
    // mended on the way (its deviation is measured from those slots).
    let followed: Vec<Pose> = run.steps.iter().map(|s| s.centre).collect();
    let bar = progress_bar(scenario.agents.len(), "bounding each agent");
    let per_agent = agent_bounds(scenario, &followed, || bar.inc(1))
        .context("the tracking bound")
        .map_err(CliError::Other)?;
    bar.finish_and_clear();
    let n = per_agent.len().max(1) as f64;
    let bound_mean = per_agent.iter().map(|a| a.mean_deviation_m).sum::<f64>() / n;
    let bound_max = per_agent
        .iter()
        .map(|a| a.max_deviation_m)
        .fold(0.0, f64::max);
    let mean_of = |f: fn(&AgentBound) -> f64| per_agent.iter().map(f).sum::<f64>() / n;
    let speed_mean = mean_of(|a| a.speed_mean_deviation_m);
    let obstacle_mean = mean_of(|a| a.obstacle_mean_deviation_m);
    let per_move = args.lattice_per_move.unwrap_or(DEFAULT_POINTS_PER_MOVE);
    let alone = if args.alone {
        Some(alone_report(
            scenario,
            &followed,
            &per_agent,
            summary.mean_deviation_m,
            per_move,
        )?)
    } else {
        None
    };
    let together = if args.together {
        let bar = indicatif::ProgressBar::new_spinner().with_message(format!(
            "searching the formation's tracks together, {} orders",
            ORDERS.len()
        ));
        bar.enable_steady_tick(std::time::Duration::from_millis(200));
        let found = best_formation_together(scenario, &followed, &per_agent, per_move);
        bar.finish_and_clear();
        if let (Some(path), Some(found)) = (&args.together_csv, &found) {
            let bytes = tracks_csv(found).context("the tracks found together as CSV")?;
            runner::output::write_atomically(path, &bytes)
                .with_context(|| format!("writing {}", path.display()))?;
        }
        found
    } else {
        None
    };
    let ratio = |ours: f64, bound: f64| (bound > 0.0).then(|| ours / bound);
    let report = BoundReport {
        scenario: summary.scenario.clone(),
        agents: summary.agents,
        steps: followed.len().saturating_sub(1),
        bound_mean_deviation_m: bound_mean,
        bound_max_deviation_m: bound_max,
        speed_bound_mean_deviation_m: speed_mean,
        obstacle_bound_mean_deviation_m: obstacle_mean,
        mean_deviation_m: summary.mean_deviation_m,
        max_deviation_m: summary.max_deviation_m,
        mean_ratio: ratio(summary.mean_deviation_m, bound_mean),
        max_ratio: ratio(summary.max_deviation_m, bound_max),
        collisions: summary.collisions,
        per_agent,
        alone,
        together,
        lattice_per_move: (args.alone || args.together).then_some(per_move),
    };
    // Three digits, so that a ratio just above a target (1.503x) does not read as 1.50x.
    let show = |r: Option<f64>| r.map_or("-".to_string(), |r| format!("{r:.3}x"));
    // A bound of a few micrometres is shown as such, not as 0.0000.
    let metres = |m: f64| {
        if m == 0.0 || m >= 1e-3 {
            format!("{m:.4}")
        } else {
            format!("{m:.1e}")
        }
    };
    eprintln!(
        "{}: mean deviation {:.4} m against the bound {} m ({}; the top speed alone {} m, the obstacles alone {} m), max {:.3} m against {} m ({})",
        report.scenario,
        report.mean_deviation_m,
        metres(report.bound_mean_deviation_m),
        show(report.mean_ratio),
        metres(report.speed_bound_mean_deviation_m),
        metres(report.obstacle_bound_mean_deviation_m),
        report.max_deviation_m,
        metres(report.bound_max_deviation_m),
        show(report.max_ratio)
    );
    if let Some(alone) = &report.alone {
        let searched = alone.searched_mean_deviation_m;
        eprintln!(
            "{}: each agent alone {:.4} m, the best track found alone {} m ({}), the mates add {:.4} m",
            report.scenario,
            alone.mean_deviation_m,
            searched.map_or("-".to_string(), |m| format!("{m:.4}")),
            show(searched.and_then(|m| ratio(alone.mean_deviation_m, m))),
            alone.mates_m,
        );
    }
    if args.together {
        match &report.together {
            Some(t) => eprintln!(
                "{}: the formation searched together {:.4} m (the bound's {}; ours is {} it)",
                report.scenario,
                t.mean_deviation_m,
                show(ratio(t.mean_deviation_m, report.bound_mean_deviation_m)),
                show(ratio(report.mean_deviation_m, t.mean_deviation_m)),
            ),
            None => eprintln!(
                "{}: the formation searched together: no track for every agent in any order (or an agent without a top speed)",
                report.scenario
            ),
        }
    }
    let json = serde_json::to_string_pretty(&report).context("writing the report")?;
    println!("{json}");
    Ok(())
}

/// A progress bar on stderr over `agents`, headed `what`.
fn progress_bar(agents: usize, what: &str) -> indicatif::ProgressBar {
    indicatif::ProgressBar::new(agents as u64).with_style(
        indicatif::ProgressStyle::with_template(&format!(
            "{what} {{bar:30}} {{pos}}/{{len}} {{eta}}"
        ))
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    )
}

/// Each agent of `scenario` alone along `centre_path`, with a progress bar on stderr;
/// `bounds` are the agents' bounds, `formation_mean_m` the whole formation's mean
/// deviation, `per_move` the search's lattice points per top-speed move.
fn alone_report(
    scenario: &Scenario,
    centre_path: &[Pose],
    bounds: &[AgentBound],
    formation_mean_m: f64,
    per_move: u32,
) -> Result<AloneReport, CliError> {
    let bar = progress_bar(scenario.agents.len(), "each agent alone");
    let per_agent = bounds
        .iter()
        .map(|b| {
            let agent = b.agent;
            let alone = agent_alone(scenario, centre_path, agent, b.max_deviation_m, per_move)
                .with_context(|| format!("agent {agent} alone"))
                .map_err(CliError::Other);
            bar.inc(1);
            alone
        })
        .collect::<Result<Vec<_>, _>>()?;
    bar.finish_and_clear();
    let n = per_agent.len().max(1) as f64;
    let mean_deviation_m = per_agent.iter().map(|a| a.mean_deviation_m).sum::<f64>() / n;
    // Without a top speed an agent can stand at its slot's nearest free point every
    // step: its bound is achieved.
    let searched: Option<Vec<f64>> = per_agent
        .iter()
        .zip(bounds)
        .map(|(a, b)| match b.max_step_m {
            Some(_) => a.searched_mean_deviation_m,
            None => Some(b.mean_deviation_m),
        })
        .collect();
    Ok(AloneReport {
        mean_deviation_m,
        searched_mean_deviation_m: searched.map(|s| s.iter().sum::<f64>() / n),
        mates_m: formation_mean_m - mean_deviation_m,
        per_agent,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use shared::geometry::{Disk, DiskGrid, Field, PolygonLayer};

    /// A slot the agent can follow: both bounds are 0 and the track is the slots.
    #[test]
    fn a_followable_slot_costs_nothing() {
        let start = Point::new(0.0, 0.0);
        let slots: Vec<Point> = (1..=5).map(|k| Point::new(0.4 * k as f64, 0.0)).collect();
        let (sum, track) = optimal_track(&start, &slots, &[], 0.5, Objective::Sum).unwrap();
        assert!(sum < 1e-6, "{sum}");
        for (p, s) in track.iter().zip(&slots) {
            assert!((p - s).norm() < 1e-5);
        }
        let (max, _) = optimal_track(&start, &slots, &[], 0.5, Objective::Max).unwrap();
        assert!(max < 1e-6, "{max}");
    }

    /// A slot running away at 1 m a step from an agent that makes 0.5 m: it falls
    /// behind by 0.5 m a step whatever it does, so the summed deviation is
    /// 0.5 (1 + 2 + ... + T) and the largest 0.5 T.
    #[test]
    fn a_runaway_slot_gives_the_closed_form() {
        let start = Point::new(0.0, 0.0);
        let t = 8;
        let slots: Vec<Point> = (1..=t).map(|k| Point::new(k as f64, 0.0)).collect();
        let (sum, _) = optimal_track(&start, &slots, &[], 0.5, Objective::Sum).unwrap();
        let exact = 0.5 * (t * (t + 1) / 2) as f64;
        assert!((sum - exact).abs() < 1e-5 * exact, "{sum} vs {exact}");
        let (max, _) = optimal_track(&start, &slots, &[], 0.5, Objective::Max).unwrap();
        assert!((max - 0.5 * t as f64).abs() < 1e-5, "{max}");
    }

    /// The agents' own look-ahead solver (`shared::control::tracking`) finds a track no better
    /// than the optimum (it is feasible) and close to it.
    #[test]
    fn the_agents_track_solver_comes_close_to_the_optimum() {
        let start = Point::new(0.0, 0.0);
        let slots: Vec<Point> = (1..=12)
            .map(|j| {
                let a = 0.3 * j as f64;
                Point::new(5.0 * a.cos() - 5.0, 5.0 * a.sin())
            })
            .collect();
        let (best, _) = optimal_track(&start, &slots, &[], 0.8, Objective::Sum).unwrap();
        let track = shared::control::tracking::least_deviation_track(&start, &slots, 0.8, 150);
        let ours = shared::control::tracking::track_deviation_m(&track, &slots);
        assert!(ours >= best - 1e-6, "{ours} below the optimum {best}");
        assert!(ours <= best * 1.02, "{ours} against the optimum {best}");
    }

    /// The floor is the distance from the slot to where the agent's disk fits: through
    /// an obstacle, out to its circle grown by the agent's radius; outside the field,
    /// back in to the field shrunk by it; elsewhere nothing.
    #[test]
    fn the_floor_is_the_distance_to_where_the_agent_fits() {
        let r = 0.5;
        let offset = Vector::new(r, r);
        let field = Field::new(20.0 - 2.0 * r, 10.0 - 2.0 * r);
        let obstacles = DiskGrid::new(vec![Disk::new(5.0 - r, 5.0 - r, 1.0 + r)]);
        let polygons = PolygonLayer::new(Vec::new());
        let layers = [&obstacles];
        let space = FreeSpace::new(field, &layers).with_polygons(&polygons);
        let floor = |x: f64, y: f64| floor_in_m(&space, &offset, &Point::new(x, y));
        assert!((floor(5.0, 5.0) - 1.5).abs() < 1e-9);
        assert!((floor(5.9, 5.0) - 0.6).abs() < 1e-9);
        assert_eq!(floor(7.0, 5.0), 0.0);
        assert!((floor(19.8, 5.0) - 0.3).abs() < 1e-9);
        assert!((floor(-1.0, 5.0) - 1.5).abs() < 1e-9);
    }

    /// A slot the agent could follow but for the floors: the optimum is the floors'
    /// sum, and the largest deviation their largest.
    #[test]
    fn floors_add_to_a_followable_slot_exactly() {
        let start = Point::new(0.0, 0.0);
        let slots: Vec<Point> = (1..=5).map(|k| Point::new(0.4 * k as f64, 0.0)).collect();
        let floors = [0.0, 0.3, 0.2, 0.0, 0.1];
        let (sum, track) = optimal_track(&start, &slots, &floors, 0.5, Objective::Sum).unwrap();
        assert!((sum - 0.6).abs() < 1e-6, "{sum}");
        for (k, (p, s)) in track.iter().zip(&slots).enumerate() {
            assert!(
                (p - s).norm() <= floors[k] + 1e-5,
                "step {k}: {p} against {s}"
            );
        }
        let (max, _) = optimal_track(&start, &slots, &floors, 0.5, Objective::Max).unwrap();
        assert!((max - 0.3).abs() < 1e-6, "{max}");
    }

    /// The floors and the top speed together bound more than either alone: a slot that
    /// runs away while passing an obstacle.
    #[test]
    fn floors_and_the_top_speed_add_up() {
        let start = Point::new(0.0, 0.0);
        let slots: Vec<Point> = (1..=6).map(|k| Point::new(k as f64, 0.0)).collect();
        let floors = [0.0, 0.0, 0.0, 0.0, 0.0, 5.0];
        let (speed, _) = optimal_track(&start, &slots, &[], 0.5, Objective::Sum).unwrap();
        let (both, _) = optimal_track(&start, &slots, &floors, 0.5, Objective::Sum).unwrap();
        // The speed alone: 0.5 + 1 + ... + 3 = 10.5; at step 6 the agent is 3 m behind,
        // below the floor of 5 m, which adds 2 m.
        assert!((speed - 10.5).abs() < 1e-5, "{speed}");
        assert!((both - 12.5).abs() < 1e-5, "{both}");
    }

    #[test]
    fn a_bad_speed_is_refused() {
        let p = Point::new(0.0, 0.0);
        assert_eq!(
            optimal_track(&p, &[p], &[], 0.0, Objective::Sum).unwrap_err(),
            BoundError::BadSpeed(0.0)
        );
    }
}
