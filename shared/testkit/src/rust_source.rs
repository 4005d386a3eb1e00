//! Reading Rust source as text, for the tests that check the code's own shape (its module
//! graph, which files import which): every `.rs` file of a folder, and a file's code with
//! its comments and literals left out.

use std::path::{Path, PathBuf};

/// Every `.rs` file under `dir`, sorted.
pub fn rust_files(dir: &Path) -> Vec<PathBuf> {
    files_under(dir, &["rs"], &[])
}

/// Every file under `dir` whose extension is one of `extensions`, sorted, the folders
/// named in `skipped` (anywhere below `dir`) left out.
pub fn files_under(dir: &Path, extensions: &[&str], skipped: &[&str]) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut pending = vec![dir.to_path_buf()];
    while let Some(dir) = pending.pop() {
        for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
            let path = entry.expect("directory entry").path();
            let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
            if path.is_dir() {
                if !skipped.contains(&name) {
                    pending.push(path);
                }
            } else if path
                .extension()
                .and_then(|x| x.to_str())
                .is_some_and(|x| extensions.contains(&x))
            {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

/// The code of `text`: comments (line, doc and block) left out, and every string, raw
/// string and character literal emptied, so that neither can hold a `crate::` path.
pub fn code_only(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let at = |i: usize| chars.get(i).copied();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let after_ident = i > 0 && is_ident_char(chars[i - 1]);
        if c == '/' && at(i + 1) == Some('/') {
            // To the end of the line (the newline itself is kept).
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && at(i + 1) == Some('*') {
            let mut depth = 0usize;
            while i < chars.len() {
                if chars[i] == '/' && at(i + 1) == Some('*') {
                    depth += 1;
                    i += 2;
                } else if chars[i] == '*' && at(i + 1) == Some('/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    i += 1;
                }
            }
        } else if c == 'r' && !after_ident && raw_string_hashes(&chars[i + 1..]).is_some() {
            // r"...", r#"..."#, ...: ends at a quote followed by as many hashes.
            let hashes = raw_string_hashes(&chars[i + 1..]).unwrap_or(0);
            let closing: Vec<char> = std::iter::once('"')
                .chain(std::iter::repeat_n('#', hashes))
                .collect();
            let body = i + 2 + hashes;
            i = (body..chars.len())
                .find(|&j| chars[j..].starts_with(&closing))
                .map_or(chars.len(), |j| j + closing.len());
            out.push_str("\"\"");
        } else if c == '"' {
            i += 1;
            while i < chars.len() && chars[i] != '"' {
                i += if chars[i] == '\\' { 2 } else { 1 };
            }
            i += 1;
            out.push_str("\"\"");
        } else if c == '\'' && !after_ident && (at(i + 1) == Some('\\') || at(i + 2) == Some('\''))
        {
            // A character literal ('x', '\n', '\'', '"'); a lifetime ('a) is kept.
            let start = if at(i + 1) == Some('\\') {
                i + 3
            } else {
                i + 2
            };
            i = (start..chars.len())
                .find(|&j| chars[j] == '\'')
                .map_or(chars.len(), |j| j + 1);
            out.push_str("' '");
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

/// The number of hashes of a raw string whose `r` comes just before `rest`, if `rest`
/// opens one.
fn raw_string_hashes(rest: &[char]) -> Option<usize> {
    let hashes = rest.iter().take_while(|&&c| c == '#').count();
    (rest.get(hashes) == Some(&'"')).then_some(hashes)
}

/// Whether `c` may stand in an identifier.
pub fn is_ident_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// The leading identifier of `s` (after spaces).
pub fn leading_ident(s: &str) -> &str {
    let s = s.trim_start();
    let end = s.find(|c| !is_ident_char(c)).unwrap_or(s.len());
    &s[..end]
}
