//! The modules of `shared` form no import cycle, and the shared vocabulary is a leaf.
//!
//! Every file under `shared/core/src/` is read; each `crate::NAME` path in its code (`use`
//! lines, grouped `use crate::{a, b::C}` lines and paths written in place, comments left
//! out) is an edge from the file's top-level module to `NAME`. The test fails, naming
//! the cycle, as soon as a module reaches itself through these edges.
//!
//! Modules refer to each other through `crate::` (never `super::super::`), which a test
//! below also checks, so the edges are complete.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use testkit::rust_source::{code_only, is_ident_char, leading_ident, rust_files};

/// The module graph: every top-level module and the top-level modules it names.
type Graph = BTreeMap<String, BTreeSet<String>>;

fn src_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The top-level module a file belongs to (`geometry.rs` and `scenario/check.rs` give
/// `geometry` and `scenario`); `None` for the crate root, `lib.rs`.
fn top_module(src: &Path, file: &Path) -> Option<String> {
    let relative = file.strip_prefix(src).expect("a file under src/");
    let first = relative.components().next()?.as_os_str().to_str()?;
    let name = first.strip_suffix(".rs").unwrap_or(first);
    (name != "lib").then(|| name.to_string())
}

/// The top-level module names `code` reaches through `crate::`: `crate::a::B`,
/// `crate::{b, c::D}` (every item of the group) and `crate::d::e()` in place.
fn crate_references(code: &str) -> BTreeSet<String> {
    let mut names = BTreeSet::new();
    let mut rest = code;
    while let Some(at) = rest.find("crate::") {
        let before = rest[..at].chars().next_back();
        rest = &rest[at + "crate::".len()..];
        if before.is_some_and(is_ident_char) {
            continue; // `my_crate::`, not `crate::`
        }
        let after = rest.trim_start();
        if let Some(group) = after.strip_prefix('{') {
            // The items of the group, split at the commas of depth 0.
            let mut depth = 0usize;
            let mut item_start = 0;
            for (i, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => {
                        names.insert(leading_ident(&group[item_start..i]).to_string());
                        break;
                    }
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        names.insert(leading_ident(&group[item_start..i]).to_string());
                        item_start = i + 1;
                    }
                    _ => {}
                }
            }
        } else {
            names.insert(leading_ident(after).to_string());
        }
    }
    names.remove("");
    names
}

/// The module graph of `shared/core/src`.
fn module_graph() -> Graph {
    let src = src_dir();
    let mut graph = Graph::new();
    for file in rust_files(&src) {
        let Some(module) = top_module(&src, &file) else {
            continue;
        };
        let text =
            std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        let edges = graph.entry(module.clone()).or_default();
        edges.extend(crate_references(&code_only(&text)));
        // A module naming itself through `crate::` is no edge.
        edges.remove(&module);
    }
    graph
}

/// A cycle of `graph` as the list of its modules (the first repeated at the end), if any.
fn find_cycle(graph: &Graph) -> Option<Vec<String>> {
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        New,
        OnPath,
        Done,
    }
    fn visit<'a>(
        graph: &'a Graph,
        node: &'a str,
        marks: &mut BTreeMap<&'a str, Mark>,
        path: &mut Vec<&'a str>,
    ) -> Option<Vec<String>> {
        marks.insert(node, Mark::OnPath);
        path.push(node);
        for next in graph.get(node).into_iter().flatten() {
            match marks.get(next.as_str()).copied().unwrap_or(Mark::New) {
                Mark::OnPath => {
                    let start = path.iter().position(|n| *n == next).expect("on the path");
                    let mut cycle: Vec<String> =
                        path[start..].iter().map(|n| n.to_string()).collect();
                    cycle.push(next.clone());
                    return Some(cycle);
                }
                Mark::New => {
                    if let Some(cycle) = visit(graph, next, marks, path) {
                        return Some(cycle);
                    }
                }
                Mark::Done => {}
            }
        }
        path.pop();
        marks.insert(node, Mark::Done);
        None
    }
    let mut marks = BTreeMap::new();
    for node in graph.keys() {
        if !marks.contains_key(node.as_str()) {
            let found = visit(graph, node, &mut marks, &mut Vec::new());
            if found.is_some() {
                return found;
            }
        }
    }
    None
}

fn describe(graph: &Graph) -> String {
    graph
        .iter()
        .map(|(m, uses)| {
            format!(
                "  {m} -> {}",
                Vec::from_iter(uses.iter().cloned()).join(", ")
            )
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn the_modules_of_shared_form_no_cycle() {
    let graph = module_graph();
    assert!(
        graph.len() >= 10,
        "too few modules found:\n{}",
        describe(&graph)
    );
    // Every name reached through `crate::` is a module of the crate: the parser misses
    // nothing by misreading a name.
    for (module, uses) in &graph {
        for used in uses {
            assert!(
                graph.contains_key(used),
                "{module} names crate::{used}, which is no module file of shared/core/src"
            );
        }
    }
    if let Some(cycle) = find_cycle(&graph) {
        panic!(
            "import cycle among the modules of shared: {}\nthe graph:\n{}",
            cycle.join(" -> "),
            describe(&graph)
        );
    }
}

#[test]
fn the_vocabulary_and_the_geometry_are_leaves() {
    let graph = module_graph();
    let allowed: [(&str, &[&str]); 3] = [
        ("geometry", &[]),
        ("formation", &["geometry"]),
        ("vocabulary", &["geometry", "formation"]),
    ];
    for (module, may_use) in allowed {
        let uses = graph
            .get(module)
            .unwrap_or_else(|| panic!("no module {module}"));
        let extra: Vec<&String> = uses
            .iter()
            .filter(|u| !may_use.contains(&u.as_str()))
            .collect();
        assert!(
            extra.is_empty(),
            "{module} may use only {may_use:?}, but uses {extra:?}"
        );
    }
}

#[test]
fn modules_refer_to_each_other_through_crate_paths_only() {
    let src = src_dir();
    for file in rust_files(&src) {
        let text = std::fs::read_to_string(&file).expect("readable");
        let code = code_only(&text);
        assert!(
            !code.contains("super::super"),
            "{}: `super::super` hides a module edge; write `crate::` instead",
            file.display()
        );
    }
}

#[test]
fn the_parser_reads_every_form_of_reference_and_no_comment() {
    let code = code_only(
        r##"
//! [`crate::docs_only`] is a doc link, not an edge.
use crate::a::B;
use crate::{b, c::{D, E}, d::F};
fn f<'x>() -> u8 { crate::e::g(); let _ = ('"', '\'', b'q'); my_crate::h::i(); 0 } // crate::comment
/* crate::block /* nested */ crate::still_block */ const S: &str = "// \" crate::in_string";
const R: &str = r#"crate::in_raw " string"#; const T: &str = r"crate::raw";
use crate::
    f;
"##,
    );
    let found: Vec<String> = crate_references(&code).into_iter().collect();
    assert_eq!(found, ["a", "b", "c", "d", "e", "f"]);
}

#[test]
fn the_cycle_check_finds_a_cycle() {
    let graph = |edges: &[(&str, &str)]| {
        let mut g = Graph::new();
        for (from, to) in edges {
            g.entry(from.to_string())
                .or_default()
                .insert(to.to_string());
            g.entry(to.to_string()).or_default();
        }
        g
    };
    // Today's graph in miniature, then the cycle this layout removed.
    let acyclic = graph(&[
        ("cbf", "vocabulary"),
        ("turn", "cbf"),
        ("turn", "vocabulary"),
        ("scenario", "vocabulary"),
        ("vocabulary", "geometry"),
    ]);
    assert_eq!(find_cycle(&acyclic), None);
    let cyclic = graph(&[
        ("cbf", "scenario"),
        ("cbf", "turn"),
        ("scenario", "cbf"),
        ("turn", "scenario"),
    ]);
    let cycle = find_cycle(&cyclic).expect("a cycle");
    assert_eq!(cycle.first(), cycle.last());
    assert!(cycle.len() >= 3, "{cycle:?}");
}
