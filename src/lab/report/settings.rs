//! The settings table: every field of the two presets (`experiments/pbcs_paper.toml`,
//! `experiments/pbcs_fast.toml`), its value in each, what it does and where its value comes
//! from (`experiments/settings.toml`). The values are read from the preset files, so the
//! report's `\res{preset:<name>:<field>}` numbers, its settings table (`presets.tex`) and the
//! Markdown table of `docs/phase2.md` (`settings_markdown`) never restate a value by hand.
//!
//! ```
//! use pbcs::config::Preset;
//! use pbcs::report::settings::preset_values;
//!
//! let fast = preset_values(Preset::Fast).unwrap();
//! let beta = fast.iter().find(|(f, _)| f == "phase2.beta").unwrap();
//! assert_eq!(beta.1, "50");
//! ```

use crate::config::Preset;
use crate::error::{Error, Result};
use serde::Deserialize;
use std::fmt::Write as _;
use std::path::Path;

/// Where a setting's value comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, strum::IntoStaticStr)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum Source {
    /// The paper gives it.
    Paper,
    /// The paper leaves it open: our choice.
    Open,
    /// Our correction of our phase 2 (in both presets).
    Correction,
    /// Our idea beside the paper's procedure (off in `paper`).
    Switch,
    /// What a run is of (seed, maze).
    Run,
}

/// One entry of `experiments/settings.toml`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SettingDoc {
    /// `section.field` as in the preset files (`phase2.beta`), or a top-level field (`seed`).
    pub field: String,
    /// Where its value comes from.
    pub source: Source,
    /// What it does, in one line (math spans `$…$` as [`super::tex`] reads them).
    pub what: String,
    /// Where its value was measured or justified (math spans as in `what`).
    pub evidence: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SettingsFile {
    setting: Vec<SettingDoc>,
}

/// The presets in the table's column order.
pub const PRESETS: [Preset; 2] = [Preset::Paper, Preset::Fast];

/// Every field of a preset file with its value as written (`phase2.beta` → `50`), in the
/// file's order.
pub fn preset_values(preset: Preset) -> Result<Vec<(String, String)>> {
    let path = Path::new("experiments").join(preset.file_name());
    let value: toml::Table =
        toml::from_str(preset.text()).map_err(|e| Error::parse(&path, e.to_string()))?;
    let mut out = Vec::new();
    flatten("", &value, &mut out);
    Ok(out)
}

/// Every field of a TOML text with its value as the settings table shows it (`phase2.beta` →
/// `50`), in the text's order: what [`preset_values`] reads from a preset file, for any job
/// (the report's `\res{<experiment>:<method>:cfg:<field>}`).
pub fn toml_values(text: &str) -> std::result::Result<Vec<(String, String)>, toml::de::Error> {
    let value: toml::Table = toml::from_str(text)?;
    let mut out = Vec::new();
    flatten("", &value, &mut out);
    Ok(out)
}

/// The constants of the code that the report quotes, as `\res{code:<name>}` (`name` is the
/// Rust constant's, lower case; a fraction shown in percent says so with `_percent`):
/// `solved_at_percent` ([`crate::runs::SOLVED_AT`]), `confidence_percent` (the level of the
/// Wilson intervals, from [`crate::stats::Z95`]), `exact_test_level`
/// ([`crate::claims::EXACT_TEST_LEVEL`]), `thresholds:<i>_percent` (the i-th of
/// [`crate::criteria::THRESHOLDS`], from 1), `max_adaptive_step`
/// ([`crate::phase2::backplay::MAX_ADAPTIVE_STEP`]), `max_handover_tries`
/// ([`crate::phase2::MAX_HANDOVER_TRIES`]) and `max_verified_candidates`
/// ([`crate::phase2::MAX_VERIFIED_CANDIDATES`]).
pub fn code_tex() -> String {
    use statrs::distribution::{ContinuousCDF, Normal};
    let percent = |x: f64| format!("{:.0}", x * 100.0);
    let level = Normal::new(0.0, 1.0).map_or(f64::NAN, |n| 2.0 * n.cdf(crate::stats::Z95) - 1.0);
    let mut values = vec![
        (
            "solved_at_percent".to_string(),
            percent(f64::from(crate::runs::SOLVED_AT)),
        ),
        ("confidence_percent".to_string(), percent(level)),
        (
            "exact_test_level".to_string(),
            crate::claims::EXACT_TEST_LEVEL.to_string(),
        ),
    ];
    for (i, t) in crate::criteria::THRESHOLDS.iter().enumerate() {
        values.push((
            format!("thresholds:{}_percent", i + 1),
            percent(f64::from(*t)),
        ));
    }
    for (name, v) in [
        (
            "max_adaptive_step",
            crate::phase2::backplay::MAX_ADAPTIVE_STEP,
        ),
        ("max_handover_tries", crate::phase2::MAX_HANDOVER_TRIES),
        (
            "max_verified_candidates",
            crate::phase2::MAX_VERIFIED_CANDIDATES,
        ),
    ] {
        values.push((name.to_string(), v.to_string()));
    }
    // The goal-conditioned chain's defaults (`[phase2.goal_conditioned]`, no preset writes
    // them): `code:goal_conditioned:<field>`.
    let gc = crate::phase2::goal_conditioned::GoalConditioned::default();
    for (name, v) in [
        ("spacing", gc.spacing.to_string()),
        ("radius", gc.radius.to_string()),
        ("steps_per_goal", gc.steps_per_goal.to_string()),
        ("window", gc.window.to_string()),
        ("test_every", gc.test_every.to_string()),
        ("test_episodes", gc.test_episodes.to_string()),
    ] {
        values.push((format!("goal_conditioned:{name}"), v));
    }
    let mut s = String::new();
    for (name, v) in values {
        let _ = writeln!(
            s,
            "\\expandafter\\def\\csname res:code:{name}\\endcsname{{{}}}",
            super::tex_code(&v)
        );
    }
    s
}

fn flatten(prefix: &str, table: &toml::Table, out: &mut Vec<(String, String)>) {
    for (key, value) in table {
        let name = format!("{prefix}{key}");
        match value {
            toml::Value::Table(t) => flatten(&format!("{name}."), t, out),
            v => out.push((name, show(v))),
        }
    }
}

/// A value as the table shows it: strings unquoted, arrays joined by commas.
fn show(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => s.clone(),
        toml::Value::Array(a) => a.iter().map(show).collect::<Vec<_>>().join(", "),
        v => v.to_string(),
    }
}

/// Reads `experiments/settings.toml` and checks it against the presets: the presets state the
/// same fields, and each has exactly one entry (an entry without a field, or a field without
/// an entry, is an error naming it); an unbalanced math span (`$…$`) in a text is an error
/// naming the entry and the field ([`super::check_math`]). Returns the entries with each
/// preset's value, in the file's order.
pub fn load(path: &Path) -> Result<Vec<(SettingDoc, Vec<String>)>> {
    let file: SettingsFile = crate::validate::read_toml(path)?;
    for doc in &file.setting {
        for (name, text) in [("what", &doc.what), ("evidence", &doc.evidence)] {
            super::check_math(text)
                .map_err(|e| Error::parse(path, format!("setting `{}`, {name}: {e}", doc.field)))?;
        }
    }
    let values = PRESETS
        .iter()
        .map(|&p| preset_values(p))
        .collect::<Result<Vec<_>>>()?;
    let fields: Vec<&String> = values[0].iter().map(|(f, _)| f).collect();
    for (p, v) in PRESETS.iter().zip(&values).skip(1) {
        let other: Vec<&String> = v.iter().map(|(f, _)| f).collect();
        let mut a = fields.clone();
        let mut b = other.clone();
        a.sort();
        b.sort();
        if a != b {
            return Err(Error::parse(
                Path::new("experiments").join(p.file_name()),
                format!(
                    "states other fields than {} ({:?} against {:?})",
                    PRESETS[0].file_name(),
                    b,
                    a
                ),
            ));
        }
    }
    for f in &fields {
        let n = file.setting.iter().filter(|s| &&s.field == f).count();
        if n != 1 {
            return Err(Error::parse(
                path,
                format!("the presets' field `{f}` has {n} entries here, not one"),
            ));
        }
    }
    file.setting
        .into_iter()
        .map(|doc| {
            let row = values
                .iter()
                .map(|v| {
                    v.iter()
                        .find(|(f, _)| f == &doc.field)
                        .map(|(_, x)| x.clone())
                })
                .collect::<Option<Vec<_>>>()
                .ok_or_else(|| {
                    Error::parse(
                        path,
                        format!("`{}` is not a field of the presets", doc.field),
                    )
                })?;
            Ok((doc, row))
        })
        .collect()
}

/// `presets.tex`: `\res{preset:<name>:<field>}` for every field of every preset, and the
/// settings table (a `longtable`: field, value in `paper`, value in `fast`, source, what,
/// evidence) as `\presetstable`.
pub fn presets_tex(rows: &[(SettingDoc, Vec<String>)]) -> String {
    let mut s = String::from(
        "% Generated by `pbcs figures` from experiments/pbcs_*.toml and experiments/settings.toml. \
         Do not edit.\n\\providecommand{\\res}[1]{\\csname res:#1\\endcsname}\n",
    );
    for (doc, values) in rows {
        for (p, v) in PRESETS.iter().zip(values) {
            let _ = writeln!(
                s,
                "\\expandafter\\def\\csname res:preset:{}:{}\\endcsname{{{}}}",
                p.name(),
                doc.field,
                super::tex_code(v)
            );
        }
    }
    s.push_str(&code_tex());
    s.push_str("\\newcommand{\\presetstable}{%\n");
    s.push_str(&longtable_head(
        &[0.21, 0.1, 0.1, 0.275, 0.24],
        "setting & \\texttt{paper} & \\texttt{fast} & what it does (source) & where its value \
         comes from",
    ));
    for (doc, values) in rows {
        let source: &str = doc.source.into();
        let _ = writeln!(
            s,
            "{} & {} \\\\",
            super::tex_code_breakable(&doc.field),
            [
                values
                    .iter()
                    .map(|v| super::tex_code_breakable(v))
                    .collect::<Vec<_>>()
                    .join(" & "),
                format!("{} ({source})", super::tex(&doc.what)),
                super::tex(&doc.evidence),
            ]
            .join(" & ")
        );
    }
    s.push_str(LONGTABLE_FOOT);
    s
}

/// The end of a table that [`longtable_head`] began (and of the command around it).
const LONGTABLE_FOOT: &str = "\\bottomrule\n\\end{longtable}}}\n";

/// The start of a generated `longtable` in a command's body: ragged-right `p` columns of these
/// fractions of the text width (with the column gaps, at most the text width), narrower gaps
/// than LaTeX's, and `header` repeated on every page. Needs the `array` package.
fn longtable_head(widths: &[f64], header: &str) -> String {
    let columns: String = widths
        .iter()
        .map(|w| format!(">{{\\raggedright\\arraybackslash}}p{{{w}\\textwidth}}"))
        .collect();
    format!(
        "{{\\setlength{{\\tabcolsep}}{{4pt}}%\n\
         \\begin{{longtable}}{{@{{}}{columns}@{{}}}}\n\\toprule\n{header} \\\\\n\\midrule\n\\endhead\n"
    )
}

/// The settings table in Markdown (`docs/phase2.md`'s): the same rows as [`presets.tex`],
/// the texts without their math spans' dollars ([`super::plain`]).
pub fn settings_markdown(rows: &[(SettingDoc, Vec<String>)]) -> String {
    let mut s = String::from(
        "| setting | `paper` | `fast` | what it does | source | where its value comes from |\n\
         | --- | --- | --- | --- | --- | --- |\n",
    );
    for (doc, values) in rows {
        let source: &str = doc.source.into();
        let cells: Vec<String> = values.iter().map(|v| format!("`{v}`")).collect();
        let _ = writeln!(
            s,
            "| `{}` | {} | {} | {source} | {} |",
            doc.field,
            cells.join(" | "),
            super::plain(&doc.what).replace('|', "\\|"),
            super::plain(&doc.evidence).replace('|', "\\|"),
        );
    }
    s
}

/// One entry of `experiments/departures.toml`: where the `paper` preset departs from the
/// paper's text. Its texts mark formulas as math spans (`$d(s′, τ_T) ≤ ε$`, read by
/// [`super::tex`]).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Departure {
    /// Where in the paper (`Algorithm 2, loop bound`).
    pub place: String,
    /// What the paper writes.
    pub paper: String,
    /// What the code does.
    pub ours: String,
    /// Why.
    pub why: String,
    /// The experiment that measured the difference, or `no`.
    pub measured: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DeparturesFile {
    departure: Vec<Departure>,
}

/// Reads `experiments/departures.toml` (at least one entry; no empty text; balanced math spans,
/// [`super::check_math`]: an error names the entry and the field).
pub fn load_departures(path: &Path) -> Result<Vec<Departure>> {
    let file: DeparturesFile = crate::validate::read_toml(path)?;
    for (i, d) in file.departure.iter().enumerate() {
        for (name, text) in [
            ("place", &d.place),
            ("paper", &d.paper),
            ("ours", &d.ours),
            ("why", &d.why),
            ("measured", &d.measured),
        ] {
            if text.trim().is_empty() {
                return Err(Error::parse(
                    path,
                    format!("departure[{i}].{name} is empty"),
                ));
            }
            super::check_math(text).map_err(|e| {
                Error::parse(path, format!("departure[{i}] ({}), {name}: {e}", d.place))
            })?;
        }
    }
    Ok(file.departure)
}

/// `departures.tex`: the departures as a `longtable` (`\departurestable`).
pub fn departures_tex(departures: &[Departure]) -> String {
    let mut s = String::from(
        "% Generated by `pbcs figures` from experiments/departures.toml. Do not edit.\n\
         \\newcommand{\\departurestable}{%\n",
    );
    s.push_str(&longtable_head(
        &[0.14, 0.2, 0.22, 0.19, 0.175],
        "where & the paper & the code & why & measured",
    ));
    for d in departures {
        let _ = writeln!(
            s,
            "{} \\\\",
            [&d.place, &d.paper, &d.ours, &d.why, &d.measured]
                .iter()
                .map(|t| super::tex(t))
                .collect::<Vec<_>>()
                .join(" & ")
        );
    }
    s.push_str(LONGTABLE_FOOT);
    s
}
