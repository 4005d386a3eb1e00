//! The modules of `shared` stand in layers and form no import cycle; the shared
//! vocabulary is a leaf.
//!
//! Every file under `shared/core/src/` is read; each `crate::NAME` path in its code (`use`
//! lines, grouped `use crate::{a, b::C}` lines and paths written in place, comments left
//! out) is an edge from the file's module to `NAME`. A module is a top-level one
//! (`geometry`, `input_file`) or, inside a layer's folder, the layer and its module
//! (`paths::dubins`, `control::turn`). The tests fail, naming the edge or the cycle, as
//! soon as a module reaches itself through these edges or a layer uses one after it.
//!
//! Modules refer to each other through `crate::` (never `super::super::`), which a test
//! below also checks, so the edges are complete.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use testkit::rust_source::{code_only, is_ident_char, leading_ident, rust_files};

/// The module graph: every module and the modules it names.
type Graph = BTreeMap<String, BTreeSet<String>>;

fn src_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The layers of the core, in order: each may use only itself and those before it.
const LAYERS: [&str; 5] = ["geometry", "paths", "control", "world", "run"];

/// The helpers beside the layers: any module may use them, they use no layer.
const HELPERS: [&str; 3] = ["input_file", "output_file", "ordered"];

/// The edges against the order of [`LAYERS`] kept on purpose (the crate's doc says why):
/// a turn reads the scenario's map and the moving obstacles it plans round.
const BACKWARD_EDGES_KEPT: [(&str, &str); 2] = [
    ("control::turn", "world::moving_obstacle"),
    ("control::turn", "world::scenario"),
];

/// Whether `name` is a layer folder holding modules (`geometry` is one module).
fn is_layer_folder(name: &str) -> bool {
    LAYERS.contains(&name) && name != "geometry"
}

/// The module a file belongs to (`geometry/pose.rs`, `control/turn/car.rs` and
/// `paths/mod.rs` give `geometry`, `control::turn` and `paths`); `None` for the crate
/// root, `lib.rs`.
fn file_module(src: &Path, file: &Path) -> Option<String> {
    let relative = file.strip_prefix(src).expect("a file under src/");
    let mut parts = relative
        .components()
        .map(|c| c.as_os_str().to_str().expect("a UTF-8 path"))
        .map(|part| part.strip_suffix(".rs").unwrap_or(part));
    let first = parts.next()?;
    if first == "lib" {
        return None;
    }
    if is_layer_folder(first) {
        match parts.next() {
            Some("mod") | None => Some(first.to_string()),
            Some(module) => Some(format!("{first}::{module}")),
        }
    } else {
        Some(first.to_string())
    }
}

/// The layer a module stands in, as an index into [`LAYERS`]; `None` for a helper.
fn layer_of(module: &str) -> Option<usize> {
    let layer = module.split("::").next().unwrap_or(module);
    LAYERS.iter().position(|l| *l == layer)
}

/// The module named by a path written after `crate::` (`a::B`, `paths::dubins::x`,
/// `run::World`), or, for a group after a layer (`paths::{dubins, curve}`), each module
/// of the group.
fn modules_named(path: &str, names: &mut BTreeSet<String>) {
    let first = leading_ident(path);
    let rest = path.trim_start()[first.len()..].trim_start();
    let Some(after_layer) = rest.strip_prefix("::").filter(|_| is_layer_folder(first)) else {
        names.insert(first.to_string());
        return;
    };
    let after_layer = after_layer.trim_start();
    if let Some(group) = after_layer.strip_prefix('{') {
        for item in group_items(group) {
            modules_named(&format!("{first}::{item}"), names);
        }
        return;
    }
    let second = leading_ident(after_layer);
    if second.starts_with(|c: char| c.is_ascii_lowercase()) {
        names.insert(format!("{first}::{second}"));
    } else {
        // An item the layer re-exports (`run::World`): the layer's own `mod.rs`.
        names.insert(first.to_string());
    }
}

/// The items of a `{...}` group whose opening brace is already read, split at the commas
/// of depth 0.
fn group_items(group: &str) -> Vec<&str> {
    let mut items = Vec::new();
    let mut depth = 0usize;
    let mut item_start = 0;
    for (i, c) in group.char_indices() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => {
                items.push(&group[item_start..i]);
                break;
            }
            '}' => depth -= 1,
            ',' if depth == 0 => {
                items.push(&group[item_start..i]);
                item_start = i + 1;
            }
            _ => {}
        }
    }
    items.retain(|item| !item.trim().is_empty());
    items
}

/// The modules `code` reaches through `crate::`: `crate::a::B`, `crate::{b, c::D}`
/// (every item of the group), `crate::layer::{d, e}` and `crate::f::g()` in place.
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
            for item in group_items(group) {
                modules_named(item, &mut names);
            }
        } else {
            modules_named(after, &mut names);
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
        let Some(module) = file_module(&src, &file) else {
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
        ("control::formation", &["geometry"]),
        ("control::vocabulary", &["geometry", "control::formation"]),
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
fn each_layer_uses_only_the_layers_before_it() {
    let graph = module_graph();
    let mut backward = Vec::new();
    for (module, uses) in &graph {
        let Some(layer) = layer_of(module) else {
            assert!(
                HELPERS.contains(&module.as_str()),
                "{module} stands in no layer: put it in one of {LAYERS:?}"
            );
            assert!(
                uses.iter().all(|u| HELPERS.contains(&u.as_str())),
                "the helper {module} uses {uses:?}: a helper uses no layer"
            );
            continue;
        };
        for used in uses {
            if layer_of(used).is_some_and(|used_layer| used_layer > layer) {
                backward.push((module.as_str(), used.as_str()));
            }
        }
    }
    assert_eq!(
        backward, BACKWARD_EDGES_KEPT,
        "edges from a layer to one after it (layers in order: {LAYERS:?})"
    );
}

#[test]
fn a_file_belongs_to_its_layer_and_module() {
    let src = Path::new("/src");
    let module = |file: &str| file_module(src, &src.join(file));
    assert_eq!(module("lib.rs"), None);
    assert_eq!(module("geometry/pose.rs").as_deref(), Some("geometry"));
    assert_eq!(module("input_file.rs").as_deref(), Some("input_file"));
    assert_eq!(module("paths/mod.rs").as_deref(), Some("paths"));
    assert_eq!(module("paths/dubins.rs").as_deref(), Some("paths::dubins"));
    assert_eq!(
        module("control/turn/car.rs").as_deref(),
        Some("control::turn")
    );
    assert_eq!(layer_of("control::turn"), Some(2));
    assert_eq!(layer_of("ordered"), None);
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
use crate::paths::{dubins, curve::Arc}; use crate::{run::step_loop, world::maps::X};
fn g() { crate::run::World::new(); crate::control::turn::plan(); }
"##,
    );
    let found: Vec<String> = crate_references(&code).into_iter().collect();
    assert_eq!(
        found,
        [
            "a",
            "b",
            "c",
            "control::turn",
            "d",
            "e",
            "f",
            "paths::curve",
            "paths::dubins",
            "run",
            "run::step_loop",
            "world::maps"
        ]
    );
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
