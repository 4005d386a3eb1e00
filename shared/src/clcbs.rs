//! Reader for the CL-CBS benchmark instances (real obstacle fields for the planners).
//!
//! The CL-CBS project (APRIL Lab, MIT licence) ships its instances as YAML files of this
//! shape, and this module reads exactly that subset, strictly:
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
//! Top-level keys come in any order, keys inside an agent in any order; blank lines and
//! `#` comments are allowed. Anything else (unknown or repeated keys, tabs, missing keys,
//! numbers that are not finite, a non-positive map size) is an error naming the line.
//!
//! The six instances the tests and benchmarks use are copied into this repository, with
//! CL-CBS's MIT licence beside them, in `shared/tests/data/clcbs`: see
//! [`default_clcbs_dir`].

use std::path::{Path, PathBuf};

use crate::geometry::{Disk, Field, Pose};

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
/// when set and not empty, else the copy in this crate, `shared/tests/data/clcbs`.
pub fn default_clcbs_dir() -> PathBuf {
    match std::env::var_os(CLCBS_DIR_ENV) {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/clcbs")),
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
    /// The text is not an instance of the supported subset.
    #[error("{}line {line}: {reason}", path_prefix(path.as_deref()))]
    Parse {
        /// The file, when the text came from one.
        path: Option<PathBuf>,
        /// The offending line, 1-based (the line where a missing key's block began).
        line: usize,
        /// What is wrong.
        reason: String,
    },
}

fn path_prefix(path: Option<&Path>) -> String {
    path.map(|p| format!("{}: ", p.display()))
        .unwrap_or_default()
}

fn parse_error(line: usize, reason: impl Into<String>) -> ClcbsError {
    ClcbsError::Parse {
        path: None,
        line,
        reason: reason.into(),
    }
}

/// An agent being read: each key with the line it came from.
#[derive(Default)]
struct AgentDraft {
    line: usize,
    name: Option<String>,
    start: Option<Pose>,
    goal: Option<Pose>,
}

#[derive(Clone, Copy, PartialEq)]
enum Section {
    None,
    Agents,
    Map,
    Obstacles,
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
        let mut section = Section::None;
        let mut seen_agents = false;
        let mut seen_map = false;
        let mut dimensions: Option<(f64, f64)> = None;
        let mut seen_obstacles = false;
        let mut obstacles = Vec::new();
        let mut drafts: Vec<AgentDraft> = Vec::new();
        // Indentation of the current agent's keys and of the map's keys, fixed by the first.
        let mut agent_key_indent: Option<usize> = None;
        let mut item_indent: Option<usize> = None;
        let mut map_key_indent: Option<usize> = None;
        let mut obstacle_indent: Option<usize> = None;

        for (index, raw) in text.lines().enumerate() {
            let line_no = index + 1;
            let line = strip_comment(raw).trim_end();
            if line.trim_start().is_empty() {
                continue;
            }
            if line.contains('\t') {
                return Err(parse_error(line_no, "tabs are not allowed"));
            }
            let indent = line.len() - line.trim_start().len();
            let content = &line[indent..];

            if indent == 0 {
                let (key, value) = split_key(content)
                    .ok_or_else(|| parse_error(line_no, "expected a top-level key"))?;
                if !value.is_empty() {
                    return Err(parse_error(line_no, format!("`{key}:` takes a block")));
                }
                section = match key {
                    "agents" if !seen_agents => {
                        seen_agents = true;
                        Section::Agents
                    }
                    "map" if !seen_map => {
                        seen_map = true;
                        Section::Map
                    }
                    "agents" | "map" => {
                        return Err(parse_error(line_no, format!("`{key}` given twice")));
                    }
                    _ => return Err(parse_error(line_no, format!("unknown key `{key}`"))),
                };
                continue;
            }

            match section {
                Section::None => {
                    return Err(parse_error(line_no, "indented line outside any section"));
                }
                Section::Agents => {
                    let (rest, rest_indent) = if let Some(rest) = content.strip_prefix("- ") {
                        if *item_indent.get_or_insert(indent) != indent {
                            return Err(parse_error(line_no, "inconsistent list indentation"));
                        }
                        drafts.push(AgentDraft {
                            line: line_no,
                            ..AgentDraft::default()
                        });
                        let skip = rest.len() - rest.trim_start().len();
                        (rest.trim_start(), indent + 2 + skip)
                    } else {
                        (content, indent)
                    };
                    let draft = drafts
                        .last_mut()
                        .ok_or_else(|| parse_error(line_no, "expected `- ` (an agent)"))?;
                    if *agent_key_indent.get_or_insert(rest_indent) != rest_indent {
                        return Err(parse_error(line_no, "inconsistent key indentation"));
                    }
                    let (key, value) = split_key(rest)
                        .ok_or_else(|| parse_error(line_no, "expected `key: value`"))?;
                    match key {
                        "name" => {
                            set_once(&mut draft.name, parse_name(value, line_no)?, key, line_no)?
                        }
                        "start" => {
                            set_once(&mut draft.start, parse_pose(value, line_no)?, key, line_no)?
                        }
                        "goal" => {
                            set_once(&mut draft.goal, parse_pose(value, line_no)?, key, line_no)?
                        }
                        _ => {
                            return Err(parse_error(line_no, format!("unknown agent key `{key}`")));
                        }
                    }
                }
                Section::Map | Section::Obstacles => {
                    let map_indent = *map_key_indent.get_or_insert(indent);
                    if indent == map_indent {
                        section = Section::Map;
                        let (key, value) = split_key(content)
                            .ok_or_else(|| parse_error(line_no, "expected `key: value`"))?;
                        match key {
                            "dimensions" => {
                                let v = parse_numbers(value, line_no)?;
                                let [w, h] = v[..] else {
                                    return Err(parse_error(
                                        line_no,
                                        "dimensions take [width, height]",
                                    ));
                                };
                                if w <= 0.0 || h <= 0.0 {
                                    return Err(parse_error(
                                        line_no,
                                        "dimensions must be positive",
                                    ));
                                }
                                set_once(&mut dimensions, (w, h), key, line_no)?;
                            }
                            "obstacles" => {
                                if seen_obstacles {
                                    return Err(parse_error(line_no, "`obstacles` given twice"));
                                }
                                seen_obstacles = true;
                                if value == "[]" {
                                    continue;
                                }
                                if !value.is_empty() {
                                    return Err(parse_error(
                                        line_no,
                                        "`obstacles:` takes a block list",
                                    ));
                                }
                                section = Section::Obstacles;
                            }
                            _ => {
                                return Err(parse_error(
                                    line_no,
                                    format!("unknown map key `{key}`"),
                                ));
                            }
                        }
                    } else if indent > map_indent && section == Section::Obstacles {
                        if *obstacle_indent.get_or_insert(indent) != indent {
                            return Err(parse_error(line_no, "inconsistent list indentation"));
                        }
                        let item = content
                            .strip_prefix("- ")
                            .ok_or_else(|| parse_error(line_no, "expected `- [x, y]`"))?;
                        let v = parse_numbers(item, line_no)?;
                        let [x, y] = v[..] else {
                            return Err(parse_error(line_no, "an obstacle takes [x, y]"));
                        };
                        obstacles.push(Disk::new(x, y, CLCBS_OBSTACLE_RADIUS_M));
                    } else {
                        return Err(parse_error(line_no, "unexpected indentation"));
                    }
                }
            }
        }

        let last_line = text.lines().count().max(1);
        if !seen_map {
            return Err(parse_error(last_line, "missing `map`"));
        }
        let (width_m, height_m) =
            dimensions.ok_or_else(|| parse_error(last_line, "missing `map.dimensions`"))?;
        if !seen_obstacles {
            return Err(parse_error(last_line, "missing `map.obstacles`"));
        }
        if !seen_agents {
            return Err(parse_error(last_line, "missing `agents`"));
        }
        let agents = drafts
            .into_iter()
            .map(|d| {
                let missing = |key: &str| parse_error(d.line, format!("agent without `{key}`"));
                Ok(ClcbsAgent {
                    start: d.start.ok_or_else(|| missing("start"))?,
                    goal: d.goal.ok_or_else(|| missing("goal"))?,
                    name: d.name.ok_or_else(|| missing("name"))?,
                })
            })
            .collect::<Result<Vec<_>, ClcbsError>>()?;
        Ok(Self {
            field: Field::new(width_m, height_m),
            obstacles,
            agents,
        })
    }
}

/// The line without a `#` comment (a `#` at the start or after a space).
fn strip_comment(line: &str) -> &str {
    let bytes = line.as_bytes();
    for (i, &b) in bytes.iter().enumerate() {
        if b == b'#' && (i == 0 || bytes[i - 1] == b' ') {
            return &line[..i];
        }
    }
    line
}

/// `key: value` (value trimmed, possibly empty), or `None` if there is no `key:`.
fn split_key(content: &str) -> Option<(&str, &str)> {
    let colon = content.find(':')?;
    let key = &content[..colon];
    let value = &content[colon + 1..];
    if key.is_empty()
        || !key.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'_')
        || !(value.is_empty() || value.starts_with(' '))
    {
        return None;
    }
    Some((key, value.trim()))
}

fn set_once<T>(slot: &mut Option<T>, value: T, key: &str, line: usize) -> Result<(), ClcbsError> {
    if slot.is_some() {
        return Err(parse_error(line, format!("`{key}` given twice")));
    }
    *slot = Some(value);
    Ok(())
}

/// A flow sequence of finite numbers: `[1, 2.5, -3]`.
fn parse_numbers(value: &str, line: usize) -> Result<Vec<f64>, ClcbsError> {
    let inner = value
        .strip_prefix('[')
        .and_then(|v| v.strip_suffix(']'))
        .ok_or_else(|| parse_error(line, format!("expected `[numbers]`, found `{value}`")))?;
    inner
        .split(',')
        .map(|item| {
            let item = item.trim();
            match item.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                _ => Err(parse_error(
                    line,
                    format!("`{item}` is not a finite number"),
                )),
            }
        })
        .collect()
}

fn parse_pose(value: &str, line: usize) -> Result<Pose, ClcbsError> {
    match parse_numbers(value, line)?[..] {
        [x, y, heading] => Ok(Pose::new(x, y, heading)),
        _ => Err(parse_error(line, "a pose takes [x, y, heading_rad]")),
    }
}

/// A plain or quoted scalar without YAML's special characters.
fn parse_name(value: &str, line: usize) -> Result<String, ClcbsError> {
    let unquoted = value
        .strip_prefix('"')
        .and_then(|v| v.strip_suffix('"'))
        .or_else(|| value.strip_prefix('\'').and_then(|v| v.strip_suffix('\'')))
        .unwrap_or(value);
    if unquoted.is_empty()
        || unquoted
            .chars()
            .any(|c| matches!(c, '[' | ']' | '{' | '}' | ',' | ':' | '"' | '\'') || c.is_control())
    {
        return Err(parse_error(line, format!("`{value}` is not a valid name")));
    }
    Ok(unquoted.to_string())
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
    fn parses_the_subset() {
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
        assert_eq!(
            error_line(&SAMPLE.replace("[3, 4.5, -1.57]", "[3, 4.5]")),
            4
        );
        assert_eq!(error_line(&SAMPLE.replace("[8, 9]", "[8, nan]")), 13);
        assert_eq!(
            error_line(&SAMPLE.replace("name: agent0", "nme: agent0")),
            3
        );
        assert_eq!(error_line(&SAMPLE.replace("[10, 20]", "[10, -1]")), 10);
        assert_eq!(
            error_line(&SAMPLE.replace("    start: [6, 7, 1.57]\n", "")),
            5
        );
        assert_eq!(error_line(&SAMPLE.replace("map:", "mapp:")), 9);
        assert_eq!(
            error_line(&SAMPLE.replace("    name: agent0", "\tname: agent0")),
            3
        );
        assert_eq!(error_line(&format!("{SAMPLE}map:\n")), 14);
        assert_eq!(error_line("agents:\n"), 1);
    }

    #[test]
    fn errors_display_the_path_and_line() {
        let e = ClcbsInstance::load(Path::new("/nonexistent/x.yaml")).expect_err("missing");
        assert!(e.to_string().contains("/nonexistent/x.yaml"), "{e}");
        let e = parse_error(3, "bad");
        assert_eq!(e.to_string(), "line 3: bad");
    }
}
