//! Runs: a validated job in, an outcome out. Each kind of run is a type whose `compute` is a
//! function from the job to the outcome that writes nothing ([`ExploreRun`], [`TrainRun`],
//! [`PbcsRun`]), and whose `write` puts the outcome into a folder (CSVs, pictures, the saved
//! chain). [`run_explore`], [`run_train`] and [`run_pbcs`] claim a folder, compute and write:
//! the CLI's subcommands are thin wrappers around them, so tests exercise exactly what users
//! run; the sweep ([`crate::experiment::run_cell_seed`]) computes and keeps only its raw files.
//!
//! Result files are CSV (deterministic: same config, same bytes) written atomically; the
//! wall-clock time of a job lives beside them in `timing.toml`, never inside a CSV.

mod eval;
mod explore;
mod pbcs;
mod train;

pub use eval::{eval_chain, evaluate_chain, ChainEval, EvalEpisode, CHAIN_JOB};
use explore::write_trajectory_csv;
pub use explore::{run_explore, ExploreRun, ExploreSummary};
use pbcs::{ball_circles, DRAWN_ROLLOUTS};
pub use pbcs::{run_pbcs, PbcsRun, RunRecord};
pub use train::{run_train, TrainRun, TrainSummary};

use crate::error::Result;
use crate::nn::kernel::Kernel;
use serde::Serialize;
use std::path::Path;

/// A run counts as solved when its evaluation (greedy episodes of a vanilla policy, or of a
/// PBCS chain) reaches the target in at least this fraction of episodes.
pub const SOLVED_AT: f32 = 0.95;

/// Claims `out` for `job` before any work ([`crate::record::claim_out_dir`]): writes the
/// resolved job as `config.toml` (so that `--config` re-runs exactly this job), refusing a
/// path that is not a writable folder or a folder of another run.
fn claim<T: Serialize>(job: &T, out: &Path) -> Result<()> {
    let text = crate::validate::to_toml(job, &out.join("config.toml"))?;
    crate::record::claim_out_dir(out, &text)
}

/// Writes a run's `timing.toml` at `path` ([`crate::record::Timing`]): its wall clock and the
/// layer kernel it ran on (`None` for phase 1, which has no networks).
pub fn write_timing(
    path: &Path,
    seconds: f64,
    env_steps: u64,
    kernel: Option<Kernel>,
) -> Result<()> {
    crate::record::Timing::now(seconds, env_steps, kernel.map(Kernel::name)).write(path)
}
