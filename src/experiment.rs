//! Experiments as data: one TOML file per paper artifact, a grid of cells (maze × method)
//! run over a range of seeds, each (cell, seed) an independent deterministic run that writes
//! its own raw CSV row.
//!
//! An experiment file names a base config per method (a [`TrainJob`] for the vanilla
//! baselines, a [`RunJob`] for PBCS), the fields each method changes (`set`, and `by_maze`
//! for one size), the mazes, the seeds, and named profiles (`smoke` for CI, or any a user adds)
//! that override seeds, mazes and fields. Resolving a cell is
//! a deep merge of TOML tables in this order: base file ← method `set` ← the file's `by_maze`
//! table for the cell's maze size ← the profile's table for the method's kind ← the profile's
//! `by_maze`; then `maze.size` and `seed` are set (a profile overrides everything the file
//! sets). A profile may also add methods (`[[profile.<p>.method]]`). The merged table is
//! parsed with unknown keys denied, so a typo in an
//! experiment file is an error that names the method.
//!
//! ```
//! use pbcs::experiment::Experiment;
//!
//! let exp = Experiment::load(std::path::Path::new("experiments/table.toml"), Some("smoke"))
//!     .unwrap();
//! assert!(exp.cells.iter().any(|c| c.id == "pbcs-maze2"));
//! assert_eq!(exp.seeds(), vec![0]);
//! ```
//!
//! Raw results of a run of cell `c` with seed `s` live in `<results>/raw/<experiment>/<c>/`:
//! `s<s>.csv` (one [`RawRow`], written last, so its presence means the run finished),
//! `s<s>.toml` (the resolved job: `pbcs run --config` or `pbcs train --config` re-runs it),
//! `s<s>.timing.toml` (wall clock, not deterministic, hence beside the CSV), `s<s>.evals.csv`
//! (vanilla: the learning curve), `s<s>.evaluation.csv` (PBCS: each evaluation episode of the
//! chain, success and steps; rows committed before it existed lack it) and, for picture seeds, `s<s>.picture.csv` (what the figures
//! draw).

use crate::config::{RunJob, TrainJob};
use crate::error::{Error, Result};
use crate::nn::kernel::Kernel;
use crate::phase2::{Failure, StartMode};
use crate::runs::{PbcsRun, RunRecord, TrainRun, TrainSummary, Variant};
use crate::validate::Check;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// What a method runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Kind {
    /// A vanilla baseline on the maze's own reward ([`TrainJob`], `pbcs train`).
    Vanilla,
    /// PBCS, phase 1 then phase 2 ([`RunJob`], `pbcs run`).
    Pbcs,
}

impl Kind {
    fn name(self) -> &'static str {
        match self {
            Kind::Vanilla => "vanilla",
            Kind::Pbcs => "pbcs",
        }
    }
}

/// One method (a column of the results table, a bar of the γ study) as written in the file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct MethodSpec {
    name: String,
    #[serde(default)]
    label: Option<String>,
    kind: Kind,
    /// Base config, relative to the experiment file's folder.
    base: PathBuf,
    #[serde(default)]
    set: toml::Table,
    /// The paper's environment steps for this method, by maze size (as a string key).
    #[serde(default)]
    paper_steps: BTreeMap<String, u64>,
    /// Whether the paper's run solved the maze, by maze size.
    #[serde(default)]
    paper_solved: BTreeMap<String, bool>,
    /// The maze sizes this method runs, a subset of the experiment's (default: all of them):
    /// a grid whose rows ask different questions (the ablations) need not run every method
    /// on every size.
    #[serde(default)]
    mazes: Option<Vec<usize>>,
}

/// Fields set on every method of one kind: `vanilla = { … }` changes the [`TrainJob`]s,
/// `pbcs = { … }` the [`RunJob`]s.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct KindTables {
    #[serde(default)]
    vanilla: toml::Table,
    #[serde(default)]
    pbcs: toml::Table,
}

impl KindTables {
    /// The profile's table for `kind` (`vanilla = …` or `pbcs = …` in the profile).
    fn of_profile(prof: &ProfileSpec, kind: Kind) -> &toml::Table {
        match kind {
            Kind::Vanilla => &prof.vanilla,
            Kind::Pbcs => &prof.pbcs,
        }
    }

    fn of(&self, kind: Kind) -> &toml::Table {
        match kind {
            Kind::Vanilla => &self.vanilla,
            Kind::Pbcs => &self.pbcs,
        }
    }
}

/// A named profile: a smaller (`smoke`) or otherwise changed version of the same grid.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct ProfileSpec {
    #[serde(default)]
    description: String,
    seeds: Option<u64>,
    mazes: Option<Vec<usize>>,
    picture_seeds: Option<Vec<u64>>,
    #[serde(default)]
    vanilla: toml::Table,
    #[serde(default)]
    pbcs: toml::Table,
    /// Fields set on one maze size only (`[profile.<p>.by_maze."15"]`), after the rest.
    #[serde(default)]
    by_maze: BTreeMap<String, KindTables>,
    /// Methods this profile adds after the file's own (`[[profile.<p>.method]]`).
    #[serde(default, rename = "method")]
    methods: Vec<MethodSpec>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct ExperimentSpec {
    title: String,
    #[serde(default)]
    description: String,
    seeds: u64,
    #[serde(default)]
    first_seed: u64,
    #[serde(default = "default_picture_seeds")]
    picture_seeds: Vec<u64>,
    mazes: Vec<usize>,
    #[serde(rename = "method")]
    methods: Vec<MethodSpec>,
    /// Fields set on one maze size only (`[by_maze."15"]`, e.g. a budget per size), applied
    /// after the methods' own tables and before the profile's.
    #[serde(default)]
    by_maze: BTreeMap<String, KindTables>,
    #[serde(default, rename = "profile")]
    profiles: BTreeMap<String, ProfileSpec>,
    #[serde(default, rename = "figure")]
    figures: Vec<FigureSpec>,
    #[serde(default)]
    report: ReportSpec,
}

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
    pub pbcs: String,
    /// A vanilla method (budget, γ, episode length, learning starts).
    pub vanilla: String,
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
        method: String,
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
    /// The `methods`' pictures side by side, on the maze where the solved counts of the first
    /// two differ most (the smallest such maze on ties).
    Panels {
        /// File stem.
        name: String,
        /// The methods shown, in order (at least two).
        methods: Vec<String>,
    },
}

impl FigureSpec {
    /// The figure's file stem.
    pub fn name(&self) -> &str {
        match self {
            FigureSpec::Grid { name }
            | FigureSpec::Mazes { name, .. }
            | FigureSpec::Curves { name }
            | FigureSpec::Bars { name }
            | FigureSpec::Scaling { name }
            | FigureSpec::Chains { name }
            | FigureSpec::Profile { name }
            | FigureSpec::Panels { name, .. } => name,
        }
    }

    /// The methods the figure names.
    fn methods(&self) -> Vec<&str> {
        match self {
            FigureSpec::Mazes { method, .. } => vec![method.as_str()],
            FigureSpec::Panels { methods, .. } => methods.iter().map(String::as_str).collect(),
            _ => Vec::new(),
        }
    }
}

fn default_picture_seeds() -> Vec<u64> {
    vec![0]
}

/// Every declared figure has a file-name-safe, unique name and names only methods of the
/// experiment.
fn check_figures(path: &Path, figures: &[FigureSpec], methods: &[(String, String)]) -> Result<()> {
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
            if !methods.iter().any(|(n, _)| n == m) {
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
fn check_report(path: &Path, report: &ReportSpec, cells: &[Cell]) -> Result<()> {
    let Some(settings) = &report.settings else {
        return Ok(());
    };
    for (field, method, pbcs) in [
        ("pbcs", &settings.pbcs, true),
        ("vanilla", &settings.vanilla, false),
    ] {
        let ok = cells
            .iter()
            .any(|c| &c.method == method && matches!(c.job, Job::Pbcs(_)) == pbcs);
        if !ok {
            return Err(Error::invalid(
                format!("report.settings.{field} in {}", path.display()),
                format!("the experiment has no {field} method `{method}`"),
            ));
        }
    }
    Ok(())
}

/// A resolved job of either kind.
#[derive(Debug, Clone, PartialEq)]
pub enum Job {
    /// `pbcs train`.
    Vanilla(TrainJob),
    /// `pbcs run`.
    Pbcs(RunJob),
}

impl Job {
    /// The job with run seed `seed`.
    pub fn with_seed(&self, seed: u64) -> Job {
        match self {
            Job::Vanilla(j) => Job::Vanilla(TrainJob { seed, ..j.clone() }),
            Job::Pbcs(j) => Job::Pbcs(RunJob { seed, ..j.clone() }),
        }
    }

    /// The job as TOML (what `--config` reads back).
    pub fn to_toml(&self) -> String {
        match self {
            Job::Vanilla(j) => toml::to_string(j),
            Job::Pbcs(j) => toml::to_string(j),
        }
        .expect("jobs serialise to TOML")
    }

    /// Whether the stored TOML `text` describes this job (compared by value: fields absent
    /// from `text` take their defaults; unparseable text is another job).
    pub fn same_as(&self, text: &str) -> bool {
        match self {
            Job::Vanilla(j) => toml::from_str::<TrainJob>(text).is_ok_and(|s| &s == j),
            Job::Pbcs(j) => toml::from_str::<RunJob>(text).is_ok_and(|s| &s == j),
        }
    }

    fn check(&self) -> Result<()> {
        match self {
            Job::Vanilla(j) => j.check(),
            Job::Pbcs(j) => j.check(),
        }
    }
}

/// One cell of the grid: a method on a maze.
#[derive(Debug, Clone)]
pub struct Cell {
    /// `<method>-maze<N>`: the cell's folder name and its name on the command line.
    pub id: String,
    /// Method name.
    pub method: String,
    /// Method label for figures and tables.
    pub label: String,
    /// Maze size N.
    pub maze: usize,
    /// The resolved job (run seed 0; [`Job::with_seed`] gives the others).
    pub job: Job,
    /// The paper's environment steps for this cell, if it reports them.
    pub paper_steps: Option<u64>,
    /// Whether the paper's run solved this cell, if it reports it.
    pub paper_solved: Option<bool>,
}

/// A resolved experiment: every cell's job, the seeds, the profile.
#[derive(Debug, Clone)]
pub struct Experiment {
    /// The file stem (`table` for `experiments/table.toml`; for [`Experiment::of_job`], the
    /// name given): the name of its raw folder.
    pub name: String,
    /// Title, for tables and figures.
    pub title: String,
    /// What the experiment shows.
    pub description: String,
    /// The profile applied, if any.
    pub profile: Option<String>,
    /// First run seed.
    pub first_seed: u64,
    /// Number of seeds.
    pub seed_count: u64,
    /// Seeds whose runs also keep the picture data.
    pub picture_seeds: Vec<u64>,
    /// Maze sizes, in order.
    pub mazes: Vec<usize>,
    /// Methods (name, label), in order.
    pub methods: Vec<(String, String)>,
    /// Cells, maze-major in the file's order of mazes and methods.
    pub cells: Vec<Cell>,
    /// The figures it declares, in order.
    pub figures: Vec<FigureSpec>,
    /// What the report takes from it besides its table.
    pub report: ReportSpec,
}

/// A validation error with where it happened (`where_`) added to its reason.
fn located(e: Error, where_: &str) -> Error {
    match e {
        Error::Invalid { field, reason } => Error::Invalid {
            field,
            reason: format!("{reason} ({where_})"),
        },
        other => other,
    }
}

/// Maze sizes of a grid: at least one, each once.
fn check_mazes(mazes: &[usize]) -> Result<()> {
    if mazes.is_empty() {
        return Err(Error::invalid("mazes", "must name at least one maze size"));
    }
    if mazes.iter().collect::<BTreeSet<_>>().len() != mazes.len() {
        return Err(Error::invalid("mazes", "maze sizes must be unique"));
    }
    Ok(())
}

/// A method name is a folder name and part of cell ids: letters, digits and `_` only.
fn check_method_name(name: &str) -> Result<()> {
    if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Err(Error::invalid(
            "method.name",
            format!("`{name}`: use letters, digits and `_` only"),
        ));
    }
    Ok(())
}

/// Merges `from` into `into`: tables merge key by key, anything else replaces.
fn merge(into: &mut toml::Table, from: &toml::Table) {
    for (k, v) in from {
        match (into.get_mut(k), v) {
            (Some(toml::Value::Table(a)), toml::Value::Table(b)) => merge(a, b),
            _ => {
                into.insert(k.clone(), v.clone());
            }
        }
    }
}

impl Experiment {
    /// Reads and resolves an experiment file under `profile` (None: the committed grid).
    /// Every cell's job is validated; duplicate method names, an unknown profile, an empty
    /// grid and keys that a job does not have are errors naming the method or field.
    pub fn load(path: &Path, profile: Option<&str>) -> Result<Experiment> {
        let spec: ExperimentSpec = crate::validate::read_toml(path)?;
        let name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .ok_or_else(|| Error::parse(path, "no file name"))?;
        let folder = path.parent().unwrap_or(Path::new("."));
        let prof = match profile {
            None => ProfileSpec::default(),
            Some(p) => spec.profiles.get(p).cloned().ok_or_else(|| {
                Error::invalid(
                    "profile",
                    format!(
                        "{} has no profile `{p}` (it has: {})",
                        path.display(),
                        spec.profiles.keys().cloned().collect::<Vec<_>>().join(", ")
                    ),
                )
            })?,
        };
        let seed_count = prof.seeds.unwrap_or(spec.seeds);
        if seed_count == 0 {
            return Err(Error::invalid("seeds", "must be at least 1"));
        }
        let mazes = prof.mazes.clone().unwrap_or(spec.mazes.clone());
        check_mazes(&mazes)?;
        let all_methods: Vec<&MethodSpec> = spec.methods.iter().chain(&prof.methods).collect();
        if all_methods.is_empty() {
            return Err(Error::invalid("method", "an experiment needs a [[method]]"));
        }
        // The file's `by_maze` may name any size the file or one of its profiles runs (a
        // profile narrows the sizes); a profile's, only the sizes that profile runs.
        let mut file_mazes: BTreeSet<usize> = spec.mazes.iter().copied().collect();
        for p in spec.profiles.values() {
            file_mazes.extend(p.mazes.iter().flatten());
        }
        let file_mazes: Vec<usize> = file_mazes.into_iter().collect();
        for (field, by_maze, sizes) in [
            ("by_maze", &spec.by_maze, &file_mazes),
            ("profile.by_maze", &prof.by_maze, &mazes),
        ] {
            for key in by_maze.keys() {
                if !key.parse::<usize>().is_ok_and(|n| sizes.contains(&n)) {
                    return Err(Error::invalid(
                        format!("{field} in {}", path.display()),
                        format!("`{key}` is not one of the maze sizes {sizes:?}"),
                    ));
                }
            }
        }
        let mut names = BTreeSet::new();
        for m in all_methods.iter().copied() {
            check_method_name(&m.name)?;
            if !names.insert(m.name.clone()) {
                return Err(Error::invalid(
                    "method.name",
                    format!("`{}` appears twice", m.name),
                ));
            }
            if let Some(own) = &m.mazes {
                if own.is_empty() || own.iter().any(|n| !spec.mazes.contains(n)) {
                    return Err(Error::invalid(
                        "method.mazes",
                        format!(
                            "method `{}`: {own:?} must be a non-empty subset of `mazes` {:?}",
                            m.name, spec.mazes
                        ),
                    ));
                }
            }
            for key in m.paper_steps.keys().chain(m.paper_solved.keys()) {
                if !key.parse::<usize>().is_ok_and(|n| spec.mazes.contains(&n)) {
                    return Err(Error::invalid(
                        "method.paper_steps",
                        format!("method `{}`: `{key}` is not one of `mazes`", m.name),
                    ));
                }
            }
        }
        // Merge each method's tables once, then resolve each cell.
        let mut methods = Vec::new();
        let mut cells = Vec::new();
        let mut resolved = Vec::new();
        for m in all_methods.iter().copied() {
            let base_path = folder.join(&m.base);
            let mut table: toml::Table = crate::validate::read_toml(&base_path)?;
            merge(&mut table, &m.set);
            let label = m.label.clone().unwrap_or_else(|| m.name.clone());
            methods.push((m.name.clone(), label.clone()));
            resolved.push((m, label, table));
        }
        for &n in &mazes {
            let key = n.to_string();
            for (m, label, table) in &resolved {
                if m.mazes.as_ref().is_some_and(|own| !own.contains(&n)) {
                    continue;
                }
                let mut table = table.clone();
                if let Some(t) = spec.by_maze.get(&key) {
                    merge(&mut table, t.of(m.kind));
                }
                merge(&mut table, KindTables::of_profile(&prof, m.kind));
                if let Some(t) = prof.by_maze.get(&key) {
                    merge(&mut table, t.of(m.kind));
                }
                let what = |e: toml::de::Error| {
                    Error::parse(
                        path,
                        format!("method `{}` ({} job, maze {n}): {e}", m.name, m.kind.name()),
                    )
                };
                let job = match m.kind {
                    Kind::Vanilla => {
                        let mut j: TrainJob = toml::Value::Table(table).try_into().map_err(what)?;
                        j.maze.size = n;
                        j.seed = 0;
                        Job::Vanilla(j)
                    }
                    Kind::Pbcs => {
                        let mut j: RunJob = toml::Value::Table(table).try_into().map_err(what)?;
                        j.maze.size = n;
                        j.seed = 0;
                        Job::Pbcs(j)
                    }
                };
                job.check()
                    .map_err(|e| located(e, &format!("method `{}`, maze {n}", m.name)))?;
                cells.push(Cell {
                    id: format!("{}-maze{n}", m.name),
                    method: m.name.clone(),
                    label: label.clone(),
                    maze: n,
                    job,
                    paper_steps: m.paper_steps.get(&n.to_string()).copied(),
                    paper_solved: m.paper_solved.get(&n.to_string()).copied(),
                });
            }
        }
        check_figures(path, &spec.figures, &methods)?;
        check_report(path, &spec.report, &cells)?;
        Ok(Experiment {
            title: spec.title,
            description: if prof.description.is_empty() {
                spec.description
            } else {
                format!("{} ({})", spec.description, prof.description)
            },
            profile: profile.map(String::from),
            first_seed: spec.first_seed,
            seed_count,
            picture_seeds: prof.picture_seeds.unwrap_or(spec.picture_seeds),
            report: spec.report,
            figures: if spec.figures.is_empty() {
                vec![FigureSpec::Bars { name: name.clone() }]
            } else {
                spec.figures
            },
            name,
            mazes,
            methods,
            cells,
        })
    }

    /// An experiment of one PBCS method `name` (letters, digits, `_`) run as `job` on each of
    /// `sizes` with seeds `0..seeds`, built from a job instead of a file: what `pbcs table`
    /// sweeps (into `<results>/raw/<name>/<name>-maze<N>/`, in the order of `sizes`). Each
    /// cell carries the paper's run of the same variant (with or without chaining) on its size
    /// ([`crate::runs::paper_figures`]); seed 0 keeps its picture.
    ///
    /// ```
    /// use pbcs::experiment::Experiment;
    /// let exp = Experiment::of_job("mine", &pbcs::config::RunJob::default(), &[2, 5], 3).unwrap();
    /// assert_eq!(exp.cells[1].id, "mine-maze5");
    /// assert_eq!(exp.seeds(), vec![0, 1, 2]);
    /// assert!(Experiment::of_job("mine", &Default::default(), &[2, 2], 3).is_err());
    /// ```
    pub fn of_job(name: &str, job: &RunJob, sizes: &[usize], seeds: u64) -> Result<Experiment> {
        check_method_name(name)?;
        check_mazes(sizes)?;
        if seeds == 0 {
            return Err(Error::invalid("seeds", "must be at least 1"));
        }
        let cells = sizes
            .iter()
            .map(|&n| {
                let mut j = job.clone();
                j.maze.size = n;
                j.seed = 0;
                j.check().map_err(|e| located(e, &format!("maze {n}")))?;
                let variant = if job.phase2.chaining {
                    Variant::Pbcs
                } else {
                    Variant::PbcsNoChaining
                };
                let (paper_steps, paper_solved) = crate::runs::paper_figures(variant, n);
                Ok(Cell {
                    id: format!("{name}-maze{n}"),
                    method: name.to_string(),
                    label: name.to_string(),
                    maze: n,
                    job: Job::Pbcs(j),
                    paper_steps,
                    paper_solved,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Experiment {
            name: name.to_string(),
            title: format!("PBCS ({name}) on mazes {sizes:?}"),
            description: String::new(),
            profile: None,
            first_seed: 0,
            seed_count: seeds,
            picture_seeds: default_picture_seeds(),
            mazes: sizes.to_vec(),
            methods: vec![(name.to_string(), name.to_string())],
            cells,
            figures: vec![FigureSpec::Bars {
                name: name.to_string(),
            }],
            report: ReportSpec::default(),
        })
    }

    /// The run seeds, in order.
    pub fn seeds(&self) -> Vec<u64> {
        (self.first_seed..self.first_seed + self.seed_count).collect()
    }

    /// The cell called `id`, or an error listing the cells.
    pub fn cell(&self, id: &str) -> Result<&Cell> {
        self.cells.iter().find(|c| c.id == id).ok_or_else(|| {
            Error::invalid(
                "cell",
                format!(
                    "experiment `{}` has no cell `{id}` (it has: {})",
                    self.name,
                    self.cells
                        .iter()
                        .map(|c| c.id.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            )
        })
    }

    /// The folder of a cell's raw results under `results`.
    pub fn cell_dir(&self, results: &Path, cell: &Cell) -> PathBuf {
        results.join("raw").join(&self.name).join(&cell.id)
    }
}

/// One run's raw result: the row every table and figure is computed from. Vanilla and PBCS
/// runs share the columns; a column that does not apply holds 0 or is empty.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RawRow {
    /// Experiment name.
    pub experiment: String,
    /// Cell id (`<method>-maze<N>`).
    pub cell: String,
    /// Method name.
    pub method: String,
    /// `vanilla` or `pbcs`.
    pub kind: Kind,
    /// Maze size N.
    pub maze: usize,
    /// Maze layout seed.
    pub maze_seed: u64,
    /// Run seed.
    pub seed: u64,
    /// [`crate::learner::LearnerConfig::record_name`]: `ddpg`, `td3`, with `_am` for the
    /// argmax actor.
    pub learner: String,
    /// γ.
    pub gamma: f32,
    /// PBCS: whether skill chaining was on.
    pub chaining: bool,
    /// PBCS: `ball` or `exact` starts; empty for vanilla.
    pub starts: Option<StartMode>,
    /// Solved: PBCS, the chain reaches the target in ≥ 95 % of the evaluation episodes;
    /// vanilla, the final greedy evaluation does.
    pub solved: bool,
    /// Success rate of that evaluation.
    pub success_rate: f32,
    /// Environment steps used (PBCS: phase 1 + training + tests; vanilla: the budget).
    pub env_steps: u64,
    /// The step budget of the run (PBCS: `phase2.max_env_steps`; vanilla: `train.steps`).
    pub budget: u64,
    /// Vanilla: environment steps at the first successful greedy evaluation, if any.
    pub first_success_steps: Option<u64>,
    /// PBCS: steps of phase 1.
    pub phase1_steps: u64,
    /// PBCS: steps of phase-2 training episodes.
    pub train_steps: u64,
    /// PBCS: steps of Backplay's tests.
    pub test_steps: u64,
    /// PBCS: skills in the chain.
    pub skills: usize,
    /// PBCS: why phase 2 stopped early (`backplay_failed`, `no_chaining`, `budget`), or empty.
    pub failure: Option<Failure>,
}

impl RawRow {
    /// The row of a vanilla run of `cell` (`job` with its seed): its summary, under the
    /// cell's names; the PBCS columns hold 0 or are empty.
    pub fn vanilla(exp: &Experiment, cell: &Cell, job: &TrainJob, s: &TrainSummary) -> RawRow {
        RawRow {
            experiment: exp.name.clone(),
            cell: cell.id.clone(),
            method: cell.method.clone(),
            kind: Kind::Vanilla,
            maze: s.maze,
            maze_seed: s.maze_seed,
            seed: job.seed,
            learner: job.learner.record_name(),
            gamma: job.learner.gamma,
            chaining: false,
            starts: None,
            solved: s.final_success >= crate::runs::SOLVED_AT,
            success_rate: s.final_success,
            env_steps: s.env_steps,
            budget: job.train.steps,
            first_success_steps: s.first_success_steps,
            phase1_steps: 0,
            train_steps: 0,
            test_steps: 0,
            skills: 0,
            failure: None,
        }
    }

    /// The row of a PBCS run of `cell` (`job` with its seed): its [`RunRecord`] (what `pbcs
    /// run` writes to `record.csv`) under the cell's names, `env_steps` its `total_steps`;
    /// the record's τ lengths and ε are left to the job file.
    pub fn pbcs(exp: &Experiment, cell: &Cell, job: &RunJob, r: RunRecord) -> RawRow {
        RawRow {
            experiment: exp.name.clone(),
            cell: cell.id.clone(),
            method: cell.method.clone(),
            kind: Kind::Pbcs,
            maze: r.maze,
            maze_seed: r.maze_seed,
            seed: r.seed,
            learner: r.learner,
            gamma: r.gamma,
            chaining: job.phase2.chaining,
            starts: Some(r.starts),
            solved: r.solved,
            success_rate: r.success_rate,
            env_steps: r.total_steps,
            budget: job.phase2.max_env_steps,
            first_success_steps: None,
            phase1_steps: r.phase1_steps,
            train_steps: r.train_steps,
            test_steps: r.test_steps,
            skills: r.skills,
            failure: r.failure,
        }
    }
}

/// Raw file names of one run.
fn run_file(dir: &Path, seed: u64, suffix: &str) -> PathBuf {
    dir.join(format!("s{seed}{suffix}"))
}

/// Runs (cell, seed) and writes its raw files into `dir` (the CSV row last): the run is
/// computed without writing anything ([`TrainRun::compute`], [`PbcsRun::compute`]), then only
/// the raw files the tables and figures need are written: `s<seed>.timing.toml`,
/// `s<seed>.evals.csv` (vanilla), `s<seed>.evaluation.csv` (PBCS), `s<seed>.picture.csv` (picture seeds), `s<seed>.toml` (the
/// job) and `s<seed>.csv` (the row). The learners run on `kernel`.
pub fn run_cell_seed(
    exp: &Experiment,
    cell: &Cell,
    seed: u64,
    dir: &Path,
    kernel: Kernel,
) -> Result<RawRow> {
    let job = cell.job.with_seed(seed);
    let (row, seconds, picture) = match &job {
        Job::Vanilla(j) => {
            let run = TrainRun::compute(j, kernel, |_, _| {})?;
            crate::record::write_records(&run_file(dir, seed, ".evals.csv"), &run.result.evals)?;
            let row = RawRow::vanilla(exp, cell, j, &run.summary);
            (row, run.seconds, run.picture)
        }
        Job::Pbcs(j) => {
            let run = PbcsRun::compute(j, kernel, |_, _| {})?;
            crate::record::write_records(&run_file(dir, seed, ".evaluation.csv"), &run.evaluation)?;
            let row = RawRow::pbcs(exp, cell, j, run.record);
            (row, run.seconds, run.picture)
        }
    };
    crate::runs::write_timing(
        &run_file(dir, seed, ".timing.toml"),
        seconds,
        row.env_steps,
        Some(kernel),
    )?;
    if exp.picture_seeds.contains(&seed) {
        picture.write_csv(&run_file(dir, seed, ".picture.csv"))?;
    }
    let config = job.to_toml();
    crate::record::write_atomic(&run_file(dir, seed, ".toml"), |w| {
        w.write_all(config.as_bytes())
    })?;
    crate::record::write_record(&run_file(dir, seed, ".csv"), &row)?;
    Ok(row)
}

/// The finished raw row of (cell, seed) in `dir`, if there is one. A finished run of another
/// config is an error: results of two configs are never mixed. Configs are compared by value,
/// so a setting added later, absent from an older stored config, takes its default (the
/// behaviour the older run had).
pub fn read_finished(cell: &Cell, seed: u64, dir: &Path) -> Result<Option<RawRow>> {
    let path = run_file(dir, seed, ".csv");
    if !path.exists() {
        return Ok(None);
    }
    let config_path = run_file(dir, seed, ".toml");
    let stored = std::fs::read_to_string(&config_path).map_err(|e| Error::io(&config_path, e))?;
    if !cell.job.with_seed(seed).same_as(&stored) {
        return Err(Error::parse(
            &config_path,
            "this finished run used another config than the experiment now gives (its file, or \
             `pbcs table`'s preset or config); remove the cell's folder to re-run it, restore \
             the file, or choose another results folder (--results, --out)",
        ));
    }
    read_row(&path).map(Some)
}

/// Reads one raw row file.
pub fn read_row(path: &Path) -> Result<RawRow> {
    let mut reader = csv::Reader::from_path(path).map_err(|e| Error::csv(path, e))?;
    reader
        .deserialize()
        .next()
        .ok_or_else(|| Error::parse(path, "empty raw row file"))?
        .map_err(|e| Error::csv(path, e))
}

/// Wall seconds of a finished run, from its timing file (None if absent or unreadable).
pub fn read_wall_seconds(exp: &Experiment, results: &Path, cell: &Cell, seed: u64) -> Option<f64> {
    let path = run_file(&exp.cell_dir(results, cell), seed, ".timing.toml");
    crate::record::Timing::read(&path)
        .ok()
        .flatten()
        .map(|t| t.wall_seconds)
}

/// Path of the picture data of (cell, seed), if it was kept.
pub fn picture_file(exp: &Experiment, results: &Path, cell: &Cell, seed: u64) -> PathBuf {
    run_file(&exp.cell_dir(results, cell), seed, ".picture.csv")
}

/// Path of the learning curve of a vanilla (cell, seed).
pub fn evals_file(exp: &Experiment, results: &Path, cell: &Cell, seed: u64) -> PathBuf {
    run_file(&exp.cell_dir(results, cell), seed, ".evals.csv")
}

/// A (cell, seed) pair of a sweep.
#[derive(Debug, Clone)]
pub struct Pending<'a> {
    /// The cell.
    pub cell: &'a Cell,
    /// The run seed.
    pub seed: u64,
}

/// What happened to one (cell, seed) of a sweep.
#[derive(Debug, Clone)]
pub enum Event {
    /// It was already finished and was read back.
    Skipped(RawRow),
    /// It ran now, in this many wall seconds.
    Ran(RawRow, f64),
}

/// Runs every (cell, seed) of `runs` that is not finished under `results`, `jobs` at a time
/// (one thread each; each run is single-threaded and deterministic, so the bytes do not
/// depend on `jobs`), every learner on `kernel`. `on_event` is called as each pair finishes.
/// Returns the rows in the order of `runs`; the first error stops handing out new runs and is
/// returned.
pub fn sweep(
    exp: &Experiment,
    runs: &[Pending],
    results: &Path,
    jobs: usize,
    kernel: Kernel,
    on_event: impl Fn(&Pending, &Event) + Sync,
) -> Result<Vec<RawRow>> {
    // Finished runs first (cheap), so that a config mismatch is reported before any work.
    let mut rows: Vec<Option<RawRow>> = Vec::with_capacity(runs.len());
    for p in runs {
        let dir = exp.cell_dir(results, p.cell);
        let done = read_finished(p.cell, p.seed, &dir)?;
        if let Some(r) = &done {
            on_event(p, &Event::Skipped(r.clone()));
        }
        rows.push(done);
    }
    let todo: Vec<usize> = (0..runs.len()).filter(|&i| rows[i].is_none()).collect();
    let ran = run_parallel(&todo, jobs, |&i| {
        let p = &runs[i];
        let clock = std::time::Instant::now();
        let dir = exp.cell_dir(results, p.cell);
        // One process per run: a second sweep into this folder stops here with a message
        // instead of doing the run again and replacing its row.
        let row = crate::record::WorkLock::acquire(&run_file(&dir, p.seed, ".lock"))
            .and_then(|_lock| {
                // Finished by another sweep while this one was planning: read it back.
                match read_finished(p.cell, p.seed, &dir)? {
                    Some(row) => Ok(row),
                    None => run_cell_seed(exp, p.cell, p.seed, &dir, kernel),
                }
            })
            .map_err(|e| Error::Run {
                cell: p.cell.id.clone(),
                seed: p.seed,
                cause: Box::new(e),
            })?;
        on_event(p, &Event::Ran(row.clone(), clock.elapsed().as_secs_f64()));
        Ok(row)
    })?;
    for (i, row) in todo.into_iter().zip(ran) {
        rows[i] = Some(row);
    }
    Ok(rows.into_iter().flatten().collect())
}

/// `f` on every item, `jobs` at a time (a pool of `jobs` threads), the results in the items'
/// order. Items start in their order (each free thread takes the next one), so an interrupted
/// sweep has finished a prefix of its plan: with the table's plan, whole mazes, smallest first.
/// After the first error no new item starts, and that error is returned. Every run is
/// single-threaded and seeded by its own job, so `jobs` changes the wall clock, never a byte.
pub fn run_parallel<T: Sync, R: Send>(
    items: &[T],
    jobs: usize,
    f: impl Fn(&T) -> Result<R> + Sync,
) -> Result<Vec<R>> {
    use rayon::prelude::*;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs.max(1))
        .build()
        .map_err(|e| Error::invalid("jobs", e.to_string()))?;
    let mut done: Vec<(usize, R)> = pool.install(|| {
        items
            .iter()
            .enumerate()
            .par_bridge()
            .map(|(i, item)| f(item).map(|r| (i, r)))
            .collect::<Result<_>>()
    })?;
    done.sort_by_key(|(i, _)| *i);
    Ok(done.into_iter().map(|(_, r)| r).collect())
}

/// Every (cell, seed) of the experiment, or of one cell, or one seed.
pub fn plan<'a>(
    exp: &'a Experiment,
    cell: Option<&str>,
    seed: Option<u64>,
) -> Result<Vec<Pending<'a>>> {
    let cells: Vec<&Cell> = match cell {
        Some(id) => vec![exp.cell(id)?],
        None => exp.cells.iter().collect(),
    };
    let seeds = match seed {
        Some(s) => {
            if !exp.seeds().contains(&s) {
                return Err(Error::invalid(
                    "seed",
                    format!(
                        "{s} is outside the experiment's seeds {}..{}",
                        exp.first_seed,
                        exp.first_seed + exp.seed_count
                    ),
                ));
            }
            vec![s]
        }
        None => exp.seeds(),
    };
    Ok(cells
        .into_iter()
        .flat_map(|c| seeds.iter().map(move |&s| Pending { cell: c, seed: s }))
        .collect())
}

/// All finished raw rows of the experiment under `results`, in (cell, seed) order; missing
/// runs are left out (and counted by the caller through `n`).
pub fn read_raw(exp: &Experiment, results: &Path) -> Result<Vec<RawRow>> {
    let mut rows = Vec::new();
    for p in plan(exp, None, None)? {
        if let Some(r) = read_finished(p.cell, p.seed, &exp.cell_dir(results, p.cell))? {
            rows.push(r);
        }
    }
    Ok(rows)
}

/// The experiment files under `dir` (every `*.toml` with a `[[method]]`), sorted.
pub fn experiment_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let path = entry.map_err(|e| Error::io(dir, e))?.path();
        if path.extension().is_some_and(|e| e == "toml") {
            let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
            if text.lines().any(|l| l.trim() == "[[method]]") {
                files.push(path);
            }
        }
    }
    files.sort();
    Ok(files)
}
