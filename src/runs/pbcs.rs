//! `pbcs run`: PBCS — phase 1, phase 2, the chain's evaluation — and its record.

use super::eval::{ball_circles, evaluate_chain, EvalEpisode, CHAIN_JOB};
use super::explore::write_trajectory_csv;
use super::folder::{claim, write_timing};
use super::pbcs_resume;
use crate::checkpoint::Checkpoint;
use crate::config::{Located, PbcsJob};
use crate::env::{Planar, SampleBall};
use crate::envs::EnvName;
use crate::error::Result;
use crate::nn::kernel::Kernel;
use crate::phase1::{explore, Exploration};
use crate::phase2::{
    ArchiveStarts, ChainStrategy, Failure, Phase2Inputs, Phase2Outcome, Progress, Ready,
    SkillChain, StartMode, Variant,
};
use crate::picture::{Draw, PictureData, RunPicture};
use crate::record::{write_csv, write_record};
use crate::rng::{Seeds, Stream};
use crate::validate::Valid;
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// The per-run record of PBCS (`record.csv` of `pbcs run`): its counts, τ's lengths and ε. A
/// sweep keeps it as a [`crate::experiment::RawRow`] ([`crate::experiment::RawRow::pbcs`]).
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct RunRecord {
    /// Maze size N (empty for another environment).
    pub maze: Option<usize>,
    /// Maze layout seed (empty for another environment).
    pub maze_seed: Option<u64>,
    /// Run seed.
    pub seed: u64,
    /// `pbcs` or `pbcs_no_chaining`.
    pub variant: Variant,
    /// [`crate::learner::LearnerConfig::record_name`]: `ddpg`, `td3`, with `_am` for the
    /// argmax actor; `sac`.
    pub learner: crate::learner::LearnerName,
    /// `ball`, `exact` or `archive` starts.
    pub starts: StartMode,
    /// γ of the learner.
    pub gamma: f32,
    /// ε.
    pub epsilon: f32,
    /// Whether the chain reaches the target in at least [`super::SOLVED_AT`] of the evaluation
    /// episodes and phase 2 did not stop early ([`crate::stats::solved`]).
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
    /// The environment ([`EnvName`]; the last column, so the others keep their places).
    pub env: EnvName,
}

/// One PBCS run's outcome ([`PbcsRun::compute`]): the record, τ, the chain and its trace,
/// the evaluation's rollouts; [`PbcsRun::write`] writes it.
#[derive(Debug, Clone)]
pub struct PbcsRun<E: Planar> {
    /// The environment solved.
    pub env: E,
    /// The `record.csv` row.
    pub record: RunRecord,
    /// What phase 1 found (τ and the archive).
    pub found: Exploration<E::State>,
    /// The trajectory phase 2 worked on (τ, or τ shortened).
    pub tau: Vec<E::State>,
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

impl<E: Planar> PbcsRun<E> {
    /// Refuses, before any work, a `job` that needs a hook `env` lacks: phase 2's
    /// ([`crate::phase2::Phase2Config::require_hooks`]) and the evaluation's starts in
    /// B_ε(s_0) (ball starts). Returns phase 2's settings checked against `env`.
    pub fn require_hooks<'j>(env: &E, job: &'j Valid<PbcsJob>) -> Result<Ready<'j, E>> {
        let ready = job.phase2.ready_checked(env)?;
        crate::env::Capability::SampleBall
            .require(env, "phase2.epsilon (the evaluation's B_ε(s_0))")?;
        Ok(ready)
    }

    /// Runs PBCS for `job` on `env` (the environment `job` names: [`run_pbcs`] and
    /// [`run_outcome`] make it from the name): phase 1, phase 2
    /// ([`crate::phase2::Phase2Run`], with the archive's starts when the job
    /// asks for them), then the chain's evaluation from starts uniform in B_ε(s_0), every
    /// network on `kernel`. A hook `env` lacks is refused before phase 1
    /// ([`PbcsRun::require_hooks`]). `progress(skill, report)` is called during phase 2.
    /// Writes nothing.
    pub fn compute(
        env: E,
        job: &Valid<PbcsJob>,
        kernel: Kernel,
        progress: impl FnMut(usize, Progress),
    ) -> Result<PbcsRun<E>> {
        let ready = Self::require_hooks(&env, job)?;
        let run = Self::compute_ready(env, job, ready, kernel, None, progress)?;
        Ok(run.expect("a run without a checkpoint does not stop"))
    }

    /// [`PbcsRun::compute`], saved to `checkpoint` between phase 2's steps (learning problems,
    /// verifications of the chain, tests of a goal-conditioned chain) and resumed from it where
    /// it holds a run of this job ([`super::pbcs_resume`]): the same bytes as an uncut run, the
    /// wall clock counting the earlier processes' up to their last save. `None`
    /// when the run stopped at the checkpoint's deadline ([`Checkpoint::stop_at`]), saved: run
    /// it again to go on. The checkpoint is left in place (delete it,
    /// [`Checkpoint::remove`], once the results are written).
    pub fn compute_resumable(
        env: E,
        job: &Valid<PbcsJob>,
        kernel: Kernel,
        checkpoint: &Checkpoint,
        progress: impl FnMut(usize, Progress),
    ) -> Result<Option<PbcsRun<E>>> {
        let ready = Self::require_hooks(&env, job)?;
        Self::compute_ready(env, job, ready, kernel, Some(checkpoint), progress)
    }

    /// [`PbcsRun::compute_resumable`] with the hooks checked ([`PbcsRun::require_hooks`]),
    /// and without a checkpoint where `checkpoint` is `None`.
    fn compute_ready(
        env: E,
        job: &Valid<PbcsJob>,
        ready: Ready<'_, E>,
        kernel: Kernel,
        checkpoint: Option<&Checkpoint>,
        progress: impl FnMut(usize, Progress),
    ) -> Result<Option<PbcsRun<E>>> {
        let seeds = Seeds::new(job.seed);
        let clock = Instant::now();
        let mut rng = seeds.stream(Stream::Explore);
        let found = explore(&env, &job.explore, &mut rng, |_, _| {})?;
        let tau = crate::phase2::phase2_trajectory(&env, &found.trajectory, &job.phase2)?.states;
        // Backplay's starts from the archive, where `phase2.start = "archive"` asks.
        let archived = (job.phase2.start == StartMode::Archive)
            .then(|| ArchiveStarts::new(&env, &found.archive, job.phase2.epsilon));
        let hash =
            checkpoint.map(|_| pbcs_resume::tau_sha256(&crate::env::observations(&env, &tau)));
        let inputs = Phase2Inputs::new(&env, &tau, ready, &job.learner, &seeds, kernel)
            .after(found.env_steps)
            .with_starts(archived.as_ref().map(|a| a as &dyn SampleBall<E::State>));
        let mut progress = progress;
        let (phase2, saver) = match &job.phase2.chain {
            ChainStrategy::PerSkill => {
                let (from, earlier) =
                    pbcs_resume::loaded(checkpoint, &hash, |c, h| pbcs_resume::load(c, h, kernel))?;
                let mut saver = pbcs_resume::saver_for(checkpoint, &hash, kernel, earlier, clock);
                let outcome = pbcs_resume::per_skill(inputs, from, saver.as_mut(), &mut progress)?;
                (outcome, saver)
            }
            ChainStrategy::GoalConditioned(settings) => {
                let (from, earlier) = pbcs_resume::loaded(checkpoint, &hash, |c, h| {
                    pbcs_resume::load_goal_conditioned(c, h, kernel)
                })?;
                let mut saver = pbcs_resume::saver_for(checkpoint, &hash, kernel, earlier, clock);
                let outcome = pbcs_resume::goal_conditioned(
                    inputs,
                    settings,
                    from,
                    saver.as_mut(),
                    &mut progress,
                )?;
                (outcome, saver)
            }
        };
        let Some(phase2) = phase2 else {
            return Ok(None);
        };
        // Evaluation: episodes from starts uniform in B_ε(s_0) (or drawn: `first_starts`),
        // stream Eval.
        let (evaluation, rollouts) = if phase2.failure.is_none() && !phase2.chain.skills.is_empty()
        {
            evaluate_chain(&env, &phase2.chain, job, job.phase2.eval_episodes, job.seed)?
        } else {
            (Vec::new(), Vec::new())
        };
        let seconds = saver.map_or(clock.elapsed().as_secs_f64(), |s| s.seconds());
        let wins = evaluation.iter().filter(|e| e.success).count();
        let success_rate = wins as f32 / job.phase2.eval_episodes as f32;
        let record = RunRecord::new(job, &found, &phase2, tau.len(), success_rate);
        let xy = |v: &[E::State]| -> Vec<(f32, f32)> { v.iter().map(|s| env.point(s)).collect() };
        let picture = PictureData {
            tau_paths: vec![xy(&tau)],
            rollout_paths: rollouts.iter().map(|r| xy(r)).collect(),
            circles: ball_circles(&env, &phase2.chain),
            ..PictureData::default()
        };
        Ok(Some(PbcsRun {
            env,
            record,
            found,
            tau,
            phase2,
            evaluation,
            picture,
            kernel,
            seconds,
        }))
    }

    /// Writes into `out`: `record.csv`, `skills.csv` (one row per skill: K, T, ball),
    /// `trace.csv` (every test, training round and verification: skill, K, T, event, success,
    /// env steps) with its wall clock in `trace.timing.csv`, `trajectory.csv`, `chain/` (the
    /// saved chain, with the job as `chain/run.toml`), `picture.csv`, `timing.toml` and
    /// what `draw` draws of the picture (`run.png`, `run.svg` with [`crate::plot::draw_run`]),
    /// all of them or none ([`crate::record::write_run_folder`]: a failure, a
    /// full disk say, leaves `out` as it was, an earlier finished run included, or marked
    /// incomplete, which `pbcs eval` refuses).
    pub fn write(&self, job: &PbcsJob, out: &Path, draw: Draw) -> Result<()> {
        crate::record::write_run_folder(out, |dir| self.write_files(job, dir, draw))
    }

    fn write_files(&self, job: &PbcsJob, out: &Path, draw: Draw) -> Result<()> {
        let (record, phase2) = (&self.record, &self.phase2);
        write_record(&out.join("record.csv"), record)?;
        write_trajectory_csv(&self.env, &self.found, &out.join("trajectory.csv"))?;
        write_skills_csv(&phase2.chain, &out.join("skills.csv"))?;
        crate::record::write_records(&out.join("trace.csv"), &phase2.trace)?;
        crate::record::write_records(&out.join("evaluation.csv"), &self.evaluation)?;
        write_csv(
            &out.join("trace.timing.csv"),
            &["seconds".to_string()],
            phase2.trace.iter().map(|r| [format!("{:.3}", r.seconds)]),
        )?;
        // The chain folder describes itself: the job (maze, ε, evaluation settings) beside the
        // manifest, so `pbcs eval --chain DIR` needs nothing else; the manifest records its
        // SHA-256 and each policy file's.
        let job_text = crate::validate::to_toml(job, &out.join("chain").join(CHAIN_JOB))?;
        phase2.chain.save_with_job(
            &out.join("chain"),
            Some((CHAIN_JOB, &job_text)),
            Some(record.phase2_trajectory_len),
        )?;
        self.picture.write_csv(&out.join("picture.csv"))?;
        let title = format!(
            "{} {}, {}, seed {}: {} steps, {} skills, chain success {:.0} %",
            record.variant.name(),
            record.learner,
            job.env_spec().label(),
            job.seed,
            record.total_steps,
            record.skills,
            100.0 * record.success_rate
        );
        draw(
            &RunPicture {
                stem: "run".into(),
                title,
                scene: self.env.scene(),
                data: &self.picture,
            },
            out,
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
    fn new<S>(
        job: &PbcsJob,
        found: &Exploration<S>,
        phase2: &Phase2Outcome,
        phase2_trajectory_len: usize,
        success_rate: f32,
    ) -> RunRecord {
        let lc = &job.learner;
        let (maze, maze_seed) = job.env_spec().maze_columns();
        RunRecord {
            env: job.env,
            maze,
            maze_seed,
            seed: job.seed,
            variant: job.phase2.variant(),
            learner: lc.record_name(),
            starts: job.phase2.start,
            gamma: lc.gamma(),
            epsilon: job.phase2.epsilon,
            solved: crate::stats::solved(phase2.failure.is_some(), success_rate),
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

/// Runs PBCS for `job` into `out` on the environment it names ([`crate::envs`]): refuses a
/// setting the environment lacks a hook for ([`PbcsRun::require_hooks`]), claims the folder
/// (writing `config.toml`) before any work, then [`PbcsRun::compute_resumable`] and
/// [`PbcsRun::write`] with the drawing step `draw` ([`crate::plot::draw_run`], or
/// [`crate::picture::no_pictures`]). `progress(skill, report)` is called during phase 2.
///
/// The run saves itself to `out/run.resume` ([`RUN_CHECKPOINT`], [`super::pbcs_resume`])
/// every ten minutes, between two of phase 2's steps, and the same call into the same folder
/// goes on from there (the bytes of a run never cut); the file goes once the run's files are
/// written. With a deadline `stop_at` it stops, saved, at the end of its first step at or past
/// it that leaves another to make, and returns `None`.
pub fn run_pbcs_until(
    job: &Valid<PbcsJob>,
    kernel: Kernel,
    out: &Path,
    draw: Draw,
    stop_at: Option<Instant>,
    progress: impl FnMut(usize, Progress),
) -> Result<Option<(RunRecord, f64)>> {
    crate::with_env!(job.env_spec().build()?, |env| {
        let ready = PbcsRun::require_hooks(&env, job)?;
        let _lock = claim(job, out)?;
        let config = crate::validate::to_toml(&**job, &out.join("config.toml"))?;
        let checkpoint = Checkpoint {
            stop_at,
            ..Checkpoint::new(out.join(RUN_CHECKPOINT), config)
        };
        let computed =
            PbcsRun::compute_ready(env, job, ready, kernel, Some(&checkpoint), progress)?;
        match computed {
            None => Ok(None),
            Some(run) => {
                run.write(job, out, draw)?;
                if let Err(e) = checkpoint.remove() {
                    eprintln!("warning: a finished run's checkpoint stays: {e}");
                }
                Ok(Some((run.record, run.seconds)))
            }
        }
    })
}

/// The file of `out` a run of [`run_pbcs_until`] saves itself to.
pub const RUN_CHECKPOINT: &str = "run.resume";

/// [`run_pbcs_until`] without a deadline: runs PBCS for `job` into `out` (resuming from
/// `out/run.resume` where an earlier call of the same job was cut).
pub fn run_pbcs(
    job: &Valid<PbcsJob>,
    kernel: Kernel,
    out: &Path,
    draw: Draw,
    progress: impl FnMut(usize, Progress),
) -> Result<(RunRecord, f64)> {
    let done = run_pbcs_until(job, kernel, out, draw, None, progress)?;
    Ok(done.expect("a run without a deadline does not stop"))
}

/// What a sweep keeps of a run ([`run_outcome`]), whatever its environment.
#[derive(Debug, Clone)]
pub struct RunOutcome {
    /// The `record.csv` row.
    pub record: RunRecord,
    /// The chain's evaluation episodes (none when phase 2 failed).
    pub evaluation: Vec<EvalEpisode>,
    /// What the run's picture draws.
    pub picture: PictureData,
    /// Wall-clock seconds of the run (not deterministic).
    pub seconds: f64,
}

impl<E: Planar> From<PbcsRun<E>> for RunOutcome {
    fn from(run: PbcsRun<E>) -> RunOutcome {
        RunOutcome {
            record: run.record,
            evaluation: run.evaluation,
            picture: run.picture,
            seconds: run.seconds,
        }
    }
}

/// [`PbcsRun::compute`] on the environment `job` names: what an experiment's (cell, seed)
/// runs.
pub fn run_outcome(
    job: &Valid<PbcsJob>,
    kernel: Kernel,
    progress: impl FnMut(usize, Progress),
) -> Result<RunOutcome> {
    crate::with_env!(job.env_spec().build()?, |env| {
        PbcsRun::compute(env, job, kernel, progress).map(RunOutcome::from)
    })
}

/// [`run_outcome`] saved to and resumed from `checkpoint` ([`PbcsRun::compute_resumable`]):
/// `None` when it stopped at the checkpoint's deadline, saved.
pub fn run_outcome_resumable(
    job: &Valid<PbcsJob>,
    kernel: Kernel,
    checkpoint: &Checkpoint,
    progress: impl FnMut(usize, Progress),
) -> Result<Option<RunOutcome>> {
    crate::with_env!(job.env_spec().build()?, |env| {
        let run = PbcsRun::compute_resumable(env, job, kernel, checkpoint, progress)?;
        Ok(run.map(RunOutcome::from))
    })
}

/// `skills.csv`: one row per skill in execution order: index, K (start index on τ), T (target
/// index), ball centre (its first two coordinates: the position; a ball in position and
/// velocity keeps its whole centre and weights in the chain's `manifest.toml`) and radius.
pub(crate) fn write_skills_csv(chain: &SkillChain, path: &Path) -> Result<()> {
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

impl RunRecord {
    /// What `pbcs run` prints: the outcome (over `eval_episodes` evaluation episodes) and where
    /// the environment steps went, with the wall clock `seconds`.
    /// A chain is evaluated only when phase 2 ended without a failure ([`PbcsRun`]); else
    /// no episode ran, and it says so.
    pub fn summary(&self, eval_episodes: usize, seconds: f64) -> String {
        let success = if self.failure.is_none() && self.skills > 0 {
            format!(
                "chain success {:.0} % over {eval_episodes} episodes",
                100.0 * self.success_rate
            )
        } else {
            "chain not evaluated".to_string()
        };
        format!(
            "{} ({}) on {}, run seed {}: {} — {success}, {} \
             skills{}\nenv steps: phase 1 {}, training {}, tests {}, total {}; |τ| = {}; {:.1} s",
            self.variant.name(),
            self.learner,
            match (self.maze, self.maze_seed) {
                (Some(n), Some(m)) => format!("maze {n} (layout seed {m})"),
                _ => self.env.name().to_string(),
            },
            self.seed,
            if self.solved { "SOLVED" } else { "not solved" },
            self.skills,
            self.failure
                .map_or(String::new(), |f| format!(", stopped: {}", f.name())),
            self.phase1_steps,
            self.train_steps,
            self.test_steps,
            self.total_steps,
            self.trajectory_len,
            seconds
        )
    }
}

/// Phase 2's progress as `pbcs run` shows it ([`Phase2Progress::report`], the `progress` of
/// [`run_pbcs_until`]): a spinner with the learning problem under way, its K, T, last event
/// and env steps per second; without a terminal (logs, CI, cluster jobs), where the spinner is
/// hidden, a line per skill attempt (a skill saved, dropped or restarted) and the status every
/// [`Phase2Progress::LOG_EVERY`] seconds.
pub struct Phase2Progress {
    bar: indicatif::ProgressBar,
    lines: bool,
    clock: Instant,
    /// Steps of the skill attempts already finished, and the running one's latest count.
    finished: u64,
    current: u64,
    current_skill: usize,
    logged: f64,
}

impl Phase2Progress {
    /// Seconds between two status lines without a terminal.
    pub const LOG_EVERY: f64 = 30.0;

    /// Shown on `bar`; with `lines`, also as lines on standard error.
    pub fn new(bar: indicatif::ProgressBar, lines: bool) -> Self {
        Phase2Progress {
            bar,
            lines,
            clock: Instant::now(),
            finished: 0,
            current: 0,
            current_skill: 0,
            logged: 0.0,
        }
    }

    /// A report of learning problem `skill`.
    pub fn report(&mut self, skill: usize, p: Progress) {
        let secs = self.clock.elapsed().as_secs_f64();
        if skill != self.current_skill {
            (self.finished, self.current_skill) = (self.finished + self.current, skill);
            if self.lines {
                eprintln!(
                    "[{secs:.0} s] {skill} skill attempts done, attempt {} starts; {} phase-2 \
                     env steps so far",
                    skill + 1,
                    self.finished
                );
            }
        }
        self.current = p.steps.train + p.steps.test;
        let total = self.finished + self.current;
        let status = p.status(skill, total, total as f64 / secs.max(1e-9));
        if self.lines && secs >= self.logged + Self::LOG_EVERY {
            self.logged = secs;
            eprintln!("[{secs:.0} s] {status}");
        }
        self.bar.set_message(status);
        self.bar.tick();
    }

    /// Clears the spinner.
    pub fn finish(self) {
        self.bar.finish_and_clear();
    }
}
