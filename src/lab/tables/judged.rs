//! Chains judged again by an outside environment: PBCS's PointMaze chains played in
//! gymnasium-robotics' own `PointMaze_<Map>-v3` by `python/benches/pointmaze_gym.py`, one row
//! `s<seed>.gym.csv` beside each run's row. `pbcs aggregate` gathers them per cell into
//! `results/tables/<experiment>.judged.csv` and `pbcs figures` writes their numbers
//! (`\res{<experiment>:<cell>:judged:<field>}`), so the report quotes the outside judge's verdict,
//! not the one measured in our own environment.

use crate::error::{Error, Result};
use crate::experiment::{CellKey, Experiment, ExperimentName, RawRow};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Successes out of 100 that count a chain as solved by the outside judge (the protocol's 95).
pub const SOLVED_SUCCESSES: u32 = 95;

/// One run's chain judged by the outside environment (`s<seed>.gym.csv`, written by
/// `python/benches/pointmaze_gym.py`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JudgedRun {
    /// The cell, as in the run's row.
    pub cell: CellKey,
    /// The run seed.
    pub seed: u64,
    /// The judge: gymnasium-robotics' environment id.
    pub gym_id: String,
    /// Start cell, `row column`.
    pub start_cell: String,
    /// Goal cell, `row column`.
    pub goal_cell: String,
    /// The judge's time limit per episode.
    pub time_limit: u32,
    /// The run's env steps (phase 1 included), as in its row.
    pub env_steps: u64,
    /// Skills of the chain.
    pub skills: u32,
    /// Whether our own evaluation counted the run solved.
    pub solved_own_env: bool,
    /// Our own evaluation's chain success.
    pub own_success_rate: f32,
    /// Episodes the judge counted a success.
    pub gym_successes: u32,
    /// Episodes played.
    pub gym_episodes: u32,
    /// At least [`SOLVED_SUCCESSES`] of 100.
    pub gym_solved: bool,
    /// Mean episode length.
    pub gym_mean_steps: f32,
}

/// One cell's verdict of the outside judge.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JudgedCell {
    /// The cell.
    pub cell: CellKey,
    /// The judge.
    pub gym_id: String,
    /// Seeds judged (all the cell's seeds).
    pub seeds: usize,
    /// Seeds whose chain the judge counted solved.
    pub solved: usize,
    /// The fewest successes of a seed.
    pub successes_min: u32,
}

/// `results/tables/<experiment>.judged.csv`.
pub fn judged_path(results: &Path, experiment: ExperimentName) -> PathBuf {
    results
        .join("tables")
        .join(format!("{experiment}.judged.csv"))
}

/// The judged runs of one cell's seeds read from `dir`, checked: none, or one per seed, each
/// naming its cell and seed, successes within the episodes, `gym_solved` agreeing with them,
/// and the run it judged the one of the cell's row (`rows`: the same env steps and our own
/// verdict), so that a verdict left from an earlier run is refused.
fn judged_runs(
    dir: &Path,
    cell: CellKey,
    seeds: &[u64],
    rows: &[RawRow],
) -> Result<Vec<JudgedRun>> {
    let paths: Vec<PathBuf> = seeds
        .iter()
        .map(|s| dir.join(format!("s{s}.gym.csv")))
        .collect();
    if !paths.iter().any(|p| p.exists()) {
        return Ok(Vec::new());
    }
    let mut runs = Vec::new();
    for (path, &seed) in paths.iter().zip(seeds) {
        if !path.exists() {
            return Err(Error::io(
                path,
                std::io::Error::other("missing: a cell is judged for all its seeds or none"),
            ));
        }
        let run: JudgedRun = crate::record::read_one_record(path)?;
        let bad = if run.cell != cell || run.seed != seed {
            Some(format!(
                "is cell {} seed {}, expected {cell} seed {seed}",
                run.cell, run.seed
            ))
        } else if run.gym_episodes != 100 || run.gym_successes > run.gym_episodes {
            Some(format!(
                "{} successes of {} episodes (100 expected)",
                run.gym_successes, run.gym_episodes
            ))
        } else if run.gym_solved != (run.gym_successes >= SOLVED_SUCCESSES) {
            Some(format!(
                "gym_solved = {} with {} successes",
                run.gym_solved, run.gym_successes
            ))
        } else {
            stale(&run, rows)
        };
        if let Some(why) = bad {
            return Err(Error::parse(path, why));
        }
        runs.push(run);
    }
    Ok(runs)
}

/// Why a judged run is not the run of its row in `rows`, if it is not.
fn stale(run: &JudgedRun, rows: &[RawRow]) -> Option<String> {
    match rows
        .iter()
        .find(|r| r.cell == run.cell && r.seed == run.seed)
    {
        None => Some("judges a run that has no row".to_string()),
        Some(r) if (r.env_steps, r.solved) != (run.env_steps, run.solved_own_env) => Some(format!(
            "judges a run of {} env steps (solved: {}), the row's run took {} (solved: {}): \
             judge the run again",
            run.env_steps, run.solved_own_env, r.env_steps, r.solved
        )),
        Some(_) => None,
    }
}

/// Per cell of `exp`, the judged runs under `results/raw/<experiment>/` of the runs in `rows`;
/// cells without any are left out. A cell's runs are judged by one environment.
pub fn judged_cells(exp: &Experiment, results: &Path, rows: &[RawRow]) -> Result<Vec<JudgedCell>> {
    let mut cells = Vec::new();
    for cell in &exp.cells {
        let seeds = exp.seeds_of(cell);
        let dir = exp.cell_dir(results, cell);
        let runs = judged_runs(&dir, cell.id, &seeds, rows)?;
        let Some(first) = runs.first() else { continue };
        if let Some(other) = runs.iter().find(|r| r.gym_id != first.gym_id) {
            return Err(Error::parse(
                dir.join(format!("s{}.gym.csv", other.seed)),
                format!(
                    "judged by {}, seed {} by {}: one judge per cell",
                    other.gym_id, first.seed, first.gym_id
                ),
            ));
        }
        cells.push(JudgedCell {
            cell: cell.id,
            gym_id: first.gym_id.clone(),
            seeds: runs.len(),
            solved: runs.iter().filter(|r| r.gym_solved).count(),
            successes_min: runs.iter().map(|r| r.gym_successes).min().unwrap_or(0),
        });
    }
    Ok(cells)
}

/// `\res{<experiment>:<cell>:judged:<field>}` (`seeds`, `solved`, `min`, `judge`) from the
/// judged table, where it exists.
pub fn judged_numbers(name: ExperimentName, results: &Path) -> Result<Vec<(String, String)>> {
    super::table_numbers(&judged_path(results, name), |c: &JudgedCell| {
        let fields = [
            ("seeds", c.seeds.to_string()),
            ("solved", c.solved.to_string()),
            ("min", c.successes_min.to_string()),
            ("judge", c.gym_id.clone()),
        ];
        (format!("{}:judged", c.cell), fields)
    })
}
