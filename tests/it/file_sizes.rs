//! No source file of the project is over 600 lines: a file is one concept, and a concept
//! that outgrows this is split along its parts (the vendored Zenoh TLS link, not ours,
//! keeps its own files).

use std::path::{Path, PathBuf};

use crate::support::repo_root;

/// The most lines a source file may have.
const MAX_LINES: usize = 600;

/// Folders that hold no source of the project's own.
const SKIPPED: [&str; 5] = ["target", ".git", "runs", "zenoh-link-tls", "__pycache__"];

/// Every `.rs` and `.py` file under `dir`, the skipped folders left out.
fn source_files(dir: &Path, found: &mut Vec<PathBuf>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries {
        let path = entry.expect("a folder entry").path();
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if path.is_dir() {
            if !SKIPPED.contains(&name) {
                source_files(&path, found);
            }
        } else if name.ends_with(".rs") || name.ends_with(".py") {
            found.push(path);
        }
    }
}

#[test]
fn no_source_file_is_over_600_lines() {
    let root = repo_root();
    let mut files = Vec::new();
    source_files(&root, &mut files);
    assert!(
        files.len() > 200,
        "only {} source files found: the walk is wrong",
        files.len()
    );
    let too_long: Vec<String> = files
        .iter()
        .filter_map(|f| {
            let lines = std::fs::read_to_string(f).ok()?.lines().count();
            (lines > MAX_LINES).then(|| format!("{} ({lines} lines)", f.display()))
        })
        .collect();
    assert!(
        too_long.is_empty(),
        "over {MAX_LINES} lines: {}",
        too_long.join(", ")
    );
}
