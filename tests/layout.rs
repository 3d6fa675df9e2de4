//! The package's shape stays as the redesign left it: no source file over 600 lines, no
//! import circle between the library's top-level modules (data flows one way) nor between
//! any two of its files ([`files`]), no function over 80 lines ([`functions`]), and the core
//! never importing the lab (`src/lab/`).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

#[path = "layout/files.rs"]
mod files;
#[path = "layout/functions.rs"]
mod functions;

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn no_source_file_is_over_600_lines() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for dir in ["src", "tests", "benches", "examples", "python/src"] {
        rust_files(&root.join(dir), &mut files);
    }
    assert!(files.len() > 50, "{} files", files.len());
    for f in files {
        let lines = std::fs::read_to_string(&f).unwrap().lines().count();
        assert!(lines <= 600, "{}: {lines} lines", f.display());
    }
}

/// The top-level module a file of `src/` belongs to (`src/phase2/task.rs` → `phase2`,
/// `src/lab/tables/mod.rs` → `tables`).
fn module_of(src: &Path, file: &Path) -> Option<String> {
    let rel = file.strip_prefix(src).ok()?;
    let first = rel
        .components()
        .next()?
        .as_os_str()
        .to_string_lossy()
        .into_owned();
    let name = first.trim_end_matches(".rs").to_string();
    if name == "lab" {
        // The lab's folder is a floor, not a module of its own: its modules are named at the
        // crate's root (`crate::experiment`), and its mod.rs only lists them.
        let second = rel
            .components()
            .nth(1)?
            .as_os_str()
            .to_string_lossy()
            .into_owned();
        let name = second.trim_end_matches(".rs").to_string();
        return (name != "mod").then_some(name);
    }
    (name != "lib" && name != "bin").then_some(name)
}

/// Which top-level modules each top-level module of `src/` names through `crate::` in its
/// code (comments and unit tests left out).
fn module_imports() -> BTreeMap<String, BTreeSet<String>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for f in &files {
        let Some(from) = module_of(&src, f) else {
            continue;
        };
        let text = std::fs::read_to_string(f).unwrap();
        // Unit tests may reach anywhere; only the code they test counts.
        let code = text.split("#[cfg(test)]\nmod tests").next().unwrap();
        let targets = edges.entry(from.clone()).or_default();
        for line in code.lines().filter(|l| !l.trim_start().starts_with("//")) {
            for part in line.split("crate::").skip(1) {
                let head = if let Some(group) = part.strip_prefix('{') {
                    // `use crate::{a, b::c}`: every name of the group.
                    for name in group.split([',', '}']).map(|n| n.trim()) {
                        let name: String = name
                            .chars()
                            .take_while(|c| c.is_alphanumeric() || *c == '_')
                            .collect();
                        if !name.is_empty() && name != from {
                            targets.insert(name);
                        }
                    }
                    continue;
                } else {
                    part
                };
                let name: String = head
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() && name != from && name.chars().next().unwrap().is_lowercase() {
                    targets.insert(name);
                }
            }
        }
    }
    edges
}

/// The files of `src/<module>/` (or `src/<module>.rs`) whose code (comments left out) holds
/// `word` as a whole identifier (`plot` in `super::super::plot` or in an import group split
/// over lines, not in `plotting`).
fn files_naming(module: &str, word: &str) -> Vec<PathBuf> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files
        .into_iter()
        .filter(|f| module_of(&src, f).as_deref() == Some(module))
        .filter(|f| {
            let text = std::fs::read_to_string(f).unwrap();
            text.lines()
                .filter(|l| !l.trim_start().starts_with("//"))
                .any(|l| {
                    l.split(|c: char| !(c.is_alphanumeric() || c == '_'))
                        .any(|token| token == word)
                })
        })
        .collect()
}

/// The core (every module of `src/` outside `src/lab/`) never imports the lab, nor names plotters
/// or polars: a user of PBCS as a library needs none of it (`cargo check --lib
/// --no-default-features`, which .ci/run runs, builds the core without the lab's crates).
#[test]
fn the_core_never_imports_the_lab() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src.join("lab"), &mut files);
    let lab: BTreeSet<String> = files.iter().filter_map(|f| module_of(&src, f)).collect();
    assert!(lab.contains("experiment") && lab.contains("tables") && lab.contains("plot"));
    let edges = module_imports();
    let core: Vec<&String> = edges.keys().filter(|m| !lab.contains(*m)).collect();
    assert!(
        core.len() > 15 && core.iter().any(|m| *m == "phase2"),
        "{core:?}"
    );
    for m in core {
        let into_lab: Vec<&String> = edges[m].intersection(&lab).collect();
        assert!(
            into_lab.is_empty(),
            "core module {m} imports the lab's {into_lab:?}"
        );
        for word in ["plotters", "polars"] {
            assert_eq!(
                files_naming(m, word),
                Vec::<PathBuf>::new(),
                "{m} names {word}"
            );
        }
    }
    // The check sees an import where there is one: the lab's tables name the experiment.
    assert!(edges["tables"].contains("experiment"));
}

/// Runs compute and write data; the drawing layer draws (a run is handed its drawing step,
/// `picture::Draw`): nothing under src/runs/ names plot.rs, figures/ or plotters.
#[test]
fn runs_draw_nothing() {
    let runs = &module_imports()["runs"];
    for drawing in ["plot", "figures"] {
        assert!(!runs.contains(drawing), "runs/ imports crate::{drawing}");
    }
    for word in ["plot", "figures", "plotters"] {
        assert_eq!(files_naming("runs", word), Vec::<PathBuf>::new(), "{word}");
    }
    // The checks see an import where there is one: figures/ draws.
    assert!(module_imports()["figures"].contains("plot"));
    assert!(!files_naming("figures", "plot").is_empty());
}

#[test]
fn the_library_modules_import_one_way() {
    let edges = module_imports();
    // Depth-first search for a cycle.
    fn visit(
        m: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) {
        if let Some(i) = path.iter().position(|p| p == m) {
            panic!("import circle: {} -> {m}", path[i..].join(" -> "));
        }
        if done.contains(m) {
            return;
        }
        path.push(m.to_string());
        for next in edges.get(m).into_iter().flatten() {
            visit(next, edges, path, done);
        }
        path.pop();
        done.insert(m.to_string());
    }
    assert!(edges.len() > 15, "{edges:?}");
    let mut done = BTreeSet::new();
    for m in edges.keys() {
        visit(m, &edges, &mut Vec::new(), &mut done);
    }
}

/// The names results are joined by (issue 50): cells, methods, experiments, learners,
/// environments and sites.
const IDENTITIES: [&str; 11] = [
    "cell",
    "method",
    "experiment",
    "learner",
    "algo",
    "env",
    "map",
    "site",
    "baseline",
    "variant",
    "than",
];

/// The types that keep a name as text.
const STRING_TYPES: [&str; 12] = [
    "String",
    "&str",
    "&'static str",
    "&String",
    "Option<String>",
    "Option<&str>",
    "Vec<String>",
    "Vec<&str>",
    "&[String]",
    "&[&str]",
    "(String, String)",
    "(&str, &str)",
];

/// The lines of `text` (comments left out) that keep an identity as a string: a field or
/// parameter `<identity>: String` (or `&str`, `Option<String>`, `Vec<String>`), or a
/// comparison of an identity with a string (`.method == "pbcs"`, `.cell.as_str() != …`,
/// `.experiment.to_string() == …`).
fn identity_strings(text: &str) -> Vec<String> {
    let mut found = Vec::new();
    for line in text.lines() {
        let code = line.trim_start();
        if code.starts_with("//") {
            continue;
        }
        for id in IDENTITIES {
            // `<id>: <string type>` or `<id>s: …` anywhere on the line (a field, a parameter,
            // a closure's argument), the name starting at a word boundary.
            let string_typed = [id.to_string(), format!("{id}s")].iter().any(|name| {
                STRING_TYPES.iter().any(|t| {
                    let at = format!("{name}: {t}");
                    code.match_indices(&at).any(|(i, _)| {
                        let before = code[..i].chars().next_back();
                        let after = code[i + at.len()..].chars().next();
                        !before.is_some_and(|c| c.is_alphanumeric() || c == '_')
                            && !after.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '<')
                    })
                })
            });
            let compared = ["", ".as_str()", ".to_string()"].iter().any(|via| {
                ["==", "!="].iter().any(|op| {
                    let at = format!(".{id}{via} {op} ");
                    code.match_indices(&at).any(|(i, _)| {
                        let rest = &code[i + at.len()..];
                        !via.is_empty() || rest.starts_with('"')
                    })
                })
            });
            if string_typed || compared {
                found.push(line.trim().to_string());
            }
        }
    }
    found
}

/// Results are joined on keys, never on strings: no code under src/ keeps a cell, method,
/// experiment, learner, environment or site as a string or compares one with a string (they
/// are `CellKey`, `Method`, `ExperimentName`, `LearnerName`, `EnvName`, `Site`).
#[test]
fn identities_are_keys_not_strings() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    // Not identities: a PointMaze map's rows of text; LaTeX table cells; a learner family's
    // `algo` tag (`ddpg`, `td3`, `sac`: the names the `learners!` line gives the families,
    // which `--algo` is checked against and the job's `[learner]` table selects its family
    // by); errors, which sit below every module (`error.rs` cannot name the key types) and
    // hold keys as their text. Unit tests' files (`tests.rs`) name what they make up by text,
    // parsed where they use it.
    let allowed = [
        ("envs/pointmaze/own.rs", "pub map: Vec<String>,"),
        (
            "lab/report/settings.rs",
            "let cells: Vec<String> = values.iter().map(|v| format!(\"`{v}`\")).collect();",
        ),
        ("bin/pbcs/args.rs", "pub algo: Option<String>,"),
        ("learner/mod.rs", "fn preset(algo: &str) -> Self;"),
        (
            "learner/mod.rs",
            "pub fn preset(algo: &str) -> Result<Self> {",
        ),
        (
            "learner/mod.rs",
            "fn from_table(algo: &str, table: toml::Table) -> std::result::Result<Self, String> {",
        ),
        ("learner/mod.rs", "fn unknown_algo(algo: &str) -> Error {"),
        (
            "learner/mod.rs",
            "pub fn switch_to(&mut self, algo: &str) -> Result<()> {",
        ),
        ("learner/td3.rs", "fn preset(algo: &str) -> Self {"),
        ("runs/train.rs", "pub algo: &'static str,"),
        ("error.rs", "cell: String,"),
        ("error.rs", "experiment: String,"),
    ];
    let mut found = Vec::new();
    for f in files.iter().filter(|f| !f.ends_with("tests.rs")) {
        let rel = f.strip_prefix(&src).unwrap().to_string_lossy().into_owned();
        for line in identity_strings(&std::fs::read_to_string(f).unwrap()) {
            if !allowed.contains(&(rel.as_str(), line.as_str())) {
                found.push(format!("{rel}: {line}"));
            }
        }
    }
    assert!(
        found.is_empty(),
        "identities kept as strings:\n{}",
        found.join("\n")
    );
    // The check sees what it forbids.
    for bad in [
        "    pub cell: String,",
        "    method: &str,",
        "    let find = |method: &str| stats.iter().find(|s| s.method.as_str() == method);",
        "fn cell(method: &'static str, maze: usize) -> CellStats {",
        "    pub methods: Vec<String>,",
        "    .filter(|c| c.method == \"pbcs\")",
        "    if r.cell.as_str() != id {",
        "    e.experiment.to_string() == name",
    ] {
        assert_eq!(identity_strings(bad).len(), 1, "{bad}");
    }
    for fine in [
        "    pub cell: CellKey,",
        "    .filter(|c| c.method == m)",
        "    // the cell: String",
        "    pub label: String,",
        "    let methods: Vec<(Method, String)> = Vec::new();",
        "    pub cell_count: String,",
        "    method: Method,",
    ] {
        assert!(identity_strings(fine).is_empty(), "{fine}");
    }
}
