//! How the tables read under other success criteria.
//!
//! The paper calls a maze solved "when a controller is able to reliably reach a rewarded
//! state"; we count a PBCS run as solved when its chain is complete and reaches the target
//! from at least [`crate::runs::SOLVED_AT`] (95 %) of its evaluation episodes from B_ε(s_0).
//! This module re-counts every PBCS cell at other thresholds, from the raw rows alone (no new
//! runs): the chain-success rate of each run ([`ChainSuccess`], `<experiment>.chains.csv`) and
//! the solved counts per criterion ([`Criteria`], `<experiment>.criteria.csv`). The same
//! per-run table gives the performance profile ([`profile`]): the fraction of runs solved
//! within x times the paper's steps.
//!
//! ```
//! use pbcs::criteria::{criteria, ChainSuccess};
//!
//! let run = |seed, complete, success_rate| ChainSuccess {
//!     experiment: "t".parse().unwrap(), cell: "pbcs-maze2".parse().unwrap(), method: "pbcs".parse().unwrap(),
//!     label: "PBCS".into(), site: pbcs::experiment::Site::Maze(2), seed, complete, success_rate,
//!     solved: complete && success_rate >= 0.95, env_steps: 1000, paper_steps: Some(321_000),
//! };
//! let c = &criteria(&[run(0, true, 1.0), run(1, true, 0.93), run(2, false, 0.0)])[0];
//! assert_eq!((c.n, c.complete, c.at_0_50, c.at_0_90, c.at_0_95, c.at_1_00), (3, 2, 2, 2, 1, 1));
//! ```

use crate::experiment::{CellKey, Experiment, ExperimentName, Kind, Method, RawRow};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The chain-success thresholds of [`Criteria`]: 0.5, 0.9, 0.95 (ours) and 1.0.
pub const THRESHOLDS: [f32; 4] = [0.5, 0.9, crate::stats::SOLVED_AT, 1.0];

/// One PBCS run's chain: whether phase 2 built it completely and the fraction of evaluation
/// episodes from B_ε(s_0) that reached the target (0 for an incomplete chain).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChainSuccess {
    /// Experiment name.
    pub experiment: ExperimentName,
    /// Cell id.
    pub cell: CellKey,
    /// Method name.
    pub method: Method,
    /// Method label.
    pub label: String,
    /// Maze size N or another environment's name (column `maze`).
    #[serde(rename = "maze")]
    pub site: crate::experiment::Site,
    /// Run seed.
    pub seed: u64,
    /// Whether phase 2 ended without a failure (a complete chain was evaluated).
    pub complete: bool,
    /// Fraction of evaluation episodes that reached the target.
    pub success_rate: f32,
    /// Whether the run counts as solved in the tables (complete chain, ≥ 95 %).
    pub solved: bool,
    /// Environment steps of the run.
    pub env_steps: u64,
    /// The paper's PBCS steps on this maze size (its one run), if the paper ran it.
    pub paper_steps: Option<u64>,
}

/// One PBCS cell's solved counts under each criterion: a complete chain, and a complete chain
/// reaching the target from at least 50, 90, 95 (ours) and 100 % of its evaluation episodes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Criteria {
    /// Experiment name.
    pub experiment: ExperimentName,
    /// Cell id.
    pub cell: CellKey,
    /// Method name.
    pub method: Method,
    /// Method label.
    pub label: String,
    /// Maze size N or another environment's name (column `maze`).
    #[serde(rename = "maze")]
    pub site: crate::experiment::Site,
    /// Runs.
    pub n: u64,
    /// Runs whose chain is complete.
    pub complete: u64,
    /// Complete chains at ≥ 50 %.
    pub at_0_50: u64,
    /// Complete chains at ≥ 90 %.
    pub at_0_90: u64,
    /// Complete chains at ≥ 95 % (the tables' "solved").
    pub at_0_95: u64,
    /// Complete chains at 100 %.
    pub at_1_00: u64,
    /// Complete chains at 0 % (a chain built whole that never reaches the target).
    pub at_zero: u64,
}

impl Criteria {
    /// The counts at [`THRESHOLDS`], in order.
    pub fn at(&self) -> [u64; 4] {
        [self.at_0_50, self.at_0_90, self.at_0_95, self.at_1_00]
    }

    /// Runs not solved: a run is solved exactly when its chain is complete and reaches the
    /// target from at least 95 % of its episodes ([`crate::stats::solved`]; a complete chain is
    /// one phase 2 did not stop), the count at 95 %.
    pub fn unsolved(&self) -> u64 {
        self.n - self.at_0_95
    }

    /// Runs whose chain is not complete (phase 2 stopped early).
    pub fn incomplete(&self) -> u64 {
        self.n - self.complete
    }
}

/// The chain of every PBCS row of `exp`, in the rows' order (vanilla rows are left out: they
/// have no chain).
pub fn chain_successes(exp: &Experiment, rows: &[RawRow]) -> Vec<ChainSuccess> {
    rows.iter()
        .filter(|r| r.kind() == Kind::Pbcs)
        .map(|r| ChainSuccess {
            experiment: r.experiment,
            cell: r.cell,
            method: r.method,
            label: exp
                .cell_at(r.cell)
                .map_or_else(|_| r.method.to_string(), |c| c.label.clone()),
            site: r.site,
            seed: r.seed,
            complete: r.failure().is_none(),
            success_rate: r.success_rate,
            solved: r.solved,
            env_steps: r.env_steps,
            paper_steps: crate::experiment::paper_run(crate::phase2::Variant::Pbcs, r.site).0,
        })
        .collect()
}

/// The solved counts of each cell of `runs` (cells in order of first appearance).
pub fn criteria(runs: &[ChainSuccess]) -> Vec<Criteria> {
    let mut out: Vec<Criteria> = Vec::new();
    for r in runs {
        let i = match out.iter().position(|c| c.cell == r.cell) {
            Some(i) => i,
            None => {
                out.push(Criteria {
                    experiment: r.experiment,
                    cell: r.cell,
                    method: r.method,
                    label: r.label.clone(),
                    site: r.site,
                    n: 0,
                    complete: 0,
                    at_0_50: 0,
                    at_0_90: 0,
                    at_0_95: 0,
                    at_1_00: 0,
                    at_zero: 0,
                });
                out.len() - 1
            }
        };
        let c = &mut out[i];
        c.n += 1;
        let solved_at = |x: f32| u64::from(r.complete && r.success_rate >= x);
        c.complete += u64::from(r.complete);
        c.at_0_50 += solved_at(THRESHOLDS[0]);
        c.at_0_90 += solved_at(THRESHOLDS[1]);
        c.at_0_95 += solved_at(THRESHOLDS[2]);
        c.at_1_00 += solved_at(THRESHOLDS[3]);
        c.at_zero += u64::from(r.complete && r.success_rate <= 0.0);
    }
    out
}

/// `results/tables/<experiment>.chains.csv`.
pub fn chains_path(results: &Path, experiment: ExperimentName) -> PathBuf {
    results
        .join("tables")
        .join(format!("{experiment}.chains.csv"))
}

/// `results/tables/<experiment>.criteria.csv`.
pub fn criteria_path(results: &Path, experiment: ExperimentName) -> PathBuf {
    results
        .join("tables")
        .join(format!("{experiment}.criteria.csv"))
}

/// Reads `<experiment>.criteria.csv`, each line's counts checked to nest (at 100 % ≤ at 95 %
/// ≤ at 90 % ≤ at 50 % ≤ complete ≤ n, and at 0 % ≤ complete): a line that does not is an
/// error naming the file and the cell, never a count the report subtracts from.
pub fn read_criteria(path: &Path) -> crate::Result<Vec<Criteria>> {
    let lines: Vec<Criteria> = crate::record::read_records(path)?;
    for c in &lines {
        let chain = [c.at_1_00, c.at_0_95, c.at_0_90, c.at_0_50, c.complete, c.n];
        if chain.windows(2).any(|w| w[0] > w[1]) || c.at_zero > c.complete {
            return Err(crate::Error::parse(
                path,
                format!(
                    "cell {}: counts that do not nest (n {}, complete {}, at 0.5/0.9/0.95/1.0 \
                     {:?}, at 0 {}): each criterion counts a subset of the one before; run \
                     `pbcs aggregate` again",
                    c.cell,
                    c.n,
                    c.complete,
                    c.at(),
                    c.at_zero
                ),
            ));
        }
    }
    Ok(lines)
}

/// Reads `<experiment>.chains.csv`.
pub fn read_chains(path: &Path) -> crate::Result<Vec<ChainSuccess>> {
    crate::record::read_records(path)
}

/// The performance profile of `runs` (one method's runs): for each ratio x of `ratios`, the
/// fraction of the runs solved within x times the paper's steps for their maze (a run not
/// solved never counts; runs on a size the paper did not run are left out).
///
/// ```
/// use pbcs::criteria::{profile, ChainSuccess};
///
/// let run = |steps, solved| ChainSuccess {
///     experiment: "t".parse().unwrap(), cell: "m-maze2".parse().unwrap(), method: "m".parse().unwrap(),
///     label: "m".into(),
///     site: pbcs::experiment::Site::Maze(2), seed: 0, complete: true, success_rate: 1.0,
///     solved, env_steps: steps,
///     paper_steps: Some(100),
/// };
/// let runs = [run(10, true), run(50, true), run(150, true), run(20, false)];
/// assert_eq!(profile(&runs, &[0.1, 0.5, 1.0, 2.0]), [0.25, 0.5, 0.5, 0.75]);
/// ```
pub fn profile(runs: &[ChainSuccess], ratios: &[f64]) -> Vec<f64> {
    let ratios_of: Vec<Option<f64>> = runs
        .iter()
        .map(|r| {
            let paper = r.paper_steps? as f64;
            Some(if r.solved {
                r.env_steps as f64 / paper
            } else {
                f64::INFINITY
            })
        })
        .collect();
    let n = ratios_of.iter().flatten().count();
    ratios
        .iter()
        .map(|&x| {
            let within = ratios_of.iter().flatten().filter(|&&r| r <= x).count();
            if n == 0 {
                0.0
            } else {
                within as f64 / n as f64
            }
        })
        .collect()
}
