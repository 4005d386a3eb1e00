//! Running a formation does not build the plotting stack: the tools (render, bench,
//! bound, compare) live in `formation-tools`, apart from `formation-runner`, so neither
//! these tests (a kill, a rogue agent, a resume) nor the agent link plotters or the
//! bound's conic solver. The closure is read from `Cargo.lock`, which lists every
//! package's dependencies, dev-dependencies and optional ones included: a superset of
//! what any build of the package compiles.

use std::collections::{BTreeMap, BTreeSet};

use crate::support::repo_root;

/// Every package of `Cargo.lock` and the names of the packages it depends on (an entry
/// is `"name"` or `"name version"`).
fn lock_graph(lock: &str) -> BTreeMap<String, Vec<String>> {
    let lock: toml::Table = lock.parse().expect("Cargo.lock is TOML");
    let packages = lock
        .get("package")
        .and_then(toml::Value::as_array)
        .expect("Cargo.lock lists its packages");
    let mut graph = BTreeMap::new();
    for package in packages {
        let name = package["name"].as_str().expect("a package's name");
        let deps = package
            .get("dependencies")
            .and_then(toml::Value::as_array)
            .into_iter()
            .flatten()
            .filter_map(toml::Value::as_str)
            .filter_map(|entry| entry.split(' ').next())
            .map(str::to_string);
        graph
            .entry(name.to_string())
            .or_insert_with(Vec::new)
            .extend(deps);
    }
    graph
}

/// `root` and every package it reaches in `graph`.
fn closure(graph: &BTreeMap<String, Vec<String>>, root: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    let mut stack = vec![root.to_string()];
    while let Some(package) = stack.pop() {
        if seen.insert(package.clone()) {
            stack.extend(graph.get(&package).into_iter().flatten().cloned());
        }
    }
    seen
}

fn workspace_graph() -> BTreeMap<String, Vec<String>> {
    let lock = std::fs::read_to_string(repo_root().join("Cargo.lock")).expect("Cargo.lock");
    lock_graph(&lock)
}

/// The packages only the tools need.
const TOOLS_ONLY: [&str; 4] = ["plotters", "clarabel", "gif", "ab_glyph"];

#[test]
fn running_a_formation_builds_no_plotting_stack() {
    let graph = workspace_graph();
    for package in ["formation-integration-tests", "formation-runner", "agent"] {
        let reached = closure(&graph, package);
        assert!(
            reached.contains("iceoryx2"),
            "{package} should reach iceoryx2: the closure is wrong"
        );
        for tool in TOOLS_ONLY {
            assert!(
                !reached.contains(tool),
                "{package} depends on {tool}, which only the tools need"
            );
        }
    }
}

#[test]
fn the_coordinator_program_has_the_tools() {
    let reached = closure(&workspace_graph(), "coordinator");
    for package in [
        "formation-runner",
        "formation-tools",
        "plotters",
        "clarabel",
    ] {
        assert!(reached.contains(package), "coordinator lacks {package}");
    }
}
