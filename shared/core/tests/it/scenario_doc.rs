//! `docs/scenario-format.md` checked against the parser, so the reference cannot rot:
//!
//! - every ```toml block is a complete scenario that `Scenario::parse` accepts and whose
//!   centre path can be planned;
//! - the key table lists exactly the keys of the complete example (the first block), so
//!   every documented key is accepted (the parser refuses unknown keys) and every key
//!   of the example is documented; every key of the shipped `scenarios/*.toml` is in the
//!   table too;
//! - each key's default cell is true: a `required` key left out is an error naming it,
//!   a literal default gives the same scenario as leaving the key out, `same as KEY`
//!   likewise with KEY's value, `none` may be left out (with the keys its limits say
//!   need it);
//! - every `float` key refuses NaN naming itself, a `> 0` key refuses 0, a `≥ 0` key
//!   refuses -1;
//! - the limits table gives the values of the constants in `shared::world::scenario` and
//!   `shared::control::vocabulary`.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use shared::control::vocabulary::{MAX_AGENTS, MAX_OBSTACLES};
use shared::run::simulate::plan_centre_path;
use shared::world::scenario::{
    MAX_ANGLE_DEG, MAX_FIELD_SIDE_M, MAX_MOVING_WAYPOINTS, MAX_ROUTE_WAYPOINTS, MAX_STEPS, Scenario,
};
use toml::{Table, Value};

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .to_path_buf()
}

fn doc() -> String {
    let path = repo_root().join("docs").join("scenario-format.md");
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()))
}

/// The ```toml blocks of `text`, with the line each starts on.
fn toml_blocks(text: &str) -> Vec<(usize, String)> {
    let mut blocks = Vec::new();
    let mut current: Option<(usize, String)> = None;
    for (i, line) in text.lines().enumerate() {
        let trimmed = line.trim();
        match &mut current {
            None if trimmed == "```toml" => current = Some((i + 1, String::new())),
            None => {}
            Some(_) if trimmed == "```" => blocks.extend(current.take()),
            Some((_, body)) => {
                body.push_str(line);
                body.push('\n');
            }
        }
    }
    assert!(current.is_none(), "a ```toml block is not closed");
    blocks
}

/// The rows of the first Markdown table after the heading `heading`, as trimmed cells.
fn table_rows(text: &str, heading: &str) -> Vec<Vec<String>> {
    let mut lines = text.lines().skip_while(|l| l.trim() != heading);
    assert!(lines.next().is_some(), "no heading {heading:?} in the doc");
    let rows: Vec<Vec<String>> = lines
        .skip_while(|l| !l.starts_with('|'))
        .take_while(|l| l.starts_with('|'))
        .skip(2) // the header and the |---| line
        .map(|l| {
            l.trim()
                .trim_matches('|')
                .split('|')
                .map(|c| c.trim().to_string())
                .collect()
        })
        .collect();
    assert!(!rows.is_empty(), "no table after {heading:?}");
    rows
}

/// The text between the first pair of backticks of `cell`.
fn backticked(cell: &str) -> Option<&str> {
    let start = cell.find('`')? + 1;
    let len = cell[start..].find('`')?;
    Some(&cell[start..start + len])
}

/// One row of the key table.
#[derive(Debug)]
struct KeyRow {
    key: String,
    kind: String,
    default: String,
    limits: String,
}

fn key_rows(text: &str) -> Vec<KeyRow> {
    table_rows(text, "## Keys")
        .into_iter()
        .map(|cells| {
            assert_eq!(cells.len(), 5, "key table row {cells:?}: five cells");
            let key = backticked(&cells[0])
                .unwrap_or_else(|| panic!("key table row {cells:?}: no `key`"))
                .to_string();
            KeyRow {
                key,
                kind: cells[1].clone(),
                default: cells[3].clone(),
                limits: cells[4].clone(),
            }
        })
        .collect()
}

/// Call `f(parent, leaf)` for every table holding `key` (`a.b[].c`: `c` of every
/// element of the array `a.b`), whether or not `leaf` is there yet.
fn for_each_parent(table: &mut Table, key: &str, f: &mut dyn FnMut(&mut Table, &str)) {
    match key.split_once('.') {
        None => f(table, key),
        Some((first, rest)) => {
            if let Some(name) = first.strip_suffix("[]") {
                if let Some(Value::Array(items)) = table.get_mut(name) {
                    for item in items {
                        if let Value::Table(t) = item {
                            for_each_parent(t, rest, f);
                        }
                    }
                }
            } else if let Some(Value::Table(t)) = table.get_mut(first) {
                for_each_parent(t, rest, f);
            }
        }
    }
}

/// How many tables hold `key` in `doc`.
fn count_key(doc: &Table, key: &str) -> usize {
    let mut doc = doc.clone();
    let mut n = 0;
    for_each_parent(&mut doc, key, &mut |t, leaf| {
        n += usize::from(t.contains_key(leaf))
    });
    n
}

/// `doc` without `key` (everywhere it occurs).
fn without(doc: &Table, key: &str) -> Table {
    let mut doc = doc.clone();
    for_each_parent(&mut doc, key, &mut |t, leaf| {
        t.remove(leaf);
    });
    doc
}

/// `doc` with `key` set to `value` (in every element, for `a[].b`).
fn with(doc: &Table, key: &str, value: &Value) -> Table {
    let mut doc = doc.clone();
    let mut n = 0;
    // A slot's key of one kinematic model is set only on the slots of that model (the
    // others refuse it, as they should).
    let formation_model = doc
        .get("formation")
        .and_then(|f| f.get("kinematics"))
        .and_then(Value::as_str)
        .unwrap_or("holonomic")
        .to_string();
    let model_of_key = match key {
        "formation.slots[].max_turn_rad" => Some("unicycle"),
        "formation.slots[].turning_radius_m" => Some("car"),
        _ => None,
    };
    for_each_parent(&mut doc, key, &mut |t, leaf| {
        let model = t
            .get("kinematics")
            .and_then(Value::as_str)
            .unwrap_or(&formation_model);
        if model_of_key.is_some_and(|m| m != model) {
            return;
        }
        t.insert(leaf.to_string(), value.clone());
        n += 1;
    });
    assert!(n > 0, "{key}: no table to set it in");
    doc
}

/// The value of the plain key `key` in `doc`.
fn value_of(doc: &Table, key: &str) -> Value {
    let mut found = None;
    let mut doc = doc.clone();
    for_each_parent(&mut doc, key, &mut |t, leaf| {
        found = found.take().or_else(|| t.get(leaf).cloned());
    });
    found.unwrap_or_else(|| panic!("{key}: not in the example"))
}

/// Every key of `table`, dotted, arrays of tables as `a[].b` (the table's own keys too).
fn all_keys(table: &Table, prefix: &str, out: &mut BTreeSet<String>) {
    for (name, value) in table {
        let key = format!("{prefix}{name}");
        match value {
            Value::Table(t) => all_keys(t, &format!("{key}."), out),
            Value::Array(items) if items.iter().all(Value::is_table) && !items.is_empty() => {
                for item in items {
                    if let Value::Table(t) = item {
                        all_keys(t, &format!("{key}[]."), out);
                    }
                }
            }
            _ => {}
        }
        out.insert(key);
    }
}

/// The examples are read as if they were files in `scenarios/`, so that a map they name
/// (`maps/depot.yaml`) is the one shipped there.
fn as_scenario_file(name: &str) -> String {
    repo_root()
        .join("scenarios")
        .join(name)
        .display()
        .to_string()
}

fn parse(doc: &Table, what: &str) -> Result<Scenario, shared::world::scenario::ScenarioError> {
    let text = toml::to_string(doc).unwrap_or_else(|e| panic!("{what}: cannot write: {e}"));
    Scenario::parse(&text, &as_scenario_file(what))
}

/// The field an error about `key` names: `a[].b` becomes `a[0].b`.
fn field_name(key: &str) -> String {
    key.to_string()
}

/// `field` with its array indices left out (`slots[3].x` is `slots[].x`): a slot's key
/// is named at the first slot that has it.
fn without_indices(field: &str) -> String {
    let mut out = String::with_capacity(field.len());
    let mut in_index = false;
    for c in field.chars() {
        match c {
            '[' => {
                in_index = true;
                out.push('[');
            }
            ']' => {
                in_index = false;
                out.push(']');
            }
            _ if in_index => {}
            _ => out.push(c),
        }
    }
    out
}

fn literal(text: &str) -> Value {
    let table: Table = toml::from_str(&format!("v = {text}"))
        .unwrap_or_else(|e| panic!("default `{text}` is not a TOML value: {e}"));
    table["v"].clone()
}

/// Every problem with `key`'s row, as messages.
fn check_row(example: &Table, row: &KeyRow, problems: &mut Vec<String>) {
    let key = &row.key;
    if count_key(example, key) == 0 {
        problems.push(format!(
            "{key}: in the key table but not in the complete example"
        ));
        return;
    }
    let expect_error = |doc: &Table, what: &str, problems: &mut Vec<String>| {
        let want = field_name(key);
        match parse(doc, "doc.toml") {
            Err(e) if without_indices(e.field()) == want => {}
            Err(e) => problems.push(format!("{key}: {what}: error names another field: {e}")),
            Ok(_) => problems.push(format!("{key}: {what}: accepted, expected an error")),
        }
    };
    // The default.
    let removed = without(example, key);
    let default = row.default.as_str();
    if default.starts_with("required") {
        expect_error(&removed, "left out", problems);
    } else if default == "none" {
        // A key other keys need ("needed by `KEY`, `KEY`" in its limits cell) may be
        // left out together with them.
        let mut removed = removed;
        if let Some((_, needers)) = row.limits.split_once("needed by ") {
            for needer in needers.split('`').skip(1).step_by(2) {
                removed = without(&removed, needer);
            }
        }
        if let Err(e) = parse(&removed, "doc.toml") {
            problems.push(format!("{key}: documented optional, but left out: {e}"));
        }
    } else {
        let value = match default.strip_prefix("same as ") {
            Some(other) => value_of(example, backticked(other).unwrap_or(other)),
            None => match backticked(default) {
                Some(lit) if default == format!("`{lit}`") => literal(lit),
                _ => {
                    problems.push(format!(
                        "{key}: default cell {default:?} is none of: required, none, \
                         `LITERAL`, same as `KEY`"
                    ));
                    return;
                }
            },
        };
        match (
            parse(&removed, "doc.toml"),
            parse(&with(example, key, &value), "doc.toml"),
        ) {
            (Ok(a), Ok(b)) if a == b => {}
            // The same scenario refused the same way (a default that moves random
            // obstacles onto the formation, say) still shows the defaults agree.
            (Err(a), Err(b)) if a == b => {}
            (Ok(_), Ok(_)) => problems.push(format!(
                "{key}: leaving it out is not the same as the documented default {value}"
            )),
            (a, b) => problems.push(format!(
                "{key}: default {value}: left out {:?}, set {:?}",
                a.err().map(|e| e.to_string()),
                b.err().map(|e| e.to_string())
            )),
        }
    }
    // The limits every number shares.
    if row.kind == "float" {
        expect_error(
            &with(example, key, &Value::Float(f64::NAN)),
            "NaN",
            problems,
        );
        if row.limits.starts_with("> 0") {
            expect_error(&with(example, key, &Value::Float(0.0)), "0", problems);
        }
        if row.limits.starts_with("≥ 0") {
            expect_error(&with(example, key, &Value::Float(-1.0)), "-1", problems);
        }
    }
}

#[test]
fn every_toml_block_of_the_doc_is_a_valid_scenario_with_a_path() {
    let text = doc();
    let blocks = toml_blocks(&text);
    assert!(
        blocks.len() >= 3,
        "the complete example and at least two more, found {}",
        blocks.len()
    );
    for (line, body) in &blocks {
        let what = format!("docs/scenario-format.md, block at line {line}");
        let scenario = Scenario::parse(body, &as_scenario_file("doc.toml"))
            .unwrap_or_else(|e| panic!("{what}: {e}"));
        let path = plan_centre_path(&scenario).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert!(path.len() >= 2, "{what}: a path of {} poses", path.len());
    }
}

#[test]
fn the_key_table_matches_the_parser() {
    let text = doc();
    let rows = key_rows(&text);
    let (_, first) = toml_blocks(&text).into_iter().next().expect("a toml block");
    let example: Table = toml::from_str(&first).expect("the complete example is TOML");
    // The round trip through toml::to_string that the checks use changes nothing.
    assert_eq!(
        parse(&example, "doc.toml").expect("the complete example parses"),
        Scenario::parse(&first, &as_scenario_file("doc.toml"))
            .expect("the complete example parses")
    );

    let documented: BTreeSet<String> = rows.iter().map(|r| r.key.clone()).collect();
    assert_eq!(documented.len(), rows.len(), "a key listed twice");
    let mut problems = Vec::new();
    let mut in_example = BTreeSet::new();
    all_keys(&example, "", &mut in_example);
    for key in in_example.difference(&documented) {
        problems.push(format!(
            "{key}: in the complete example but not in the key table"
        ));
    }
    let scenarios = repo_root().join("scenarios");
    for entry in std::fs::read_dir(&scenarios).expect("the scenarios folder") {
        let path = entry.expect("a scenarios entry").path();
        if path.extension().is_none_or(|x| x != "toml") {
            continue;
        }
        let table: Table = toml::from_str(&std::fs::read_to_string(&path).expect("readable"))
            .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        let mut keys = BTreeSet::new();
        all_keys(&table, "", &mut keys);
        for key in keys.difference(&documented) {
            problems.push(format!(
                "{key}: used by {} but not in the key table",
                path.display()
            ));
        }
    }
    // Keys the complete example cannot hold beside its other keys (agents with a heading
    // refuse moving obstacles, polygons refuse both) are checked in further complete
    // examples, blocks opening with `# complete example`: each key in the first that
    // holds it.
    let others: Vec<Table> = toml_blocks(&text)
        .into_iter()
        .skip(1)
        .filter(|(_, b)| b.trim_start().starts_with("# complete example"))
        .map(|(_, b)| toml::from_str(&b).expect("a further complete example is TOML"))
        .collect();
    for other in &others {
        parse(other, "doc.toml").expect("a further complete example parses");
        let mut keys = BTreeSet::new();
        all_keys(other, "", &mut keys);
        for key in keys.difference(&documented) {
            problems.push(format!(
                "{key}: in a further complete example but not in the key table"
            ));
        }
    }
    for row in &rows {
        let holder = std::iter::once(&example)
            .chain(&others)
            .find(|t| count_key(t, &row.key) > 0)
            .unwrap_or(&example);
        check_row(holder, row, &mut problems);
    }
    assert!(
        problems.is_empty(),
        "docs/scenario-format.md disagrees with the parser:\n{}",
        problems.join("\n")
    );
}

#[test]
fn the_limits_table_gives_the_constants() {
    let text = doc();
    let rows = table_rows(&text, "## Limits");
    let want = [
        ("MAX_AGENTS", MAX_AGENTS as f64),
        ("MAX_OBSTACLES", MAX_OBSTACLES as f64),
        ("MAX_FIELD_SIDE_M", MAX_FIELD_SIDE_M),
        ("MAX_STEPS", MAX_STEPS as f64),
        ("MAX_ANGLE_DEG", MAX_ANGLE_DEG),
        ("MAX_ROUTE_WAYPOINTS", MAX_ROUTE_WAYPOINTS as f64),
        ("MAX_MOVING_WAYPOINTS", MAX_MOVING_WAYPOINTS as f64),
    ];
    assert_eq!(rows.len(), want.len(), "one row per constant: {rows:?}");
    for (name, value) in want {
        let row = rows
            .iter()
            .find(|r| backticked(&r[0]) == Some(name))
            .unwrap_or_else(|| panic!("{name}: not in the limits table"));
        let documented: f64 = row[1]
            .parse()
            .unwrap_or_else(|e| panic!("{name}: {:?} is not a number: {e}", row[1]));
        assert_eq!(documented, value, "{name}");
    }
}
