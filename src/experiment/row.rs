//! The raw row: one finished (cell, seed) run's outcome, the unit every table is built from.

use super::{Cell, Experiment, Kind};
use crate::config::{PbcsJob, TrainJob};
use crate::error::{Error, Result};
use crate::phase2::{Failure, StartMode};
use crate::runs::{RunRecord, TrainSummary};
use serde::{Deserialize, Serialize};
use std::path::Path;

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
    /// vanilla, the final greedy evaluation does (or, with `train.final_eval_episodes`, ≥ 95 %
    /// of PBCS's evaluation episodes).
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
    /// cell's names; the PBCS columns hold 0 or are empty. With `final_eval` (PBCS's protocol,
    /// `train.final_eval_episodes`), the run is judged on those episodes as a PBCS run is;
    /// else on its last greedy evaluation.
    pub fn vanilla(
        exp: &Experiment,
        cell: &Cell,
        job: &TrainJob,
        s: &TrainSummary,
        final_eval: &[crate::env::EvalEpisode],
    ) -> RawRow {
        let success_rate = if final_eval.is_empty() {
            s.final_success
        } else {
            final_eval.iter().filter(|e| e.success).count() as f32 / final_eval.len() as f32
        };
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
            solved: success_rate >= crate::runs::SOLVED_AT,
            success_rate,
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
    pub fn pbcs(exp: &Experiment, cell: &Cell, job: &PbcsJob, r: RunRecord) -> RawRow {
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

/// Reads one raw row file.
pub fn read_row(path: &Path) -> Result<RawRow> {
    let mut reader = csv::Reader::from_path(path).map_err(|e| Error::csv(path, e))?;
    reader
        .deserialize()
        .next()
        .ok_or_else(|| Error::parse(path, "empty raw row file"))?
        .map_err(|e| Error::csv(path, e))
}

/// One line per run, as sweeps print it: `pbcs-maze2 seed 3: solved (success 1.00) in 160484
/// env steps`, with the failure where phase 2 stopped.
impl std::fmt::Display for RawRow {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} seed {}: {} (success {:.2}) in {} env steps",
            self.cell,
            self.seed,
            if self.solved { "solved" } else { "not solved" },
            self.success_rate,
            self.env_steps
        )?;
        match self.failure {
            Some(failure) => write!(f, ", {}", failure.name()),
            None => Ok(()),
        }
    }
}
