//! No two files of the workspace import each other.
//!
//! Every library file of every crate is read (binaries' own roots, `main.rs` and
//! `src/bin/`, are left out: nothing imports them). Each `crate::` and `super::` path in
//! its code, grouped (`use super::{a, b::C}`) or written in place, is resolved to the
//! deepest module file it names (`crate::turns::answer::Answer` is
//! `turns/answer.rs`); a file then imports that file. A pair of files each importing the
//! other fails the test, named.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use testkit::rust_source::{code_only, is_ident_char, rust_files};

/// Every library `src/` folder of the workspace.
fn source_dirs() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    [
        "shared",
        "shared/wire",
        "shared/net",
        "shared/testkit",
        "agent",
        "coordinator",
    ]
    .iter()
    .map(|c| root.join(c).join("src"))
    .collect()
}

/// The module path of `file` in its crate: `a/b.rs` and `a/b/mod.rs` are `[a, b]`,
/// `lib.rs` is `[]`.
fn module_path(src: &Path, file: &Path) -> Vec<String> {
    let relative = file.strip_prefix(src).expect("a file under src/");
    let mut path: Vec<String> = relative
        .iter()
        .map(|c| c.to_string_lossy().into_owned())
        .collect();
    let last = path.pop().unwrap_or_default();
    match last.as_str() {
        "mod.rs" | "lib.rs" => {}
        other => path.push(other.trim_end_matches(".rs").to_string()),
    }
    path
}

/// The deepest module file on `path` from the crate root (`lib.rs` for none).
fn module_file(src: &Path, path: &[String]) -> PathBuf {
    let mut found = src.join("lib.rs");
    let mut dir = src.to_path_buf();
    for name in path {
        let (file, module) = (
            dir.join(format!("{name}.rs")),
            dir.join(name).join("mod.rs"),
        );
        if file.is_file() {
            found = file;
        } else if module.is_file() {
            found = module;
        } else {
            break;
        }
        dir = dir.join(name);
    }
    found
}

/// The paths of a use tree starting at `at` in `chars` (`a::b`, `a::{b, c::d}`, `*`),
/// each as its names, and where the tree ends.
fn use_tree(chars: &[char], mut at: usize) -> (Vec<Vec<String>>, usize) {
    let skip_space = |mut i: usize| {
        while chars.get(i).is_some_and(|c| c.is_whitespace()) {
            i += 1;
        }
        i
    };
    let mut prefix = Vec::new();
    loop {
        at = skip_space(at);
        if chars.get(at) == Some(&'{') {
            let mut paths = Vec::new();
            at += 1;
            loop {
                at = skip_space(at);
                match chars.get(at) {
                    Some('}') | None => return (paths, at + 1),
                    Some(',') => at += 1,
                    _ => {
                        let (inner, end) = use_tree(chars, at);
                        for p in inner {
                            let mut full = prefix.clone();
                            full.extend(p.into_iter().filter(|n| n != "self"));
                            paths.push(full);
                        }
                        at = end;
                    }
                }
            }
        }
        let start = at;
        while chars.get(at).copied().is_some_and(is_ident_char) {
            at += 1;
        }
        if at == start {
            return (vec![prefix], at);
        }
        prefix.push(chars[start..at].iter().collect());
        if chars.get(at) == Some(&':') && chars.get(at + 1) == Some(&':') {
            at += 2;
        } else {
            return (vec![prefix], at);
        }
    }
}

/// The module paths (from the crate root) that `code`, the code of the file at module
/// path `module`, names through `crate::` and `super::`.
fn references(code: &str, module: &[String]) -> Vec<Vec<String>> {
    let chars: Vec<char> = code.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let boundary = i == 0 || !(is_ident_char(chars[i - 1]) || chars[i - 1] == ':');
        let starts = |word: &str| chars[i..].starts_with(&word.chars().collect::<Vec<_>>());
        if boundary && (starts("crate::") || starts("super::")) {
            let mut base: Vec<String> = Vec::new();
            let mut at = i;
            if starts("crate::") {
                at += "crate::".len();
            } else {
                // Each `super` is one module up (`a/mod.rs` is module `a`, so its
                // `super` is the crate root).
                base = module.to_vec();
                while chars[at..].starts_with(&"super::".chars().collect::<Vec<_>>()) {
                    base.pop();
                    at += "super::".len();
                }
            }
            let (paths, end) = use_tree(&chars, at);
            for p in paths {
                let mut full = base.clone();
                full.extend(p);
                out.push(full);
            }
            i = end.max(i + 1);
        } else {
            i += 1;
        }
    }
    out
}

/// Which files each library file imports (other files only), in one crate.
fn imports_of_crate(src: &Path) -> BTreeMap<PathBuf, BTreeSet<PathBuf>> {
    let mut imports = BTreeMap::new();
    for file in rust_files(src) {
        let relative = file.strip_prefix(src).expect("under src");
        if relative.starts_with("bin") || relative == Path::new("main.rs") {
            continue;
        }
        let text =
            std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        let module = module_path(src, &file);
        let targets: BTreeSet<PathBuf> = references(&code_only(&text), &module)
            .iter()
            .map(|p| module_file(src, p))
            .filter(|t| t != &file)
            .collect();
        imports.insert(file, targets);
    }
    imports
}

/// Every pair of files that import each other.
fn mutual_pairs(imports: &BTreeMap<PathBuf, BTreeSet<PathBuf>>) -> Vec<(PathBuf, PathBuf)> {
    let mut pairs = Vec::new();
    for (a, targets) in imports {
        for b in targets {
            if a < b && imports.get(b).is_some_and(|back| back.contains(a)) {
                pairs.push((a.clone(), b.clone()));
            }
        }
    }
    pairs
}

#[test]
fn no_two_files_import_each_other() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut pairs = Vec::new();
    let mut files = 0;
    for src in source_dirs() {
        let imports = imports_of_crate(&src);
        files += imports.len();
        pairs.extend(mutual_pairs(&imports));
    }
    assert!(files > 100, "only {files} files read");
    let named: Vec<String> = pairs
        .iter()
        .map(|(a, b)| {
            let rel = |p: &Path| p.strip_prefix(root).unwrap_or(p).display().to_string();
            format!("{} <-> {}", rel(a), rel(b))
        })
        .collect();
    assert!(
        named.is_empty(),
        "files that import each other:\n{}",
        named.join("\n")
    );
}

/// The check itself: paths of every form resolve to the right module files, and a pair
/// of files naming each other is found.
#[test]
fn the_check_resolves_every_form_of_path_and_finds_a_mutual_pair() {
    let dir = tempfile::tempdir().expect("tempdir");
    let src = dir.path();
    std::fs::create_dir_all(src.join("turns")).expect("mkdir");
    let write = |path: &str, text: &str| std::fs::write(src.join(path), text).expect("write");
    write("lib.rs", "pub mod turns;\npub mod geometry;\n");
    write(
        "geometry.rs",
        "// use crate::turns::answer;\npub struct P;\n",
    );
    write(
        "turns/mod.rs",
        "mod answer;\nmod turn;\npub use answer::A;\nuse crate::geometry::P;\n",
    );
    write(
        "turns/answer.rs",
        "use super::turn::{T, self};\npub struct A;\n",
    );
    write(
        "turns/turn.rs",
        "use crate::{geometry, turns::answer::{A}};\nfn f() { let _ = \"super::x\"; }\npub struct T;\n",
    );
    let imports = imports_of_crate(src);
    let of = |p: &str| imports[&src.join(p)].clone();
    let set = |ps: &[&str]| -> BTreeSet<PathBuf> { ps.iter().map(|p| src.join(p)).collect() };
    assert_eq!(of("geometry.rs"), set(&[]), "a comment is no import");
    assert_eq!(of("turns/mod.rs"), set(&["geometry.rs"]));
    assert_eq!(of("turns/answer.rs"), set(&["turns/turn.rs"]));
    assert_eq!(
        of("turns/turn.rs"),
        set(&["geometry.rs", "turns/answer.rs"])
    );
    assert_eq!(
        mutual_pairs(&imports),
        [(src.join("turns/answer.rs"), src.join("turns/turn.rs"))]
    );
}
