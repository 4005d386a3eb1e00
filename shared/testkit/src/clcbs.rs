//! Reader for the CL-CBS benchmark instances (real obstacle fields for the controllers).
//!
//! The CL-CBS project (APRIL Lab, MIT licence) ships its instances as YAML files of this
//! shape:
//!
//! ```yaml
//! agents:
//!   - start: [61, 59, 0]        # x_m, y_m, heading_rad
//!     name: agent0
//!     goal: [88, 22, -1.57]
//! map:
//!   dimensions: [100, 100]      # width_m, height_m
//!   obstacles:
//!     - [88.9605, 88.8407]      # centre of a disk of radius 0.8 m
//! ```
//!
//! The YAML is read by `serde-saphyr`, strictly: an unknown or repeated key, a missing
//! key, a list of the wrong length, a number that is not finite or a map side that is
//! not positive is an error naming the line.
//!
//! The six instances the tests and benchmarks use are copied into this repository, with
//! CL-CBS's MIT licence beside them, in `shared/core/tests/data/clcbs`: see
//! [`default_clcbs_dir`].
//!
//! ```
//! use testkit::clcbs::{CLCBS_INSTANCE_FILES, ClcbsInstance, default_clcbs_dir};
//! let instance = ClcbsInstance::load(&default_clcbs_dir().join(CLCBS_INSTANCE_FILES[0])).unwrap();
//! assert_eq!((instance.field.width_m, instance.field.height_m), (50.0, 50.0));
//! assert_eq!(instance.agents.len(), 10);
//! ```

use std::path::{Path, PathBuf};

use serde::Deserialize;
use serde_saphyr::Spanned;
use shared::geometry::{Disk, Field, Pose};

/// Radius of every CL-CBS obstacle, in metres (the obstacles are given as points).
pub const CLCBS_OBSTACLE_RADIUS_M: f64 = 0.8;

/// The instance files expected in [`default_clcbs_dir`]: two each of the 50 m, 100 m and
/// 300 m maps.
pub const CLCBS_INSTANCE_FILES: [&str; 6] = [
    "map_50by50_obst25_agents10_ex0.yaml",
    "map_50by50_obst25_agents20_ex3.yaml",
    "map_100by100_obst50_agents10_ex0.yaml",
    "map_100by100_obst50_agents50_ex7.yaml",
    "map_300by300_obst100_agents10_ex0.yaml",
    "map_300by300_obst100_agents100_ex2.yaml",
];

/// Environment variable that overrides [`default_clcbs_dir`].
pub const CLCBS_DIR_ENV: &str = "FORMATION_CLCBS_DIR";

/// Folder holding the CL-CBS instances: the environment variable `FORMATION_CLCBS_DIR`
/// when set and not empty, else the copy in this repository, `shared/core/tests/data/clcbs`.
pub fn default_clcbs_dir() -> PathBuf {
    match std::env::var_os(CLCBS_DIR_ENV) {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../core/tests/data/clcbs"
        )),
    }
}

/// One agent of an instance: a start and a goal pose.
#[derive(Clone, Debug, PartialEq)]
pub struct ClcbsAgent {
    /// The agent's name in the file (for example `agent0`).
    pub name: String,
    /// Start pose (metres, radians).
    pub start: Pose,
    /// Goal pose (metres, radians).
    pub goal: Pose,
}

/// A parsed CL-CBS instance.
#[derive(Clone, Debug, PartialEq)]
pub struct ClcbsInstance {
    /// The map, `[0, width_m] x [0, height_m]`.
    pub field: Field,
    /// The obstacles, disks of radius [`CLCBS_OBSTACLE_RADIUS_M`], in file order.
    pub obstacles: Vec<Disk>,
    /// The agents, in file order.
    pub agents: Vec<ClcbsAgent>,
}

/// Why an instance could not be read.
#[derive(thiserror::Error, Debug)]
pub enum ClcbsError {
    /// The file could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// The text is not an instance of the CL-CBS format.
    #[error("{}line {line}: {reason}", path_prefix(path.as_deref()))]
    Parse {
        /// The file, when the text came from one.
        path: Option<PathBuf>,
        /// The offending line, 1-based (0 when the YAML reader could not tell).
        line: usize,
        /// What is wrong.
        reason: String,
    },
}

fn path_prefix(path: Option<&Path>) -> String {
    path.map(|p| format!("{}: ", p.display()))
        .unwrap_or_default()
}

/// The file as serde reads it; each number list with the place it was written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct InstanceFile {
    agents: Vec<AgentFile>,
    map: MapFile,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AgentFile {
    name: String,
    start: Spanned<[f64; 3]>,
    goal: Spanned<[f64; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MapFile {
    dimensions: Spanned<[f64; 2]>,
    obstacles: Vec<Spanned<[f64; 2]>>,
}

/// The 1-based line of `at`.
fn line_of(at: &serde_saphyr::Location) -> usize {
    usize::try_from(at.line()).unwrap_or(usize::MAX)
}

/// `numbers` if every one is finite, else the error naming their line.
fn finite<const N: usize>(numbers: &Spanned<[f64; N]>) -> Result<[f64; N], ClcbsError> {
    if numbers.value.iter().all(|v| v.is_finite()) {
        Ok(numbers.value)
    } else {
        Err(ClcbsError::Parse {
            path: None,
            line: line_of(&numbers.referenced),
            reason: format!("{:?}: every number must be finite", numbers.value),
        })
    }
}

fn pose(numbers: &Spanned<[f64; 3]>) -> Result<Pose, ClcbsError> {
    let [x_m, y_m, heading_rad] = finite(numbers)?;
    Ok(Pose::new(x_m, y_m, heading_rad))
}

impl ClcbsInstance {
    /// Read the instance in the file at `path`.
    pub fn load(path: &Path) -> Result<Self, ClcbsError> {
        let text = std::fs::read_to_string(path).map_err(|source| ClcbsError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::parse(&text).map_err(|e| match e {
            ClcbsError::Parse { line, reason, .. } => ClcbsError::Parse {
                path: Some(path.to_path_buf()),
                line,
                reason,
            },
            other => other,
        })
    }

    /// Parse the text of an instance.
    pub fn parse(text: &str) -> Result<Self, ClcbsError> {
        let file: InstanceFile = serde_saphyr::from_str(text).map_err(|e| ClcbsError::Parse {
            path: None,
            line: e.location().map_or(0, |at| line_of(&at)),
            reason: e.to_string().lines().next().unwrap_or_default().to_string(),
        })?;
        let [width_m, height_m] = finite(&file.map.dimensions)?;
        if width_m <= 0.0 || height_m <= 0.0 {
            return Err(ClcbsError::Parse {
                path: None,
                line: line_of(&file.map.dimensions.referenced),
                reason: format!("the map's dimensions {width_m} x {height_m} must be positive"),
            });
        }
        let obstacles = file
            .map
            .obstacles
            .iter()
            .map(|o| finite(o).map(|[x, y]| Disk::new(x, y, CLCBS_OBSTACLE_RADIUS_M)))
            .collect::<Result<_, _>>()?;
        let agents = file
            .agents
            .iter()
            .map(|a| {
                Ok(ClcbsAgent {
                    name: a.name.clone(),
                    start: pose(&a.start)?,
                    goal: pose(&a.goal)?,
                })
            })
            .collect::<Result<_, ClcbsError>>()?;
        Ok(Self {
            field: Field::new(width_m, height_m),
            obstacles,
            agents,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SAMPLE: &str = "\
agents:
  - start: [1, 2, 0]
    name: agent0
    goal: [3, 4.5, -1.57]
  - name: agent1   # a comment
    goal: [5, 5, 3.14]
    start: [6, 7, 1.57]
map:
  dimensions: [10, 20]
  obstacles:
    - [1.5, 2.5]
    - [8, 9]
";

    #[test]
    fn parses_an_instance() {
        let inst = ClcbsInstance::parse(SAMPLE).expect("valid");
        assert_eq!(inst.field, Field::new(10.0, 20.0));
        assert_eq!(
            inst.obstacles,
            vec![Disk::new(1.5, 2.5, 0.8), Disk::new(8.0, 9.0, 0.8)]
        );
        assert_eq!(inst.agents.len(), 2);
        assert_eq!(inst.agents[1].name, "agent1");
        assert_eq!(inst.agents[1].start, Pose::new(6.0, 7.0, 1.57));
        assert_eq!(inst.agents[0].goal, Pose::new(3.0, 4.5, -1.57));
    }

    fn error_line(text: &str) -> usize {
        match ClcbsInstance::parse(text) {
            Err(ClcbsError::Parse { line, .. }) => line,
            other => panic!("expected a parse error, got {other:?}"),
        }
    }

    #[test]
    fn rejects_bad_input_naming_the_line() {
        // A pose of two numbers.
        assert_eq!(
            error_line(&SAMPLE.replace("[3, 4.5, -1.57]", "[3, 4.5]")),
            4
        );
        // An obstacle centre that is not a finite number.
        assert_eq!(error_line(&SAMPLE.replace("[8, 9]", "[8, .nan]")), 12);
        assert_eq!(error_line(&SAMPLE.replace("[8, 9]", "[8, 1e999]")), 12);
        // An unknown key in an agent, at the top level.
        assert_eq!(
            error_line(&SAMPLE.replace("name: agent0", "nme: agent0")),
            3
        );
        assert_eq!(error_line(&SAMPLE.replace("map:", "mapp:")), 8);
        // A map side that is not positive.
        assert_eq!(error_line(&SAMPLE.replace("[10, 20]", "[10, -1]")), 9);
        // A repeated key.
        assert_eq!(error_line(&format!("{SAMPLE}map:\n")), 13);
    }

    #[test]
    fn rejects_missing_keys_and_tabs() {
        for text in [
            SAMPLE.replace("    start: [6, 7, 1.57]\n", ""),
            SAMPLE.replace("    name: agent0", "\tname: agent0"),
            "agents:\n".to_string(),
            String::new(),
        ] {
            assert!(
                matches!(ClcbsInstance::parse(&text), Err(ClcbsError::Parse { .. })),
                "{text}"
            );
        }
    }

    #[test]
    fn errors_name_the_file_and_the_line() {
        let e = ClcbsInstance::load(Path::new("/nonexistent/x.yaml")).expect_err("missing");
        assert!(e.to_string().contains("/nonexistent/x.yaml"), "{e}");
        let e = ClcbsInstance::parse(&SAMPLE.replace("[10, 20]", "[10, -1]")).expect_err("bad");
        assert!(e.to_string().starts_with("line 9: "), "{e}");
    }
}
