//! ARCHITECTURE.md's "Where each concept lives" table against the repository: every path
//! the table names exists. A path is a backticked span in the table's `file` column
//! outside parentheses (those name items inside a file, such as `TurnController::plan_turn`);
//! `{a,b,c}` lists expand to one path each (`shared/core/src/geometry/{pose,disk}.rs` is
//! `shared/core/src/geometry/pose.rs` and `shared/core/src/geometry/disk.rs`), and a path ending in
//! `/` names a folder.

use std::path::Path;

/// The heading of the table's section in ARCHITECTURE.md.
const SECTION: &str = "## Where each concept lives";

/// Fewer rows than this means the table was not read (a changed heading or layout), not
/// that it is short.
const MIN_ROWS: usize = 20;

/// The `file` cells of the table under [`SECTION`], each with its line number (1-based).
fn file_cells(architecture: &str) -> Vec<(usize, String)> {
    let mut lines = architecture.lines().enumerate();
    assert!(
        lines.any(|(_, line)| line.trim_end() == SECTION),
        "ARCHITECTURE.md has no section {SECTION:?}"
    );
    let mut cells = Vec::new();
    let mut in_table = false;
    for (index, line) in lines {
        let line = line.trim();
        if line.starts_with("## ") {
            break;
        }
        if !line.starts_with('|') {
            if in_table {
                break;
            }
            continue;
        }
        in_table = true;
        let columns: Vec<&str> = line.trim_matches('|').split('|').map(str::trim).collect();
        assert_eq!(
            columns.len(),
            2,
            "ARCHITECTURE.md:{}: a row of the concept table has two columns: {line}",
            index + 1
        );
        let file = columns[1];
        if file == "file" || file.chars().all(|c| c == '-' || c == ':') {
            continue; // the header and its rule
        }
        cells.push((index + 1, file.to_owned()));
    }
    cells
}

/// `cell` with every parenthesised part left out.
fn outside_parentheses(cell: &str) -> String {
    let mut depth = 0usize;
    let mut kept = String::new();
    for c in cell.chars() {
        match c {
            '(' => depth += 1,
            ')' => depth = depth.saturating_sub(1),
            _ if depth == 0 => kept.push(c),
            _ => {}
        }
    }
    kept
}

/// The backticked spans of `text`.
fn backticked(text: &str) -> Vec<String> {
    text.split('`')
        .skip(1)
        .step_by(2)
        .map(str::to_owned)
        .collect()
}

/// `pattern` with its first `{a,b,...}` list expanded, recursively: one path per choice.
fn expand_braces(pattern: &str) -> Vec<String> {
    let Some(open) = pattern.find('{') else {
        assert!(
            !pattern.contains('}'),
            "a `}}` without its `{{` in {pattern:?}"
        );
        return vec![pattern.to_owned()];
    };
    let close = open
        + pattern[open..]
            .find('}')
            .unwrap_or_else(|| panic!("a `{{` without its `}}` in {pattern:?}"));
    let (head, choices, tail) = (
        &pattern[..open],
        &pattern[open + 1..close],
        &pattern[close + 1..],
    );
    assert!(
        !choices.contains('{'),
        "nested braces are not expanded: {pattern:?}"
    );
    choices
        .split(',')
        .flat_map(|choice| {
            let choice = choice.trim();
            assert!(!choice.is_empty(), "an empty choice in {pattern:?}");
            expand_braces(&format!("{head}{choice}{tail}"))
        })
        .collect()
}

/// The paths one `file` cell names, brace lists expanded.
fn paths_in_cell(cell: &str) -> Vec<String> {
    backticked(&outside_parentheses(cell))
        .iter()
        .flat_map(|span| expand_braces(span))
        .collect()
}

/// Every path `paths` names that is missing under `root` (a trailing `/`: not a folder;
/// otherwise: not a file), each with the line of the table that names it.
fn missing(root: &Path, paths: &[(usize, String)]) -> Vec<String> {
    paths
        .iter()
        .filter(|(_, path)| {
            let on_disk = root.join(path);
            if path.ends_with('/') {
                !on_disk.is_dir()
            } else {
                !on_disk.is_file()
            }
        })
        .map(|(line, path)| format!("ARCHITECTURE.md:{line}: {path}"))
        .collect()
}

#[test]
fn every_path_in_the_concept_table_exists() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let architecture =
        std::fs::read_to_string(root.join("ARCHITECTURE.md")).expect("reading ARCHITECTURE.md");
    let cells = file_cells(&architecture);
    assert!(
        cells.len() >= MIN_ROWS,
        "only {} rows read from the concept table (at least {MIN_ROWS} expected)",
        cells.len()
    );
    let mut paths = Vec::new();
    for (line, cell) in &cells {
        let in_cell = paths_in_cell(cell);
        assert!(
            !in_cell.is_empty(),
            "ARCHITECTURE.md:{line}: a row names no path: {cell}"
        );
        paths.extend(in_cell.into_iter().map(|path| (*line, path)));
    }
    let missing = missing(root, &paths);
    assert!(
        missing.is_empty(),
        "paths in ARCHITECTURE.md's concept table that do not exist:\n{}",
        missing.join("\n")
    );
}

#[test]
fn brace_lists_expand_to_one_path_per_choice() {
    assert_eq!(
        expand_braces("shared/core/src/geometry/{pose,disk}.rs"),
        [
            "shared/core/src/geometry/pose.rs",
            "shared/core/src/geometry/disk.rs"
        ]
    );
    assert_eq!(
        expand_braces("a/{b,c}/{d,e}.rs"),
        ["a/b/d.rs", "a/b/e.rs", "a/c/d.rs", "a/c/e.rs"]
    );
    assert_eq!(expand_braces("agent/src/lib.rs"), ["agent/src/lib.rs"]);
}

#[test]
fn items_in_parentheses_are_not_paths() {
    assert_eq!(
        paths_in_cell("`shared/core/src/control/turn.rs` (`TurnController::plan_turn`)"),
        ["shared/core/src/control/turn.rs"]
    );
    assert_eq!(
        paths_in_cell("`shared/wire/src/misbehave.rs`, `agent/src/{misbehave,rogue}.rs`"),
        [
            "shared/wire/src/misbehave.rs",
            "agent/src/misbehave.rs",
            "agent/src/rogue.rs"
        ]
    );
}

#[test]
fn a_wrong_path_is_reported_with_its_line() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let table = format!(
        "{SECTION}\n\n| concept | file |\n|---|---|\n\
         | exists | `shared/core/src/{{lib,ordered}}.rs` |\n\
         | a folder | `shared/core/src/control/vocabulary/` |\n\
         | wrong | `shared/core/src/{{ordered,no_such_module}}.rs` |\n\
         | a file named as a folder | `shared/core/src/lib.rs/` |\n"
    );
    let paths: Vec<(usize, String)> = file_cells(&table)
        .iter()
        .flat_map(|(line, cell)| paths_in_cell(cell).into_iter().map(|p| (*line, p)))
        .collect();
    assert_eq!(paths.len(), 6);
    assert_eq!(
        missing(root, &paths),
        [
            "ARCHITECTURE.md:7: shared/core/src/no_such_module.rs",
            "ARCHITECTURE.md:8: shared/core/src/lib.rs/"
        ]
    );
}
