//! The raw row: one finished (cell, seed) run's outcome, the unit every table is built from.

use super::{Cell, CellKey, Experiment, ExperimentName, Kind, Method, Site};
use crate::config::{Located, PbcsJob, TrainJob};
use crate::error::Result;
use crate::learner::LearnerName;
use crate::phase2::{Failure, StartMode};
use crate::runs::{RunRecord, TrainSummary};
use serde::{Deserialize, Serialize};

/// One run's raw result: the row every table and figure is computed from. What every run
/// records is a field here; what only a vanilla or only a PBCS run records is its [`KindRow`].
/// On disk both kinds share one header ([`RowRecord`]); reading a row turns it into its
/// kind, checking that the other kind's columns are empty.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RowRecord", into = "RowRecord")]
pub struct RawRow {
    /// Experiment name.
    pub experiment: ExperimentName,
    /// The cell (`<method>-maze<N>`, `<method>-rooms`).
    pub cell: CellKey,
    /// Its method.
    pub method: Method,
    /// Where it ran: the maze size N, or another environment's name (column `maze`).
    pub site: Site,
    /// Maze layout seed (0 for another environment).
    pub maze_seed: u64,
    /// Run seed.
    pub seed: u64,
    /// The learner: [`crate::learner::LearnerConfig::record_name`] (`ddpg`, `td3`, with `_am`
    /// for the argmax actor; `sac`), with `_her` for a vanilla run with HER
    /// ([`crate::config::TrainJob::learner_name`]).
    pub learner: crate::learner::LearnerName,
    /// γ.
    pub gamma: f32,
    /// Solved: PBCS, the chain reaches the target in ≥ 95 % of the evaluation episodes;
    /// vanilla, the final greedy evaluation does (or, with `train.final_eval_episodes`, ≥ 95 %
    /// of PBCS's evaluation episodes).
    pub solved: bool,
    /// Success rate of that evaluation.
    pub success_rate: f32,
    /// Environment steps used (PBCS: phase 1 + training + tests; vanilla: the budget, or
    /// fewer where `train.stop_at_successes` stopped the run).
    pub env_steps: u64,
    /// The step budget of the run (PBCS: `phase2.max_env_steps`; vanilla: `train.steps`).
    pub budget: u64,
    /// What only its kind of run records.
    pub kind: KindRow,
}

/// What only one kind of run records.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum KindRow {
    /// A vanilla run.
    Vanilla(VanillaRow),
    /// A PBCS run.
    Pbcs(PbcsRow),
}

/// What only a vanilla run records.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VanillaRow {
    /// Environment steps at the first successful greedy evaluation, if any.
    pub first_success_steps: Option<u64>,
}

/// What only a PBCS run records.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PbcsRow {
    /// Whether skill chaining was on.
    pub chaining: bool,
    /// `ball`, `exact` or `archive` starts.
    pub starts: StartMode,
    /// Steps of phase 1.
    pub phase1_steps: u64,
    /// Steps of phase-2 training episodes.
    pub train_steps: u64,
    /// Steps of Backplay's tests.
    pub test_steps: u64,
    /// Skills in the chain.
    pub skills: usize,
    /// Why phase 2 stopped early (`backplay_failed`, `no_chaining`, `budget`), or none.
    pub failure: Option<Failure>,
}

impl RawRow {
    /// `vanilla` or `pbcs`.
    pub fn kind(&self) -> Kind {
        match self.kind {
            KindRow::Vanilla(_) => Kind::Vanilla,
            KindRow::Pbcs(_) => Kind::Pbcs,
        }
    }

    /// What a PBCS run records; none for a vanilla run.
    pub fn pbcs_row(&self) -> Option<&PbcsRow> {
        match &self.kind {
            KindRow::Pbcs(p) => Some(p),
            KindRow::Vanilla(_) => None,
        }
    }

    /// Skills in the chain (0 for a vanilla run, which has none).
    pub fn skills(&self) -> usize {
        self.pbcs_row().map_or(0, |p| p.skills)
    }

    /// Why phase 2 stopped early (none for a vanilla run).
    pub fn failure(&self) -> Option<Failure> {
        self.pbcs_row().and_then(|p| p.failure)
    }

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
            experiment: exp.name,
            cell: cell.id,
            method: cell.method,
            site: Site::of(&job.env_spec()),
            maze_seed: layout_seed(job),
            seed: job.seed,
            learner: job.learner_name(),
            gamma: job.learner.gamma(),
            solved: crate::stats::solved(false, success_rate),
            success_rate,
            env_steps: s.env_steps,
            budget: job.train.steps,
            kind: KindRow::Vanilla(VanillaRow {
                first_success_steps: s.first_success_steps,
            }),
        }
    }

    /// The row of a PBCS run of `cell` (`job` with its seed): its [`RunRecord`] (what `pbcs
    /// run` writes to `record.csv`) under the cell's names, `env_steps` its `total_steps`;
    /// the record's τ lengths and ε are left to the job file.
    pub fn pbcs(exp: &Experiment, cell: &Cell, job: &PbcsJob, r: RunRecord) -> RawRow {
        RawRow {
            experiment: exp.name,
            cell: cell.id,
            method: cell.method,
            site: Site::of(&job.env_spec()),
            maze_seed: layout_seed(job),
            seed: r.seed,
            learner: r.learner,
            gamma: r.gamma,
            solved: r.solved,
            success_rate: r.success_rate,
            env_steps: r.total_steps,
            budget: job.phase2.max_env_steps,
            kind: KindRow::Pbcs(PbcsRow {
                chaining: job.phase2.chaining,
                starts: r.starts,
                phase1_steps: r.phase1_steps,
                train_steps: r.train_steps,
                test_steps: r.test_steps,
                skills: r.skills,
                failure: r.failure,
            }),
        }
    }
}

/// A raw row's `maze_seed` of a job: the maze's layout seed ([`crate::envs::EnvSpec::maze_columns`]),
/// 0 for another environment.
pub(super) fn layout_seed(job: &impl Located) -> u64 {
    job.env_spec().maze_columns().1.unwrap_or(0)
}

/// A raw row as its CSV holds it: vanilla and PBCS runs share one header, so every row file
/// and table written since the first sweep reads as it did; a column of the other kind holds
/// 0 or nothing. Reading one turns it into its kind ([`RawRow`] with its [`KindRow`]), and a
/// column of the other kind that holds something is an error naming the kind and the column.
#[derive(Clone, Serialize, Deserialize)]
pub(super) struct RowRecord {
    experiment: ExperimentName,
    cell: CellKey,
    method: Method,
    kind: Kind,
    maze: Site,
    maze_seed: u64,
    seed: u64,
    learner: LearnerName,
    gamma: f32,
    chaining: bool,
    starts: Option<StartMode>,
    solved: bool,
    success_rate: f32,
    env_steps: u64,
    budget: u64,
    first_success_steps: Option<u64>,
    phase1_steps: u64,
    train_steps: u64,
    test_steps: u64,
    skills: usize,
    failure: Option<Failure>,
}

impl From<RawRow> for RowRecord {
    fn from(r: RawRow) -> RowRecord {
        let (first_success_steps, p) = match r.kind {
            KindRow::Vanilla(v) => (v.first_success_steps, None),
            KindRow::Pbcs(p) => (None, Some(p)),
        };
        RowRecord {
            experiment: r.experiment,
            cell: r.cell,
            method: r.method,
            kind: r.kind(),
            maze: r.site,
            maze_seed: r.maze_seed,
            seed: r.seed,
            learner: r.learner,
            gamma: r.gamma,
            chaining: p.is_some_and(|p| p.chaining),
            starts: p.map(|p| p.starts),
            solved: r.solved,
            success_rate: r.success_rate,
            env_steps: r.env_steps,
            budget: r.budget,
            first_success_steps,
            phase1_steps: p.map_or(0, |p| p.phase1_steps),
            train_steps: p.map_or(0, |p| p.train_steps),
            test_steps: p.map_or(0, |p| p.test_steps),
            skills: p.map_or(0, |p| p.skills),
            failure: p.and_then(|p| p.failure),
        }
    }
}

impl TryFrom<RowRecord> for RawRow {
    type Error = String;

    /// The row of its kind; an error (`column `kind`: …, but column `skills` holds 2`) where a
    /// column of the other kind holds something, or a PBCS row has no starts.
    fn try_from(r: RowRecord) -> Result<RawRow, String> {
        if r.cell.method != r.method || r.cell.site != r.maze {
            let (method, site) = (r.method, r.maze);
            return Err(format!(
                "column `cell`: {}, but column `method` holds {method} and column `maze` {site}",
                r.cell
            ));
        }
        let kind = match r.kind {
            Kind::Vanilla => {
                let pbcs_only = [
                    (
                        "phase1_steps",
                        r.phase1_steps.to_string(),
                        r.phase1_steps != 0,
                    ),
                    ("train_steps", r.train_steps.to_string(), r.train_steps != 0),
                    ("test_steps", r.test_steps.to_string(), r.test_steps != 0),
                    ("skills", r.skills.to_string(), r.skills != 0),
                    ("chaining", r.chaining.to_string(), r.chaining),
                    (
                        "starts",
                        r.starts.map_or("", <&str>::from).to_string(),
                        r.starts.is_some(),
                    ),
                    (
                        "failure",
                        r.failure.map_or("", Failure::name).to_string(),
                        r.failure.is_some(),
                    ),
                ];
                if let Some((column, value, _)) = pbcs_only.into_iter().find(|c| c.2) {
                    return Err(format!(
                        "column `kind`: vanilla, but column `{column}` holds {value} (a PBCS \
                         column: 0 or empty in a vanilla row)"
                    ));
                }
                KindRow::Vanilla(VanillaRow {
                    first_success_steps: r.first_success_steps,
                })
            }
            Kind::Pbcs => {
                let Some(starts) = r.starts else {
                    return Err("column `starts`: empty in a PBCS row (`ball`, `exact` or \
                                `archive`)"
                        .into());
                };
                if let Some(first) = r.first_success_steps {
                    return Err(format!(
                        "column `first_success_steps`: {first} in a PBCS row (vanilla only: \
                         empty)"
                    ));
                }
                KindRow::Pbcs(PbcsRow {
                    chaining: r.chaining,
                    starts,
                    phase1_steps: r.phase1_steps,
                    train_steps: r.train_steps,
                    test_steps: r.test_steps,
                    skills: r.skills,
                    failure: r.failure,
                })
            }
        };
        Ok(RawRow {
            experiment: r.experiment,
            cell: r.cell,
            method: r.method,
            site: r.maze,
            maze_seed: r.maze_seed,
            seed: r.seed,
            learner: r.learner,
            gamma: r.gamma,
            solved: r.solved,
            success_rate: r.success_rate,
            env_steps: r.env_steps,
            budget: r.budget,
            kind,
        })
    }
}
