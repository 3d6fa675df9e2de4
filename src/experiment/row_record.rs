//! A raw row as its CSV holds it: vanilla and PBCS runs share one header, so every row file
//! and table written since the first sweep reads as it did; a column of the other kind holds
//! 0 or nothing. Reading one turns it into its kind ([`RawRow`] with its [`KindRow`]), and a
//! column of the other kind that holds something is an error naming the kind and the column.

use super::row::{KindRow, PbcsRow, RawRow, VanillaRow};
use super::{CellKey, ExperimentName, Kind, Method, Site};
use crate::learner::LearnerName;
use crate::phase2::{Failure, StartMode};
use serde::{Deserialize, Serialize};

/// The columns of a raw row file, in order.
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
