//! The routes table (`results/tables/<experiment>.routes.csv`): for each PBCS run with
//! evaluation episodes, how long the chain's paths are beside phase 1's trajectory τ and the
//! fewest steps possible — the paper's claim that PBCS "is able to improve on the trajectory
//! obtained by the motion planning phase", measured.
//!
//! * the chain's path: the median steps of the run's successful evaluation episodes from
//!   B_ε(s_0) (`s<seed>.evaluation.csv`);
//! * |τ|: phase 1 is deterministic in the run's seed, so τ is recomputed here (milliseconds)
//!   instead of stored: its steps N, and those of the trajectory phase 2 worked on (τ
//!   shortened with clearance ε where the job says `shorten`);
//! * the fewest steps: the shortest collision-free path from s_0 to the target disc, at the
//!   largest action per step ([`Maze::fewest_steps`]).

use crate::envs::maze::Maze;
use crate::error::{Error, Result};
use crate::experiment::{
    evaluation_file, CellKey, Experiment, ExperimentName, Job, Kind, Method, RawRow,
};
use crate::rng::{Seeds, Stream};
use crate::runs::EvalEpisode;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// One PBCS run's path lengths, in environment steps.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Route {
    /// Cell id.
    pub cell: CellKey,
    /// Method name.
    pub method: Method,
    /// Maze size N or another environment's name (column `maze`).
    #[serde(rename = "maze")]
    pub site: crate::experiment::Site,
    /// Run seed.
    pub seed: u64,
    /// Whether the run counts as solved.
    pub solved: bool,
    /// Steps of phase 1's τ (its N).
    pub tau_steps: usize,
    /// Steps of the trajectory phase 2 worked on (τ, or τ shortened).
    pub phase2_tau_steps: usize,
    /// Median steps of the successful evaluation episodes (empty if none succeeded).
    pub chain_steps: Option<f64>,
    /// Successful evaluation episodes.
    pub successes: u64,
    /// The fewest steps any controller needs from s_0 ([`Maze::fewest_steps`]).
    pub fewest_steps: usize,
}

/// The ratios the report's numbers and the routes figure read, each written once here.
impl Route {
    /// The chain's path over the fewest steps (none without a successful episode).
    pub fn chain_over_fewest(&self) -> Option<f64> {
        Some(self.chain_steps? / self.fewest_steps.max(1) as f64)
    }

    /// The τ phase 2 worked on over the fewest steps.
    pub fn tau_over_fewest(&self) -> f64 {
        self.phase2_tau_steps as f64 / self.fewest_steps.max(1) as f64
    }

    /// The τ phase 2 worked on over the chain's path.
    pub fn phase2_tau_over_chain(&self) -> Option<f64> {
        Some(self.phase2_tau_steps as f64 / self.chain_steps?)
    }

    /// Phase 1's τ over the chain's path.
    pub fn phase1_tau_over_chain(&self) -> Option<f64> {
        Some(self.tau_steps as f64 / self.chain_steps?)
    }

    /// The share of phase 1's τ that phase 2 worked on.
    pub fn tau_left(&self) -> f64 {
        self.phase2_tau_steps as f64 / self.tau_steps.max(1) as f64
    }
}

/// `<results>/tables/<experiment>.routes.csv`.
pub fn routes_path(results: &Path, experiment: ExperimentName) -> PathBuf {
    results
        .join("tables")
        .join(format!("{experiment}.routes.csv"))
}

/// The route of every PBCS row of `exp` under `results` that ran on a maze (the fewest steps
/// are the maze's, [`Maze::fewest_steps`]) and has its evaluation episodes (rows committed
/// before `s<seed>.evaluation.csv` existed are left out), in the rows' order.
pub fn routes(exp: &Experiment, results: &Path, rows: &[RawRow]) -> Result<Vec<Route>> {
    let mut out = Vec::new();
    let on_maze = |r: &&RawRow| r.kind() == Kind::Pbcs && r.site.size().is_some();
    for r in rows.iter().filter(on_maze) {
        let cell = exp.cell_at(r.cell)?;
        let path = evaluation_file(exp, results, cell, r.seed);
        if !path.exists() {
            continue;
        }
        let episodes: Vec<EvalEpisode> = crate::record::read_records(&path)?;
        let Job::Pbcs(job) = cell.job.with_seed(r.seed) else {
            continue;
        };
        let maze = Maze::new(&job.maze)?;
        let mut rng = Seeds::new(job.seed).stream(Stream::Explore);
        let found = crate::phase1::explore(&maze, &job.explore, &mut rng, |_, _| {})?;
        let walked = crate::phase2::phase2_trajectory(&maze, &found.trajectory, &job.phase2)?;
        let mut steps: Vec<f64> = episodes
            .iter()
            .filter(|e| e.success)
            .map(|e| e.steps as f64)
            .collect();
        let fewest = maze.fewest_steps().ok_or_else(|| {
            Error::invalid("maze", format!("{}: the target cannot be reached", r.cell))
        })?;
        out.push(Route {
            cell: r.cell,
            method: r.method,
            site: r.site,
            seed: r.seed,
            solved: r.solved,
            tau_steps: found.trajectory.states.len() - 1,
            phase2_tau_steps: walked.states.len() - 1,
            chain_steps: (!steps.is_empty()).then(|| crate::stats::median(&mut steps)),
            successes: steps.len() as u64,
            fewest_steps: fewest,
        });
    }
    Ok(out)
}

/// Reads a routes table written by [`crate::pipeline::write_tables`].
pub fn read_routes(path: &Path) -> Result<Vec<Route>> {
    crate::record::read_records(path)
}

/// One line of `<results>/tables/<experiment>.route_cells.csv`: a cell's routes summarised over
/// its runs, what the report quotes (it reads this table and aggregates nothing).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RouteCell {
    /// Cell id.
    pub cell: CellKey,
    /// Runs with a route.
    pub runs: u64,
    /// Of them, runs with a successful evaluation episode (a chain's path).
    pub chain_runs: u64,
    /// Of those, runs whose chain's path is shorter than the τ phase 2 worked on.
    pub shorter: u64,
    /// Median of the fewest steps from s_0 over the runs.
    pub fewest_steps: f64,
    /// Median share of phase 1's τ that phase 2 worked on ([`Route::tau_left`]).
    pub tau_left: f64,
    /// Median chain's path over the fewest steps ([`Route::chain_over_fewest`]; empty without
    /// a chain's path).
    pub chain_over_fewest: Option<f64>,
    /// Median τ phase 2 worked on over the chain's path ([`Route::phase2_tau_over_chain`]).
    pub phase2_tau_over_chain: Option<f64>,
    /// Median phase 1's τ over the chain's path ([`Route::phase1_tau_over_chain`]).
    pub phase1_tau_over_chain: Option<f64>,
}

/// `<results>/tables/<experiment>.route_cells.csv`.
pub fn route_cells_path(results: &Path, experiment: ExperimentName) -> PathBuf {
    results
        .join("tables")
        .join(format!("{experiment}.route_cells.csv"))
}

/// Each cell's [`RouteCell`] from the routes table, cells in the order they first appear
/// (whatever the rows' order).
pub fn route_cells(routes: &[Route]) -> Vec<RouteCell> {
    super::distinct(routes.iter().map(|r| r.cell))
        .into_iter()
        .map(|cell| {
            let runs: Vec<&Route> = routes.iter().filter(|r| r.cell == cell).collect();
            let median = |v: Vec<f64>| -> Option<f64> {
                let mut v = v;
                (!v.is_empty()).then(|| crate::stats::median(&mut v))
            };
            let of =
                |f: fn(&Route) -> Option<f64>| median(runs.iter().filter_map(|r| f(r)).collect());
            RouteCell {
                cell,
                runs: runs.len() as u64,
                chain_runs: runs.iter().filter(|r| r.chain_steps.is_some()).count() as u64,
                shorter: runs
                    .iter()
                    .filter(|r| r.chain_steps.is_some_and(|c| c < r.phase2_tau_steps as f64))
                    .count() as u64,
                fewest_steps: median(runs.iter().map(|r| r.fewest_steps as f64).collect())
                    .unwrap_or(f64::NAN),
                tau_left: median(runs.iter().map(|r| r.tau_left()).collect()).unwrap_or(f64::NAN),
                chain_over_fewest: of(Route::chain_over_fewest),
                phase2_tau_over_chain: of(Route::phase2_tau_over_chain),
                phase1_tau_over_chain: of(Route::phase1_tau_over_chain),
            }
        })
        .collect()
}

/// The line of `<results>/tables/<experiment>.route_spread.csv`: the routes over every cell,
/// what the report quotes as `\res{<experiment>:routes:<key>}` (it reads this line and
/// aggregates nothing). The spreads are the least and largest, over cells, of a cell's median
/// ([`RouteCell`]); ±∞ where no cell has the ratio.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RouteSpread {
    /// Runs with a chain's path, over every cell.
    pub chain_runs: u64,
    /// Of them, runs whose chain's path is shorter than the τ phase 2 worked on.
    pub shorter: u64,
    /// Least cell median of the chain's path over the fewest steps.
    pub fewest_lo: f64,
    /// Largest.
    pub fewest_hi: f64,
    /// Least cell median of the τ phase 2 worked on over the chain's path.
    pub tau_lo: f64,
    /// Largest.
    pub tau_hi: f64,
    /// Least cell median of phase 1's τ over the chain's path.
    pub phase1_lo: f64,
    /// Largest.
    pub phase1_hi: f64,
}

/// `<results>/tables/<experiment>.route_spread.csv`.
pub fn route_spread_path(results: &Path, experiment: ExperimentName) -> PathBuf {
    results
        .join("tables")
        .join(format!("{experiment}.route_spread.csv"))
}

/// The routes of `cells` over every cell.
pub fn route_spread(cells: &[RouteCell]) -> RouteSpread {
    let spread = |f: fn(&RouteCell) -> Option<f64>| {
        let v: Vec<f64> = cells.iter().filter_map(f).collect();
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        (lo, hi)
    };
    let (fewest_lo, fewest_hi) = spread(|c| c.chain_over_fewest);
    let (tau_lo, tau_hi) = spread(|c| c.phase2_tau_over_chain);
    let (phase1_lo, phase1_hi) = spread(|c| c.phase1_tau_over_chain);
    RouteSpread {
        chain_runs: cells.iter().map(|c| c.chain_runs).sum(),
        shorter: cells.iter().map(|c| c.shorter).sum(),
        fewest_lo,
        fewest_hi,
        tau_lo,
        tau_hi,
        phase1_lo,
        phase1_hi,
    }
}
