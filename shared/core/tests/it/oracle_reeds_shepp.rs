//! Reeds-Shepp lengths against an independent oracle (OMPL 2.0.1).
//!
//! Reads every `*.jsonl` file in `tests/data/` and, when the environment variable
//! `FORMATION_ORACLE_DIR` is set, every `*.jsonl` file in that folder. A line is a
//! Reeds-Shepp case iff it has the key `"turning_radius_m"`:
//! `{"from": [x, y, heading_rad], "to": [...], "turning_radius_m": rho, "length_m": L}`.
//! Other lines (other oracles share the folder) are skipped.

use std::f64::consts::TAU;
use std::path::{Path, PathBuf};

use serde_json::Value;
use shared::geometry::Pose;
use shared::paths::reeds_shepp::{shortest_length_m, shortest_path};

/// One oracle case and where it came from.
struct Case {
    origin: String,
    from: Pose,
    to: Pose,
    turning_radius_m: f64,
    length_m: f64,
}

/// The `*.jsonl` files of `dir`, sorted; an unreadable folder is an error.
fn jsonl_files(dir: &Path) -> Vec<PathBuf> {
    let entries = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("cannot read oracle folder {}: {e}", dir.display()));
    let mut files: Vec<PathBuf> = entries
        .map(|entry| entry.expect("oracle folder entry").path())
        .filter(|path| path.extension().is_some_and(|ext| ext == "jsonl"))
        .collect();
    files.sort();
    files
}

fn pose(value: &Value, origin: &str) -> Pose {
    let numbers: Vec<f64> = value
        .as_array()
        .unwrap_or_else(|| panic!("{origin}: pose is not an array"))
        .iter()
        .map(|n| {
            n.as_f64()
                .unwrap_or_else(|| panic!("{origin}: pose entry is not a number"))
        })
        .collect();
    assert_eq!(numbers.len(), 3, "{origin}: pose needs [x, y, heading_rad]");
    Pose::new(numbers[0], numbers[1], numbers[2])
}

fn number(line: &Value, key: &str, origin: &str) -> f64 {
    line[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{origin}: missing number {key:?}"))
}

/// Every Reeds-Shepp case of every oracle file.
fn cases() -> Vec<Case> {
    let mut dirs = vec![Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data")];
    if let Some(extra) = std::env::var_os("FORMATION_ORACLE_DIR") {
        dirs.push(PathBuf::from(extra));
    }
    let mut cases = Vec::new();
    for file in dirs.iter().flat_map(|dir| jsonl_files(dir)) {
        let text = std::fs::read_to_string(&file)
            .unwrap_or_else(|e| panic!("cannot read {}: {e}", file.display()));
        for (index, line) in text.lines().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            let origin = format!("{}:{}", file.display(), index + 1);
            let value: Value = serde_json::from_str(line)
                .unwrap_or_else(|e| panic!("{origin}: invalid JSON: {e}"));
            if value.get("turning_radius_m").is_none() {
                continue;
            }
            cases.push(Case {
                from: pose(&value["from"], &origin),
                to: pose(&value["to"], &origin),
                turning_radius_m: number(&value, "turning_radius_m", &origin),
                length_m: number(&value, "length_m", &origin),
                origin,
            });
        }
    }
    cases
}

#[test]
fn reeds_shepp_matches_ompl() {
    let cases = cases();
    assert!(!cases.is_empty(), "no Reeds-Shepp oracle case found");

    let mut failures = Vec::new();
    for case in &cases {
        let tolerance_m = 1e-9 * case.length_m.max(1.0);
        let rho = case.turning_radius_m;

        let length_m = shortest_length_m(&case.from, &case.to, rho);
        if (length_m - case.length_m).abs() > tolerance_m {
            failures.push(format!(
                "{}: shortest_length_m {length_m} != oracle {} (diff {:e})",
                case.origin,
                case.length_m,
                length_m - case.length_m
            ));
        }

        let path = shortest_path(&case.from, &case.to, rho);
        if (path.length_m() - case.length_m).abs() > tolerance_m {
            failures.push(format!(
                "{}: path length {} != oracle {}",
                case.origin,
                path.length_m(),
                case.length_m
            ));
        }

        let end = path.end_pose(&case.from);
        let position_error_m = (end.position() - case.to.position()).norm();
        let heading_error_rad = (end.heading_rad - case.to.heading_rad).rem_euclid(TAU);
        let heading_error_rad = heading_error_rad.min(TAU - heading_error_rad);
        if position_error_m > 1e-6 || heading_error_rad > 1e-6 {
            failures.push(format!(
                "{}: path ends at {end:?}, goal {:?} (position error {position_error_m:e} m, \
                 heading error {heading_error_rad:e} rad)",
                case.origin, case.to
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} oracle cases failed:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
    println!("{} Reeds-Shepp oracle cases passed", cases.len());
}
