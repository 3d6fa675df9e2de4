//! Runs: a validated job in, an outcome out. Each kind of run is a type whose `compute` is a
//! function from the job to the outcome that writes nothing ([`ExploreRun`], [`TrainRun`],
//! [`PbcsRun`]), and whose `write` puts the outcome into a folder (CSVs, pictures, the saved
//! chain). [`run_explore`], [`run_train`] and [`run_pbcs`] claim a folder, compute and write:
//! the CLI's subcommands are thin wrappers around them, so tests exercise exactly what users
//! run; the sweep ([`crate::experiment::run_cell_seed`]) computes and keeps only its raw files.
//!
//! Result files are CSV (deterministic: same config, same bytes) written atomically; the
//! wall-clock time of a job lives beside them in `timing.toml`, never inside a CSV.

use crate::config::{ExploreJob, RunJob, TrainJob};
use crate::env::Env;
use crate::error::{Error, Result};
use crate::explore::{explore, Exploration, NO_PARENT};
use crate::maze::Maze;
use crate::nn::kernel::Kernel;
use crate::phase2::{chain_skills, Failure, Phase2Outcome, Progress, SkillChain, StartMode};
use crate::plot::{render_maze, MazePicture, PictureData, SVG_MAX_POINTS};
use crate::record::{write_atomic, write_csv, write_record};
use crate::rng::{Seeds, Stream};
use crate::train::train_vanilla;
use crate::validate::Check;
use parry2d::math::Point;
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// The one-row summary of a phase-1 run (`summary.csv`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExploreSummary {
    /// Maze size N.
    pub maze: usize,
    /// Maze layout seed.
    pub maze_seed: u64,
    /// Run seed.
    pub seed: u64,
    /// Environment steps phase 1 used.
    pub env_steps: u64,
    /// Number of states of τ (N + 1).
    pub trajectory_len: usize,
    /// States in the archive when the target was reached.
    pub archive_states: usize,
    /// Non-empty bins of the archive.
    pub archive_bins: usize,
}

/// A run counts as solved when its evaluation (greedy episodes of a vanilla policy, or of a
/// PBCS chain) reaches the target in at least this fraction of episodes.
pub const SOLVED_AT: f32 = 0.95;

/// One phase-1 run's outcome ([`ExploreRun::compute`]): the summary row, everything
/// exploration found and the wall-clock seconds; [`ExploreRun::write`] writes it.
#[derive(Debug, Clone)]
pub struct ExploreRun {
    /// The maze explored.
    pub maze: Maze,
    /// The one-row summary.
    pub summary: ExploreSummary,
    /// τ and the archive.
    pub found: Exploration<Point<f32>>,
    /// Wall-clock seconds of the run (not deterministic).
    pub seconds: f64,
}

impl ExploreRun {
    /// Runs phase 1 for `job`; `progress(steps, archive_len)` is called during the run.
    /// Writes nothing.
    pub fn compute(job: &ExploreJob, progress: impl FnMut(u64, usize)) -> Result<ExploreRun> {
        job.check()?;
        let maze = Maze::new(&job.maze)?;
        let mut rng = Seeds::new(job.seed).stream(Stream::Explore);
        let clock = Instant::now();
        let found = explore(&maze, &job.explore, &mut rng, progress)?;
        let seconds = clock.elapsed().as_secs_f64();
        let summary = ExploreSummary {
            maze: job.maze.size,
            maze_seed: job.maze.seed,
            seed: job.seed,
            env_steps: found.env_steps,
            trajectory_len: found.trajectory.len(),
            archive_states: found.archive.len(),
            archive_bins: found.archive.bins(),
        };
        Ok(ExploreRun {
            maze,
            summary,
            found,
            seconds,
        })
    }

    /// Writes into `out`: `summary.csv`, `trajectory.csv`, `archive.csv`, `explore.png`,
    /// `explore.svg` and `timing.toml`.
    pub fn write(&self, job: &ExploreJob, out: &Path) -> Result<()> {
        let (maze, found) = (&self.maze, &self.found);
        write_record(&out.join("summary.csv"), &self.summary)?;
        write_trajectory_csv(maze, found, &out.join("trajectory.csv"))?;
        write_archive_csv(maze, found, &out.join("archive.csv"))?;
        render_exploration(maze, found, job, out)?;
        write_timing(
            &out.join("timing.toml"),
            self.seconds,
            found.env_steps,
            None,
        )
    }
}

/// Runs phase 1 for `job` into `out`: claims the folder (writing `config.toml`, the resolved
/// job) before any work, then [`ExploreRun::compute`] and [`ExploreRun::write`].
/// `progress(steps, archive_len)` is called during the run.
pub fn run_explore(
    job: &ExploreJob,
    out: &Path,
    progress: impl FnMut(u64, usize),
) -> Result<(ExploreSummary, f64)> {
    job.check()?;
    claim(job, out)?;
    let run = ExploreRun::compute(job, progress)?;
    run.write(job, out)?;
    Ok((run.summary, run.seconds))
}

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

/// `trajectory.csv`: `t, x, y, a0, a1`, where `(a0, a1)` led from τ_t to τ_{t+1} (empty on
/// the last row).
fn write_trajectory_csv(maze: &Maze, found: &Exploration<Point<f32>>, path: &Path) -> Result<()> {
    let mut header = vec!["t".to_string()];
    header.extend(maze.obs_names());
    header.extend((0..maze.action_dim()).map(|i| format!("a{i}")));
    let tau = &found.trajectory;
    let rows = tau.states.iter().enumerate().map(|(t, s)| {
        let mut row = vec![t.to_string(), s.x.to_string(), s.y.to_string()];
        match tau.actions.get(t) {
            Some(a) => row.extend(a.iter().map(f32::to_string)),
            None => row.extend((0..maze.action_dim()).map(|_| String::new())),
        }
        row
    });
    write_csv(path, &header, rows)
}

/// `archive.csv`: `id, parent, state_usage, bin_usage, x, y` (parent empty for s_0).
fn write_archive_csv(maze: &Maze, found: &Exploration<Point<f32>>, path: &Path) -> Result<()> {
    let mut header: Vec<String> = ["id", "parent", "state_usage", "bin_usage"]
        .map(String::from)
        .to_vec();
    header.extend(maze.obs_names());
    let archive = &found.archive;
    let rows = (0..archive.len() as u32).map(|id| {
        let s = archive.state(id);
        let parent = archive.parent(id);
        let (cs, cb) = archive.usage(id);
        [
            id.to_string(),
            if parent == NO_PARENT {
                String::new()
            } else {
                parent.to_string()
            },
            cs.to_string(),
            cb.to_string(),
            s.x.to_string(),
            s.y.to_string(),
        ]
    });
    write_csv(path, &header, rows)
}

fn render_exploration(
    maze: &Maze,
    found: &Exploration<Point<f32>>,
    job: &ExploreJob,
    out: &Path,
) -> Result<()> {
    let points: Vec<(f32, f32)> = (0..found.archive.len() as u32)
        .map(|i| {
            let s = found.archive.state(i);
            (s.x, s.y)
        })
        .collect();
    let path: Vec<(f32, f32)> = found.trajectory.states.iter().map(|s| (s.x, s.y)).collect();
    let picture = MazePicture {
        title: format!(
            "phase 1, maze {} (layout {}), seed {}: {} steps, |τ| = {}",
            job.maze.size,
            job.maze.seed,
            job.seed,
            found.env_steps,
            found.trajectory.len()
        ),
        points: &points,
        red_paths: vec![&path],
        ..MazePicture::default()
    };
    render_maze(
        maze,
        &picture,
        &out.join("explore.png"),
        &out.join("explore.svg"),
        SVG_MAX_POINTS,
    )
}

/// The one-row summary of a vanilla training run (`summary.csv`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrainSummary {
    /// Maze size N.
    pub maze: usize,
    /// Maze layout seed.
    pub maze_seed: u64,
    /// Run seed.
    pub seed: u64,
    /// `ddpg` or `td3`.
    pub algo: String,
    /// `gradient` or `argmax`.
    pub actor_update: String,
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
    pub result: crate::train::TrainOutcome,
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
            algo: job.learner.algo.name().to_string(),
            actor_update: job.learner.actor_update.name().to_string(),
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

    /// Writes into `out`: `summary.csv`, `evals.csv` (one row per evaluation), `visited.csv`
    /// (lower-left corners of visited bins), `actor.safetensors`, `picture.csv`, `train.png`,
    /// `train.svg`, `timing.toml`.
    pub fn write(&self, job: &TrainJob, out: &Path) -> Result<()> {
        let summary = &self.summary;
        write_record(&out.join("summary.csv"), summary)?;
        crate::record::write_records(&out.join("evals.csv"), &self.result.evals)?;
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
            summary.algo,
            job.maze.size,
            job.maze.seed,
            job.seed,
            job.train.steps,
            100.0 * summary.final_success
        );
        render_maze(
            &self.maze,
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

/// The per-run record of PBCS (`record.csv` of `pbcs run`): its counts, τ's lengths and ε. A
/// sweep keeps it as a [`crate::experiment::RawRow`] ([`crate::experiment::RawRow::pbcs`]).
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct RunRecord {
    /// Maze size N.
    pub maze: usize,
    /// Maze layout seed.
    pub maze_seed: u64,
    /// Run seed.
    pub seed: u64,
    /// `pbcs` or `pbcs_no_chaining`.
    pub variant: Variant,
    /// [`crate::learner::LearnerConfig::record_name`]: `ddpg`, `td3`, with `_am` for the
    /// argmax actor.
    pub learner: String,
    /// `ball` or `exact` starts.
    pub starts: StartMode,
    /// γ of the learner.
    pub gamma: f32,
    /// ε.
    pub epsilon: f32,
    /// Whether the chain reaches the target in at least [`SOLVED_AT`] of the evaluation episodes.
    pub solved: bool,
    /// Fraction of evaluation episodes that reached the target.
    pub success_rate: f32,
    /// Why phase 2 stopped early (`backplay_failed`, `no_chaining`, `budget`), or empty.
    pub failure: Option<Failure>,
    /// Environment steps of phase 1.
    pub phase1_steps: u64,
    /// Environment steps of phase-2 training episodes.
    pub train_steps: u64,
    /// Environment steps of Backplay's tests.
    pub test_steps: u64,
    /// phase1 + train + test (evaluation episodes are not counted).
    pub total_steps: u64,
    /// Skills in the chain.
    pub skills: usize,
    /// States of the phase-1 trajectory τ.
    pub trajectory_len: usize,
    /// States of the trajectory phase 2 worked on (τ, or τ shortened).
    pub phase2_trajectory_len: usize,
}

/// Which PBCS a record comes from (`phase2.chaining`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Variant {
    /// PBCS: skill chaining on.
    Pbcs,
    /// PBCS without skill chaining (the paper's ablation).
    PbcsNoChaining,
}

impl Variant {
    /// Its name in records and messages (its serde name): `pbcs`, `pbcs_no_chaining`.
    pub fn name(self) -> &'static str {
        match self {
            Variant::Pbcs => "pbcs",
            Variant::PbcsNoChaining => "pbcs_no_chaining",
        }
    }
}

/// Chain rollouts drawn in the picture.
const DRAWN_ROLLOUTS: usize = 10;

/// One PBCS run's outcome ([`PbcsRun::compute`]): the record, τ, the chain and its trace,
/// the evaluation's rollouts; [`PbcsRun::write`] writes it.
#[derive(Debug, Clone)]
pub struct PbcsRun {
    /// The maze solved.
    pub maze: Maze,
    /// The `record.csv` row.
    pub record: RunRecord,
    /// What phase 1 found (τ and the archive).
    pub found: Exploration<Point<f32>>,
    /// The trajectory phase 2 worked on (τ, or τ shortened).
    pub tau: Vec<Point<f32>>,
    /// The chain, its step counts and Backplay's trace.
    pub phase2: Phase2Outcome,
    /// The chain's evaluation episodes (none when phase 2 failed).
    pub evaluation: Vec<EvalEpisode>,
    /// What `run.png` draws: τ, the first evaluation rollouts, the activation balls.
    pub picture: PictureData,
    /// The layer kernel the learners and the chain ran on.
    pub kernel: Kernel,
    /// Wall-clock seconds of the run (not deterministic).
    pub seconds: f64,
}

impl PbcsRun {
    /// Runs PBCS for `job`: phase 1, phase 2 ([`chain_skills`]), then the chain's evaluation
    /// from starts uniform in B_ε(s_0), every network on `kernel`. `progress(skill, report)`
    /// is called during phase 2. Writes nothing.
    pub fn compute(
        job: &RunJob,
        kernel: Kernel,
        progress: impl FnMut(usize, Progress),
    ) -> Result<PbcsRun> {
        job.check()?;
        let maze = Maze::new(&job.maze)?;
        let seeds = Seeds::new(job.seed);
        let clock = Instant::now();
        let mut rng = seeds.stream(Stream::Explore);
        let found = explore(&maze, &job.explore, &mut rng, |_, _| {})?;
        let tau = crate::phase2::phase2_trajectory(&maze, &found.trajectory, &job.phase2).states;
        let phase2 = chain_skills(
            &maze,
            &tau,
            &job.learner,
            &job.phase2,
            &seeds,
            found.env_steps,
            kernel,
            progress,
        )?;
        // Evaluation: episodes from starts uniform in B_ε(s_0), stream Eval.
        let (evaluation, rollouts) = if phase2.failure.is_none() && !phase2.chain.skills.is_empty()
        {
            evaluate_chain(
                &maze,
                &phase2.chain,
                job,
                job.phase2.eval_episodes,
                job.seed,
            )
        } else {
            (Vec::new(), Vec::new())
        };
        let seconds = clock.elapsed().as_secs_f64();
        let wins = evaluation.iter().filter(|e| e.success).count();
        let success_rate = wins as f32 / job.phase2.eval_episodes as f32;
        let record = RunRecord::new(job, &found, &phase2, tau.len(), success_rate);
        let xy = |v: &[Point<f32>]| -> Vec<(f32, f32)> { v.iter().map(|p| (p.x, p.y)).collect() };
        let picture = PictureData {
            red_paths: vec![xy(&tau)],
            green_paths: rollouts.iter().map(|r| xy(r)).collect(),
            circles: ball_circles(&phase2.chain),
            ..PictureData::default()
        };
        Ok(PbcsRun {
            maze,
            record,
            found,
            tau,
            phase2,
            evaluation,
            picture,
            kernel,
            seconds,
        })
    }

    /// Writes into `out`: `record.csv`, `skills.csv` (one row per skill: K, T, ball),
    /// `trace.csv` (every test, training round and verification: skill, K, T, event, success,
    /// env steps) with its wall clock in `trace.timing.csv`, `trajectory.csv`, `chain/` (the
    /// saved chain, with the job as `chain/run.toml`), `picture.csv`, `run.png`, `run.svg`,
    /// `timing.toml`.
    pub fn write(&self, job: &RunJob, out: &Path) -> Result<()> {
        let (record, phase2) = (&self.record, &self.phase2);
        write_record(&out.join("record.csv"), record)?;
        write_trajectory_csv(&self.maze, &self.found, &out.join("trajectory.csv"))?;
        write_skills_csv(&phase2.chain, &out.join("skills.csv"))?;
        crate::record::write_records(&out.join("trace.csv"), &phase2.trace)?;
        crate::record::write_records(&out.join("evaluation.csv"), &self.evaluation)?;
        write_csv(
            &out.join("trace.timing.csv"),
            &["seconds".to_string()],
            phase2.trace.iter().map(|r| [format!("{:.3}", r.seconds)]),
        )?;
        phase2.chain.save(&out.join("chain"))?;
        // The chain folder describes itself: the job (maze, ε, evaluation settings) beside the
        // manifest, so `pbcs eval --chain DIR` needs nothing else.
        let job_text = crate::validate::to_toml(job, &out.join("chain").join(CHAIN_JOB))?;
        write_atomic(&out.join("chain").join(CHAIN_JOB), |w| {
            w.write_all(job_text.as_bytes())
        })?;
        self.picture.write_csv(&out.join("picture.csv"))?;
        let title = format!(
            "{} {}, maze {} (layout {}), seed {}: {} steps, {} skills, chain success {:.0} %",
            record.variant.name(),
            record.learner,
            job.maze.size,
            job.maze.seed,
            job.seed,
            record.total_steps,
            record.skills,
            100.0 * record.success_rate
        );
        render_maze(
            &self.maze,
            &self.picture.picture(title),
            &out.join("run.png"),
            &out.join("run.svg"),
            SVG_MAX_POINTS,
        )?;
        write_timing(
            &out.join("timing.toml"),
            self.seconds,
            record.total_steps,
            Some(self.kernel),
        )
    }
}

impl RunRecord {
    /// The record of `job` from what its run found.
    fn new(
        job: &RunJob,
        found: &Exploration<Point<f32>>,
        phase2: &Phase2Outcome,
        phase2_trajectory_len: usize,
        success_rate: f32,
    ) -> RunRecord {
        let lc = &job.learner;
        RunRecord {
            maze: job.maze.size,
            maze_seed: job.maze.seed,
            seed: job.seed,
            variant: if job.phase2.chaining {
                Variant::Pbcs
            } else {
                Variant::PbcsNoChaining
            },
            learner: lc.record_name(),
            starts: job.phase2.start,
            gamma: lc.gamma,
            epsilon: job.phase2.epsilon,
            solved: phase2.failure.is_none() && success_rate >= SOLVED_AT,
            success_rate,
            failure: phase2.failure,
            phase1_steps: found.env_steps,
            train_steps: phase2.steps.train,
            test_steps: phase2.steps.test,
            total_steps: found.env_steps + phase2.steps.train + phase2.steps.test,
            skills: phase2.chain.skills.len(),
            trajectory_len: found.trajectory.len(),
            phase2_trajectory_len,
        }
    }
}

/// The activation balls of `chain` as drawn circles.
fn ball_circles(chain: &SkillChain) -> Vec<((f32, f32), f32)> {
    chain
        .skills
        .iter()
        .map(|s| {
            (
                (s.activation.center[0], s.activation.center[1]),
                s.activation.radius,
            )
        })
        .collect()
}

/// Runs PBCS for `job` into `out`: claims the folder (writing `config.toml`) before any work,
/// then [`PbcsRun::compute`] and [`PbcsRun::write`]. `progress(skill, report)` is called
/// during phase 2.
pub fn run_pbcs(
    job: &RunJob,
    kernel: Kernel,
    out: &Path,
    progress: impl FnMut(usize, Progress),
) -> Result<(RunRecord, f64)> {
    job.check()?;
    claim(job, out)?;
    let run = PbcsRun::compute(job, kernel, progress)?;
    run.write(job, out)?;
    Ok((run.record, run.seconds))
}

/// One evaluation episode of a chain: whether it reached the target, and in how many steps
/// (`evaluation.csv` of `pbcs run`, `s<seed>.evaluation.csv` of a sweep, `eval-s<seed>.csv` of
/// `pbcs eval`). The steps of the successful episodes are the chain's path lengths.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct EvalEpisode {
    /// The episode reached the target.
    pub success: bool,
    /// Steps taken (at most `phase2.eval_max_steps`).
    pub steps: usize,
}

/// The evaluation of a chain built for `job`: `episodes` episodes from starts uniform in
/// B_ε(s_0) drawn from the `Eval` stream of `seed`, each at most `phase2.eval_max_steps`
/// steps; the episodes and the first [`DRAWN_ROLLOUTS`] rollouts.
pub fn evaluate_chain(
    maze: &Maze,
    chain: &SkillChain,
    job: &RunJob,
    episodes: usize,
    seed: u64,
) -> (Vec<EvalEpisode>, Vec<Vec<Point<f32>>>) {
    let mut rng = Seeds::new(seed).stream(Stream::Eval);
    let mut rows = Vec::with_capacity(episodes);
    let mut rollouts = Vec::new();
    for _ in 0..episodes {
        let start = maze.sample_ball(&maze.start(), job.phase2.epsilon, &mut rng);
        let r = chain.run(maze, start, job.phase2.eval_max_steps);
        rows.push(EvalEpisode {
            success: r.success,
            steps: r.states.len() - 1,
        });
        if rollouts.len() < DRAWN_ROLLOUTS {
            rollouts.push(r.states);
        }
    }
    (rows, rollouts)
}

/// The file in a saved chain's folder that holds the job that built it.
pub const CHAIN_JOB: &str = "run.toml";

/// What `pbcs eval` measured: a saved chain re-run from starts uniform in B_ε(s_0).
#[derive(Debug, Clone)]
pub struct ChainEval {
    /// The job that built the chain (from the chain folder).
    pub job: RunJob,
    /// Skills in the chain.
    pub skills: usize,
    /// Episodes run.
    pub episodes: usize,
    /// Episodes that reached the target.
    pub successes: usize,
    /// Wilson 95 % interval of the success rate.
    pub interval: (f64, f64),
}

/// Re-runs the chain saved in `chain_dir` on the maze it was built for: `episodes` episodes
/// from starts uniform in B_ε(s_0), drawn from the `Eval` stream of `seed` (the run's own seed
/// reproduces the run's evaluation exactly), each at most `phase2.eval_max_steps` steps.
/// Writes `eval-s<seed>.csv` (one row per episode: success, steps) and `eval-s<seed>.png`/`.svg`
/// (the first rollouts over the maze) into `chain_dir`. A folder without the chain's job
/// (`run.toml`, or `../config.toml` for chains saved before it existed), a malformed manifest
/// or bad weights are errors naming the file. The policies run on `kernel`.
pub fn eval_chain(
    chain_dir: &Path,
    episodes: usize,
    seed: Option<u64>,
    kernel: Kernel,
) -> Result<ChainEval> {
    if episodes == 0 {
        return Err(Error::invalid("--episodes", "must be at least 1"));
    }
    let own = chain_dir.join(CHAIN_JOB);
    let job_path = if own.exists() {
        own
    } else {
        let parent = chain_dir.join("..").join("config.toml");
        if !parent.exists() {
            return Err(Error::io(
                &own,
                std::io::Error::other(
                    "not found: not a chain saved by `pbcs run` (it writes run.toml beside \
                     manifest.toml)",
                ),
            ));
        }
        parent
    };
    let job: RunJob = crate::validate::load(&job_path)?;
    let maze = Maze::new(&job.maze)?;
    let chain = SkillChain::load(chain_dir, kernel)?;
    let seed = seed.unwrap_or(job.seed);
    let (rows, rollouts) = evaluate_chain(&maze, &chain, &job, episodes, seed);
    let successes = rows.iter().filter(|r| r.success).count();
    let interval = crate::stats::wilson(successes as u64, episodes as u64, crate::stats::Z95);
    crate::record::write_records(&chain_dir.join(format!("eval-s{seed}.csv")), &rows)?;
    let xy = |v: &[Point<f32>]| -> Vec<(f32, f32)> { v.iter().map(|p| (p.x, p.y)).collect() };
    let data = PictureData {
        green_paths: rollouts.iter().map(|r| xy(r)).collect(),
        circles: ball_circles(&chain),
        ..PictureData::default()
    };
    let title = format!(
        "saved chain, maze {} (layout {}), eval seed {seed}: success {successes}/{episodes}",
        job.maze.size, job.maze.seed
    );
    render_maze(
        &maze,
        &data.picture(title),
        &chain_dir.join(format!("eval-s{seed}.png")),
        &chain_dir.join(format!("eval-s{seed}.svg")),
        SVG_MAX_POINTS,
    )?;
    Ok(ChainEval {
        skills: chain.skills.len(),
        job,
        episodes,
        successes,
        interval,
    })
}

/// `skills.csv`: one row per skill in execution order: index, K (start index on τ), T (target
/// index), ball centre and radius.
fn write_skills_csv(chain: &SkillChain, path: &Path) -> Result<()> {
    let header: Vec<String> = ["skill", "start_index", "target_index", "x", "y", "radius"]
        .map(String::from)
        .to_vec();
    let rows = chain.skills.iter().enumerate().map(|(i, s)| {
        [
            i.to_string(),
            s.start_index.to_string(),
            s.target_index.to_string(),
            s.activation.center[0].to_string(),
            s.activation.center[1].to_string(),
            s.activation.radius.to_string(),
        ]
    });
    write_csv(path, &header, rows)
}

/// The paper's single run of `variant` on a maze (results table, one seed each): its
/// environment steps and whether it solved the maze, from the method of that name (`pbcs`,
/// `pbcs_no_chaining`) in `experiments/table.toml`, the one place they are written (read at
/// compile time, so the binary needs no experiments folder). `(None, None)` for a size the
/// paper did not run.
///
/// ```
/// use pbcs::runs::{paper_figures, Variant};
/// assert_eq!(paper_figures(Variant::Pbcs, 2), (Some(321_000), Some(true)));
/// assert_eq!(paper_figures(Variant::PbcsNoChaining, 2), (Some(146_000), Some(false)));
/// assert_eq!(paper_figures(Variant::Pbcs, 3), (None, None));
/// ```
pub fn paper_figures(variant: Variant, maze: usize) -> (Option<u64>, Option<bool>) {
    let table: Option<toml::Table> = include_str!("../experiments/table.toml").parse().ok();
    let method = table.as_ref().and_then(|t| {
        t.get("method")?
            .as_array()?
            .iter()
            .find(|m| m.get("name").and_then(|v| v.as_str()) == Some(variant.name()))
    });
    let field = |name: &str| method.and_then(|m| m.get(name)?.get(maze.to_string()));
    (
        field("paper_steps")
            .and_then(|v| v.as_integer())
            .and_then(|v| u64::try_from(v).ok()),
        field("paper_solved").and_then(|v| v.as_bool()),
    )
}
