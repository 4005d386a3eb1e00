//! No two files of the workspace import each other.
//!
//! Every library file of every crate is read (binaries' own roots, `main.rs` and
//! `src/bin/`, are left out: nothing imports them). Each `crate::` and `super::` path in
//! its code, and each path through a module the file itself declares (`mod answer;` then
//! `answer::check(..)`: in `lib.rs` these are the crate-root paths), grouped
//! (`use super::{a, b::C}`) or written in place, is resolved to the deepest module file it
//! names (`crate::turns::answer::Answer` is `turns/answer.rs`); a file then imports that
//! file. A parent's re-export of its child (`pub use answer::Answer;`) is the child's
//! public face, not a use of it. A pair of files each importing the other fails the test,
//! named.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use testkit::rust_source::{code_only, is_ident_char, rust_files};

/// Every library `src/` folder of the workspace.
fn source_dirs() -> Vec<PathBuf> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    [
        "shared/core",
        "shared/wire",
        "shared/net",
        "shared/testkit",
        "agent",
        "coordinator/runner",
        "coordinator/tools",
        "coordinator/cli",
    ]
    .iter()
    .map(|c| root.join(c).join("src"))
    .inspect(|src| assert!(src.is_dir(), "{} is no folder", src.display()))
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

/// The modules `code` declares as its children (`mod a;`, `pub(crate) mod b;`), by name.
fn child_modules(code: &str) -> BTreeSet<String> {
    code.split(';')
        .filter_map(|statement| {
            let words: Vec<&str> = statement.split_whitespace().collect();
            match words.as_slice() {
                [.., "mod", name] if name.chars().all(is_ident_char) => Some(name.to_string()),
                _ => None,
            }
        })
        .collect()
}

/// Whether the statement around `at` in `chars` is a re-export (`pub use ...`,
/// `pub(crate) use ...`).
fn in_re_export(chars: &[char], at: usize) -> bool {
    let start = chars[..at]
        .iter()
        .rposition(|c| matches!(c, ';' | '{' | '}'))
        .map_or(0, |p| p + 1);
    let statement: String = chars[start..at].iter().collect();
    let mut words = statement.split_whitespace();
    words.next().is_some_and(|w| w.starts_with("pub")) && statement.contains("use ")
}

/// `code` without its inline test modules (`#[cfg(test)] mod tests { ... }`): a test
/// may use any file of its crate; the files' design is what must not loop.
fn without_test_modules(code: &str) -> String {
    let mut out = String::new();
    let mut rest = code;
    while let Some(at) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..at]);
        let after = rest[at + "#[cfg(test)]".len()..].trim_start();
        let body = after
            .strip_prefix("mod ")
            .and_then(|m| m.find(['{', ';']).map(|end| (m, end)))
            .filter(|(m, end)| m.as_bytes()[*end] == b'{');
        let Some((module, open)) = body else {
            out.push_str("#[cfg(test)]");
            rest = &rest[at + "#[cfg(test)]".len()..];
            continue;
        };
        let mut depth = 0usize;
        let mut end = module.len();
        for (i, c) in module[open..].char_indices() {
            match c {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = open + i + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        rest = &module[end..];
    }
    out.push_str(rest);
    out
}

/// For each character of `chars`, how many inline modules (`mod tests { ... }`) it is in:
/// there `super::` first leaves those, back to the file's own module.
fn inline_module_depth(chars: &[char]) -> Vec<usize> {
    let mut depth = vec![0; chars.len()];
    // The brace depth at which each open inline module's body started.
    let mut open: Vec<usize> = Vec::new();
    let mut braces = 0usize;
    let mut i = 0;
    while i < chars.len() {
        let boundary = i == 0 || !is_ident_char(chars[i - 1]);
        if boundary && chars[i..].starts_with(&['m', 'o', 'd', ' ']) {
            let mut at = i + 4;
            while chars.get(at).copied().is_some_and(is_ident_char) {
                at += 1;
            }
            while chars.get(at).is_some_and(|c| c.is_whitespace()) {
                at += 1;
            }
            if chars.get(at) == Some(&'{') {
                open.push(braces);
            }
        }
        match chars[i] {
            '{' => braces += 1,
            '}' => {
                braces = braces.saturating_sub(1);
                if open.last() == Some(&braces) {
                    open.pop();
                }
            }
            _ => {}
        }
        depth[i] = open.len();
        i += 1;
    }
    depth
}

/// A path `code` names into its own crate, from the crate root.
struct NamedPath {
    /// The names, from the crate root.
    path: Vec<String>,
    /// Written through a module the file itself declares (`answer::check`), not through
    /// `crate::` or `super::`.
    through_child: bool,
    /// In a re-export (`pub use ...`).
    re_exported: bool,
}

/// Every path that `code`, the code of the file at module path `module`, names into its
/// crate: through `crate::`, `super::` (an inline module's first) and the modules it
/// declares; grouped paths one by one.
fn named_paths(code: &str, module: &[String]) -> Vec<NamedPath> {
    let chars: Vec<char> = code.chars().collect();
    let children = child_modules(code);
    let inline = inline_module_depth(&chars);
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let boundary = i == 0 || !(is_ident_char(chars[i - 1]) || chars[i - 1] == ':');
        let starts = |word: &str| chars[i..].starts_with(&word.chars().collect::<Vec<_>>());
        let name: String = chars[i..]
            .iter()
            .take_while(|c| is_ident_char(**c))
            .collect();
        let after = i + name.chars().count();
        let through_child = children.contains(&name)
            && chars.get(after) == Some(&':')
            && chars.get(after + 1) == Some(&':');
        // Where the path starts (from the crate root) and where its tree begins.
        let (base, at) = if !boundary {
            i += 1;
            continue;
        } else if through_child {
            (module.to_vec(), i)
        } else if starts("crate::") {
            (Vec::new(), i + "crate::".len())
        } else if starts("super::") {
            // Each `super` is one module up (`a/mod.rs` is module `a`, so its `super` is
            // the crate root), after leaving the inline modules the path is in.
            let mut base = module.to_vec();
            let mut inline_levels = inline[i];
            let mut at = i;
            while chars[at..].starts_with(&"super::".chars().collect::<Vec<_>>()) {
                if inline_levels > 0 {
                    inline_levels -= 1;
                } else {
                    base.pop();
                }
                at += "super::".len();
            }
            (base, at)
        } else {
            i += 1;
            continue;
        };
        let re_exported = in_re_export(&chars, i);
        let (paths, end) = use_tree(&chars, at);
        for p in paths {
            let mut path = base.clone();
            path.extend(p);
            out.push(NamedPath {
                path,
                through_child,
                re_exported,
            });
        }
        i = end.max(i + 1);
    }
    out
}

/// The module paths (from the crate root) that `code`, the code of the file at module
/// path `module`, uses: [`named_paths`] but a parent's re-exports of its children.
fn references(code: &str, module: &[String]) -> Vec<Vec<String>> {
    named_paths(code, module)
        .into_iter()
        .filter(|p| !(p.through_child && p.re_exported))
        .map(|p| p.path)
        .collect()
}

/// What `code`, the file at module path `module`, re-exports from modules of its crate
/// (`pub use answer::{Answer, check};`): each name, and the path (from the crate root)
/// of the item it stands for.
fn re_exports(code: &str, module: &[String]) -> BTreeMap<String, Vec<String>> {
    named_paths(code, module)
        .into_iter()
        .filter(|p| p.re_exported)
        .filter_map(|p| Some((p.path.last()?.clone(), p.path)))
        .collect()
}

/// The file an item path (from the crate root) lives in: the deepest module file on it,
/// and when that file re-exports the next name, where that name comes from.
fn resolve(
    src: &Path,
    path: &[String],
    re_exported: &BTreeMap<PathBuf, BTreeMap<String, Vec<String>>>,
) -> PathBuf {
    let mut path = path.to_vec();
    // A re-export of a re-export is followed, a few levels at most (no loop).
    for _ in 0..8 {
        let file = module_file(src, &path);
        let depth = module_path(src, &file).len();
        let next = path
            .get(depth)
            .and_then(|name| re_exported.get(&file)?.get(name));
        match next {
            Some(origin) if origin != &path[..=depth] => {
                let mut deeper = origin.clone();
                deeper.extend_from_slice(&path[depth + 1..]);
                path = deeper;
            }
            _ => return file,
        }
    }
    module_file(src, &path)
}

/// Which files each library file imports (other files only), in one crate.
fn imports_of_crate(src: &Path) -> BTreeMap<PathBuf, BTreeSet<PathBuf>> {
    let mut codes = Vec::new();
    for file in rust_files(src) {
        let relative = file.strip_prefix(src).expect("under src");
        if relative.starts_with("bin") || relative == Path::new("main.rs") {
            continue;
        }
        let text =
            std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        let module = module_path(src, &file);
        codes.push((file, module, without_test_modules(&code_only(&text))));
    }
    let re_exported: BTreeMap<PathBuf, BTreeMap<String, Vec<String>>> = codes
        .iter()
        .map(|(file, module, code)| (file.clone(), re_exports(code, module)))
        .collect();
    let mut imports = BTreeMap::new();
    for (file, module, code) in codes {
        let targets: BTreeSet<PathBuf> = references(&code, &module)
            .iter()
            .map(|p| resolve(src, p, &re_exported))
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

/// The cycles the check once missed: a crate root calling into a module it declares
/// (`misbehave::serve_ipc(..)` in `lib.rs`) while that module calls back (`crate::serve`).
/// A re-export is followed to the file the item lives in, a parent's re-export of its
/// child is no use of it, and a test module's `use super::*` stays in its own file.
#[test]
fn the_check_reads_crate_root_paths_and_follows_re_exports() {
    let dir = tempfile::tempdir().expect("tempdir");
    let src = dir.path();
    let write = |path: &str, text: &str| std::fs::write(src.join(path), text).expect("write");
    write(
        "lib.rs",
        "mod keys;\nmod loop_;\nmod modes;\nmod session;\npub use keys::KEY;\n\
         pub fn serve() {}\npub fn run() { modes::serve_ipc(); }\n",
    );
    write("keys.rs", "pub const KEY: &str = \"k\";\n");
    write("modes.rs", "pub fn serve_ipc() { crate::serve(); }\n");
    write(
        "session.rs",
        "pub fn open() -> &'static str { crate::KEY }\n\
         #[cfg(test)]\nmod tests {\n    use super::*;\n}\n",
    );
    write(
        "loop_.rs",
        "mod inner { pub fn f() { super::super::serve(); } }\n",
    );
    let imports = imports_of_crate(src);
    let of = |p: &str| imports[&src.join(p)].clone();
    let set = |ps: &[&str]| -> BTreeSet<PathBuf> { ps.iter().map(|p| src.join(p)).collect() };
    assert_eq!(
        of("lib.rs"),
        set(&["modes.rs"]),
        "the re-export of keys is no use"
    );
    assert_eq!(
        of("session.rs"),
        set(&["keys.rs"]),
        "crate::KEY lives in keys.rs"
    );
    assert_eq!(of("loop_.rs"), set(&["lib.rs"]), "an inline module's super");
    assert_eq!(
        mutual_pairs(&imports),
        [(src.join("lib.rs"), src.join("modes.rs"))]
    );
}
