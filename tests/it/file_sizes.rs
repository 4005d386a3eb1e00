//! No source file of the project is over 600 lines: a file is one concept, and a concept
//! that outgrows this is split along its parts (the vendored Zenoh TLS link, not ours,
//! keeps its own files).

use testkit::rust_source::files_under;

use crate::support::repo_root;

/// The most lines a source file may have.
const MAX_LINES: usize = 600;

/// Folders that hold no source of the project's own.
const SKIPPED: [&str; 5] = ["target", ".git", "runs", "zenoh-link-tls", "__pycache__"];

#[test]
fn no_source_file_is_over_600_lines() {
    let files = files_under(&repo_root(), &["rs", "py"], &SKIPPED);
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
