//! # pbcs — Plan, Backplay, Chain Skills, reproduced in Rust
//!
//! A reproduction of *PBCS: Efficient Exploration and Exploitation Using a Synergy between
//! Reinforcement Learning and Motion Planning* (Matheron, Perrin, Sigaud, 2020).
//!
//! ## Where each part of the paper lives
//!
//! | paper | module |
//! | --- | --- |
//! | Appendix "Experimental Setup": the maze MDP | [`envs::maze`] |
//! | Background, "Reset-anywhere" | [`env`] (pure `step(&State, action)`; PBCS's optional hooks as capabilities) |
//! | Phase 1 and appendix algorithm "Exploration algorithm" | [`phase1`] |
//! | Settings the paper gives or leaves open | [`config`] |
//! | Background, "DDPG"; the TD3 baseline; appendix "Replacing the actor update" | [`learner`] (TD3, DDPG preset, argmax actor) on [`nn`] |
//! | Results table, "Vanilla" columns | [`vanilla`] (training on the environment's own reward) |
//! | Phase 2: Algorithm 1 (skill chaining), 2 (Backplay), 3 (training with reward shaping) | [`phase2`] |
//! | Wilson score intervals (appendix on γ); Fisher's exact test | [`stats`] |
//! | "solved when a controller is able to reliably reach a rewarded state": other thresholds | [`criteria`] |
//!
//! [`envs`] names the environments jobs and the command run, one module each:
//! [`envs::maze`], [`envs::rooms`] (two rooms and a door, every hook offered),
//! [`envs::pointmaze`] (gymnasium-robotics' PointMaze on MuJoCo, feature `mujoco`),
//! [`envs::pendulum`] (gymnasium's Pendulum-v1) and [`envs::toy`] (a 1-D task the tests use to
//! check that the learners learn). Around them:
//! [`validate`] (the `Check` trait and the one TOML loader), [`rng`] derives every random
//! stream from one run seed, [`record`] writes result files atomically, [`plot`] draws planar
//! environments with plotters, and [`runs`] turns a job into an outcome (`compute`) and writes it (`write`):
//! what the `pbcs` command runs. The experiment pipeline, one way: [`experiment`] (grids of
//! cells × seeds, declared in TOML, swept with resume) → `aggregate` and [`tables`] (per-cell
//! statistics, curves, shortest paths, routes) → [`pipeline`] (writes `results/tables/`, then
//! renders) → [`figures`], [`claims`] (the paper's claims, as data) and [`report`] (LaTeX), which
//! read tables only; [`fmt`] formats numbers; [`launch`] (make, SLURM) and [`reproduce`]
//! (re-running committed rows). Words: a *job* is a validated config (`config::PbcsJob`, …), a *run* executes one
//! ([`runs`]), `--jobs N` is how many runs go at once.
//!
//! ```
//! use pbcs::config::ExploreJob;
//! use pbcs::runs::run_explore;
//! use pbcs::validate::Check;
//!
//! let mut job = ExploreJob::default();
//! job.maze.size = 2;
//! let out = tempfile::tempdir().unwrap();
//! // Runs write data; the drawing step they are handed draws (`picture::no_pictures`: none).
//! let draw = &pbcs::plot::draw_run;
//! let (summary, _seconds) = run_explore(&job.valid().unwrap(), out.path(), draw, |_, _| {}).unwrap();
//! assert!(summary.trajectory_len >= 2);
//! assert!(out.path().join("explore.png").exists());
//! ```

#![warn(missing_docs)]

pub mod checkpoint;
pub mod config;
pub mod env;
pub mod envs;
pub mod error;
pub mod fmt;
pub mod learner;
pub mod name;
pub mod nn;
pub mod phase1;
pub mod phase2;
pub mod picture;
pub mod policy;
pub mod record;
pub mod rng;
pub mod rollout;
pub mod runs;
pub mod stats;
pub mod validate;
pub mod vanilla;

pub use error::{Error, Result};

/// The lab that reproduces the paper (experiments, sweeps, tables, claims, figures, the
/// report): feature `lab`, on by default; the core above compiles without it, and without
/// plotters and polars (`cargo check --lib --no-default-features`). Its modules are named at
/// the crate's root as they were before it had a folder (`pbcs::experiment`, `pbcs::tables`).
#[cfg(feature = "lab")]
pub mod lab;
#[cfg(feature = "polars")]
pub use lab::aggregate;
#[cfg(feature = "lab")]
pub use lab::{
    claims, criteria, experiment, figures, launch, mathtext, pipeline, plot, report, reproduce,
    tables,
};
