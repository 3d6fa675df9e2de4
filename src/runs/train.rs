//! `pbcs train`: a vanilla baseline (DDPG, TD3, argmax actor) on an environment's own reward.

use super::folder::{claim, write_timing};
use crate::checkpoint::Checkpoint;
use crate::config::{Located, TrainJob};
use crate::env::{Planar, Scene};
use crate::envs::EnvName;
use crate::error::Result;
use crate::learner::td3::ActorUpdate;
use crate::nn::kernel::Kernel;
use crate::picture::{Draw, PictureData, RunPicture};
use crate::record::{write_csv, write_record};
use crate::rng::Seeds;
use crate::validate::Valid;
use crate::vanilla::resume::train_vanilla_resumable;
use crate::vanilla::train_vanilla;
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// The one-row summary of a vanilla training run (`summary.csv`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrainSummary {
    /// Maze size N (empty for another environment).
    pub maze: Option<usize>,
    /// Maze layout seed (empty for another environment).
    pub maze_seed: Option<u64>,
    /// Run seed.
    pub seed: u64,
    /// The learner's `algo` (`ddpg`, `td3`, `sac` in `summary.csv`).
    pub algo: &'static str,
    /// TD3's actor update (`gradient`, `argmax`; empty for another learner).
    pub actor_update: Option<ActorUpdate>,
    /// Environment steps.
    pub env_steps: u64,
    /// Training episodes begun.
    pub episodes: u64,
    /// Greedy success at the last evaluation.
    pub final_success: f32,
    /// Best greedy success over all evaluations.
    pub best_success: f32,
    /// Bins of side `train.visit_bin` visited during training.
    pub visited_bins: usize,
    /// Environment steps at the first evaluation whose greedy success solved the task
    /// ([`crate::stats::solved`]), if any.
    pub first_success_steps: Option<u64>,
    /// The environment ([`EnvName`]; the last column, so the others keep their places).
    pub env: EnvName,
}

/// One vanilla training run's outcome ([`TrainRun::compute`]); [`TrainRun::write`] writes it.
pub struct TrainRun {
    /// The picture's frame: the environment trained on.
    pub scene: Scene,
    /// The one-row summary.
    pub summary: TrainSummary,
    /// Evaluations, visited bins, the trained learner.
    pub result: crate::vanilla::TrainOutcome,
    /// What `train.png` draws: the visited bins (of the observation's first two components,
    /// drawn where [`Planar::ball_point`] puts a position) as red squares.
    pub picture: PictureData,
    /// The layer kernel the learner ran on.
    pub kernel: Kernel,
    /// Wall-clock seconds of the run (not deterministic), with those before a resume.
    pub seconds: f64,
}

impl TrainRun {
    /// Trains the vanilla baseline of `job` on `env`'s own reward (the environment `job`
    /// names: [`run_train`] makes it from the name), the learner's layers on `kernel`;
    /// `progress(steps, success)` is called at each evaluation. Writes nothing.
    pub fn compute<E: Planar>(
        env: E,
        job: &Valid<TrainJob>,
        kernel: Kernel,
        progress: impl FnMut(u64, f32),
    ) -> Result<TrainRun> {
        let clock = Instant::now();
        let (learner, train, seeds) = (&job.learner, &job.train, &Seeds::new(job.seed));
        let result = train_vanilla(&env, learner, train, seeds, kernel, progress)?;
        Ok(Self::of(env, job, kernel, result, clock))
    }

    /// [`TrainRun::compute`], saved to `checkpoint` now and then and resumed from it where it
    /// holds this run ([`crate::vanilla::resume`]); `None` when the run stopped, saved, at the
    /// checkpoint's deadline ([`Checkpoint::stop_at`]).
    pub fn compute_resumable<E: Planar>(
        env: E,
        job: &Valid<TrainJob>,
        kernel: Kernel,
        checkpoint: &Checkpoint,
        progress: impl FnMut(u64, f32),
    ) -> Result<Option<TrainRun>> {
        let clock = Instant::now();
        let (learner, train, seeds) = (&job.learner, &job.train, &Seeds::new(job.seed));
        let ended =
            train_vanilla_resumable(&env, learner, train, seeds, kernel, checkpoint, progress)?;
        Ok(ended.map(|result| Self::of(env, job, kernel, result, clock)))
    }

    /// The run of `job` on `env` whose training gave `result`, begun (in this process) at
    /// `clock`.
    fn of<E: Planar>(
        env: E,
        job: &Valid<TrainJob>,
        kernel: Kernel,
        result: crate::vanilla::TrainOutcome,
        clock: Instant,
    ) -> TrainRun {
        let seconds = result.earlier_seconds + clock.elapsed().as_secs_f64();
        let (maze, maze_seed) = job.env_spec().maze_columns();
        let summary = TrainSummary {
            maze,
            maze_seed,
            seed: job.seed,
            algo: job.learner.algo(),
            actor_update: job.learner.as_td3().map(|l| l.actor_update),
            env_steps: result.steps,
            episodes: result.episodes,
            final_success: result.evals.last().map_or(0.0, |e| e.success),
            best_success: result.evals.iter().map(|e| e.success).fold(0.0, f32::max),
            visited_bins: result.visited.len(),
            first_success_steps: result
                .evals
                .iter()
                .find(|e| crate::stats::solved(false, e.success))
                .map(|e| e.steps),
            env: job.env,
        };
        let side = job.train.visit_bin;
        let picture = PictureData {
            red_area: result
                .visited
                .iter()
                .map(|b| env.ball_point(&[b[0] as f32 * side, b[1] as f32 * side]))
                .collect(),
            red_area_side: side,
            ..PictureData::default()
        };
        TrainRun {
            scene: env.scene(),
            summary,
            result,
            picture,
            kernel,
            seconds,
        }
    }

    /// Writes into `out`: `summary.csv`, `evals.csv` (one row per evaluation),
    /// `evaluation.csv` (PBCS's protocol after training, when `train.final_eval_episodes` asks
    /// for it: success and steps of each episode), `visited.csv`
    /// (lower-left corners of visited bins), `actor.safetensors`, `picture.csv`,
    /// `timing.toml` and what `draw` draws of the picture (`train.png`, `train.svg` with
    /// [`crate::plot::draw_run`]), all of them or none ([`crate::record::write_run_folder`]: a
    /// failure leaves `out` as it was, or marked incomplete).
    pub fn write(&self, job: &TrainJob, out: &Path, draw: Draw) -> Result<()> {
        crate::record::write_run_folder(out, |dir| self.write_files(job, dir, draw))
    }

    fn write_files(&self, job: &TrainJob, out: &Path, draw: Draw) -> Result<()> {
        let summary = &self.summary;
        write_record(&out.join("summary.csv"), summary)?;
        crate::record::write_records(&out.join("evals.csv"), &self.result.evals)?;
        if !self.result.final_eval.is_empty() {
            crate::record::write_records(&out.join("evaluation.csv"), &self.result.final_eval)?;
        }
        write_csv(
            &out.join("visited.csv"),
            &["x".to_string(), "y".to_string()],
            self.picture
                .red_area
                .iter()
                .map(|(x, y)| [x.to_string(), y.to_string()]),
        )?;
        self.result
            .learner
            .policy()
            .save(&out.join("actor.safetensors"))?;
        self.picture.write_csv(&out.join("picture.csv"))?;
        let title = format!(
            "{} on {}, seed {}: {} steps, greedy success {:.0} %",
            summary.algo,
            job.env_spec().label(),
            job.seed,
            self.result.steps,
            100.0 * summary.final_success
        );
        draw(
            &RunPicture {
                stem: "train".into(),
                title,
                scene: self.scene.clone(),
                data: &self.picture,
            },
            out,
        )?;
        write_timing(
            &out.join("timing.toml"),
            self.seconds,
            self.result.steps,
            Some(self.kernel),
        )
    }
}

/// Trains the vanilla baseline of `job` into `out`: claims the folder (writing
/// `config.toml`) before any work, then [`TrainRun::compute`] and [`TrainRun::write`] with
/// the drawing step `draw` ([`crate::plot::draw_run`], or [`crate::picture::no_pictures`]).
pub fn run_train(
    job: &Valid<TrainJob>,
    kernel: Kernel,
    out: &Path,
    draw: Draw,
    progress: impl FnMut(u64, f32),
) -> Result<(TrainSummary, f64)> {
    let built = job.env_spec().build()?;
    let _lock = claim(job, out)?;
    let run = crate::with_env!(built, |env| {
        TrainRun::compute(env, job, kernel, progress)?
    });
    run.write(job, out, draw)?;
    Ok((run.summary, run.seconds))
}

/// [`TrainRun::compute_resumable`] on the environment `job` names: what an experiment's
/// vanilla (cell, seed) runs, saved to and resumed from `checkpoint`; `None` when it stopped,
/// saved, at the checkpoint's deadline.
pub fn train_outcome(
    job: &Valid<TrainJob>,
    kernel: Kernel,
    checkpoint: &Checkpoint,
    progress: impl FnMut(u64, f32),
) -> Result<Option<TrainRun>> {
    crate::with_env!(job.env_spec().build()?, |env| {
        TrainRun::compute_resumable(env, job, kernel, checkpoint, progress)
    })
}

impl TrainSummary {
    /// What `pbcs train` prints, with the wall clock `seconds` and the visit bins' side.
    pub fn summary(&self, seconds: f64, visit_bin: f32) -> String {
        format!(
            "{}{} on {}, run seed {}: {} env steps, {} episodes, {:.1} s ({:.0} \
             steps/s)\ngreedy success: final {}, best {}; visited {} bins of side {}",
            self.algo,
            self.actor_update
                .map(|a| format!(" ({} actor)", a.name()))
                .unwrap_or_default(),
            match (self.maze, self.maze_seed) {
                (Some(n), Some(m)) => format!("maze {n} (layout seed {m})"),
                _ => self.env.name().to_string(),
            },
            self.seed,
            self.env_steps,
            self.episodes,
            seconds,
            self.env_steps as f64 / seconds.max(1e-9),
            self.final_success,
            self.best_success,
            self.visited_bins,
            visit_bin
        )
    }
}
