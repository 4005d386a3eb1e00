//! The best point against independent oracle answers (see `tests/data/README.md`).
//!
//! Reads every `*.jsonl` in `tests/data/` and in `$FORMATION_ORACLE_DIR` when set; a line
//! is a best-point case iff it has the key `best_dist_m`.

use std::path::{Path, PathBuf};

use serde_json::Value;
use shared::control::best_point::{
    BestPointError, nearest_free_point, nearest_reachable_free_point,
};
use shared::geometry::{Disk, DiskGrid, Field, FreeSpace, Point};

/// The oracle's tolerance on distances and feasibility, in metres.
const TOLERANCE_M: f64 = 1e-9;

/// One best-point case: field, query, inflated disks, and the oracle's distance
/// (`None`: no free point).
struct OracleCase {
    origin: String,
    field: Field,
    query: Point,
    disks: Vec<Disk>,
    best_dist_m: Option<f64>,
}

fn oracle_files() -> Vec<PathBuf> {
    let mut dirs = vec![Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data")];
    if let Some(extra) = std::env::var_os("FORMATION_ORACLE_DIR") {
        dirs.push(PathBuf::from(extra));
    }
    let mut files = Vec::new();
    for dir in dirs {
        let entries = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("cannot read oracle folder {}: {e}", dir.display()));
        let mut found: Vec<PathBuf> = entries
            .map(|entry| entry.expect("readable folder entry").path())
            .filter(|path| path.extension().is_some_and(|ext| ext == "jsonl"))
            .collect();
        found.sort();
        files.extend(found);
    }
    files
}

fn number(value: &Value, what: &str, origin: &str) -> f64 {
    value
        .as_f64()
        .unwrap_or_else(|| panic!("{origin}: {what} is not a number"))
}

fn pair(value: &Value, what: &str, origin: &str) -> (f64, f64) {
    match value.as_array().map(Vec::as_slice) {
        Some([a, b]) => (number(a, what, origin), number(b, what, origin)),
        _ => panic!("{origin}: {what} is not a pair of numbers"),
    }
}

fn parse_case(line: &Value, origin: String) -> OracleCase {
    let (width_m, height_m) = pair(&line["field_m"], "field_m", &origin);
    let (qx, qy) = pair(&line["query"], "query", &origin);
    let disks = line["disks"]
        .as_array()
        .unwrap_or_else(|| panic!("{origin}: disks is not an array"))
        .iter()
        .map(|disk| match disk.as_array().map(Vec::as_slice) {
            Some([x, y, r]) => Disk::new(
                number(x, "disk x", &origin),
                number(y, "disk y", &origin),
                number(r, "disk radius", &origin),
            ),
            _ => panic!("{origin}: a disk is not [x, y, r]"),
        })
        .collect();
    let best_dist_m = match &line["best_dist_m"] {
        Value::Null => None,
        d => Some(number(d, "best_dist_m", &origin)),
    };
    OracleCase {
        origin,
        field: Field::new(width_m, height_m),
        query: Point::new(qx, qy),
        disks,
        best_dist_m,
    }
}

fn oracle_cases() -> Vec<OracleCase> {
    let mut cases = Vec::new();
    for file in oracle_files() {
        let text = std::fs::read_to_string(&file)
            .unwrap_or_else(|e| panic!("cannot read {}: {e}", file.display()));
        for (number, line) in text.lines().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            let origin = format!("{}:{}", file.display(), number + 1);
            let value: Value =
                serde_json::from_str(line).unwrap_or_else(|e| panic!("{origin}: not JSON: {e}"));
            if value.get("best_dist_m").is_some() {
                cases.push(parse_case(&value, origin));
            }
        }
    }
    cases
}

/// Why `p` is not feasible to the oracle's tolerance, if it is not.
fn infeasibility(case: &OracleCase, p: &Point) -> Option<String> {
    if !case.field.contains(p, TOLERANCE_M) {
        return Some(format!("{p:?} is outside the field"));
    }
    case.disks
        .iter()
        .find(|d| (p - d.centre).norm() < d.radius_m - TOLERANCE_M)
        .map(|d| format!("{p:?} is inside {d:?}"))
}

/// A free point of the case as far from the query as the corners and a coarse lattice
/// allow, for use as the agent's position.
fn far_free_point(case: &OracleCase) -> Option<Point> {
    let steps = 40;
    let lattice = (0..=steps).flat_map(|i| {
        (0..=steps).map(move |j| {
            Point::new(
                case.field.width_m * f64::from(i) / f64::from(steps),
                case.field.height_m * f64::from(j) / f64::from(steps),
            )
        })
    });
    lattice
        .filter(|p| infeasibility(case, p).is_none())
        .max_by(|a, b| (a - case.query).norm().total_cmp(&(b - case.query).norm()))
}

#[test]
fn best_point_matches_every_oracle_case() {
    let cases = oracle_cases();
    assert!(!cases.is_empty(), "no best-point oracle case found");
    let mut reachable_checked = 0;
    for case in &cases {
        let grid = DiskGrid::new(case.disks.clone());
        let layers = [&grid];
        let space = FreeSpace::new(case.field, &layers);
        let result = nearest_free_point(&space, &case.query);
        match (case.best_dist_m, result) {
            (None, result) => assert_eq!(
                result,
                Err(BestPointError::NoFreePoint),
                "{}: the oracle has no free point",
                case.origin
            ),
            (Some(d), Err(e)) => panic!("{}: expected distance {d}, got {e}", case.origin),
            (Some(d), Ok(p)) => {
                let got_m = (p - case.query).norm();
                assert!(
                    (got_m - d).abs() <= TOLERANCE_M,
                    "{}: distance {got_m} != oracle {d} (point {p:?})",
                    case.origin
                );
                if let Some(why) = infeasibility(case, &p) {
                    panic!("{}: {why}", case.origin);
                }
                if let Some(from) = far_free_point(case)
                    && d < (from - case.query).norm()
                {
                    let reached =
                        nearest_reachable_free_point(&space, &case.query, &from, |_| true)
                            .unwrap_or_else(|e| {
                                panic!("{}: reachable search failed: {e}", case.origin)
                            });
                    let reached_m = (reached - case.query).norm();
                    assert!(
                        (reached_m - d).abs() <= TOLERANCE_M,
                        "{}: reachable distance {reached_m} != oracle {d}",
                        case.origin
                    );
                    reachable_checked += 1;
                }
            }
        }
    }
    assert!(
        reachable_checked > 0,
        "no case exercised the reachable search"
    );
    println!(
        "{} best-point oracle cases passed ({reachable_checked} also through the reachable search)",
        cases.len()
    );
}
