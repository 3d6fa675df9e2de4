//! Where a PBCS run's environment steps go (`results/tables/<experiment>.phases.csv`): phase 1,
//! phase 2's training episodes and its test episodes (Backplay's β tests of each stage, each
//! skill's verification and the chain's), per cell, as medians over the cell's PBCS runs.
//!
//! A row's `env_steps` counts all three. A learner whose evaluations are not counted as env
//! steps — SB3's SAC+HER on PointMaze, evaluated every 10 000 steps by 100 episodes that its
//! step count leaves out — compares with PBCS's `learning` steps (phase 1 + training) as well,
//! so both are tabled. `pbcs figures` writes their numbers
//! (`\res{<experiment>:<cell>:phases:<field>}`).

use crate::experiment::{CellKey, Experiment, ExperimentName, Method, PbcsRow, RawRow, Site};
use crate::fmt::human_steps;
use crate::stats::median;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// One cell's split of env steps, over its PBCS runs (solved or not).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CellPhases {
    /// Cell id.
    pub cell: CellKey,
    /// Method name.
    pub method: Method,
    /// Maze size N or another environment's name (column `maze`).
    #[serde(rename = "maze")]
    pub site: Site,
    /// PBCS runs of the cell.
    pub runs: u64,
    /// Median env steps, all three parts.
    pub env_steps_median: f64,
    /// Median steps of phase 1.
    pub phase1_median: f64,
    /// Median steps of phase 2's training episodes.
    pub train_median: f64,
    /// Median steps of phase 2's test episodes.
    pub test_median: f64,
    /// Median of each run's phase 1 + training steps (its test episodes left out).
    pub learning_median: f64,
    /// The fewest phase 1 + training steps of a run.
    pub learning_min: u64,
    /// The most phase 1 + training steps of a run.
    pub learning_max: u64,
    /// The cell's test steps over its env steps, all runs summed.
    pub test_share: f64,
}

/// `<results>/tables/<experiment>.phases.csv`.
pub fn phases_path(results: &Path, experiment: ExperimentName) -> PathBuf {
    results
        .join("tables")
        .join(format!("{experiment}.phases.csv"))
}

/// The split of every cell of `exp` with PBCS rows, in the file's order of cells.
///
/// ```
/// use pbcs::experiment::Experiment;
/// // Without rows, no cell to split.
/// let exp = Experiment::load(std::path::Path::new("experiments/pointmaze.toml"), None).unwrap();
/// assert!(pbcs::tables::phases::cell_phases(&exp, &[]).is_empty());
/// ```
pub fn cell_phases(exp: &Experiment, rows: &[RawRow]) -> Vec<CellPhases> {
    let mut out = Vec::new();
    for c in &exp.cells {
        // Each PBCS run of the cell: its row and its phases.
        let runs: Vec<(&RawRow, &PbcsRow)> = rows
            .iter()
            .filter(|r| r.cell == c.id)
            .filter_map(|r| Some((r, r.pbcs_row()?)))
            .collect();
        if runs.is_empty() {
            continue;
        }
        type Part = fn(&(&RawRow, &PbcsRow)) -> u64;
        let mid = |part: Part| median(&mut runs.iter().map(|r| part(r) as f64).collect::<Vec<_>>());
        let learning: Part = |(_, p)| p.phase1_steps + p.train_steps;
        let sum = |part: Part| runs.iter().map(part).sum::<u64>() as f64;
        out.push(CellPhases {
            cell: c.id,
            method: c.method,
            site: c.site,
            runs: runs.len() as u64,
            env_steps_median: mid(|(r, _)| r.env_steps),
            phase1_median: mid(|(_, p)| p.phase1_steps),
            train_median: mid(|(_, p)| p.train_steps),
            test_median: mid(|(_, p)| p.test_steps),
            learning_median: mid(learning),
            learning_min: runs.iter().map(learning).min().unwrap_or(0),
            learning_max: runs.iter().map(learning).max().unwrap_or(0),
            test_share: sum(|(_, p)| p.test_steps) / sum(|(r, _)| r.env_steps).max(1.0),
        });
    }
    out
}

/// `\res{<experiment>:<cell>:phases:<field>}` from the phases table, where it exists:
/// `learning`, `learningmin`, `learningmax`, `phase1`, `train`, `test` (env steps as people
/// write them, [`human_steps`]) and `testshare` (percent, no decimals).
pub fn phases_numbers(
    name: ExperimentName,
    results: &Path,
) -> crate::Result<Vec<(String, String)>> {
    super::table_numbers(&phases_path(results, name), |c: &CellPhases| {
        let fields = [
            ("learning", human_steps(c.learning_median)),
            ("learningmin", human_steps(c.learning_min as f64)),
            ("learningmax", human_steps(c.learning_max as f64)),
            ("phase1", human_steps(c.phase1_median)),
            ("train", human_steps(c.train_median)),
            ("test", human_steps(c.test_median)),
            ("testshare", format!("{:.0}", c.test_share * 100.0)),
        ];
        (format!("{}:phases", c.cell), fields)
    })
}
