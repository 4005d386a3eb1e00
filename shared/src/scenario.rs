//! The scenario: field, obstacles, formation and path settings, read from TOML and
//! validated into a [`Scenario`] every other part can trust.
//!
//! Every error names the file and the field: `FILE: FIELD: REASON`. The format is
//! documented in `docs/scenario-format.md`.

use std::path::Path;

use rand::{Rng, SeedableRng};
use serde::Deserialize;

use crate::formation::Slot;
use crate::geometry::{Disk, Field, Point, Pose};
use crate::vocabulary::{AgentSpec, MAX_AGENTS, MAX_OBSTACLES, PlannerKind, PlannerSpec};
/// Largest field side accepted, in metres: beyond this the numbers stop being a field.
pub const MAX_FIELD_SIDE_M: f64 = 10_000.0;
/// Bound on the number of centre steps: `step_m` may not cut the field's diagonal into
/// more than a quarter of this many steps. It also bounds how finely the centre path
/// planner samples the path: every `turning_radius_m / 16` and `center_clearance_m / 2`
/// at most, so neither may cut the diagonal into more than this many samples.
pub const MAX_STEPS: usize = 200_000;
/// Largest magnitude of an angle in degrees (headings and slot angles): beyond it an
/// angle is a typo, and far beyond it a double has no precision left for the angle.
pub const MAX_ANGLE_DEG: f64 = 360.0;

/// The paper's example (section III), embedded so `coordinator run` works with no file.
pub const PAPER_SCENARIO_TOML: &str = include_str!("../../scenarios/paper.toml");
/// The name shown for the embedded paper scenario in messages.
pub const PAPER_SCENARIO_NAME: &str = "<embedded paper.toml>";

/// A validated scenario: every number finite and in range, every body placed legally.
#[derive(Clone, Debug, PartialEq)]
pub struct Scenario {
    /// Name, used in output folder names and plot titles.
    pub name: String,
    /// Seed for every random choice.
    pub seed: u64,
    /// The playing field.
    pub field: Field,
    /// Every obstacle with its true (not inflated) radius, explicit ones first, then the
    /// generated ones.
    pub obstacles: Vec<Disk>,
    /// The agents, in turn order.
    pub agents: Vec<AgentSpec>,
    /// Formation centre path settings.
    pub path: PathSpec,
    /// The controller and its settings.
    pub planner: PlannerSpec,
}

/// Settings of the formation centre's path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSpec {
    /// Start pose of the centre.
    pub start: Pose,
    /// Goal pose of the centre.
    pub goal: Pose,
    /// Minimum turning radius of the centre, in metres.
    pub turning_radius_m: f64,
    /// Centre travel between two steps, in metres.
    pub step_m: f64,
    /// Clearance the centre keeps from every obstacle boundary and field edge, in metres.
    pub center_clearance_m: f64,
    /// Whether the centre may drive backwards.
    pub allow_reverse: bool,
}

/// Why a scenario was rejected. Every variant displays as `FILE: FIELD: REASON`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ScenarioError {
    /// The file could not be read (missing, a directory, not UTF-8, ...).
    #[error("{file}: (file): {reason}")]
    Read {
        /// The file as given.
        file: String,
        /// What went wrong.
        reason: String,
    },
    /// The text is not a scenario: TOML syntax, an unknown field, a missing field or a
    /// value of the wrong type.
    #[error("{file}: {field}: {reason}")]
    Parse {
        /// The file as given.
        file: String,
        /// Dotted path of the offending field, or `line L, column C` for syntax errors.
        field: String,
        /// What went wrong.
        reason: String,
    },
    /// The values are well-formed but not a legal scenario (NaN, a negative size, an
    /// obstacle outside the field, overlapping slots, a blocked start, no path, ...).
    #[error("{file}: {field}: {reason}")]
    Invalid {
        /// The file as given.
        file: String,
        /// Dotted path of the offending field.
        field: String,
        /// What went wrong.
        reason: String,
    },
}

impl ScenarioError {
    /// The field the error names (`(file)` for read errors).
    pub fn field(&self) -> &str {
        match self {
            Self::Read { .. } => "(file)",
            Self::Parse { field, .. } | Self::Invalid { field, .. } => field,
        }
    }
}

// ---------------------------------------------------------------------------------------
// The file format (serde side). Units are in the names; unknown fields are errors.

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ScenarioFile {
    name: String,
    #[serde(default)]
    seed: u64,
    field: FieldFile,
    #[serde(default)]
    obstacles: ObstaclesFile,
    formation: FormationFile,
    path: PathFile,
    #[serde(default)]
    planner: PlannerKind,
    cbf: Option<CbfFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CbfFile {
    gamma_per_s: Option<f64>,
    dt_s: Option<f64>,
    gain_per_s: Option<f64>,
    max_speed_m_per_s: Option<f64>,
    sensing_radius_m: Option<f64>,
    lse_sharpness_per_m: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FieldFile {
    width_m: f64,
    height_m: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObstaclesFile {
    #[serde(default = "default_obstacle_radius_m")]
    radius_m: f64,
    /// `[x_m, y_m]` pairs; the length is checked by the [`Checker`] (serde would take the
    /// first two numbers of a longer array without a word).
    #[serde(default)]
    positions_m: Vec<Vec<f64>>,
    #[serde(default)]
    disk: Vec<DiskFile>,
    random: Option<RandomFile>,
}

impl Default for ObstaclesFile {
    fn default() -> Self {
        Self {
            radius_m: default_obstacle_radius_m(),
            positions_m: Vec::new(),
            disk: Vec::new(),
            random: None,
        }
    }
}

/// The paper's Assumption 4: one obstacle radius for all, 1 m unless the file says.
fn default_obstacle_radius_m() -> f64 {
    1.0
}

/// The paper's Assumption 3: one agent radius for all, 0.3 m unless the file says.
fn default_agent_radius_m() -> f64 {
    0.3
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DiskFile {
    x_m: f64,
    y_m: f64,
    radius_m: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RandomFile {
    count: usize,
    #[serde(default)]
    keep_clear_m: f64,
    radius_m: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FormationFile {
    #[serde(default = "default_agent_radius_m")]
    agent_radius_m: f64,
    slots: Vec<SlotFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SlotFile {
    r_m: f64,
    theta_deg: f64,
    radius_m: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PathFile {
    start: PoseFile,
    goal: PoseFile,
    turning_radius_m: f64,
    step_m: f64,
    center_clearance_m: f64,
    #[serde(default)]
    allow_reverse: bool,
}

#[derive(Deserialize, Clone, Copy)]
#[serde(deny_unknown_fields)]
struct PoseFile {
    x_m: f64,
    y_m: f64,
    heading_deg: f64,
}

impl PoseFile {
    fn pose(&self) -> Pose {
        Pose::new(self.x_m, self.y_m, self.heading_deg.to_radians())
    }
}

// ---------------------------------------------------------------------------------------

impl Scenario {
    /// The same scenario run by another planner.
    pub fn with_planner(&self, kind: PlannerKind) -> Self {
        let mut s = self.clone();
        s.planner.kind = kind;
        s
    }

    /// Read and validate the scenario file at `path`.
    pub fn load(path: &Path) -> Result<Self, ScenarioError> {
        Self::parse(&Self::read(path)?, &path.display().to_string())
    }

    /// The text of the scenario file at `path` (a directory, a missing file or a file
    /// that is not UTF-8 is a [`ScenarioError::Read`]).
    pub fn read(path: &Path) -> Result<String, ScenarioError> {
        let file = path.display().to_string();
        if path.is_dir() {
            return Err(ScenarioError::Read {
                file,
                reason: "is a directory, not a scenario file".into(),
            });
        }
        std::fs::read_to_string(path).map_err(|e| ScenarioError::Read {
            file,
            reason: e.to_string(),
        })
    }

    /// The paper's example, embedded in the library.
    pub fn paper() -> Self {
        match Self::parse(PAPER_SCENARIO_TOML, PAPER_SCENARIO_NAME) {
            Ok(s) => s,
            // The embedded file is checked by the test suite; reaching this is a build bug.
            Err(e) => panic!("embedded paper scenario is invalid: {e}"),
        }
    }

    /// Parse and validate scenario text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Self, ScenarioError> {
        let raw = parse_file(text, file)?;
        Checker { file }.check(raw)
    }

    /// Number of agents.
    pub fn agent_count(&self) -> usize {
        self.agents.len()
    }
}

/// Why a scenario has no resolved TOML form (only a scenario built by hand, not one this
/// module parsed, can meet these).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ResolveError {
    /// A value the file format cannot hold so that it reads back to the same bits.
    #[error("{field}: {reason}")]
    NotRepresentable {
        /// Dotted path of the field in the file format.
        field: String,
        /// Why it cannot be written.
        reason: String,
    },
}

impl Scenario {
    /// The scenario as a self-contained TOML file in this module's format: every obstacle
    /// listed in `obstacles.disk`, one `{ x_m, y_m, radius_m }` a line (random ones as drawn,
    /// no `[obstacles.random]` left), every agent with its own radius, every default
    /// written out (the planner, the `[cbf]` settings, `allow_reverse`). Numbers are
    /// written in their shortest round-trip form and angles in the degrees that convert
    /// back to the same radians, so [`Scenario::parse`] of the text gives this scenario
    /// bit for bit. `source` (a file name) is named in the comment header.
    ///
    /// Fails only for a scenario that no file could give: a seed beyond TOML's integers
    /// or an angle no degree value converts to.
    pub fn to_resolved_toml(&self, source: &str) -> Result<String, ResolveError> {
        use std::fmt::Write as _;
        let mut t = String::new();
        let source = comment_safe(source);
        let name = toml_string(&self.name);
        // `write!` into a String cannot fail.
        let _ = writeln!(
            t,
            "# Resolved form of scenario {name} as run, from {source}:\n\
             # every obstacle listed explicitly (those drawn from the seed included), every\n\
             # default written out, the planner as run. It loads to the same scenario, bit for\n\
             # bit; numbers are in their shortest round-trip form."
        );
        let seed = i64::try_from(self.seed).map_err(|_| ResolveError::NotRepresentable {
            field: "seed".into(),
            reason: format!("{} is beyond TOML's integers", self.seed),
        })?;
        let _ = writeln!(t, "name = {name}");
        let _ = writeln!(
            t,
            "seed = {seed}  # drew the generated obstacles, now listed below; no longer used"
        );
        let _ = writeln!(t, "planner = {}", toml_string(self.planner.kind.name()));

        let _ = writeln!(t, "\n[field]");
        let _ = writeln!(t, "width_m = {}", toml_f64(self.field.width_m));
        let _ = writeln!(t, "height_m = {}", toml_f64(self.field.height_m));

        let c = &self.planner.cbf;
        let _ = writeln!(t, "\n[cbf]");
        for (key, v) in [
            ("gamma_per_s", c.gamma_per_s),
            ("dt_s", c.dt_s),
            ("gain_per_s", c.gain_per_s),
            ("max_speed_m_per_s", c.max_speed_m_per_s),
            ("sensing_radius_m", c.sensing_radius_m),
            ("lse_sharpness_per_m", self.planner.lse_sharpness_per_m),
        ] {
            let _ = writeln!(t, "{key} = {}", toml_f64(v));
        }

        // The default radius is checked even when every obstacle has its own: write one
        // the checks accept (the first obstacle's, or at most the field's side).
        let side_m = self.field.width_m.max(self.field.height_m);
        let default_obstacle_m = self
            .obstacles
            .first()
            .map_or(default_obstacle_radius_m().min(side_m), |o| o.radius_m);
        let _ = writeln!(t, "\n[obstacles]  # {} obstacles", self.obstacles.len());
        let _ = writeln!(t, "radius_m = {}", toml_f64(default_obstacle_m));
        let _ = writeln!(t, "disk = [");
        for o in &self.obstacles {
            let _ = writeln!(
                t,
                "  {{ x_m = {}, y_m = {}, radius_m = {} }},",
                toml_f64(o.center.x),
                toml_f64(o.center.y),
                toml_f64(o.radius_m)
            );
        }
        let _ = writeln!(t, "]");

        let _ = writeln!(t, "\n[formation]");
        let default_agent_m = self
            .agents
            .first()
            .map_or(default_agent_radius_m(), |a| a.radius_m);
        let _ = writeln!(t, "agent_radius_m = {}", toml_f64(default_agent_m));
        let _ = writeln!(t, "slots = [");
        for (i, a) in self.agents.iter().enumerate() {
            let theta_deg = degrees_for(a.slot.theta_rad).ok_or_else(|| {
                not_in_degrees(format!("formation.slots[{i}].theta_deg"), a.slot.theta_rad)
            })?;
            let _ = writeln!(
                t,
                "  {{ r_m = {}, theta_deg = {}, radius_m = {} }},",
                toml_f64(a.slot.r_m),
                toml_f64(theta_deg),
                toml_f64(a.radius_m)
            );
        }
        let _ = writeln!(t, "]");

        let p = &self.path;
        let _ = writeln!(t, "\n[path]");
        for (key, pose) in [("start", &p.start), ("goal", &p.goal)] {
            let heading_deg = degrees_for(pose.heading_rad).ok_or_else(|| {
                not_in_degrees(format!("path.{key}.heading_deg"), pose.heading_rad)
            })?;
            let _ = writeln!(
                t,
                "{key} = {{ x_m = {}, y_m = {}, heading_deg = {} }}",
                toml_f64(pose.x_m),
                toml_f64(pose.y_m),
                toml_f64(heading_deg)
            );
        }
        let _ = writeln!(t, "turning_radius_m = {}", toml_f64(p.turning_radius_m));
        let _ = writeln!(t, "step_m = {}", toml_f64(p.step_m));
        let _ = writeln!(t, "center_clearance_m = {}", toml_f64(p.center_clearance_m));
        let _ = writeln!(t, "allow_reverse = {}", p.allow_reverse);
        Ok(t)
    }
}

fn not_in_degrees(field: String, rad: f64) -> ResolveError {
    ResolveError::NotRepresentable {
        field,
        reason: format!(
            "no angle in degrees within -{MAX_ANGLE_DEG}..={MAX_ANGLE_DEG} converts to {rad:?} rad"
        ),
    }
}

/// A TOML float that parses back to the same bits: Rust's shortest round-trip form,
/// always with a fraction or an exponent (`1.0`, not the integer `1`), and TOML's names
/// for the non-finite values.
fn toml_f64(v: f64) -> String {
    if v.is_nan() {
        "nan".into()
    } else if v.is_infinite() {
        if v > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        // Debug is the shortest round-trip form with `.0` or an exponent (`1e-7`,
        // `1.5e16`), both valid TOML floats.
        format!("{v:?}")
    }
}

/// A TOML basic string, quoted and escaped.
fn toml_string(s: &str) -> String {
    toml::Value::String(s.to_string()).to_string()
}

/// `s` fit for a TOML comment (no control characters).
fn comment_safe(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_control() { '?' } else { c })
        .collect()
}

/// An angle in degrees within the format's range whose `to_radians()` is exactly `rad`
/// (bit for bit), preferring a short decimal (`120.0` rather than `119.99999999999999`):
/// the file's value when `rad` came from a file.
fn degrees_for(rad: f64) -> Option<f64> {
    if !rad.is_finite() {
        return None;
    }
    let exact = |d: f64| d.abs() <= MAX_ANGLE_DEG && d.to_radians().to_bits() == rad.to_bits();
    let d0 = rad.to_degrees();
    for digits in 0..=15 {
        let scale = 10f64.powi(digits);
        let d = (d0 * scale).round() / scale;
        if exact(d) {
            return Some(d);
        }
    }
    // `to_radians` is one rounded multiplication, so monotone: walk towards `rad`.
    let mut d = d0;
    for _ in 0..256 {
        if exact(d) {
            return Some(d);
        }
        d = if d.to_radians() < rad {
            d.next_up()
        } else {
            d.next_down()
        };
    }
    None
}

fn parse_file(text: &str, file: &str) -> Result<ScenarioFile, ScenarioError> {
    let syntax = |e: toml::de::Error| ScenarioError::Parse {
        file: file.to_string(),
        field: e
            .span()
            .map(|s| line_column(text, s.start))
            .unwrap_or_else(|| "(syntax)".into()),
        reason: one_line(e.message()),
    };
    let deserializer = toml::Deserializer::parse(text).map_err(syntax)?;
    let raw = serde_path_to_error::deserialize(deserializer).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner();
        let top = path == "." || path.is_empty();
        // A missing field is reported at the table that lacks it: name the field itself.
        let missing = inner
            .message()
            .strip_prefix("missing field `")
            .and_then(|rest| rest.strip_suffix('`'))
            .map(str::to_owned);
        let field = match missing {
            Some(name) if top => name,
            Some(name) => format!("{path}.{name}"),
            None if top => inner
                .span()
                .map(|s| line_column(text, s.start))
                .unwrap_or_else(|| "(top level)".into()),
            None => path,
        };
        ScenarioError::Parse {
            file: file.to_string(),
            field,
            reason: one_line(inner.message()),
        }
    })?;
    let document: toml::Table = toml::from_str(text).map_err(syntax)?;
    if let Some(field) = table_given_as_array(&document) {
        return Err(ScenarioError::Parse {
            file: file.to_string(),
            field,
            reason:
                "invalid type: array, expected a table of named values (units are in the names)"
                    .into(),
        });
    }
    Ok(raw)
}

/// The first table of the format written as an array (`start = [3.0, 5.0, 0.0]`), if
/// any. Serde fills a struct from an array by position, silently dropping extra items;
/// the format wants every value named with its unit.
fn table_given_as_array(document: &toml::Table) -> Option<String> {
    const TABLES: [&str; 7] = [
        "field",
        "obstacles",
        "obstacles.random",
        "formation",
        "path",
        "path.start",
        "path.goal",
    ];
    const ARRAYS_OF_TABLES: [&str; 2] = ["obstacles.disk", "formation.slots"];
    let lookup = |path: &str| {
        let mut parts = path.split('.');
        let mut value = document.get(parts.next()?)?;
        for part in parts {
            value = value.as_table()?.get(part)?;
        }
        Some(value)
    };
    if let Some(path) = TABLES
        .into_iter()
        .find(|path| lookup(path).is_some_and(toml::Value::is_array))
    {
        return Some(path.to_string());
    }
    ARRAYS_OF_TABLES.into_iter().find_map(|path| {
        let items = lookup(path)?.as_array()?;
        let i = items.iter().position(toml::Value::is_array)?;
        Some(format!("{path}[{i}]"))
    })
}

/// A number for a message: plain when short, in exponent form when huge or tiny (a
/// 1e308 m field should not print 309 digits).
fn num(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || !a.is_finite() || (1e-4..1e9).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// `line L, column C` of a byte offset (both from 1, the column in characters). An
/// offset past the end or inside a character is taken back to the character's start.
fn line_column(text: &str, offset: usize) -> String {
    let mut end = offset.min(text.len());
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    let before = &text[..end];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let column = before[line_start..].chars().count() + 1;
    format!("line {line}, column {column}")
}

fn one_line(message: &str) -> String {
    message.split_whitespace().collect::<Vec<_>>().join(" ")
}

struct Checker<'a> {
    file: &'a str,
}

impl Checker<'_> {
    fn invalid(&self, field: impl Into<String>, reason: impl Into<String>) -> ScenarioError {
        ScenarioError::Invalid {
            file: self.file.to_string(),
            field: field.into(),
            reason: reason.into(),
        }
    }

    fn finite(&self, field: &str, v: f64) -> Result<f64, ScenarioError> {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(self.invalid(field, format!("must be a finite number, got {v}")))
        }
    }

    fn angle_deg(&self, field: &str, v: f64) -> Result<f64, ScenarioError> {
        self.finite(field, v)?;
        if v.abs() > MAX_ANGLE_DEG {
            return Err(self.invalid(
                field,
                format!(
                    "{} degrees is outside -{MAX_ANGLE_DEG}..={MAX_ANGLE_DEG}",
                    num(v)
                ),
            ));
        }
        Ok(v)
    }

    fn positive(&self, field: &str, v: f64, max: f64) -> Result<f64, ScenarioError> {
        self.finite(field, v)?;
        if v <= 0.0 {
            return Err(self.invalid(field, format!("must be positive, got {}", num(v))));
        }
        if v > max {
            return Err(self.invalid(
                field,
                format!("{} is larger than the limit {}", num(v), num(max)),
            ));
        }
        Ok(v)
    }

    fn non_negative(&self, field: &str, v: f64, max: f64) -> Result<f64, ScenarioError> {
        self.finite(field, v)?;
        if v < 0.0 {
            return Err(self.invalid(field, format!("must not be negative, got {}", num(v))));
        }
        if v > max {
            return Err(self.invalid(
                field,
                format!("{} is larger than the limit {}", num(v), num(max)),
            ));
        }
        Ok(v)
    }

    fn pose(&self, field: &str, p: &PoseFile, area: &Field) -> Result<Pose, ScenarioError> {
        self.finite(&format!("{field}.x_m"), p.x_m)?;
        self.finite(&format!("{field}.y_m"), p.y_m)?;
        self.angle_deg(&format!("{field}.heading_deg"), p.heading_deg)?;
        if !area.contains(&Point::new(p.x_m, p.y_m), 0.0) {
            return Err(self.invalid(
                field,
                format!(
                    "({}, {}) is outside the {} x {} m field",
                    num(p.x_m),
                    num(p.y_m),
                    area.width_m,
                    area.height_m
                ),
            ));
        }
        Ok(p.pose())
    }

    fn check(&self, raw: ScenarioFile) -> Result<Scenario, ScenarioError> {
        if raw.name.trim().is_empty() {
            return Err(self.invalid("name", "must not be empty"));
        }
        let width_m = self.positive("field.width_m", raw.field.width_m, MAX_FIELD_SIDE_M)?;
        let height_m = self.positive("field.height_m", raw.field.height_m, MAX_FIELD_SIDE_M)?;
        let field = Field::new(width_m, height_m);
        let side_m = width_m.max(height_m);

        // Path settings first: random obstacles keep clear of the start and goal.
        let p = &raw.path;
        let start = self.pose("path.start", &p.start, &field)?;
        let goal = self.pose("path.goal", &p.goal, &field)?;
        let path = PathSpec {
            start,
            goal,
            turning_radius_m: self.positive("path.turning_radius_m", p.turning_radius_m, side_m)?,
            step_m: self.positive("path.step_m", p.step_m, side_m)?,
            center_clearance_m: self.non_negative(
                "path.center_clearance_m",
                p.center_clearance_m,
                0.5 * width_m.min(height_m),
            )?,
            allow_reverse: p.allow_reverse,
        };
        let diagonal_m = width_m.hypot(height_m);
        if diagonal_m / path.step_m > MAX_STEPS as f64 / 4.0 {
            return Err(self.invalid(
                "path.step_m",
                format!(
                    "{} m is too small for a {width_m} x {height_m} m field (more than {MAX_STEPS} steps)",
                    num(path.step_m)
                ),
            ));
        }
        // The planner samples the centre path every turning_radius_m / 16 and
        // center_clearance_m / 2 at most: bound the samples as the steps are bounded.
        let finest_m = diagonal_m / MAX_STEPS as f64;
        if path.turning_radius_m / 16.0 < finest_m {
            return Err(self.invalid(
                "path.turning_radius_m",
                format!(
                    "{} m is too small for a {width_m} x {height_m} m field (the planner would sample the path more than {MAX_STEPS} times across it; at least {} m)",
                    num(path.turning_radius_m),
                    num(16.0 * finest_m)
                ),
            ));
        }
        if path.center_clearance_m > 0.0 && path.center_clearance_m / 2.0 < finest_m {
            return Err(self.invalid(
                "path.center_clearance_m",
                format!(
                    "{} m is too small for a {width_m} x {height_m} m field (the planner would sample the path more than {MAX_STEPS} times across it; 0 or at least {} m)",
                    num(path.center_clearance_m),
                    num(2.0 * finest_m)
                ),
            ));
        }

        let obstacles = self.obstacles(&raw.obstacles, &field, &path, raw.seed)?;
        let agents = self.agents(&raw.formation, &field)?;
        self.start_and_goal_clear(&obstacles, &field, &path)?;
        self.formation_fits_at_start(&agents, &obstacles, &field, &path)?;
        let planner = self.planner(raw.planner, raw.cbf.as_ref(), &agents, side_m)?;

        Ok(Scenario {
            name: raw.name,
            seed: raw.seed,
            field,
            obstacles,
            agents,
            path,
            planner,
        })
    }

    fn planner(
        &self,
        kind: PlannerKind,
        raw: Option<&CbfFile>,
        agents: &[AgentSpec],
        side_m: f64,
    ) -> Result<PlannerSpec, ScenarioError> {
        let mut spec = PlannerSpec {
            kind,
            ..PlannerSpec::default()
        };
        if let Some(c) = raw {
            let set = |name: &str, v: Option<f64>, slot: &mut f64| -> Result<(), ScenarioError> {
                if let Some(v) = v {
                    *slot = self.positive(&format!("cbf.{name}"), v, side_m.max(1e3))?;
                }
                Ok(())
            };
            set("gamma_per_s", c.gamma_per_s, &mut spec.cbf.gamma_per_s)?;
            set("dt_s", c.dt_s, &mut spec.cbf.dt_s)?;
            set("gain_per_s", c.gain_per_s, &mut spec.cbf.gain_per_s)?;
            set(
                "max_speed_m_per_s",
                c.max_speed_m_per_s,
                &mut spec.cbf.max_speed_m_per_s,
            )?;
            set(
                "sensing_radius_m",
                c.sensing_radius_m,
                &mut spec.cbf.sensing_radius_m,
            )?;
            set(
                "lse_sharpness_per_m",
                c.lse_sharpness_per_m,
                &mut spec.lse_sharpness_per_m,
            )?;
        }
        spec.check(agents)
            .map_err(|e| self.invalid("cbf", e.to_string()))?;
        Ok(spec)
    }

    fn obstacles(
        &self,
        raw: &ObstaclesFile,
        field: &Field,
        path: &PathSpec,
        seed: u64,
    ) -> Result<Vec<Disk>, ScenarioError> {
        let side_m = field.width_m.max(field.height_m);
        let default_radius_m = self.positive("obstacles.radius_m", raw.radius_m, side_m)?;
        let explicit = raw.positions_m.len() + raw.disk.len();
        if explicit > MAX_OBSTACLES {
            return Err(self.invalid(
                "obstacles",
                format!(
                    "{} explicit obstacles ({} in positions_m, {} in disk) exceed the capacity of {MAX_OBSTACLES}",
                    explicit,
                    raw.positions_m.len(),
                    raw.disk.len()
                ),
            ));
        }
        let mut obstacles = Vec::with_capacity(explicit);
        // `name` is the obstacle's path, `x` and `y` those of its coordinates.
        let mut place = |name: String, x: (String, f64), y: (String, f64), radius_m: f64| {
            let x_m = self.finite(&x.0, x.1)?;
            let y_m = self.finite(&y.0, y.1)?;
            if !field.contains(&Point::new(x_m, y_m), 0.0) {
                return Err(self.invalid(
                    name,
                    format!(
                        "obstacle centre ({}, {}) is outside the {} x {} m field",
                        num(x_m),
                        num(y_m),
                        field.width_m,
                        field.height_m
                    ),
                ));
            }
            obstacles.push(Disk::new(x_m, y_m, radius_m));
            Ok(())
        };
        for (i, xy) in raw.positions_m.iter().enumerate() {
            let name = format!("obstacles.positions_m[{i}]");
            let &[x_m, y_m] = xy.as_slice() else {
                return Err(self.invalid(
                    name,
                    format!("must be a pair [x_m, y_m], got {} value(s)", xy.len()),
                ));
            };
            place(
                name.clone(),
                (format!("{name}[0]"), x_m),
                (format!("{name}[1]"), y_m),
                default_radius_m,
            )?;
        }
        for (i, d) in raw.disk.iter().enumerate() {
            let name = format!("obstacles.disk[{i}]");
            let x = (format!("{name}.x_m"), d.x_m);
            let y = (format!("{name}.y_m"), d.y_m);
            let radius_m = match d.radius_m {
                Some(r) => self.positive(&format!("{name}.radius_m"), r, side_m)?,
                None => default_radius_m,
            };
            place(name, x, y, radius_m)?;
        }
        if let Some(random) = &raw.random {
            if random.count > MAX_OBSTACLES - explicit {
                return Err(self.invalid(
                    "obstacles.random.count",
                    format!(
                        "{} random obstacles and {explicit} explicit ones exceed the capacity of {MAX_OBSTACLES}",
                        random.count
                    ),
                ));
            }
            let radius_m = match random.radius_m {
                Some(r) => self.positive("obstacles.random.radius_m", r, side_m)?,
                None => default_radius_m,
            };
            let keep_clear_m =
                self.non_negative("obstacles.random.keep_clear_m", random.keep_clear_m, side_m)?;
            obstacles.extend(self.random_obstacles(
                random.count,
                radius_m,
                keep_clear_m,
                field,
                path,
                seed,
            )?);
        }
        if obstacles.len() > MAX_OBSTACLES {
            return Err(self.invalid(
                "obstacles",
                format!(
                    "{} obstacles exceed the capacity of {MAX_OBSTACLES}",
                    obstacles.len()
                ),
            ));
        }
        Ok(obstacles)
    }

    /// Uniformly placed obstacles whose disks stay `keep_clear_m` away from the start and
    /// goal positions, drawn from a ChaCha8 stream seeded with the scenario's seed.
    fn random_obstacles(
        &self,
        count: usize,
        radius_m: f64,
        keep_clear_m: f64,
        field: &Field,
        path: &PathSpec,
        seed: u64,
    ) -> Result<Vec<Disk>, ScenarioError> {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let keep = [path.start.position(), path.goal.position()];
        let mut disks = Vec::with_capacity(count);
        let max_attempts = 1000 * count.max(1);
        let mut attempts = 0;
        while disks.len() < count {
            attempts += 1;
            if attempts > max_attempts {
                return Err(self.invalid(
                    "obstacles.random",
                    format!(
                        "could place only {} of {count} obstacles clear of the start and goal",
                        disks.len()
                    ),
                ));
            }
            let c = Point::new(
                rng.random_range(0.0..=field.width_m),
                rng.random_range(0.0..=field.height_m),
            );
            if keep
                .iter()
                .all(|k| (c - k).norm() >= radius_m + keep_clear_m)
            {
                disks.push(Disk {
                    center: c,
                    radius_m,
                });
            }
        }
        Ok(disks)
    }

    fn agents(&self, raw: &FormationFile, field: &Field) -> Result<Vec<AgentSpec>, ScenarioError> {
        let hold_m = 0.5 * field.width_m.min(field.height_m);
        let default_radius_m =
            self.positive("formation.agent_radius_m", raw.agent_radius_m, hold_m)?;
        if raw.slots.is_empty() {
            return Err(self.invalid("formation.slots", "the formation has no agents"));
        }
        if raw.slots.len() > MAX_AGENTS {
            return Err(self.invalid(
                "formation.slots",
                format!(
                    "{} agents exceed the capacity of {MAX_AGENTS}",
                    raw.slots.len()
                ),
            ));
        }
        let mut agents = Vec::with_capacity(raw.slots.len());
        for (i, s) in raw.slots.iter().enumerate() {
            let name = format!("formation.slots[{i}]");
            let r_m = self.non_negative(
                &format!("{name}.r_m"),
                s.r_m,
                field.width_m.hypot(field.height_m),
            )?;
            let theta_deg = self.angle_deg(&format!("{name}.theta_deg"), s.theta_deg)?;
            let radius_m = match s.radius_m {
                Some(r) => self.positive(&format!("{name}.radius_m"), r, hold_m)?,
                None => default_radius_m,
            };
            agents.push(AgentSpec {
                slot: Slot::new(r_m, theta_deg.to_radians()),
                radius_m,
            });
        }
        // The paper's Assumption 2: the nominal formation is itself collision-free.
        let origin = Pose::new(0.0, 0.0, 0.0);
        for i in 0..agents.len() {
            for j in 0..i {
                let d = (agents[i].slot.ideal_position(&origin)
                    - agents[j].slot.ideal_position(&origin))
                .norm();
                let need = agents[i].radius_m + agents[j].radius_m;
                if d < need {
                    return Err(self.invalid(
                        format!("formation.slots[{i}]"),
                        format!(
                            "slot is {d:.4} m from slot {j}, closer than their radii sum {need:.4} m (Assumption 2)"
                        ),
                    ));
                }
            }
        }
        Ok(agents)
    }

    fn start_and_goal_clear(
        &self,
        obstacles: &[Disk],
        field: &Field,
        path: &PathSpec,
    ) -> Result<(), ScenarioError> {
        for (name, pose) in [("path.start", &path.start), ("path.goal", &path.goal)] {
            let p = pose.position();
            if field.signed_inset_m(&p) < path.center_clearance_m {
                return Err(self.invalid(
                    name,
                    format!(
                        "({}, {}) is closer to the field's edge than the centre clearance {} m",
                        p.x, p.y, path.center_clearance_m
                    ),
                ));
            }
            if let Some((k, o)) = obstacles
                .iter()
                .enumerate()
                .find(|(_, o)| o.signed_distance_m(&p) < path.center_clearance_m)
            {
                return Err(self.invalid(
                    name,
                    format!(
                        "({}, {}) is within the centre clearance {} m of obstacle {k} at ({}, {}) radius {} m",
                        p.x, p.y, path.center_clearance_m, o.center.x, o.center.y, o.radius_m
                    ),
                ));
            }
        }
        Ok(())
    }

    fn formation_fits_at_start(
        &self,
        agents: &[AgentSpec],
        obstacles: &[Disk],
        field: &Field,
        path: &PathSpec,
    ) -> Result<(), ScenarioError> {
        for (i, a) in agents.iter().enumerate() {
            let name = format!("formation.slots[{i}]");
            let p = a.slot.ideal_position(&path.start);
            if field.signed_inset_m(&p) < a.radius_m {
                return Err(self.invalid(
                    name,
                    format!(
                        "at the start pose the agent at ({:.3}, {:.3}) does not fit inside the field",
                        p.x, p.y
                    ),
                ));
            }
            if let Some((k, o)) = obstacles
                .iter()
                .enumerate()
                .find(|(_, o)| o.signed_distance_m(&p) < a.radius_m)
            {
                return Err(self.invalid(
                    name,
                    format!(
                        "at the start pose the agent at ({:.3}, {:.3}) overlaps obstacle {k} at ({}, {})",
                        p.x, p.y, o.center.x, o.center.y
                    ),
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = r#"
name = "t"
[field]
width_m = 20.0
height_m = 10.0
[formation]
slots = [ { r_m = 0.0, theta_deg = 0.0 }, { r_m = 1.0, theta_deg = 90.0 } ]
[path]
start = { x_m = 3.0, y_m = 5.0, heading_deg = 0.0 }
goal = { x_m = 17.0, y_m = 5.0, heading_deg = 0.0 }
turning_radius_m = 2.0
step_m = 0.5
center_clearance_m = 0.3
"#;

    #[test]
    fn a_minimal_file_gets_the_papers_default_radii() {
        let s = Scenario::parse(MINIMAL, "min.toml").unwrap();
        assert_eq!(s.agents.len(), 2);
        assert!(s.agents.iter().all(|a| a.radius_m == 0.3));
        assert!(s.obstacles.is_empty());
    }

    #[test]
    fn the_embedded_paper_scenario_is_valid_and_has_the_papers_formation() {
        let s = Scenario::paper();
        let want = [
            (1.0, 0.0),
            (0.0, 0.0),
            (1.5, 45.0),
            (1.0, 120.0),
            (1.5, 180.0),
            (2.0, -120.0),
        ];
        assert_eq!(s.agents.len(), want.len());
        for (a, (r, th)) in s.agents.iter().zip(want) {
            assert_eq!(a.slot.r_m, r);
            assert!((a.slot.theta_rad - f64::to_radians(th)).abs() < 1e-15);
        }
        assert_eq!(s.path.start, Pose::new(2.0, 2.0, 0.0));
    }

    #[test]
    fn random_obstacles_are_reproducible_and_keep_clear_of_start_and_goal() {
        let text = MINIMAL.replace(
            "[formation]",
            "[obstacles.random]\ncount = 25\nkeep_clear_m = 2.0\n[formation]",
        );
        let a = Scenario::parse(&text, "r.toml").unwrap();
        let b = Scenario::parse(&text, "r.toml").unwrap();
        assert_eq!(a.obstacles, b.obstacles);
        assert_eq!(a.obstacles.len(), 25);
        for o in &a.obstacles {
            for p in [a.path.start.position(), a.path.goal.position()] {
                assert!(o.signed_distance_m(&p) >= 2.0 - 1e-12);
            }
        }
        let c = Scenario::parse(
            &text.replace("name = \"t\"", "name = \"t\"\nseed = 9"),
            "r.toml",
        )
        .unwrap();
        assert_ne!(a.obstacles, c.obstacles, "the seed drives the field");
    }

    #[test]
    fn errors_name_the_file_and_the_field() {
        let cases = [
            (
                MINIMAL.replace("width_m = 20.0", "width_m = -1.0"),
                "field.width_m",
            ),
            (
                MINIMAL.replace("width_m = 20.0", "width_m = nan"),
                "field.width_m",
            ),
            (
                MINIMAL.replace("step_m = 0.5", "step_m = inf"),
                "path.step_m",
            ),
            (MINIMAL.replace("[path]", "[path]\nspeed = 1"), "path.speed"),
            (
                MINIMAL.replace("r_m = 1.0", "r_m = 0.5"),
                "formation.slots[1]",
            ),
            (
                MINIMAL.replace("r_m = 1.0", "r_m = \"far\""),
                "formation.slots[1].r_m",
            ),
            (MINIMAL.replace("x_m = 3.0", "x_m = 30.0"), "path.start"),
        ];
        for (text, field) in cases {
            let e = Scenario::parse(&text, "bad.toml").unwrap_err();
            assert_eq!(e.field(), field, "{e}");
            let line = e.to_string();
            assert!(line.starts_with("bad.toml: "), "{line}");
            assert!(!line.contains('\n'), "one line: {line}");
        }
    }

    /// `a` and `b` equal and bit for bit the same (Debug prints every float in its
    /// shortest round-trip form, so `-0.0` and `0.0` differ there).
    fn assert_same(a: &Scenario, b: &Scenario, what: &str) {
        assert_eq!(a, b, "{what}");
        assert_eq!(format!("{a:?}"), format!("{b:?}"), "{what}: bit for bit");
    }

    /// The resolved text of `s`, checked to parse back to `s`.
    fn round_trip(s: &Scenario, what: &str) -> String {
        let text = s
            .to_resolved_toml(what)
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        let back = Scenario::parse(&text, "resolved.toml")
            .unwrap_or_else(|e| panic!("{what}: resolved text does not load: {e}\n{text}"));
        assert_same(&back, s, what);
        assert_eq!(back.obstacles.len(), s.obstacles.len(), "{what}");
        text
    }

    #[test]
    fn every_shipped_scenario_resolves_to_a_file_that_loads_to_the_same_scenario() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios");
        let mut files: Vec<_> = std::fs::read_dir(&dir)
            .expect("scenarios/")
            .map(|e| e.expect("entry").path())
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        files.sort();
        assert!(files.len() >= 5, "{files:?}");
        let mut generated = 0;
        for file in &files {
            let what = file.display().to_string();
            let s = Scenario::load(file).unwrap_or_else(|e| panic!("{e}"));
            let original = Scenario::read(file).expect("read");
            generated += usize::from(original.contains("[obstacles.random]"));
            for kind in PlannerKind::ALL {
                let s = s.with_planner(kind);
                let text = round_trip(&s, &what);
                assert!(!text.contains("random"), "{what}: {text}");
                let doc: toml::Table = toml::from_str(&text).expect("TOML");
                let obstacles = doc["obstacles"].as_table().expect("[obstacles]");
                assert!(!obstacles.contains_key("random"), "{what}");
                assert!(!obstacles.contains_key("positions_m"), "{what}");
                assert_eq!(
                    obstacles["disk"].as_array().expect("disk").len(),
                    s.obstacles.len(),
                    "{what}: every obstacle listed"
                );
                assert_eq!(doc["planner"].as_str(), Some(kind.name()), "{what}");
                assert!(text.starts_with("# Resolved form"), "{what}");
                assert!(text.contains(&what), "{what}: the source is named");
            }
        }
        assert!(
            generated >= 3,
            "the shipped scenarios draw obstacles from a seed"
        );
    }

    #[test]
    fn awkward_values_round_trip_bit_for_bit() {
        let text = r#"
name = "odd \"name\" \u00e9 # not a comment"
seed = 9223372036854775807
planner = "cbf"
[cbf]
gamma_per_s = 0.30000000000000004
dt_s = 3.0
gain_per_s = 1e-7
max_speed_m_per_s = 0.1
sensing_radius_m = 1.2345678901234567
lse_sharpness_per_m = 987.125
[field]
width_m = 20.000000000000004
height_m = 10.0
[obstacles]
radius_m = 0.3
positions_m = [[10.0, 9.9999999999999982]]
disk = [ { x_m = 12.5, y_m = 0.1, radius_m = 0.7 } ]
[obstacles.random]
count = 5
keep_clear_m = 1.5
radius_m = 0.45
[formation]
agent_radius_m = 0.2
slots = [
  { r_m = 0.0, theta_deg = -0.0 },
  { r_m = 1.0000000000000002, theta_deg = 33.333333333333336, radius_m = 0.25 },
  { r_m = 1.0, theta_deg = -179.99999999999997 },
  { r_m = 1.0, theta_deg = 360.0 },
  { r_m = 1.5, theta_deg = 0.1 },
]
[path]
start = { x_m = 3.0, y_m = 5.0, heading_deg = -0.0 }
goal = { x_m = 17.0, y_m = 5.0, heading_deg = -359.99999999999994 }
turning_radius_m = 2.0
step_m = 0.1
center_clearance_m = 0.0
allow_reverse = true
"#;
        let s = Scenario::parse(text, "odd.toml").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.obstacles.len(), 7);
        let resolved = round_trip(&s, "odd\nfile # name.toml");
        assert!(resolved.contains("odd?file # name.toml"), "{resolved}");
        assert!(
            resolved.contains("theta_deg = 33.333333333333336"),
            "{resolved}"
        );
        assert!(resolved.contains("theta_deg = 360.0"), "{resolved}");
        assert!(resolved.contains("heading_deg = -0.0"), "{resolved}");
        // A field smaller than the default radii: the written defaults must still pass.
        let tiny = r#"
name = "tiny"
[field]
width_m = 0.8
height_m = 0.6
[obstacles]
radius_m = 0.05
[formation]
agent_radius_m = 0.1
slots = [ { r_m = 0.0, theta_deg = 0.0 } ]
[path]
start = { x_m = 0.2, y_m = 0.3, heading_deg = 0.0 }
goal = { x_m = 0.6, y_m = 0.3, heading_deg = 0.0 }
turning_radius_m = 0.1
step_m = 0.05
center_clearance_m = 0.1
"#;
        let s = Scenario::parse(tiny, "tiny.toml").unwrap_or_else(|e| panic!("{e}"));
        round_trip(&s, "tiny.toml");
    }

    #[test]
    fn every_angle_in_range_has_exact_degrees() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        for _ in 0..20_000 {
            let d: f64 = rng.random_range(-MAX_ANGLE_DEG..=MAX_ANGLE_DEG);
            let rad = d.to_radians();
            let back = degrees_for(rad).unwrap_or_else(|| panic!("{d:?}"));
            assert_eq!(back.to_radians().to_bits(), rad.to_bits(), "{d:?}");
        }
        assert_eq!(degrees_for(f64::NAN), None);
        assert_eq!(degrees_for(100.0), None, "about 5730 degrees: out of range");
    }

    #[test]
    fn a_scenario_no_file_could_give_has_no_resolved_form() {
        let mut s = Scenario::paper();
        s.seed = u64::MAX;
        let e = s.to_resolved_toml("x").unwrap_err();
        assert!(e.to_string().starts_with("seed: "), "{e}");
        let mut s = Scenario::paper();
        s.agents[2].slot.theta_rad = f64::NAN;
        let e = s.to_resolved_toml("x").unwrap_err();
        assert!(
            e.to_string().starts_with("formation.slots[2].theta_deg: "),
            "{e}"
        );
    }

    #[test]
    fn syntax_errors_point_at_the_line() {
        let e = Scenario::parse("name = \"x\"\n[field\n", "s.toml").unwrap_err();
        assert!(e.field().starts_with("line 2"), "{e}");
    }
}
