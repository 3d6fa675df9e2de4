//! What an experiment file declares besides its grid: the figures drawn from its tables
//! (`[[figure]]`) and what the report's generated LaTeX takes from it (`[report]`), with the
//! checks that tie both to the experiment's methods.

use super::{Cell, ExperimentName, Job, Method};
use crate::error::{Error, Result};
use serde::Deserialize;
use std::collections::BTreeSet;
use std::path::Path;

/// What the report's generated LaTeX takes from an experiment besides its per-cell table
/// (`[report]` in its file).
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReportSpec {
    /// Write `table.tex`: the results table (mazes × methods, the paper's figures below).
    #[serde(default)]
    pub results_table: bool,
    /// Write `settings.tex`: the settings of these methods' jobs on the first maze, quoted by
    /// the report instead of retyped.
    #[serde(default)]
    pub settings: Option<SettingsSpec>,
}

/// The methods whose settings `settings.tex` quotes.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SettingsSpec {
    /// A PBCS method (phase 2 and learner settings).
    pub pbcs: Method,
    /// A vanilla method (budget, γ, episode length, learning starts).
    pub vanilla: Method,
}

/// A baseline bar: `method` of the experiment `experiment`, drawn as `label`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Baseline {
    /// The experiment whose table holds it (e.g. `table`).
    pub experiment: ExperimentName,
    /// Its method there (e.g. `pbcs`).
    pub method: Method,
    /// Its label in the figure.
    pub label: String,
}

/// A figure an experiment declares (`[[figure]]` in its file, `kind` naming the variant);
/// `pbcs figures` draws each into `<name>.png` and `<name>.svg`. An experiment that declares
/// none gets one [`FigureSpec::Bars`] named after it.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum FigureSpec {
    /// The results table as a grid of pictures: rows = mazes, columns = methods.
    Grid {
        /// File stem.
        name: String,
    },
    /// One enlarged picture per maze of `method`'s first picture seed: `<name><N>`.
    Mazes {
        /// File stem, followed by the maze size.
        name: String,
        /// The method drawn.
        method: Method,
    },
    /// Learning curves of the experiment's vanilla methods (drawn only if it has some).
    Curves {
        /// File stem.
        name: String,
    },
    /// Success rate per maze and method with Wilson 95 % error bars.
    Bars {
        /// File stem.
        name: String,
        /// Methods of other experiments drawn first, in this order: the baselines the
        /// experiment's methods change one thing of (their cells on this experiment's mazes,
        /// from those experiments' tables).
        #[serde(default)]
        baselines: Vec<Baseline>,
    },
    /// Environment steps (median, quartiles) of each cell against the length of its maze's
    /// shortest path from start to target, on log–log axes, one colour per method, with the
    /// power law fitted to the cells' medians: does the cost grow like the path?
    Scaling {
        /// File stem.
        name: String,
    },
    /// Each PBCS run's chain success (evaluation episodes from B_ε(s_0) that reached the
    /// target), one column per cell, the 95 % line of "solved" drawn across: how the table
    /// reads under other success criteria (`<experiment>.chains.csv`).
    Chains {
        /// File stem.
        name: String,
    },
    /// The performance profile of each PBCS method: the fraction of its runs solved within
    /// x times the paper's steps for the maze, x on a log axis (`<experiment>.chains.csv`).
    Profile {
        /// File stem.
        name: String,
    },
    /// Each PBCS run's path (the chain's, and τ's) divided by the fewest steps from s_0
    /// (`<experiment>.routes.csv`).
    Routes {
        /// File stem.
        name: String,
    },
    /// The `methods`' pictures side by side, on the maze where the solved counts of the first
    /// two differ most (the smallest such maze on ties).
    Panels {
        /// File stem.
        name: String,
        /// The methods shown, in order (at least two).
        methods: Vec<Method>,
    },
}

impl FigureSpec {
    /// The figure's file stem.
    pub fn name(&self) -> &str {
        match self {
            FigureSpec::Grid { name }
            | FigureSpec::Mazes { name, .. }
            | FigureSpec::Curves { name }
            | FigureSpec::Bars { name, .. }
            | FigureSpec::Scaling { name }
            | FigureSpec::Chains { name }
            | FigureSpec::Profile { name }
            | FigureSpec::Routes { name }
            | FigureSpec::Panels { name, .. } => name,
        }
    }

    /// The methods the figure names.
    fn methods(&self) -> Vec<Method> {
        match self {
            FigureSpec::Mazes { method, .. } => vec![*method],
            FigureSpec::Panels { methods, .. } => methods.clone(),
            _ => Vec::new(),
        }
    }
}

/// The methods a registered paired comparison names (`[registered] paired`): two different
/// methods of the file.
pub(crate) fn check_paired(
    path: &Path,
    registered: Option<&super::Registration>,
    methods: &[(Method, String)],
) -> Result<()> {
    let Some([baseline, variant]) = registered.and_then(|r| r.paired.as_ref()) else {
        return Ok(());
    };
    let field = format!("registered.paired in {}", path.display());
    let from = registered.and_then(|r| r.baseline_from);
    if let Some(from) = from {
        let file = path.with_file_name(format!("{from}.toml"));
        if path.file_stem().and_then(|s| s.to_str()) == Some(from.as_str()) || !file.is_file() {
            return Err(Error::invalid(
                format!("registered.baseline_from in {}", path.display()),
                format!(
                    "`{from}` is not another experiment file of the folder ({})",
                    file.display()
                ),
            ));
        }
    } else if baseline == variant {
        return Err(Error::invalid(field, format!("names `{baseline}` twice")));
    }
    // The baseline of another file is checked against that file's methods when the rows are
    // paired ([`crate::pipeline::aggregate`]).
    let own = if from.is_some() {
        vec![variant]
    } else {
        vec![baseline, variant]
    };
    match own
        .into_iter()
        .find(|m| !methods.iter().any(|(n, _)| n == *m))
    {
        Some(m) => Err(Error::invalid(
            field,
            format!("`{m}` is not a method of the file"),
        )),
        None => Ok(()),
    }
}

/// Every declared figure has a file-name-safe, unique name and names only methods of the
/// experiment.
pub(crate) fn check_figures(
    path: &Path,
    figures: &[FigureSpec],
    methods: &[(Method, String)],
) -> Result<()> {
    let mut names = BTreeSet::new();
    for (i, f) in figures.iter().enumerate() {
        let field = |what: &str| format!("figure[{i}].{what} in {}", path.display());
        let name = f.name();
        if name.is_empty()
            || !name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-')
        {
            return Err(Error::invalid(
                field("name"),
                format!("must be letters, digits, `_` or `-`, got `{name}`"),
            ));
        }
        if !names.insert(name) {
            return Err(Error::invalid(
                field("name"),
                format!("`{name}` is used twice"),
            ));
        }
        for m in f.methods() {
            if !methods.iter().any(|(n, _)| *n == m) {
                return Err(Error::invalid(
                    field("method"),
                    format!("the experiment has no method `{m}`"),
                ));
            }
        }
        if let FigureSpec::Panels { methods: ms, .. } = f {
            if ms.len() < 2 {
                return Err(Error::invalid(
                    field("methods"),
                    "needs at least two methods",
                ));
            }
        }
    }
    Ok(())
}

/// The methods `[report].settings` names exist and are of the kind it says.
pub(crate) fn check_report(path: &Path, report: &ReportSpec, cells: &[Cell]) -> Result<()> {
    let Some(settings) = &report.settings else {
        return Ok(());
    };
    for (field, method, pbcs) in [
        ("pbcs", &settings.pbcs, true),
        ("vanilla", &settings.vanilla, false),
    ] {
        let ok = cells
            .iter()
            .any(|c| c.method == *method && matches!(c.job, Job::Pbcs(_)) == pbcs);
        if !ok {
            return Err(Error::invalid(
                format!("report.settings.{field} in {}", path.display()),
                format!("the experiment has no {field} method `{method}`"),
            ));
        }
    }
    Ok(())
}

/// A registered grid runs its registered preset: some method's base is that file, and every
/// method of the same kind runs on it (a method of another kind, the baselines beside PBCS, may
/// have its own base). Else the registration's hash would vouch for a file the grid does not
/// run. `methods`: each method's (name, kind, base file as written).
pub(crate) fn check_registered_base(
    path: &Path,
    registered: Option<&super::Registration>,
    methods: &[(&str, super::Kind, &Path)],
) -> Result<()> {
    let Some(r) = registered else { return Ok(()) };
    let preset = Path::new(&r.preset);
    let Some(&(_, kind, _)) = methods.iter().find(|(_, _, base)| *base == preset) else {
        return Err(Error::parse(
            path,
            format!(
                "registered.preset: {} is the base of no method: the grid would not run the \
                 preset its registration covers",
                r.preset
            ),
        ));
    };
    if let Some((name, _, base)) = methods.iter().find(|(_, k, b)| *k == kind && *b != preset) {
        return Err(Error::parse(
            path,
            format!(
                "method `{name}`: runs on {}, but the grid is registered for {}, the base of \
                 its other methods of that kind",
                base.display(),
                r.preset
            ),
        ));
    }
    Ok(())
}
