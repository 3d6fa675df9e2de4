//! No two files of `src/` import each other, directly or around a circle (issue 78): the
//! module-level check above cannot see a circle inside one module (`phase2/chaining.rs` →
//! `task.rs` → `lookahead.rs` → `chaining.rs`).
//!
//! A file's imports are the paths its code names (`use` trees, and `crate::`, `super::` and
//! `self::` paths inline, and a `mod.rs`'s `child::` paths; comments and unit tests left out),
//! each resolved to the file that defines the module it reaches. A name a folder's `mod.rs`
//! hands on (`pub use child::Name`) resolves to the child that defines it; `mod.rs`'s own `mod`
//! and `pub use` lines are its face, not imports; and a folder's `mod.rs` and the files inside it
//! stand on one another (as `farm-studio look` reads the house), so their arrows are not drawn.
//! Names used without a path (a type imported by a `use` of its folder) reach the file of that
//! `use`; names used bare in the file that defines them are no arrow at all.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A module of the crate: its path (`["phase2", "task"]`) and its file.
struct Module {
    path: Vec<String>,
    file: PathBuf,
}

/// Every module file of `src/` (the binary's folder left out: nothing imports it).
fn modules(src: &Path) -> Vec<Module> {
    let mut files = Vec::new();
    super::rust_files(src, &mut files);
    files
        .into_iter()
        .filter(|f| !f.starts_with(src.join("bin")))
        .map(|file| {
            let rel = file.strip_prefix(src).unwrap().with_extension("");
            let mut path: Vec<String> = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            if path.last().is_some_and(|l| l == "mod" || l == "lib") {
                path.pop();
            }
            // The lab's folder is a floor: its modules are named at the crate's root.
            if path.first().is_some_and(|l| l == "lab") {
                path.remove(0);
            }
            Module { path, file }
        })
        .filter(|m| !m.path.is_empty() || m.file.ends_with("lib.rs"))
        .collect()
}

/// `text` without comments, string literals' contents, and the unit tests at its end.
fn code_of(text: &str) -> String {
    let text = text.split("#[cfg(test)]\nmod ").next().unwrap();
    let mut out = String::new();
    for line in text.lines() {
        let line = line.split("//").next().unwrap();
        let mut in_string = false;
        for c in line.chars() {
            if c == '"' {
                in_string = !in_string;
            } else if !in_string {
                out.push(c);
            }
        }
        out.push('\n');
    }
    out
}

/// The paths of one `use` tree (`a::{b, c::{d, e}}` → `a::b`, `a::c::d`, `a::c::e`).
fn expand(tree: &str, prefix: &[String], out: &mut Vec<Vec<String>>) {
    let tree = tree.trim();
    if let Some(open) = tree.find('{') {
        let head: Vec<String> = split_path(&tree[..open]);
        let close = tree.rfind('}').filter(|&c| c > open).unwrap_or(tree.len());
        let inner = &tree[open + 1..close];
        let base: Vec<String> = prefix.iter().cloned().chain(head).collect();
        let mut depth = 0;
        let mut start = 0;
        for (i, c) in inner.char_indices() {
            match c {
                '{' => depth += 1,
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    expand(&inner[start..i], &base, out);
                    start = i + 1;
                }
                _ => {}
            }
        }
        expand(&inner[start..], &base, out);
    } else {
        let name = tree.split(" as ").next().unwrap();
        let path: Vec<String> = prefix.iter().cloned().chain(split_path(name)).collect();
        if !path.is_empty() {
            out.push(path);
        }
    }
}

fn split_path(p: &str) -> Vec<String> {
    p.split("::")
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty() && s != "self" && s != "*")
        .collect()
}

/// The `use` statements of `code`: (whether `pub`, the paths). (`use` lines are also read by
/// [`inline_paths`]: the same edges twice.)
fn uses(code: &str) -> Vec<(bool, Vec<Vec<String>>)> {
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find("use ") {
        let before = &rest[..at];
        let word_start = before.is_empty() || before.ends_with([' ', '\n', '(', ')', '{', ';']);
        let end = rest[at..].find(';').map_or(rest.len(), |e| at + e);
        if word_start {
            let public = before.trim_end().ends_with("pub") || before.trim_end().ends_with(')');
            let mut paths = Vec::new();
            expand(&rest[at + 4..end], &[], &mut paths);
            out.push((public, paths));
        }
        rest = &rest[(end + 1).min(rest.len())..];
    }
    out
}

/// The paths of `code` outside `use` statements (`crate::a::f`, `super::T`, in a folder's
/// `mod.rs` `child::f`; [`absolute`] keeps those of this crate).
fn inline_paths(code: &str) -> Vec<Vec<String>> {
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut out = Vec::new();
    for (i, _) in code.match_indices("::") {
        let start = code[..i].rfind(|c: char| !ident(c)).map_or(0, |s| s + 1);
        if start == i {
            continue;
        }
        if start > 1 && &code[start - 2..start] == "::" {
            continue; // the tail of a longer path (`super::super::x`), counted at its head
        }
        let end = code[start..]
            .find(|c: char| !(ident(c) || c == ':'))
            .map_or(code.len(), |e| start + e);
        out.push(split_path(&code[start..end]));
    }
    out
}

/// The module path `path` names, read in module `at` (`crate`, `super`, `self`, a child of
/// `at`); `None` for another crate's.
fn absolute(
    path: &[String],
    at: &[String],
    is_mod: bool,
    all: &BTreeSet<Vec<String>>,
) -> Option<Vec<String>> {
    let mut here: Vec<String> = at.to_vec();
    let mut rest = path;
    match path.first().map(String::as_str) {
        Some("crate") => {
            here.clear();
            rest = &path[1..];
        }
        Some("super") | Some("self") => {
            while let Some(first) = rest.first() {
                if first == "super" {
                    here.pop();
                } else if first != "self" {
                    break;
                }
                rest = &rest[1..];
            }
        }
        Some(first) => {
            let child: Vec<String> = at.iter().cloned().chain([first.to_string()]).collect();
            if !(is_mod || at.is_empty()) || !all.contains(&child) {
                return None;
            }
        }
        None => return None,
    }
    Some(here.into_iter().chain(rest.iter().cloned()).collect())
}

#[test]
fn no_two_files_import_each_other() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mods = modules(&src);
    let all: BTreeSet<Vec<String>> = mods.iter().map(|m| m.path.clone()).collect();
    // A folder's face: its mod.rs, or lib.rs for src/.
    let is_folder = |p: &[String]| {
        p.is_empty()
            || mods
                .iter()
                .any(|m| m.path == p && m.file.ends_with("mod.rs"))
    };
    let code: BTreeMap<Vec<String>, String> = mods
        .iter()
        .map(|m| {
            (
                m.path.clone(),
                code_of(&std::fs::read_to_string(&m.file).unwrap()),
            )
        })
        .collect();
    // What each folder's mod.rs (and lib.rs) hands on: name → the path it comes from.
    let mut handed: BTreeMap<Vec<String>, BTreeMap<String, Vec<String>>> = BTreeMap::new();
    for m in &mods {
        let face = is_folder(&m.path);
        for (public, paths) in uses(&code[&m.path]) {
            for p in paths.iter().filter(|_| public && face) {
                if let Some(abs) = absolute(p, &m.path, true, &all) {
                    let name = abs.last().unwrap().clone();
                    handed.entry(m.path.clone()).or_default().insert(name, abs);
                }
            }
        }
    }
    // The file an absolute path reaches: its deepest module, or the child a face hands on.
    let resolve = |abs: &[String]| -> Vec<String> {
        let mut path = abs.to_vec();
        for _ in 0..8 {
            let depth = (0..=path.len())
                .rev()
                .find(|&d| all.contains(&path[..d]))
                .unwrap();
            let module = path[..depth].to_vec();
            let next = path
                .get(depth)
                .and_then(|name| handed.get(&module)?.get(name));
            match next {
                Some(to) if to != &path => path = to.clone(),
                _ => return module,
            }
        }
        path
    };
    let mut edges: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for m in &mods {
        let face = is_folder(&m.path);
        let text = &code[&m.path];
        let mut named: Vec<Vec<String>> = inline_paths(text);
        for (public, paths) in uses(text) {
            if !(public && face) {
                named.extend(paths);
            }
        }
        for p in named {
            let Some(abs) = absolute(&p, &m.path, face, &all) else {
                continue;
            };
            let to = resolve(&abs);
            // A folder's mod.rs and the files inside it stand on one another, as a house's
            // floors: a file using what its folder's mod.rs defines, or mod.rs using its files,
            // is not an arrow between rooms (as `farm-studio look` reads the house too).
            let inside = |a: &[String], b: &[String]| is_folder(a) && b.starts_with(a);
            if to != m.path && !inside(&to, &m.path) && !inside(&m.path, &to) {
                edges.entry(m.path.clone()).or_default().insert(to);
            }
        }
    }
    // Each file's circle: the files it reaches that reach it back.
    let reach = |from: &Vec<String>| {
        let mut seen = BTreeSet::new();
        let mut todo = vec![from.clone()];
        while let Some(x) = todo.pop() {
            for y in edges.get(&x).into_iter().flatten() {
                if seen.insert(y.clone()) {
                    todo.push(y.clone());
                }
            }
        }
        seen
    };
    let reached: BTreeMap<&Vec<String>, BTreeSet<Vec<String>>> =
        edges.keys().map(|a| (a, reach(a))).collect();
    let mut circles: BTreeSet<Vec<String>> = BTreeSet::new();
    for (a, from_a) in &reached {
        let mut circle: Vec<String> = from_a
            .iter()
            .filter(|b| reached.get(b).is_some_and(|r| r.contains(*a)))
            .map(|b| b.join("::"))
            .collect();
        if !circle.is_empty() {
            circle.sort();
            circle.dedup();
            circles.insert(circle);
        }
    }
    // The check sees an import where there is one: phase2/section.rs names task.rs, and in the
    // lab's folder experiment/read_row.rs names row.rs.
    let path = |p: &[&str]| p.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    assert!(edges[&path(&["phase2", "section"])].contains(&path(&["phase2", "task"])));
    assert!(edges[&path(&["experiment", "read_row"])].contains(&path(&["experiment", "row"])));
    let circles: Vec<String> = circles.into_iter().map(|c| c.join(" ")).collect();
    // Six groups were broken for issue 78: the experiment files around site.rs ↔ spec.rs,
    // phase2/backplay.rs ↔ procedure.rs, runs/eval.rs ↔ pbcs.rs, the chainer's four files (one
    // owned run), a row ↔ its CSV record and the results layout ↔ the sweep (one file for the
    // row and its record, one for reading rows back, one for the plan), and the procedure ↔
    // its flat form (the flat form implements the procedure's serde).
    assert!(
        circles.is_empty(),
        "the files on each import circle (a file a → … → b → … → a): {circles:#?}"
    );
}
