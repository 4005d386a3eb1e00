//! The CSV files of a run folder, made from a run: its rows ([`super::rows`]) in order,
//! each file with its header.

use shared::control::kinematics::{car_piece, driving_headings};
use shared::control::vocabulary::Kinematics;
use shared::geometry::{Point, Pose, wrap_angle_rad};
use shared::run::record::Run;
use shared::world::scenario::Scenario;

use super::csv_format::{csv_bytes, csv_bytes_with_columns, header};
use super::rows::{
    MoveRow, ObstacleKind, ObstacleRow, PathRow, PlanReason, PlanRow, TrajectoryRow,
};

/// The centre path as CSV: `step,x_m,y_m,heading_rad` ([`PathRow`]), full precision
/// (the shortest decimal form that reads back to the same bits). In a run folder this is
/// the path the centre actually followed ([`Run::centre_path`]: one pose per step, a wait
/// repeats the pose); `coordinator plan` writes the planned path in this form.
pub fn path_csv(path: &[Pose]) -> anyhow::Result<Vec<u8>> {
    csv_bytes(path.iter().enumerate().map(|(step, p)| PathRow {
        step,
        x_m: p.x_m,
        y_m: p.y_m,
        heading_rad: p.heading_rad,
    }))
}

/// The trajectory as CSV, one row per agent per step ([`TrajectoryRow`],
/// `docs/outputs.md`), full precision.
pub fn trajectory_csv(run: &Run) -> anyhow::Result<Vec<u8>> {
    // The heading columns only when some agent has a heading: a holonomic run's file is
    // as it always was.
    let headings = run
        .steps
        .iter()
        .any(|s| s.agents.iter().any(|a| a.heading_rad.is_some()));
    let columns = header::<TrajectoryRow>().len() - if headings { 0 } else { 2 };
    csv_bytes_with_columns(
        run.steps.iter().flat_map(|s| {
            s.agents
                .iter()
                .enumerate()
                .map(move |(agent, a)| TrajectoryRow {
                    heading_rad: headings.then_some(a.heading_rad),
                    heading_error_rad: headings.then(|| {
                        a.heading_rad
                            .map(|h| shared::geometry::wrap_angle_rad(h - s.centre.heading_rad))
                    }),
                    step: s.step,
                    agent,
                    x: a.position.x,
                    y: a.position.y,
                    slot_x: a.slot.x,
                    slot_y: a.slot.y,
                    best_x: a.best.x,
                    best_y: a.best.y,
                    deviation_m: a.deviation_m,
                    clearance_m: a.clearance_m,
                    status: a.status,
                    alive: a.alive,
                })
        }),
        columns,
    )
}

/// Every move's polyline as CSV: `step,agent,index,x,y` ([`MoveRow`], one row per
/// waypoint), and, when some agent of `scenario` has a heading, the exact primitive that
/// reaches each waypoint: the heading there, the signed length and the curvature of the
/// arc from the waypoint before (a unicycle drives straight segments, turning in place
/// between them; each chord of a car stands for exactly one arc,
/// [`shared::control::kinematics::car_piece`]).
pub fn moves_csv(scenario: &Scenario, run: &Run) -> anyhow::Result<Vec<u8>> {
    let headings = scenario.agents.iter().any(|a| a.kinematics.has_heading());
    let columns = header::<MoveRow>().len() - if headings { 0 } else { 3 };
    let mut rows = Vec::new();
    for (i, s) in run.steps.iter().enumerate() {
        for (agent, a) in s.agents.iter().enumerate() {
            // The heading it started the step with: where it faced at the step before.
            let start_rad = i
                .checked_sub(1)
                .and_then(|b| run.steps[b].agents.get(agent))
                .and_then(|b| b.heading_rad)
                .or(a.heading_rad);
            let kinematics = scenario.agents.get(agent).map(|spec| spec.kinematics);
            let primitives = match (headings, kinematics, start_rad) {
                (true, Some(k), Some(h)) if i > 0 => {
                    move_primitives(&k, h, &a.waypoints, a.heading_rad)
                }
                _ => Vec::new(),
            };
            for (index, p) in a.waypoints.iter().enumerate() {
                let primitive = primitives.get(index).copied();
                // At step 0 (no move yet) its first heading.
                let heading_rad = primitive
                    .map(|m| m.heading_rad)
                    .or(start_rad.filter(|_| index == 0));
                rows.push(MoveRow {
                    step: s.step,
                    agent,
                    index,
                    x: p.x,
                    y: p.y,
                    heading_rad: headings.then_some(heading_rad),
                    drive_m: headings.then(|| primitive.and_then(|m| m.drive_m)),
                    curvature_per_m: headings.then(|| primitive.and_then(|m| m.curvature_per_m)),
                });
            }
        }
    }
    csv_bytes_with_columns(rows, columns)
}

/// The primitive that reaches one waypoint of a move ([`move_primitives`]).
#[derive(Clone, Copy)]
struct Primitive {
    heading_rad: f64,
    /// Absent at the move's start.
    drive_m: Option<f64>,
    curvature_per_m: Option<f64>,
}

/// The primitive reaching each of `waypoints`, driven by an agent of `kinematics` from
/// `start_rad` and ending facing `end_rad` (empty for a holonomic agent).
fn move_primitives(
    kinematics: &Kinematics,
    start_rad: f64,
    waypoints: &[Point],
    end_rad: Option<f64>,
) -> Vec<Primitive> {
    let first = Primitive {
        heading_rad: wrap_angle_rad(start_rad),
        drive_m: None,
        curvature_per_m: None,
    };
    match *kinematics {
        Kinematics::Holonomic => Vec::new(),
        Kinematics::Car { .. } => {
            let mut heading_rad = start_rad;
            let mut out = vec![first];
            for w in waypoints.windows(2) {
                let piece = car_piece(heading_rad, &w[0], &w[1]);
                heading_rad += piece.turn_rad;
                let sign = if piece.reverse { -1.0 } else { 1.0 };
                out.push(Primitive {
                    heading_rad: wrap_angle_rad(heading_rad),
                    drive_m: Some(sign * piece.length_m),
                    curvature_per_m: Some(if piece.length_m > 0.0 {
                        piece.turn_rad / piece.length_m
                    } else {
                        0.0
                    }),
                });
            }
            out
        }
        Kinematics::Unicycle { reverse, .. } => {
            let (segment_headings, _) = driving_headings(start_rad, waypoints, end_rad, reverse);
            let mut heading_rad = wrap_angle_rad(start_rad);
            let mut out = vec![first];
            for (w, h) in waypoints.windows(2).zip(segment_headings) {
                let d = w[1] - w[0];
                if let Some(h) = h {
                    heading_rad = h;
                }
                let ahead = d.x * heading_rad.cos() + d.y * heading_rad.sin();
                out.push(Primitive {
                    heading_rad,
                    drive_m: Some(if ahead < 0.0 { -d.norm() } else { d.norm() }),
                    curvature_per_m: Some(0.0),
                });
            }
            out
        }
    }
}

/// The centre's plans as CSV, one row per pose: `plan,step,reason,x_m,y_m,heading_rad`
/// ([`PlanRow`]). Plan 0 is `first_plan` (step 0, reason [`PlanReason::First`]); plans
/// 1, 2, ... are the replans that found a path, in order, each from the pose the centre
/// stood at when it was planned at the start of `step` (reasons `found-obstacle`,
/// `moving-obstacle`). Replans that found no path (the centre waited) have no rows:
/// `summary.json` `replans` lists them all.
pub fn plans_csv(first_plan: &[Pose], run: &Run) -> anyhow::Result<Vec<u8>> {
    let replans = run
        .course
        .replans
        .iter()
        .filter(|r| r.found)
        .map(|r| (r.step, PlanReason::Replan(r.reason), r.path.as_slice()));
    let plans = std::iter::once((0, PlanReason::First, first_plan)).chain(replans);
    csv_bytes(plans.enumerate().flat_map(|(plan, (step, reason, poses))| {
        poses.iter().map(move |p| PlanRow {
            plan,
            step,
            reason,
            x_m: p.x_m,
            y_m: p.y_m,
            heading_rad: p.heading_rad,
        })
    }))
}

/// The obstacles of a changing world as CSV:
/// `step,kind,index,x_m,y_m,radius_m,known_from_step` ([`ObstacleRow`]). First one row
/// per moving obstacle per recorded step (kind `moving`, `index` its place in
/// `[[obstacles.moving]]`, where it stands during the step, `known_from_step` empty: the
/// centre's planner knows their routes); then one row per `[[obstacles.unknown]]`
/// obstacle (kind `unknown`, `step` empty, `known_from_step` the step it joined the known
/// map, empty when never). A static world gives the header alone.
pub fn obstacles_csv(scenario: &Scenario, run: &Run) -> anyhow::Result<Vec<u8>> {
    let moving = run.steps.iter().flat_map(|s| {
        s.moving
            .iter()
            .zip(&scenario.moving)
            .enumerate()
            .map(|(index, (p, m))| ObstacleRow {
                step: Some(s.step),
                kind: ObstacleKind::Moving,
                index,
                x_m: p.x,
                y_m: p.y,
                radius_m: m.radius_m,
                known_from_step: None,
            })
    });
    let unknown = scenario
        .unknown
        .iter()
        .enumerate()
        .map(|(index, o)| ObstacleRow {
            step: None,
            kind: ObstacleKind::Unknown,
            index,
            x_m: o.centre.x,
            y_m: o.centre.y,
            radius_m: o.radius_m,
            known_from_step: run.course.found_at.get(index).copied().flatten(),
        });
    csv_bytes(moving.chain(unknown))
}
