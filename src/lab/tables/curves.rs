//! The learning-curve table (`results/tables/<experiment>.curves.csv`): for each vanilla cell
//! and each evaluation point, how many seeds' greedy policies reached the target and their
//! mean greedy return — what the curves figure draws, aggregated from each seed's
//! `s<seed>.evals.csv` so that the figure reads a table only.

use crate::error::{Error, Result};
use crate::experiment::{evals_file, CellKey, Experiment, ExperimentName, Job, Method};
use crate::vanilla::EvalRow;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One evaluation point of one vanilla cell, over the cell's seeds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CurvePoint {
    /// Cell id.
    pub cell: CellKey,
    /// Method name.
    pub method: Method,
    /// Maze size N or another environment's name (column `maze`).
    #[serde(rename = "maze")]
    pub site: crate::experiment::Site,
    /// Environment steps of training at this evaluation.
    pub steps: u64,
    /// Seeds evaluated at these steps.
    pub seeds: u64,
    /// Seeds whose greedy policy reached the target ([`crate::runs::SOLVED_AT`]).
    pub solved: u64,
    /// Mean over those seeds of the greedy episode's return.
    pub mean_return: f64,
}

/// `<results>/tables/<experiment>.curves.csv`.
pub fn curves_path(results: &Path, experiment: ExperimentName) -> PathBuf {
    results
        .join("tables")
        .join(format!("{experiment}.curves.csv"))
}

/// The curve points of every vanilla cell of `exp`, from each seed's `evals.csv` under
/// `results`, in cell order then steps; seeds without the file are left out. A run its job
/// stopped at a solving evaluation (`train.stop_at_successes`) counts as solved, with that
/// evaluation's return, at every later step of its cell's curve.
pub fn curve_points(exp: &Experiment, results: &Path) -> Result<Vec<CurvePoint>> {
    let mut out = Vec::new();
    for c in &exp.cells {
        let Job::Vanilla(job) = &c.job else { continue };
        let stops = job.train.stop_at_successes.is_some();
        let mut runs: Vec<Vec<EvalRow>> = Vec::new();
        for seed in exp.seeds() {
            let path = evals_file(exp, results, c, seed);
            if !path.exists() {
                continue;
            }
            let mut reader = csv::Reader::from_path(&path).map_err(|e| Error::csv(&path, e))?;
            let evals = reader
                .deserialize::<EvalRow>()
                .collect::<std::result::Result<Vec<_>, _>>()
                .map_err(|e| Error::csv(&path, e))?;
            runs.push(evals);
        }
        // steps → (seeds reaching the target, seeds, sum of returns), summed in seed order.
        let mut by_step: BTreeMap<u64, (u64, u64, f64)> = BTreeMap::new();
        let mut add = |steps: u64, e: &EvalRow| {
            let slot = by_step.entry(steps).or_default();
            slot.0 += u64::from(crate::stats::solved(false, e.success));
            slot.1 += 1;
            slot.2 += f64::from(e.mean_return);
        };
        let all_steps: std::collections::BTreeSet<u64> =
            runs.iter().flatten().map(|e| e.steps).collect();
        for evals in &runs {
            for e in evals {
                add(e.steps, e);
            }
            let stopped = evals
                .last()
                .filter(|last| stops && crate::stats::solved(false, last.success));
            if let Some(last) = stopped {
                for &later in all_steps.range(last.steps + 1..) {
                    add(later, last);
                }
            }
        }
        out.extend(by_step.into_iter().map(|(steps, (k, n, r))| CurvePoint {
            cell: c.id,
            method: c.method,
            site: c.site,
            steps,
            seeds: n,
            solved: k,
            mean_return: r / n as f64,
        }));
    }
    Ok(out)
}

/// Reads a curves table written by [`crate::pipeline::write_tables`].
pub fn read_curves(path: &Path) -> Result<Vec<CurvePoint>> {
    crate::record::read_records(path)
}
