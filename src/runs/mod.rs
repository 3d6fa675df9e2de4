//! Runs: a validated job in, an outcome out. Each kind of run is a type whose `compute` is a
//! function from the job to the outcome that writes nothing ([`ExploreRun`], [`TrainRun`],
//! [`PbcsRun`]), and whose `write` puts the outcome into a folder (CSVs, the picture's data,
//! the saved chain) and hands its picture to the drawing step it is given
//! ([`crate::picture::Draw`]: [`crate::plot::draw_run`] draws PNG and SVG): runs compute and
//! write data, and nothing here draws (tests/layout.rs holds runs/ to it). [`run_explore`],
//! [`run_train`] and [`run_pbcs`] claim a folder, compute and write: the CLI's subcommands are
//! thin wrappers around them, so tests exercise exactly what users run; the sweep ([`crate::experiment::run_cell_seed`]) computes and keeps only its raw files.
//!
//! Result files are CSV (deterministic: same config, same bytes) written atomically; the
//! wall-clock time of a job lives beside them in `timing.toml`, never inside a CSV.

mod eval;
mod explore;
mod folder;
mod pbcs;
pub mod pbcs_resume;
mod train;

pub use eval::{
    chain_eval_starts, eval_chain, evaluate_chain, load_saved_chain, load_saved_job, ChainEval,
    EvalEpisode, CHAIN_JOB, DRAWN_ROLLOUTS,
};
pub use explore::{run_explore, ExploreRun, ExploreSummary};
pub use folder::{explore_out, method_name, run_out, train_out, write_timing};
pub use pbcs::{
    run_outcome, run_outcome_resumable, run_pbcs, run_pbcs_until, PbcsRun, Phase2Progress,
    RunOutcome, RunRecord, RUN_CHECKPOINT,
};
pub use train::{run_train, train_outcome, TrainRun, TrainSummary};

pub use crate::stats::SOLVED_AT;
