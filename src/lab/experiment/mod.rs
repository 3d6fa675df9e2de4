//! Experiments as data: one TOML file per paper artifact, a grid of cells (site × method: a
//! [`Site`] is a maze size or another environment of the registry) run over a range of
//! seeds, each (cell, seed) an independent deterministic run that writes its own raw CSV row.
//!
//! An experiment file names a base config per method (a [`TrainJob`] for the vanilla
//! baselines, a [`PbcsJob`] for PBCS), the fields each method changes (`set`, and `by_maze`
//! for one size or environment), the mazes and other environments (`envs = ["rooms"]`), the
//! seeds, and named profiles (`smoke` for CI, or any a user adds)
//! that override seeds, mazes and fields. Resolving a cell is
//! a deep merge of TOML tables in this order: base file ← method `set` ← the file's `by_maze`
//! table for the cell's maze size ← the profile's table for the method's kind ← the profile's
//! `by_maze`; then `maze.size` (or `env`) and `seed` are set (a profile overrides everything
//! the file sets). A `learner.algo` of another learner family than the table's so far (`sac`
//! over the presets' `ddpg`) starts the learner table afresh: `set = { learner.algo = "sac" }`
//! is SAC with its own defaults, never SAC with TD3's noise settings. A profile may also add
//! methods (`[[profile.<p>.method]]`). The merged table is
//! parsed with unknown keys denied, so a typo in an
//! experiment file is an error that names the method.
//!
//! ```
//! use pbcs::experiment::Experiment;
//!
//! let exp = Experiment::load(std::path::Path::new("experiments/table.toml"), Some("smoke"))
//!     .unwrap();
//! assert!(exp.cells.iter().any(|c| c.id == "pbcs-maze2".parse().unwrap()));
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

mod declared;
mod key;
mod layout;
mod legacy;
mod merge;
mod plan;
mod progress;
mod read_row;
mod row;
mod site;
mod spec;
mod sweep;

pub use declared::{Baseline, FigureSpec, ReportSpec, SettingsSpec};
pub use key::{CellKey, ExperimentName, Method};
pub use layout::run_file;
pub use layout::{evals_file, evaluation_file, experiment_files, picture_file, read_wall_seconds};
pub use plan::{plan, Pending};
pub use progress::SweepProgress;
pub use read_row::{read_finished, read_raw, read_row, read_run_row};
pub use row::{KindRow, PbcsRow, RawRow, VanillaRow};
pub use site::{paper_run, Site};
pub use sweep::{checkpoint, run_cell_seed, run_parallel, sweep, sweep_until, Event, Swept};

use crate::config::{PbcsJob, TrainJob};
use crate::error::{Error, Result};
use crate::validate::Check;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// What a method runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, strum::IntoStaticStr)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum Kind {
    /// A vanilla baseline on the maze's own reward ([`TrainJob`], `pbcs train`).
    Vanilla,
    /// PBCS, phase 1 then phase 2 ([`PbcsJob`], `pbcs run`).
    Pbcs,
}

impl Kind {
    fn name(self) -> &'static str {
        self.into()
    }
}

/// A resolved job of either kind.
#[derive(Debug, Clone, PartialEq)]
pub enum Job {
    /// `pbcs train`.
    Vanilla(TrainJob),
    /// `pbcs run`.
    Pbcs(PbcsJob),
}

impl Job {
    /// The job with run seed `seed`.
    pub fn with_seed(&self, seed: u64) -> Job {
        match self {
            Job::Vanilla(j) => Job::Vanilla(TrainJob { seed, ..j.clone() }),
            Job::Pbcs(j) => Job::Pbcs(PbcsJob { seed, ..j.clone() }),
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
            Job::Pbcs(j) => toml::from_str::<PbcsJob>(text).is_ok_and(|s| &s == j),
        }
    }

    fn check(&self) -> Result<()> {
        match self {
            Job::Vanilla(j) => j.check(),
            Job::Pbcs(j) => j.check(),
        }
    }
}

/// One cell of the grid: a method on a site.
#[derive(Debug, Clone)]
pub struct Cell {
    /// `<method>-<site id>` (`pbcs-maze5`, `pbcs-rooms`): the cell's folder name and its name
    /// on the command line.
    pub id: CellKey,
    /// Its method (`id.method`).
    pub method: Method,
    /// Method label for figures and tables.
    pub label: String,
    /// Where it runs: a maze size or another environment.
    pub site: Site,
    /// The resolved job (run seed 0; [`Job::with_seed`] gives the others).
    pub job: Job,
    /// The paper's environment steps for this cell, if it reports them.
    pub paper_steps: Option<u64>,
    /// Whether the paper's run solved this cell, if it reports it.
    pub paper_solved: Option<bool>,
}

impl Cell {
    /// What a picture of the cell draws its runs over: its environment's scene.
    pub fn scene(&self) -> Result<crate::env::Scene> {
        use crate::config::Located;
        match &self.job {
            Job::Vanilla(j) => j.env_spec().scene(),
            Job::Pbcs(j) => j.env_spec().scene(),
        }
    }
}

/// The most seeds a cell runs: each is a run of seconds to hours, so more is a typo (and the
/// plan lists every run in memory).
pub const MAX_SEEDS: u64 = 100_000;

/// A grid's seeds `first_seed`, …, `first_seed + count − 1` (`field` names the count): 1 to
/// [`MAX_SEEDS`] of them, the last one a `u64`, and each of `pictures` (the `picture_seeds`
/// the same file gives) among them, so that no picture is asked for and silently not drawn.
///
/// ```
/// use pbcs::experiment::check_seeds;
/// assert!(check_seeds("seeds", 0, 10, &[0]).is_ok());
/// assert!(check_seeds("seeds", u64::MAX, 1, &[]).is_ok()); // the largest seed, alone
/// for (first, count, pictures) in [(0, 0, vec![]), (0, u64::MAX, vec![]), (u64::MAX, 2, vec![]), (0, 2, vec![50])] {
///     assert!(check_seeds("seeds", first, count, &pictures).is_err());
/// }
/// ```
pub fn check_seeds(field: &str, first_seed: u64, count: u64, pictures: &[u64]) -> Result<()> {
    if !(1..=MAX_SEEDS).contains(&count) {
        return Err(Error::invalid(
            field,
            format!("{count}: needs 1 to {MAX_SEEDS} seeds (each is a whole run; more is a typo)"),
        ));
    }
    let Some(last) = first_seed.checked_add(count - 1) else {
        return Err(Error::invalid(
            "first_seed",
            format!("{first_seed} + {count} seeds passes the largest seed, 2^64 − 1"),
        ));
    };
    if let Some(p) = pictures.iter().find(|p| !(first_seed..=last).contains(p)) {
        return Err(Error::invalid(
            "picture_seeds",
            format!(
                "{p} is not one of the grid's seeds {first_seed}..={last} (its picture would \
                 never be drawn)"
            ),
        ));
    }
    Ok(())
}

/// A resolved experiment: every cell's job, the seeds, the profile.
#[derive(Debug, Clone)]
pub struct Experiment {
    /// The file stem (`table` for `experiments/table.toml`; for [`Experiment::of_job`], the
    /// name given): the name of its raw folder.
    pub name: ExperimentName,
    /// Title, for tables and figures.
    pub title: String,
    /// What the experiment shows.
    pub description: String,
    /// The profile applied, if any.
    pub profile: Option<String>,
    /// First run seed.
    pub first_seed: u64,
    /// Number of seeds (of every site but those of `seeds_by_maze`).
    pub seed_count: u64,
    /// Fewer seeds on some sites (`seeds_by_maze = { "32" = 3 }`): site → seed count.
    pub seeds_by_maze: std::collections::BTreeMap<Site, u64>,
    /// Seeds whose runs also keep the picture data.
    pub picture_seeds: Vec<u64>,
    /// For a pre-registered grid, what was registered (`[registered]`).
    pub registered: Option<Registration>,
    /// Whether its rows are committed as its runs finish (`in_progress = true`): its tables
    /// hold the cells and seeds with rows so far, and the checks of whole committed grids
    /// check those rows only. A grid in progress whose every run has its row is refused by
    /// them (set it to false: the grid is whole).
    pub in_progress: bool,
    /// The grid's rows: its maze sizes, then its other environments, in the file's order.
    pub sites: Vec<Site>,
    /// Methods (name, label), in order.
    pub methods: Vec<(Method, String)>,
    /// Cells, site-major in the file's order of sites and methods.
    pub cells: Vec<Cell>,
    /// The figures it declares, in order.
    pub figures: Vec<FigureSpec>,
    /// What the report takes from it besides its table.
    pub report: ReportSpec,
}

/// A grid registered before any of its runs existed (`[registered]` of an experiment file):
/// the preset file its methods run and that file's SHA-256 then. When the preset no longer
/// has that hash the grid says nothing about the preset as it is: a sweep refuses to run it
/// ([`Registration::check`], called by [`sweep`]), and `tests/heldout.rs` fails; the grid must
/// then be registered again, on new layouts or seeds.
#[derive(Debug, Clone, PartialEq, Eq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Registration {
    /// The preset file, beside the experiment file (`pbcs_fast.toml`).
    pub preset: String,
    /// Its SHA-256 (lower-case hex) when the grid was registered.
    pub sha256: String,
    /// The commit message's date of the registration (`2026-11-25`).
    pub date: String,
    /// The registered analysis, where it is a paired comparison: `[baseline, variant]`, two
    /// of the file's methods, run on the same sites and seeds (`pbcs aggregate` writes
    /// `<experiment>.paired.csv`, [`crate::tables::paired`]).
    #[serde(default)]
    pub paired: Option<[Method; 2]>,
    /// Where the baseline's rows are, where they are not this file's: another experiment of
    /// the folder (`baseline_from = "table"`) whose method `paired[0]` ran the same sites and
    /// seeds; `pbcs aggregate` pairs the variant's rows with that experiment's.
    #[serde(default)]
    pub baseline_from: Option<ExperimentName>,
    /// Where the preset file is: `preset` in the experiment file's folder (set by
    /// [`Experiment::load`]).
    #[serde(skip)]
    pub preset_path: std::path::PathBuf,
}

impl Registration {
    /// The SHA-256 (lower-case hex) of the preset file as it is now.
    pub fn preset_sha256(&self) -> Result<String> {
        crate::record::file_sha256(&self.preset_path)
    }

    /// Ok when the preset file still has the registered hash; else an error naming the
    /// experiment, the preset and both hashes. A grid run with another preset would write rows
    /// the registration does not cover.
    ///
    /// ```
    /// use pbcs::experiment::Experiment;
    /// use std::path::Path;
    /// let exp = Experiment::load(Path::new("experiments/heldout.toml"), None).unwrap();
    /// exp.registered.as_ref().unwrap().check(exp.name).unwrap();
    /// let mut moved = exp.registered.clone().unwrap();
    /// moved.sha256 = "0".repeat(64);
    /// let e = moved.check(exp.name).unwrap_err().to_string();
    /// assert!(e.contains(&"0".repeat(64)) && e.contains("pbcs_fast.toml"), "{e}");
    /// ```
    pub fn check(&self, experiment: ExperimentName) -> Result<()> {
        let now = self.preset_sha256()?;
        if now == self.sha256 {
            return Ok(());
        }
        Err(Error::invalid(
            format!("registered.sha256 of {experiment}"),
            format!(
                "the grid was registered on {} for {} with SHA-256 {}, but that file's SHA-256 \
                 is now {now}: its runs would not be the registered grid's. Restore the preset \
                 as registered (git log -- {}), or register a new grid (new layouts or seeds) \
                 for the preset as it is",
                self.date,
                self.preset_path.display(),
                self.sha256,
                self.preset_path.display(),
            ),
        ))
    }
}

/// The make target that builds pbcs with MuJoCo and runs every experiment that needs it (the
/// Makefile's `MUJOCO_EXPERIMENTS`, read from the experiment files; a test holds the two to
/// [`Experiment::features`]).
pub const MUJOCO_TARGET: &str = "pointmaze";

impl Experiment {
    /// The run seeds, in order.
    pub fn seeds(&self) -> Vec<u64> {
        self.first_n_seeds(self.seed_count)
    }

    /// The run seeds of `cell`: [`Self::seeds`], or the first `seeds_by_maze[site]` of them.
    pub fn seeds_of(&self, cell: &Cell) -> Vec<u64> {
        let n = self
            .seeds_by_maze
            .get(&cell.site)
            .map_or(self.seed_count, |&n| n.min(self.seed_count));
        self.first_n_seeds(n)
    }

    /// The first `n` run seeds (`n` ≤ the grid's count, whose last seed [`check_seeds`] keeps
    /// within `u64`).
    fn first_n_seeds(&self, n: u64) -> Vec<u64> {
        (0..n).map(|i| self.first_seed + i).collect()
    }

    /// The environments of the grid this build cannot run, with the cargo feature each needs
    /// ([`crate::envs::EnvName::missing_feature`]): empty when every run can run here.
    pub fn missing_features(&self) -> Vec<(crate::envs::EnvName, &'static str)> {
        self.sites
            .iter()
            .filter_map(|s| match s {
                Site::Env(e) => e.missing_feature().map(|f| (*e, f)),
                Site::Maze(_) => None,
            })
            .collect()
    }

    /// The cargo features some environment of the grid needs in any build
    /// ([`crate::envs::EnvName::feature`]), each once: which make target runs the grid
    /// ([`MUJOCO_TARGET`] for `mujoco`; `make results` skips it in a build without).
    pub fn features(&self) -> Vec<&'static str> {
        let mut features: Vec<&'static str> = self
            .sites
            .iter()
            .filter_map(|s| match s {
                Site::Env(e) => e.feature(),
                Site::Maze(_) => None,
            })
            .collect();
        features.sort_unstable();
        features.dedup();
        features
    }

    /// None when this build runs every environment of the grid; else what it lacks and how
    /// to run the grid, in one line.
    pub fn unavailable(&self) -> Option<String> {
        let missing = self.missing_features();
        let (_, feature) = missing.first()?;
        let names: Vec<&str> = missing.iter().map(|(e, _)| <&str>::from(*e)).collect();
        Some(format!(
            "{}: running {} needs the cargo feature `{feature}`, which this build of pbcs \
             lacks: build with `--features {feature}`{}",
            self.name,
            names.join(", "),
            if *feature == "mujoco" {
                format!(
                    " after `make mujoco` (`make {MUJOCO_TARGET}` does both and runs every \
                     experiment with a PointMaze or AntMaze site, this one among them)"
                )
            } else {
                String::new()
            }
        ))
    }

    /// How many runs the grid has: the seeds of every cell.
    pub fn run_count(&self) -> u64 {
        self.cells
            .iter()
            .map(|c| self.seeds_of(c).len() as u64)
            .sum()
    }

    /// The cell written `id` (`pbcs-maze5`, as on the command line), or an error listing the
    /// cells.
    pub fn cell(&self, id: &str) -> Result<&Cell> {
        match id.parse::<CellKey>() {
            Ok(key) => self.cell_at(key),
            Err(e) => Err(Error::invalid(
                "cell",
                format!("{e} (experiment `{}` has: {})", self.name, self.cell_list()),
            )),
        }
    }

    /// The cell of `key`, or an error listing the cells.
    pub fn cell_at(&self, key: CellKey) -> Result<&Cell> {
        self.cells.iter().find(|c| c.id == key).ok_or_else(|| {
            Error::invalid(
                "cell",
                format!(
                    "experiment `{}` has no cell `{key}` (it has: {})",
                    self.name,
                    self.cell_list()
                ),
            )
        })
    }

    /// The cells' keys, comma-separated (for messages).
    fn cell_list(&self) -> String {
        self.cells
            .iter()
            .map(|c| c.id.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// The folder of a cell's raw results under `results`.
    pub fn cell_dir(&self, results: &Path, cell: &Cell) -> PathBuf {
        results
            .join("raw")
            .join(self.name)
            .join(cell.id.to_string())
    }
}
