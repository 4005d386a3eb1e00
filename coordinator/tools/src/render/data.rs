//! Reading a run directory written by `coordinator run` back into memory: the scenario
//! (obstacles included, rebuilt deterministically from `scenario.toml`), the centre path,
//! every agent's state and move at every step, the faults, and in a changing world the
//! centre's plans (`plans.csv`), the moving obstacles at every step and the unknown ones
//! with the step they became known (`obstacles.csv`). Nothing is re-planned.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use shared::geometry::{Disk, Point, Pose};
use shared::input_file::{Links, open_input, read_input_text};
use shared::run::record::AgentStep;
use shared::world::scenario::{MAX_SCENARIO_BYTES, Scenario};

pub use runner::output::FaultRecord;
use runner::output::SummaryRead;
use runner::output::rows::{
    MoveRow, ObstacleKind, ObstacleRow, PathRow, PlanReason, PlanRow, TrajectoryRow,
};

/// The files a run directory must hold, in the order they are checked.
pub const REQUIRED_FILES: [&str; 5] = [
    "scenario.toml",
    "path.csv",
    "trajectory.csv",
    "moves.csv",
    "summary.json",
];

/// Why a run directory cannot be read. Every message is one line naming the file.
#[derive(Debug, thiserror::Error)]
pub enum RunDirError {
    /// The directory itself is missing or is not a directory.
    #[error("{}: not a directory", .dir.display())]
    NotADirectory {
        /// The directory as given.
        dir: PathBuf,
    },
    /// A required file is missing.
    #[error("{}: not found (is {} a run directory written by `coordinator run`?)", .path.display(), .dir.display())]
    Missing {
        /// The missing file.
        path: PathBuf,
        /// The run directory.
        dir: PathBuf,
    },
    /// A file is present but unreadable or not what `coordinator run` writes.
    #[error("{}: {reason}", .path.display())]
    Invalid {
        /// The offending file.
        path: PathBuf,
        /// What is wrong, on one line.
        reason: String,
    },
}

/// The formation centre at one step (`path.csv`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CentrePose {
    /// The step.
    pub step: usize,
    /// The centre's pose.
    pub pose: Pose,
}

/// Every agent at the end of one step.
#[derive(Clone, Debug, PartialEq)]
pub struct StepRecord {
    /// The step.
    pub step: usize,
    /// The agents, indexed by agent id.
    pub agents: Vec<AgentStep>,
}

/// One plan of the formation centre (`plans.csv`): the first, or a replan that found a
/// path.
#[derive(Clone, Debug, PartialEq)]
pub struct PlanRecord {
    /// Its number: 0 for the first plan, then 1, 2, ... in the order planned.
    pub plan: usize,
    /// The step at whose start it was planned (0 for the first).
    pub step: usize,
    /// Why it was planned.
    pub reason: PlanReason,
    /// Its poses, one per step, from the pose the centre stood at.
    pub poses: Vec<Pose>,
}

/// Every moving obstacle during one step (`obstacles.csv`, kind `moving`).
#[derive(Clone, Debug, PartialEq)]
pub struct MovingStep {
    /// The step.
    pub step: usize,
    /// Where each moving obstacle stands, in `[[obstacles.moving]]` order.
    pub positions: Vec<Point>,
}

/// An obstacle the centre's planner did not know at the start (`obstacles.csv`, kind
/// `unknown`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UnknownRecord {
    /// The obstacle.
    pub disk: Disk,
    /// The step it joined the known map; `None` when it never did.
    pub known_from_step: Option<usize>,
}

impl UnknownRecord {
    /// Whether the centre's planner knew it during `step`.
    pub fn known_at(&self, step: usize) -> bool {
        self.known_from_step.is_some_and(|k| k <= step)
    }
}

/// A run directory, read and checked.
#[derive(Clone, Debug)]
pub struct RunData {
    /// The directory it was read from.
    pub dir: PathBuf,
    /// The scenario, rebuilt from `scenario.toml` (obstacles with their true radii).
    pub scenario: Scenario,
    /// The centre path, one pose per step, in step order.
    pub centre: Vec<CentrePose>,
    /// The steps, in step order.
    pub steps: Vec<StepRecord>,
    /// The faults, in the order the run recorded them.
    pub faults: Vec<FaultRecord>,
    /// Whether the run went through the whole centre path (`None` when not recorded).
    pub completed: Option<bool>,
    /// The centre's plans in order, the first one first (empty when the folder has no
    /// `plans.csv`).
    pub plans: Vec<PlanRecord>,
    /// The moving obstacles at every step, in step order (empty for a static world).
    pub moving: Vec<MovingStep>,
    /// The unknown obstacles, in `[[obstacles.unknown]]` order.
    pub unknown: Vec<UnknownRecord>,
}

impl RunData {
    /// Read the run directory `dir`. `plans.csv` and `obstacles.csv` are optional: run
    /// folders written before the world could change lack them, and are drawn from the
    /// scenario instead (every moving obstacle where its route puts it, the steps the
    /// unknown obstacles were found at from `summary.json`, no plan but the path followed).
    pub fn load(dir: &Path) -> Result<Self, RunDirError> {
        if !dir.is_dir() {
            return Err(RunDirError::NotADirectory {
                dir: dir.to_path_buf(),
            });
        }
        for name in REQUIRED_FILES {
            let path = dir.join(name);
            if !path.is_file() {
                return Err(RunDirError::Missing {
                    path,
                    dir: dir.to_path_buf(),
                });
            }
        }
        let scenario = read_scenario(&dir.join("scenario.toml"))?;
        let centre = read_centre(&dir.join("path.csv"))?;
        let mut steps = read_trajectory(&dir.join("trajectory.csv"), scenario.agents.len())?;
        read_moves(&dir.join("moves.csv"), &mut steps)?;
        let summary = read_summary(&dir.join("summary.json"))?;
        let plans_path = dir.join("plans.csv");
        let plans = if plans_path.is_file() {
            read_plans(&plans_path)?
        } else {
            Vec::new()
        };
        let obstacles_path = dir.join("obstacles.csv");
        let (moving, unknown) = if obstacles_path.is_file() {
            read_obstacles(&obstacles_path, &scenario)?
        } else {
            // An older run folder: the routes are in the scenario, the steps the unknown
            // obstacles were found at (if anywhere) in summary.json.
            let moving = steps
                .iter()
                .filter(|_| !scenario.moving.is_empty())
                .map(|st| MovingStep {
                    step: st.step,
                    positions: scenario
                        .moving
                        .iter()
                        .map(|m| m.position_at(st.step))
                        .collect(),
                })
                .collect();
            let unknown = scenario
                .unknown
                .iter()
                .enumerate()
                .map(|(i, &disk)| UnknownRecord {
                    disk,
                    known_from_step: summary.unknown_found_at_step.get(i).copied().flatten(),
                })
                .collect();
            (moving, unknown)
        };
        Ok(Self {
            dir: dir.to_path_buf(),
            scenario,
            centre,
            steps,
            faults: summary.faults,
            completed: summary.completed,
            plans,
            moving,
            unknown,
        })
    }

    /// Where each moving obstacle stands during `step`, or during the nearest recorded
    /// step before it; `None` before the first (or in a static world).
    pub fn moving_at(&self, step: usize) -> Option<&[Point]> {
        let i = self.moving.partition_point(|m| m.step <= step);
        self.moving
            .get(i.checked_sub(1)?)
            .map(|m| m.positions.as_slice())
    }

    /// Whether the centre replanned and took a new path at least once (more than the first
    /// plan to draw).
    pub fn replanned(&self) -> bool {
        self.plans.len() > 1
    }

    /// The last step recorded (0 for an empty run).
    pub fn last_step(&self) -> usize {
        let traj = self.steps.last().map_or(0, |s| s.step);
        let path = self.centre.last().map_or(0, |c| c.step);
        traj.max(path)
    }

    /// The centre pose at `step`, or the nearest recorded one before it.
    pub fn centre_at(&self, step: usize) -> Option<Pose> {
        let i = self.centre.partition_point(|c| c.step <= step);
        self.centre.get(i.checked_sub(1)?).map(|c| c.pose)
    }
}

fn invalid(path: &Path, reason: impl std::fmt::Display) -> RunDirError {
    RunDirError::Invalid {
        path: path.to_path_buf(),
        reason: reason.to_string().replace('\n', " "),
    }
}

/// The largest table (`trajectory.csv`, `moves.csv`, ...) or `summary.json` read, in
/// bytes: the bound of the log they are made from.
const MAX_TABLE_BYTES: u64 = runner::run_log::MAX_RUN_LOG_BYTES;

/// A file of the run folder: a regular file, not a link (the folder may be someone
/// else's), of at most `max_bytes`.
fn read_text(path: &Path, max_bytes: u64) -> Result<String, RunDirError> {
    read_input_text(path, max_bytes, Links::Refuse).map_err(|e| invalid(path, e))
}

fn read_scenario(path: &Path) -> Result<Scenario, RunDirError> {
    let text = read_text(path, MAX_SCENARIO_BYTES)?;
    // The scenario error already reads `FILE: FIELD: REASON`.
    Scenario::parse(&text, &path.display().to_string()).map_err(|e| RunDirError::Invalid {
        path: path.to_path_buf(),
        reason: e
            .to_string()
            .trim_start_matches(&format!("{}: ", path.display()))
            .to_string(),
    })
}

/// Rows of a CSV file deserialized by header name, each with its line number.
fn csv_rows<T: DeserializeOwned>(
    path: &Path,
    mut each: impl FnMut(u64, T) -> Result<(), String>,
) -> Result<(), RunDirError> {
    let file = open_input(path, MAX_TABLE_BYTES, Links::Refuse).map_err(|e| invalid(path, e))?;
    let mut reader = csv::Reader::from_reader(file);
    let headers = reader.headers().map_err(|e| invalid(path, e))?.clone();
    let mut record = csv::StringRecord::new();
    loop {
        match reader.read_record(&mut record) {
            Ok(false) => return Ok(()),
            Ok(true) => {}
            Err(e) => return Err(invalid(path, e)),
        }
        let line = record.position().map_or(0, |p| p.line());
        let row: T = record
            .deserialize(Some(&headers))
            .map_err(|e| invalid(path, format!("line {line}: {e}")))?;
        each(line, row).map_err(|reason| invalid(path, format!("line {line}: {reason}")))?;
    }
}

fn finite(name: &str, v: f64) -> Result<f64, String> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("{name} is {v}, not a finite number"))
    }
}

fn point(x_name: &str, x: f64, y_name: &str, y: f64) -> Result<Point, String> {
    Ok(Point::new(finite(x_name, x)?, finite(y_name, y)?))
}

fn read_centre(path: &Path) -> Result<Vec<CentrePose>, RunDirError> {
    let mut centre: Vec<CentrePose> = Vec::new();
    csv_rows(path, |_, r: PathRow| {
        if centre.last().is_some_and(|c| c.step >= r.step) {
            return Err(format!("step {} is out of order", r.step));
        }
        centre.push(CentrePose {
            step: r.step,
            pose: Pose::new(
                finite("x_m", r.x_m)?,
                finite("y_m", r.y_m)?,
                finite("heading_rad", r.heading_rad)?,
            ),
        });
        Ok(())
    })?;
    if centre.is_empty() {
        return Err(invalid(path, "no rows"));
    }
    Ok(centre)
}

fn read_trajectory(path: &Path, agents: usize) -> Result<Vec<StepRecord>, RunDirError> {
    let mut steps: Vec<(usize, Vec<Option<AgentStep>>)> = Vec::new();
    csv_rows(path, |_, r: TrajectoryRow| {
        if r.agent >= agents {
            return Err(format!(
                "agent {} does not exist (scenario.toml has {agents} agents)",
                r.agent
            ));
        }
        let record = AgentStep {
            position: point("x", r.x, "y", r.y)?,
            slot: point("slot_x", r.slot_x, "slot_y", r.slot_y)?,
            best: point("best_x", r.best_x, "best_y", r.best_y)?,
            deviation_m: r.deviation_m,
            clearance_m: r.clearance_m,
            status: r.status,
            alive: r.alive,
            waypoints: Vec::new(),
            heading_rad: r.heading_rad.flatten(),
        };
        match steps.last_mut() {
            Some((step, _)) if *step > r.step => {
                return Err(format!("step {} is out of order", r.step));
            }
            Some((step, _)) if *step == r.step => {}
            _ => steps.push((r.step, vec![None; agents])),
        }
        let Some((_, slots)) = steps.last_mut() else {
            return Err("internal: no step".into());
        };
        if slots[r.agent].replace(record).is_some() {
            return Err(format!(
                "agent {} appears twice in step {}",
                r.agent, r.step
            ));
        }
        Ok(())
    })?;
    if steps.is_empty() {
        return Err(invalid(path, "no rows"));
    }
    steps
        .into_iter()
        .map(|(step, slots)| {
            let have = slots.iter().filter(|a| a.is_some()).count();
            let complete: Option<Vec<AgentStep>> = slots.into_iter().collect();
            complete
                .map(|records| StepRecord {
                    step,
                    agents: records,
                })
                .ok_or_else(|| invalid(path, format!("step {step} has {have} of {agents} agents")))
        })
        .collect()
}

fn read_moves(path: &Path, steps: &mut [StepRecord]) -> Result<(), RunDirError> {
    let at: HashMap<usize, usize> = steps.iter().enumerate().map(|(i, s)| (s.step, i)).collect();
    let mut indexed: HashMap<(usize, usize), Vec<(usize, Point)>> = HashMap::new();
    csv_rows(path, |_, r: MoveRow| {
        let Some(&i) = at.get(&r.step) else {
            return Err(format!("step {} is not in trajectory.csv", r.step));
        };
        if r.agent >= steps[i].agents.len() {
            return Err(format!("agent {} does not exist", r.agent));
        }
        indexed
            .entry((i, r.agent))
            .or_default()
            .push((r.index, point("x", r.x, "y", r.y)?));
        Ok(())
    })?;
    for ((i, agent), mut points) in indexed {
        points.sort_by_key(|&(index, _)| index);
        steps[i].agents[agent].waypoints = points.into_iter().map(|(_, p)| p).collect();
    }
    Ok(())
}

fn read_summary(path: &Path) -> Result<SummaryRead, RunDirError> {
    let text = read_text(path, MAX_TABLE_BYTES)?;
    serde_json::from_str(&text).map_err(|e| invalid(path, e))
}

fn read_plans(path: &Path) -> Result<Vec<PlanRecord>, RunDirError> {
    let mut plans: Vec<PlanRecord> = Vec::new();
    csv_rows(path, |_, r: PlanRow| {
        let pose = Pose::new(
            finite("x_m", r.x_m)?,
            finite("y_m", r.y_m)?,
            finite("heading_rad", r.heading_rad)?,
        );
        match plans.last_mut() {
            Some(last) if last.plan == r.plan => {
                if last.step != r.step || last.reason != r.reason {
                    return Err(format!(
                        "plan {} changes its step or reason within its rows",
                        r.plan
                    ));
                }
                last.poses.push(pose);
            }
            last => {
                let expected = last.map_or(0, |p| p.plan + 1);
                if r.plan != expected {
                    return Err(format!("plan {} where plan {expected} was due", r.plan));
                }
                plans.push(PlanRecord {
                    plan: r.plan,
                    step: r.step,
                    reason: r.reason,
                    poses: vec![pose],
                });
            }
        }
        Ok(())
    })?;
    Ok(plans)
}

fn read_obstacles(
    path: &Path,
    scenario: &Scenario,
) -> Result<(Vec<MovingStep>, Vec<UnknownRecord>), RunDirError> {
    let n_moving = scenario.moving.len();
    let mut moving: Vec<(usize, Vec<Option<Point>>)> = Vec::new();
    let mut unknown: Vec<Option<UnknownRecord>> = vec![None; scenario.unknown.len()];
    csv_rows(path, |_, r: ObstacleRow| {
        let at = point("x_m", r.x_m, "y_m", r.y_m)?;
        let radius_m = finite("radius_m", r.radius_m)?;
        match r.kind {
            ObstacleKind::Moving => {
                let Some(step) = r.step else {
                    return Err("a moving obstacle's row has no step".into());
                };
                if r.index >= n_moving {
                    return Err(format!(
                        "moving obstacle {} does not exist (scenario.toml has {n_moving})",
                        r.index
                    ));
                }
                match moving.last() {
                    Some((s, _)) if *s > step => {
                        return Err(format!("step {step} is out of order"));
                    }
                    Some((s, _)) if *s == step => {}
                    _ => moving.push((step, vec![None; n_moving])),
                }
                let Some((_, slots)) = moving.last_mut() else {
                    return Err("internal: no step".into());
                };
                if slots[r.index].replace(at).is_some() {
                    return Err(format!(
                        "moving obstacle {} appears twice in step {step}",
                        r.index
                    ));
                }
            }
            ObstacleKind::Unknown => {
                let Some(slot) = unknown.get_mut(r.index) else {
                    return Err(format!(
                        "unknown obstacle {} does not exist (scenario.toml has {})",
                        r.index,
                        scenario.unknown.len()
                    ));
                };
                let record = UnknownRecord {
                    disk: Disk {
                        centre: at,
                        radius_m,
                    },
                    known_from_step: r.known_from_step,
                };
                if slot.replace(record).is_some() {
                    return Err(format!("unknown obstacle {} appears twice", r.index));
                }
            }
        }
        Ok(())
    })?;
    let moving = moving
        .into_iter()
        .map(|(step, slots)| {
            let have = slots.iter().filter(|p| p.is_some()).count();
            let complete: Option<Vec<Point>> = slots.into_iter().collect();
            complete
                .map(|positions| MovingStep { step, positions })
                .ok_or_else(|| {
                    invalid(
                        path,
                        format!("step {step} has {have} of {n_moving} moving obstacles"),
                    )
                })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let unknown = unknown
        .into_iter()
        .enumerate()
        .map(|(i, u)| u.ok_or_else(|| invalid(path, format!("unknown obstacle {i} is missing"))))
        .collect::<Result<Vec<_>, _>>()?;
    Ok((moving, unknown))
}
