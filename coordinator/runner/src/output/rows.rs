//! The rows of the CSV files of a run folder (`docs/outputs.md`): one serde struct per
//! file, written by `output::tables` and read back by `coordinator render` (the `tools` crate). A column's name
//! is its field's name, so the writer and the reader cannot disagree on it.
//! The cells are written as `output::csv_format` says; the move status by its name.

use serde::{Deserialize, Deserializer, Serialize, Serializer};
use shared::control::vocabulary::{MoveStatus, Named, named};
use shared::world::course::ReplanReason;

use super::csv_format::{cell_f64, display_f64, zero_one};

/// A row of `path.csv`: the formation centre at one step.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PathRow {
    /// The step.
    pub step: usize,
    /// Where the centre is, in metres.
    #[serde(with = "display_f64")]
    pub x_m: f64,
    /// Where the centre is, in metres.
    #[serde(with = "display_f64")]
    pub y_m: f64,
    /// Its heading, in radians.
    #[serde(with = "display_f64")]
    pub heading_rad: f64,
}

/// A row of `trajectory.csv`: one agent at the end of one step (positions in metres).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrajectoryRow {
    /// The step.
    pub step: usize,
    /// The agent.
    pub agent: usize,
    /// Where it is.
    #[serde(with = "display_f64")]
    pub x: f64,
    /// Where it is.
    #[serde(with = "display_f64")]
    pub y: f64,
    /// Its ideal slot.
    #[serde(with = "display_f64")]
    pub slot_x: f64,
    /// Its ideal slot.
    #[serde(with = "display_f64")]
    pub slot_y: f64,
    /// The best point it aimed for.
    #[serde(with = "display_f64")]
    pub best_x: f64,
    /// The best point it aimed for.
    #[serde(with = "display_f64")]
    pub best_y: f64,
    /// Distance from its slot.
    #[serde(with = "display_f64")]
    pub deviation_m: f64,
    /// Clearance to the nearest other body.
    #[serde(with = "display_f64")]
    pub clearance_m: f64,
    /// Outcome of its turn, by [`MoveStatus::name`].
    #[serde(with = "named")]
    pub status: MoveStatus,
    /// Whether it is still in the formation: `1` or `0` (read: anything but `0` is alive).
    #[serde(with = "zero_one")]
    pub alive: bool,
    /// Where it faces, radians: a column only in runs with agents that have a heading
    /// (`None`), empty for a holonomic agent among them (`Some(None)`).
    #[serde(default, skip_serializing_if = "Option::is_none", with = "cell_f64")]
    pub heading_rad: Option<Option<f64>>,
    /// Its heading minus the centre's, wrapped into `(-pi, pi]`, radians: present when
    /// `heading_rad` is.
    #[serde(default, skip_serializing_if = "Option::is_none", with = "cell_f64")]
    pub heading_error_rad: Option<Option<f64>>,
}

/// A row of `moves.csv`: one waypoint of the polyline an agent followed in one step.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MoveRow {
    /// The step.
    pub step: usize,
    /// The agent.
    pub agent: usize,
    /// The waypoint's place in the polyline, from 0.
    pub index: usize,
    /// The waypoint, in metres.
    #[serde(with = "display_f64")]
    pub x: f64,
    /// The waypoint, in metres.
    #[serde(with = "display_f64")]
    pub y: f64,
    /// The heading on reaching the waypoint, radians: a column only in runs with agents
    /// that have a heading (`None`), empty for a holonomic agent among them (`Some(None)`).
    #[serde(default, skip_serializing_if = "Option::is_none", with = "cell_f64")]
    pub heading_rad: Option<Option<f64>>,
    /// The length of the arc driven from the waypoint before to this one, metres,
    /// negative when driven in reverse: a column as `heading_rad`, empty at index 0.
    #[serde(default, skip_serializing_if = "Option::is_none", with = "cell_f64")]
    pub drive_m: Option<Option<f64>>,
    /// That arc's curvature, 1/m, positive when the heading turns counter-clockwise as
    /// the agent drives it (0: straight): a column as `heading_rad`, empty at index 0.
    #[serde(default, skip_serializing_if = "Option::is_none", with = "cell_f64")]
    pub curvature_per_m: Option<Option<f64>>,
}

/// A row of `plans.csv`: one pose of one plan of the formation centre.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlanRow {
    /// The plan: 0 for the first, then 1, 2, ... for the replans that found a path.
    pub plan: usize,
    /// The step at whose start it was planned (0 for the first).
    pub step: usize,
    /// Why it was planned.
    pub reason: PlanReason,
    /// The pose, in metres.
    #[serde(with = "display_f64")]
    pub x_m: f64,
    /// The pose, in metres.
    #[serde(with = "display_f64")]
    pub y_m: f64,
    /// The pose's heading, in radians.
    #[serde(with = "display_f64")]
    pub heading_rad: f64,
}

/// A row of `obstacles.csv`: a moving obstacle during one step, or an obstacle unknown at
/// the start.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObstacleRow {
    /// The step (a moving obstacle's row; empty for an unknown obstacle).
    pub step: Option<usize>,
    /// Which list the obstacle is in.
    pub kind: ObstacleKind,
    /// Its place in `[[obstacles.moving]]` or `[[obstacles.unknown]]`.
    pub index: usize,
    /// Its centre (a moving obstacle's during the step), in metres.
    #[serde(with = "display_f64")]
    pub x_m: f64,
    /// Its centre, in metres.
    #[serde(with = "display_f64")]
    pub y_m: f64,
    /// Its radius, in metres.
    #[serde(with = "display_f64")]
    pub radius_m: f64,
    /// The step an unknown obstacle joined the known map (empty: never, or a moving
    /// obstacle, whose route the centre's planner knows).
    pub known_from_step: Option<usize>,
}

/// The kind of an `obstacles.csv` row.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ObstacleKind {
    /// A moving obstacle, where it stands during the row's step.
    Moving,
    /// An obstacle the centre's planner did not know at the start.
    Unknown,
}

/// Why a plan of `plans.csv` was made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlanReason {
    /// Plan 0: the path planned before the run.
    First,
    /// A replan during the run.
    Replan(ReplanReason),
}

impl PlanReason {
    /// Every reason.
    pub const ALL: [PlanReason; 3] = [
        Self::First,
        Self::Replan(ReplanReason::FoundObstacle),
        Self::Replan(ReplanReason::MovingObstacle),
    ];

    /// The name `plans.csv` gives it: `first`, or the replan's
    /// ([`ReplanReason::name`]).
    pub fn name(self) -> &'static str {
        match self {
            Self::First => "first",
            Self::Replan(r) => r.name(),
        }
    }
}

/// A new [`ReplanReason`] fails to compile here: add it to [`PlanReason::ALL`] too.
const _: fn(ReplanReason) = |r| match r {
    ReplanReason::FoundObstacle | ReplanReason::MovingObstacle => {}
};

impl Named for PlanReason {
    const ALL: &'static [Self] = &Self::ALL;
    const WHAT: &'static str = "plan reason";

    fn name(&self) -> &'static str {
        PlanReason::name(*self)
    }
}

impl Serialize for PlanReason {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        named::serialize(self, serializer)
    }
}

impl<'de> Deserialize<'de> for PlanReason {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        named::deserialize(deserializer)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::csv_format::{csv_bytes, csv_bytes_with_columns, header};
    use serde::de::DeserializeOwned;

    /// Values whose text differs between `Display` and other float forms.
    const AWKWARD: [f64; 12] = [
        -0.0,
        0.0,
        1e-7,
        0.30000000000000004,
        1.0,
        1e16,
        1e300,
        5e-324,
        -1.7976931348623157e308,
        f64::NAN,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];

    fn read<R: DeserializeOwned>(bytes: &[u8]) -> Vec<R> {
        csv::Reader::from_reader(bytes)
            .deserialize()
            .collect::<Result<_, _>>()
            .expect("rows read back")
    }

    fn same_bits(a: f64, b: f64) -> bool {
        a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
    }

    #[test]
    fn numbers_are_written_as_display_gives_them_and_read_back_to_the_same_bits() {
        let rows: Vec<PlanRow> = AWKWARD
            .iter()
            .zip(AWKWARD.iter().rev())
            .enumerate()
            .map(|(i, (&a, &b))| PlanRow {
                plan: i,
                step: 7 * i,
                reason: PlanReason::ALL[i % 3],
                x_m: a,
                y_m: b,
                heading_rad: -a,
            })
            .collect();
        let bytes = csv_bytes(rows.iter().copied()).expect("csv");
        let mut want = String::from("plan,step,reason,x_m,y_m,heading_rad\n");
        for r in &rows {
            want += &format!(
                "{},{},{},{},{},{}\n",
                r.plan,
                r.step,
                r.reason.name(),
                r.x_m,
                r.y_m,
                r.heading_rad
            );
        }
        assert_eq!(String::from_utf8(bytes.clone()).expect("utf-8"), want);
        assert!(
            want.contains(",0.0000001,") && want.contains(",-0,"),
            "{want}"
        );
        let back: Vec<PlanRow> = read(&bytes);
        assert_eq!(back.len(), rows.len());
        for (a, b) in rows.iter().zip(&back) {
            assert_eq!((a.plan, a.step, a.reason), (b.plan, b.step, b.reason));
            for (x, y) in [
                (a.x_m, b.x_m),
                (a.y_m, b.y_m),
                (a.heading_rad, b.heading_rad),
            ] {
                assert!(same_bits(x, y), "{x:?} read back as {y:?}");
            }
        }
    }

    #[test]
    fn every_float_column_of_every_file_is_written_with_display() {
        // 1e-7 is `0.0000001` with Display and `1e-7` in the csv crate's own form.
        let v = 1e-7;
        let files = [
            csv_bytes([PathRow {
                step: 0,
                x_m: v,
                y_m: v,
                heading_rad: v,
            }]),
            csv_bytes([TrajectoryRow {
                step: 0,
                agent: 0,
                x: v,
                y: v,
                slot_x: v,
                slot_y: v,
                best_x: v,
                best_y: v,
                deviation_m: v,
                clearance_m: v,
                status: MoveStatus::AtSlot,
                alive: true,
                heading_rad: Some(Some(v)),
                heading_error_rad: Some(Some(v)),
            }]),
            csv_bytes([MoveRow {
                step: 0,
                agent: 0,
                index: 0,
                x: v,
                y: v,
                heading_rad: Some(Some(v)),
                drive_m: Some(Some(v)),
                curvature_per_m: Some(Some(v)),
            }]),
            csv_bytes([ObstacleRow {
                step: None,
                kind: ObstacleKind::Unknown,
                index: 0,
                x_m: v,
                y_m: v,
                radius_m: v,
                known_from_step: None,
            }]),
        ];
        for bytes in files {
            let text = String::from_utf8(bytes.expect("csv")).expect("utf-8");
            assert!(!text.contains("1e-7"), "{text}");
            let header_columns = text.lines().next().expect("header").split(',').count();
            let row = text.lines().nth(1).expect("row");
            let cells: Vec<&str> = row.split(',').collect();
            assert_eq!(cells.len(), header_columns, "{text}");
            let floats = cells.iter().filter(|c| **c == "0.0000001").count();
            let other = cells.iter().filter(|c| c.contains('.')).count();
            assert_eq!(floats, other, "{text}");
            assert!(floats >= 2, "{text}");
        }
    }

    /// A row of step 1 for `agent` with plain numbers and no heading columns.
    fn trajectory_row(agent: usize, status: MoveStatus, alive: bool) -> TrajectoryRow {
        TrajectoryRow {
            step: 1,
            agent,
            x: 0.5,
            y: 1.0,
            slot_x: 2.0,
            slot_y: 3.0,
            best_x: 4.0,
            best_y: 5.0,
            deviation_m: 0.25,
            clearance_m: -0.125,
            status,
            alive,
            heading_rad: None,
            heading_error_rad: None,
        }
    }

    #[test]
    fn the_heading_columns_are_absent_empty_or_a_number_and_read_back() {
        let row = |heading: Option<Option<f64>>| TrajectoryRow {
            heading_rad: heading,
            heading_error_rad: heading.map(|h| h.map(|v| -v)),
            ..trajectory_row(0, MoveStatus::AtSlot, true)
        };
        let columns = header::<TrajectoryRow>().len() - 2;
        let without = String::from_utf8(csv_bytes_with_columns([row(None)], columns).expect("csv"))
            .expect("utf-8");
        assert!(!without.contains("heading"), "{without}");
        let rows = [row(Some(Some(-1.5))), row(Some(None))];
        let with = String::from_utf8(csv_bytes(rows).expect("csv")).expect("utf-8");
        let lines: Vec<&str> = with.lines().collect();
        assert!(
            lines[0].ends_with(",alive,heading_rad,heading_error_rad"),
            "{with}"
        );
        assert!(lines[1].ends_with(",1,-1.5,1.5"), "{with}");
        assert!(lines[2].ends_with(",1,,"), "{with}");
        let mut reader = csv::Reader::from_reader(with.as_bytes());
        let back: Vec<TrajectoryRow> = reader
            .deserialize()
            .collect::<Result<_, _>>()
            .expect("reads back");
        assert_eq!(back, rows);
        let mut reader = csv::Reader::from_reader(without.as_bytes());
        let back: Vec<TrajectoryRow> = reader
            .deserialize()
            .collect::<Result<_, _>>()
            .expect("reads back");
        assert_eq!(back, [row(None)]);
    }

    #[test]
    fn status_and_alive_keep_their_encodings() {
        let rows: Vec<TrajectoryRow> = MoveStatus::ALL
            .iter()
            .enumerate()
            .map(|(i, &status)| trajectory_row(i, status, i % 2 == 0))
            .collect();
        let columns = header::<TrajectoryRow>().len() - 2;
        let bytes = csv_bytes_with_columns(rows.iter().copied(), columns).expect("csv");
        let text = String::from_utf8(bytes.clone()).expect("utf-8");
        let mut lines = text.lines();
        assert_eq!(
            lines.next(),
            Some("step,agent,x,y,slot_x,slot_y,best_x,best_y,deviation_m,clearance_m,status,alive")
        );
        for (line, r) in lines.zip(&rows) {
            let alive = if r.alive { "1" } else { "0" };
            assert_eq!(
                line,
                format!(
                    "1,{},0.5,1,2,3,4,5,0.25,-0.125,{},{alive}",
                    r.agent,
                    r.status.name()
                )
            );
        }
        assert_eq!(read::<TrajectoryRow>(&bytes), rows);
        // Any non-zero `alive` is alive; an unknown status is refused.
        let header = header::<TrajectoryRow>()[..columns].join(",");
        let two: Vec<TrajectoryRow> =
            read(format!("{header}\n0,0,0,0,0,0,0,0,0,0,dead,2\n").as_bytes());
        assert!(two[0].alive);
        assert_eq!(two[0].status, MoveStatus::Dead);
        let bad = format!("{header}\n0,0,0,0,0,0,0,0,0,0,asleep,1\n");
        let e = csv::Reader::from_reader(bad.as_bytes())
            .deserialize::<TrajectoryRow>()
            .next()
            .expect("a row")
            .expect_err("unknown status");
        assert!(e.to_string().contains("asleep"), "{e}");
    }

    #[test]
    fn an_obstacle_row_writes_its_missing_steps_as_empty_fields() {
        let rows = [
            ObstacleRow {
                step: Some(3),
                kind: ObstacleKind::Moving,
                index: 1,
                x_m: 1.5,
                y_m: 2.0,
                radius_m: 0.5,
                known_from_step: None,
            },
            ObstacleRow {
                step: None,
                kind: ObstacleKind::Unknown,
                index: 0,
                x_m: 4.0,
                y_m: 5.0,
                radius_m: 1.0,
                known_from_step: Some(12),
            },
        ];
        let bytes = csv_bytes(rows).expect("csv");
        assert_eq!(
            String::from_utf8(bytes.clone()).expect("utf-8"),
            "step,kind,index,x_m,y_m,radius_m,known_from_step\n\
             3,moving,1,1.5,2,0.5,\n\
             ,unknown,0,4,5,1,12\n"
        );
        assert_eq!(read::<ObstacleRow>(&bytes), rows);
        assert_eq!(
            csv_bytes(Vec::<ObstacleRow>::new()).expect("csv"),
            b"step,kind,index,x_m,y_m,radius_m,known_from_step\n"
        );
    }
}
