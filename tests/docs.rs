//! The README and the pages of `docs/`: the cover stays a cover (at most 200 lines, none wider
//! than 100 characters), every relative link resolves (file and heading), and every generated
//! block quotes exactly what the committed tables and files give, so no number there is typed.
//! When a block differs, the failure prints the block to paste.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The README and every page of `docs/`.
fn pages() -> Vec<PathBuf> {
    let mut pages = vec![PathBuf::from("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir("docs")
        .expect("a docs/ folder")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    pages.extend(docs);
    pages
}

/// The text between `<!-- {name}:begin … -->\n` and `<!-- {name}:end -->` in `page`.
fn block(page: &str, name: &str) -> String {
    let text = std::fs::read_to_string(page).unwrap();
    let begin = format!("<!-- {name}:begin");
    let at = text
        .find(&begin)
        .unwrap_or_else(|| panic!("{page} has no `{begin}` marker"));
    let from = at + text[at..].find("-->\n").expect("the marker's end") + "-->\n".len();
    let to = from
        + text[from..]
            .find(&format!("<!-- {name}:end -->"))
            .unwrap_or_else(|| panic!("{page} has no `{name}:end` marker"));
    text[from..to].to_string()
}

/// `page`'s block `name` is `generated` (with a blank line either side).
fn assert_block(page: &str, name: &str, generated: &str) {
    let want = format!("\n{generated}\n");
    assert!(
        block(page, name) == want,
        "{page}'s `{name}` block differs from what the committed files give; put the text \
         between the >>> and <<< lines between its markers:\n>>>\n{want}<<<"
    );
}

#[test]
fn the_readme_is_a_cover() {
    let text = std::fs::read_to_string("README.md").unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert!(lines.len() <= 200, "README.md has {} lines", lines.len());
    for (i, line) in lines.iter().enumerate() {
        let width = line.chars().count();
        assert!(
            width <= 100,
            "README.md:{} is {width} characters wide",
            i + 1
        );
    }
    // The first lines: exactly the two set-up commands, the test command the one CI calls.
    assert_eq!(lines[2], "```sh");
    assert!(
        lines[3].starts_with("cargo run --release -- run "),
        "{}",
        lines[3]
    );
    assert!(
        lines[4].starts_with("cargo test --release --locked "),
        "{}",
        lines[4]
    );
    assert_eq!(lines[5], "```");
    let ci = std::fs::read_to_string(".ci/run").unwrap();
    assert!(ci.lines().any(|l| l == "cargo test --release --locked"));
}

/// GitHub's anchor of a heading: lower case, punctuation but `-` and `_` dropped, spaces as
/// `-`.
fn anchor(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

#[test]
fn anchors_are_githubs() {
    assert_eq!(
        anchor("The commands: `pbcs run`, `pbcs eval`, `pbcs table`"),
        "the-commands-pbcs-run-pbcs-eval-pbcs-table"
    );
    assert_eq!(anchor("Phase 2 and the presets"), "phase-2-and-the-presets");
    assert_eq!(
        anchor("Balls in position and velocity, registered"),
        "balls-in-position-and-velocity-registered"
    );
}

/// The lines of a Markdown text outside fenced code blocks.
fn prose_lines(text: &str) -> Vec<&str> {
    let mut fenced = false;
    text.lines()
        .filter(|line| {
            if line.starts_with("```") {
                fenced = !fenced;
                return false;
            }
            !fenced
        })
        .collect()
}

/// The anchors of a Markdown file's headings (outside code blocks).
fn anchors(text: &str) -> BTreeSet<String> {
    prose_lines(text)
        .into_iter()
        .filter(|line| line.starts_with('#'))
        .map(|line| anchor(line.trim_start_matches('#')))
        .collect()
}

/// The targets of the inline links `[text](target)` and images of a Markdown text, outside
/// code blocks and code spans.
fn links(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for line in prose_lines(text) {
        // Code spans cannot hold links: drop them.
        let plain: String = line
            .split('`')
            .enumerate()
            .filter(|(i, _)| i % 2 == 0)
            .map(|(_, s)| s)
            .collect::<Vec<_>>()
            .join(" ");
        let mut rest = plain.as_str();
        while let Some(at) = rest.find("](") {
            let after = &rest[at + 2..];
            let Some(end) = after.find(')') else { break };
            out.push(after[..end].to_string());
            rest = &after[end..];
        }
    }
    out
}

#[test]
fn every_relative_link_resolves() {
    let mut checked = 0;
    for page in pages() {
        let text = std::fs::read_to_string(&page).unwrap();
        let dir = page.parent().unwrap_or(Path::new("."));
        for target in links(&text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            let (file, fragment) = match target.split_once('#') {
                Some((f, a)) => (f, Some(a)),
                None => (target.as_str(), None),
            };
            let path = if file.is_empty() {
                page.clone()
            } else {
                dir.join(file)
            };
            assert!(
                path.exists(),
                "{}: the link `{target}` names {}, which does not exist",
                page.display(),
                path.display()
            );
            if let Some(fragment) = fragment {
                let text = std::fs::read_to_string(&path).unwrap();
                assert!(
                    anchors(&text).contains(fragment),
                    "{}: the link `{target}` names no heading of {}",
                    page.display(),
                    path.display()
                );
            }
            checked += 1;
        }
    }
    assert!(
        checked > 50,
        "only {checked} links found: is the link reader broken?"
    );
}

/// The reader finds links and images, and none in code.
#[test]
fn the_link_reader_reads_links_not_code() {
    let text = "a [b](c.md) and ![d](e.png#f)\n`[x](y)` [g](h.md#i)\n```\n[j](k)\n```\n";
    assert_eq!(links(text), ["c.md", "e.png#f", "h.md#i"]);
}

#[test]
fn the_readme_quotes_the_headline_tables() {
    let generated = pbcs::tables::headline::headline_markdown(Path::new("results")).unwrap();
    assert_block("README.md", "headline", &generated);
}

#[test]
fn the_cost_table_is_the_timing_tables_sums() {
    let exps = pbcs::pipeline::load_experiments(Path::new("experiments"), None).unwrap();
    let generated = pbcs::tables::cost::cost_markdown(&exps, Path::new("results")).unwrap();
    assert_block("docs/experiments.md", "costs", &generated);
}

/// docs/pointmaze.md's table of the learners by SB3's protocol is `outside.pointmaze.csv`'s.
#[test]
fn the_docs_quote_the_goal_conditioned_baselines_as_generated() {
    let path = pbcs::tables::outside::outside_table(Path::new("results"), "pointmaze");
    let lines = pbcs::record::read_records(&path).unwrap();
    let generated = pbcs::tables::headline::goal_baselines_markdown(&lines);
    assert_block("docs/pointmaze.md", "her", &generated);
}

/// The settings table is the generated one, byte for byte.
#[test]
fn the_docs_quote_the_generated_settings_table() {
    use pbcs::report::settings::{load, settings_markdown};
    let rows = load(Path::new("experiments/settings.toml")).unwrap();
    assert_block("docs/phase2.md", "settings", &settings_markdown(&rows));
}

/// The held-out grid's results as `methods_by_maze_markdown` generates them from the committed
/// tables.
#[test]
fn the_docs_quote_the_held_out_results_as_generated() {
    let results = Path::new("results");
    let stats = pbcs::tables::read_table(&pbcs::tables::table_path(
        results,
        "heldout".parse().unwrap(),
    ))
    .unwrap();
    let runs = pbcs::criteria::read_chains(&pbcs::criteria::chains_path(
        results,
        "heldout".parse().unwrap(),
    ))
    .unwrap();
    assert_eq!(runs.len(), 56, "every registered run has its chain row");
    let generated = pbcs::tables::methods_by_maze_markdown(&stats, &runs);
    assert_block("docs/results.md", "heldout", &generated);
}

/// The figure the README shows is one `make figures` draws from the committed tables.
#[test]
fn the_readme_shows_a_generated_figure() {
    let text = std::fs::read_to_string("README.md").unwrap();
    let table =
        pbcs::experiment::Experiment::load(Path::new("experiments/table.toml"), None).unwrap();
    let grid = table
        .figures
        .iter()
        .find(|f| matches!(f, pbcs::experiment::FigureSpec::Grid { .. }))
        .expect("table.toml declares the results grid");
    let file = format!("results/figures/{}.png", grid.name());
    assert!(
        text.contains(&format!("]({file})")),
        "README.md shows {file}"
    );
    assert!(Path::new(&file).exists());
}
