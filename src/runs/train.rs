//! `pbcs train`: a vanilla baseline (DDPG, TD3, argmax actor) on the maze's own reward.

use super::{claim, write_timing, SOLVED_AT};
use crate::config::TrainJob;
use crate::env::Planar;
use crate::envs::maze::Maze;
use crate::error::Result;
use crate::learner::{ActorUpdate, Algo};
use crate::nn::kernel::Kernel;
use crate::plot::{render_scene, PictureData, SVG_MAX_POINTS};
use crate::record::{write_csv, write_record};
use crate::rng::Seeds;
use crate::validate::Check;
use crate::vanilla::train_vanilla;
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// The one-row summary of a vanilla training run (`summary.csv`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrainSummary {
    /// Maze size N.
    pub maze: usize,
    /// Maze layout seed.
    pub maze_seed: u64,
    /// Run seed.
    pub seed: u64,
    /// DDPG or TD3 (`ddpg`, `td3` in `summary.csv`).
    pub algo: Algo,
    /// The actor update (`gradient`, `argmax`).
    pub actor_update: ActorUpdate,
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
    /// Environment steps at the first evaluation whose greedy success was ≥ [`SOLVED_AT`], if any.
    pub first_success_steps: Option<u64>,
}

/// One vanilla training run's outcome ([`TrainRun::compute`]); [`TrainRun::write`] writes it.
pub struct TrainRun {
    /// The maze trained on.
    pub maze: Maze,
    /// The one-row summary.
    pub summary: TrainSummary,
    /// Evaluations, visited bins, the trained learner.
    pub result: crate::vanilla::TrainOutcome,
    /// What `train.png` draws: the visited bins as red squares.
    pub picture: PictureData,
    /// The layer kernel the learner ran on.
    pub kernel: Kernel,
    /// Wall-clock seconds of the run (not deterministic).
    pub seconds: f64,
}

impl TrainRun {
    /// Trains the vanilla baseline of `job` on the maze's own reward, the learner's layers on
    /// `kernel`; `progress(steps, success)` is called at each evaluation. Writes nothing.
    pub fn compute(
        job: &TrainJob,
        kernel: Kernel,
        progress: impl FnMut(u64, f32),
    ) -> Result<TrainRun> {
        job.check()?;
        let maze = Maze::new(&job.maze)?;
        let clock = Instant::now();
        let result = train_vanilla(
            &maze,
            &job.learner,
            &job.train,
            &Seeds::new(job.seed),
            kernel,
            progress,
        )?;
        let seconds = clock.elapsed().as_secs_f64();
        let summary = TrainSummary {
            maze: job.maze.size,
            maze_seed: job.maze.seed,
            seed: job.seed,
            algo: job.learner.algo,
            actor_update: job.learner.actor_update,
            env_steps: job.train.steps,
            episodes: result.episodes,
            final_success: result.evals.last().map_or(0.0, |e| e.success),
            best_success: result.evals.iter().map(|e| e.success).fold(0.0, f32::max),
            visited_bins: result.visited.len(),
            first_success_steps: result
                .evals
                .iter()
                .find(|e| e.success >= SOLVED_AT)
                .map(|e| e.steps),
        };
        let side = job.train.visit_bin;
        let picture = PictureData {
            red_area: result
                .visited
                .iter()
                .map(|b| (b[0] as f32 * side, b[1] as f32 * side))
                .collect(),
            red_area_side: side,
            ..PictureData::default()
        };
        Ok(TrainRun {
            maze,
            summary,
            result,
            picture,
            kernel,
            seconds,
        })
    }

    /// Writes into `out`: `summary.csv`, `evals.csv` (one row per evaluation),
    /// `evaluation.csv` (PBCS's protocol after training, when `train.final_eval_episodes` asks
    /// for it: success and steps of each episode), `visited.csv`
    /// (lower-left corners of visited bins), `actor.safetensors`, `picture.csv`, `train.png`,
    /// `train.svg`, `timing.toml`, all of them or none ([`crate::record::write_run_folder`]: a
    /// failure leaves `out` as it was, or marked incomplete).
    pub fn write(&self, job: &TrainJob, out: &Path) -> Result<()> {
        crate::record::write_run_folder(out, |dir| self.write_files(job, dir))
    }

    fn write_files(&self, job: &TrainJob, out: &Path) -> Result<()> {
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
            .actor
            .save(&out.join("actor.safetensors"))?;
        self.picture.write_csv(&out.join("picture.csv"))?;
        let title = format!(
            "{} on maze {} (layout {}), seed {}: {} steps, greedy success {:.0} %",
            summary.algo.name(),
            job.maze.size,
            job.maze.seed,
            job.seed,
            job.train.steps,
            100.0 * summary.final_success
        );
        render_scene(
            &self.maze.scene(),
            &self.picture.picture(title),
            &out.join("train.png"),
            &out.join("train.svg"),
            SVG_MAX_POINTS,
        )?;
        write_timing(
            &out.join("timing.toml"),
            self.seconds,
            job.train.steps,
            Some(self.kernel),
        )
    }
}

/// Trains the vanilla baseline of `job` into `out`: claims the folder (writing
/// `config.toml`) before any work, then [`TrainRun::compute`] and [`TrainRun::write`].
pub fn run_train(
    job: &TrainJob,
    kernel: Kernel,
    out: &Path,
    progress: impl FnMut(u64, f32),
) -> Result<(TrainSummary, f64)> {
    job.check()?;
    claim(job, out)?;
    let run = TrainRun::compute(job, kernel, progress)?;
    run.write(job, out)?;
    Ok((run.summary, run.seconds))
}

impl TrainSummary {
    /// What `pbcs train` prints, with the wall clock `seconds` and the visit bins' side.
    pub fn summary(&self, seconds: f64, visit_bin: f32) -> String {
        format!(
            "{} ({} actor) on maze {} (layout seed {}), run seed {}: {} env steps, {} episodes, \
             {:.1} s ({:.0} steps/s)\ngreedy success: final {}, best {}; visited {} bins of side \
             {}",
            self.algo.name(),
            self.actor_update.name(),
            self.maze,
            self.maze_seed,
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
