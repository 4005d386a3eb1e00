//! The resolved form of a scenario: the scenario written back as a self-contained TOML
//! file that loads to the same scenario, bit for bit (the `scenario.toml` of a run's
//! output folder).

use super::Scenario;
use super::check::MAX_ANGLE_DEG;
use super::file::{default_agent_radius_m, default_obstacle_radius_m};
use crate::moving_obstacle::MovingObstacle;

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
    /// The scenario as a self-contained TOML file in the scenario format: every obstacle
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
                toml_f64(o.centre.x),
                toml_f64(o.centre.y),
                toml_f64(o.radius_m)
            );
        }
        let _ = writeln!(t, "]");
        for m in &self.moving {
            t.push('\n');
            t.push_str(&moving_obstacle_table(m));
        }
        for o in &self.unknown {
            let _ = writeln!(t, "\n[[obstacles.unknown]]");
            let _ = writeln!(
                t,
                "x_m = {}\ny_m = {}\nradius_m = {}",
                toml_f64(o.centre.x),
                toml_f64(o.centre.y),
                toml_f64(o.radius_m)
            );
        }

        let _ = writeln!(t, "\n[formation]");
        let default_agent_m = self
            .agents
            .first()
            .map_or(default_agent_radius_m(), |a| a.radius_m);
        let _ = writeln!(t, "agent_radius_m = {}", toml_f64(default_agent_m));
        // The file has one sensing radius for the formation.
        let sensing = self.agents.first().and_then(|a| a.sensing_radius_m);
        if let Some(i) = self
            .agents
            .iter()
            .position(|a| a.sensing_radius_m != sensing)
        {
            return Err(ResolveError::NotRepresentable {
                field: format!("formation.slots[{i}]"),
                reason: "the file format has one sensing radius for every agent".into(),
            });
        }
        if let Some(v) = sensing {
            let _ = writeln!(t, "sensing_radius_m = {}", toml_f64(v));
        }
        let _ = writeln!(t, "slots = [");
        for (i, a) in self.agents.iter().enumerate() {
            let theta_deg = degrees_for(a.slot.theta_rad).ok_or_else(|| {
                not_in_degrees(format!("formation.slots[{i}].theta_deg"), a.slot.theta_rad)
            })?;
            let max_step = a
                .max_step_m
                .map_or(String::new(), |v| format!(", max_step_m = {}", toml_f64(v)));
            let _ = writeln!(
                t,
                "  {{ r_m = {}, theta_deg = {}, radius_m = {}{max_step} }},",
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
        let _ = writeln!(t, "centre_clearance_m = {}", toml_f64(p.centre_clearance_m));
        let _ = writeln!(t, "allow_reverse = {}", p.allow_reverse);
        if let Some(v) = p.max_lag_m {
            let _ = writeln!(t, "max_lag_m = {}", toml_f64(v));
        }

        let _ = writeln!(t, "\n[turns]");
        let _ = writeln!(t, "mode = {}", toml_string(self.turns.name()));
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

/// `obstacle` as a `[[obstacles.moving]]` table of a scenario file, numbers in their
/// shortest round-trip form, ending in a newline: what [`Scenario::to_resolved_toml`]
/// writes for it, and what a program adding moving obstacles to a scenario text appends.
///
/// ```
/// use shared::geometry::Point;
/// use shared::moving_obstacle::{MovingObstacle, Route};
/// use shared::scenario::moving_obstacle_table;
/// let patrol = MovingObstacle::new(
///     0.5,
///     vec![Point::new(15.0, 2.0), Point::new(15.0, 18.0)],
///     0.4,
///     Route::Loop,
/// );
/// assert_eq!(
///     moving_obstacle_table(&patrol),
///     "[[obstacles.moving]]\nradius_m = 0.5\nwaypoints_m = [[15.0, 2.0], [15.0, 18.0]]\n\
///      speed_m_per_step = 0.4\nroute = \"loop\"\n"
/// );
/// ```
pub fn moving_obstacle_table(obstacle: &MovingObstacle) -> String {
    let waypoints: Vec<String> = obstacle
        .waypoints_m
        .iter()
        .map(|p| format!("[{}, {}]", toml_f64(p.x), toml_f64(p.y)))
        .collect();
    format!(
        "[[obstacles.moving]]\nradius_m = {}\nwaypoints_m = [{}]\nspeed_m_per_step = {}\nroute = {}\n",
        toml_f64(obstacle.radius_m),
        waypoints.join(", "),
        toml_f64(obstacle.speed_m_per_step),
        toml_string(obstacle.route.name())
    )
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

#[cfg(test)]
mod tests {
    use std::path::Path;

    use rand::{Rng, SeedableRng};

    use super::*;
    use crate::vocabulary::PlannerKind;

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
max_step_m = 0.15000000000000002
sensing_radius_m = 0.75
slots = [
  { r_m = 0.0, theta_deg = -0.0 },
  { r_m = 1.0000000000000002, theta_deg = 33.333333333333336, radius_m = 0.25, max_step_m = 0.1 },
  { r_m = 1.0, theta_deg = -179.99999999999997 },
  { r_m = 1.0, theta_deg = 360.0 },
  { r_m = 1.5, theta_deg = 0.1 },
]
[path]
start = { x_m = 3.0, y_m = 5.0, heading_deg = -0.0 }
goal = { x_m = 17.0, y_m = 5.0, heading_deg = -359.99999999999994 }
turning_radius_m = 2.0
step_m = 0.1
centre_clearance_m = 0.0
allow_reverse = true
[turns]
mode = "parallel"
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
centre_clearance_m = 0.1
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
}
