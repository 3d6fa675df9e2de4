//! Checkpoints of a vanilla run: its whole state saved now and then, so that a run cut short
//! (a session's end, a killed process) goes on where it was saved and ends with the same bytes
//! as a run never cut.
//!
//! A checkpoint holds the learner's state ([`crate::learner::Learner::save_state`]: weights,
//! targets, optimiser moments, the update stream's position) and the rest of the run's (the
//! replay buffer, the generators' positions, the environment's state, the episode so far, the
//! evaluations and visited bins), postcard-encoded, with the job it belongs to, the wall-clock
//! seconds so far and a SHA-256 of the two states (it catches a damaged file; the job is
//! compared whole). It is saved after an evaluation, atomically; a file of another job or
//! kernel, of another format or version, cut short or damaged is refused with what to do, and
//! left as it is: nothing is lost.
//!
//! The format's version ([`FORMAT`]) is also the version of what a run computes: a change to
//! the code that changes a run's bytes (as `pbcs exp check --exact` would show) or the layout
//! of its state bumps it, so that a run is never finished by other arithmetic than it began
//! with.
//!
//! ```
//! use pbcs::envs::toy::Toy1D;
//! use pbcs::learner::LearnerConfig;
//! use pbcs::nn::kernel::Kernel;
//! use pbcs::rng::Seeds;
//! use pbcs::vanilla::resume::Checkpoint;
//! use pbcs::vanilla::{train_vanilla, TrainConfig, VanillaRun};
//! let learner: LearnerConfig = toml::from_str("algo = \"td3\"\nhidden = [8]").unwrap();
//! let train = TrainConfig { steps: 300, learning_starts: 100, eval_every: 100,
//!                           max_episode_steps: 20, ..TrainConfig::default() };
//! let (seeds, kernel) = (Seeds::new(0), Kernel::detect());
//! let dir = tempfile::tempdir().unwrap();
//! let checkpoint = Checkpoint::new(dir.path().join("s0.resume"), "toy, seed 0");
//! // A run cut after 200 steps, saved...
//! let mut cut = VanillaRun::new(&Toy1D, &learner, &train, &seeds, kernel).unwrap();
//! cut.train_until(200, |_, _, _| Ok(())).unwrap();
//! checkpoint.save(&cut, 1.5).unwrap();
//! // ...goes on from there, and ends as the run never cut.
//! let mut resumed = checkpoint.resume(&Toy1D, &learner, &train, &seeds, kernel).unwrap().unwrap();
//! assert_eq!(resumed.steps(), 200);
//! resumed.train_until(u64::MAX, |_, _, _| Ok(())).unwrap();
//! let whole = train_vanilla(&Toy1D, &learner, &train, &seeds, kernel, |_, _| {}).unwrap();
//! assert_eq!(resumed.finish().unwrap().evals, whole.evals);
//! // A checkpoint is resumed only by its own job.
//! let other = Checkpoint::new(checkpoint.path.clone(), "toy, seed 1");
//! let err = other.resume(&Toy1D, &learner, &train, &seeds, kernel).err().unwrap();
//! assert!(err.to_string().contains("another job"), "{err}");
//! ```

use super::{TrainConfig, TrainOutcome, VanillaRun};
use crate::env::Env;
use crate::error::{Error, Result};
use crate::learner::LearnerConfig;
use crate::nn::kernel::Kernel;
use crate::rng::Seeds;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// How often `pbcs exp run` saves a vanilla run: at the first evaluation ten minutes or more
/// after the run (re)started or was last saved.
pub const EVERY: Duration = Duration::from_secs(600);

/// The first field of every checkpoint: a file of another format or version is refused by it.
/// Bump the version with any change to what a vanilla run computes or to its state's layout.
pub const FORMAT: &str = "pbcs vanilla run checkpoint, version 1";

/// The first field of a PBCS run's checkpoint (`crate::runs::pbcs_resume`, whose files begin
/// with this file's head: [`Checkpoint::peek`] reads both). Bump the version with any change to
/// what a PBCS run computes or to its saved state's layout.
pub const PBCS_FORMAT: &str = "pbcs PBCS run checkpoint, version 1";

/// Where a run saves its state, for which job, and how often.
#[derive(Debug, Clone, PartialEq)]
pub struct Checkpoint {
    /// The file (an experiment's run: `s<seed>.resume` beside its row).
    pub path: PathBuf,
    /// What identifies the run (an experiment's run: its job's TOML and its kernel): a
    /// checkpoint is resumed only by a run of the same job.
    pub job: String,
    /// Saved at the first evaluation this long after the run (re)started or was last saved.
    pub every: Duration,
    /// A deadline (`pbcs exp run --stop-after`): at the first evaluation at or past it the run
    /// is saved and stops, unfinished ([`train_vanilla_resumable`] returns `None`).
    pub stop_at: Option<Instant>,
}

/// What a checkpoint file holds.
#[derive(Serialize, Deserialize)]
struct Envelope {
    format: String,
    job: String,
    /// Wall-clock seconds of the run so far.
    seconds: f64,
    steps: u64,
    /// SHA-256 of `learner` followed by `progress`.
    sha256: String,
    learner: Vec<u8>,
    progress: Vec<u8>,
}

/// The head of a checkpoint file: [`Envelope`]'s first fields, which postcard writes first.
#[derive(Deserialize)]
struct Head {
    format: String,
    job: String,
    seconds: f64,
    steps: u64,
}

/// How far a saved run got ([`Checkpoint::peek`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Saved {
    /// Environment steps taken.
    pub steps: u64,
    /// Wall-clock seconds of the run up to the save.
    pub seconds: f64,
}

impl Checkpoint {
    /// The checkpoint at `path` of the run of `job`, saved every [`EVERY`], without a
    /// deadline.
    pub fn new(path: impl Into<PathBuf>, job: impl Into<String>) -> Self {
        Checkpoint {
            path: path.into(),
            job: job.into(),
            every: EVERY,
            stop_at: None,
        }
    }

    /// Saves `run`, `seconds` of wall clock into it, replacing the file at once and whole.
    pub fn save<E: Env>(&self, run: &VanillaRun<'_, E>, seconds: f64) -> Result<()> {
        let (learner, progress) = run.saved()?;
        let envelope = Envelope {
            format: FORMAT.into(),
            job: self.job.clone(),
            seconds,
            steps: run.steps(),
            sha256: checksum(&learner, &progress),
            learner,
            progress,
        };
        crate::record::write_atomic(&self.path, |w| {
            postcard::to_io(&envelope, w)
                .map(|_| ())
                .map_err(std::io::Error::other)
        })
    }

    /// The run saved at [`Checkpoint::path`], or `None` where there is no file. A file that
    /// does not decode, is damaged, is another job's or does not fit the run that `env`,
    /// `learner`, `train`, `seeds` and `kernel` make is refused, naming it; it is left as it is.
    pub fn resume<'a, E: Env>(
        &self,
        env: &'a E,
        learner: &LearnerConfig,
        train: &'a TrainConfig,
        seeds: &'a Seeds,
        kernel: Kernel,
    ) -> Result<Option<VanillaRun<'a, E>>> {
        let bytes = match std::fs::read(&self.path) {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(Error::io(&self.path, e)),
        };
        let afresh = "delete it to start the run afresh";
        let decoded: Option<Envelope> = postcard::from_bytes(&bytes).ok();
        drop(bytes);
        let envelope = decoded.filter(|e| e.format == FORMAT).ok_or_else(|| {
            self.refused(format!(
                "is not a {FORMAT} (another version, another file, or cut short); {afresh}"
            ))
        })?;
        if envelope.sha256 != checksum(&envelope.learner, &envelope.progress) {
            return Err(self.refused(format!("is damaged: its checksum does not match; {afresh}")));
        }
        if envelope.job != self.job {
            return Err(self.refused(format!(
                "was saved by another job, not this one; {afresh} (its job:\n{}\n)",
                envelope.job
            )));
        }
        let mut run = VanillaRun::new(env, learner, train, seeds, kernel)?;
        run.restore(&envelope.learner, &envelope.progress, envelope.steps)
            .map_err(|e| self.refused(format!("does not fit this run: {e}; {afresh}")))?;
        run.earlier_seconds = envelope.seconds;
        Ok(Some(run))
    }

    /// How far the run saved at [`Checkpoint::path`] got (a vanilla run's or a PBCS run's,
    /// [`crate::runs::pbcs_resume`]), read from the file's head without the states: `None`
    /// where there is no file; an error where the head does not decode or
    /// belongs to another format, version or job (the file would be refused,
    /// [`Checkpoint::resume`] says why). Its states are not checked.
    pub fn peek(&self) -> Result<Option<Saved>> {
        let file = match std::fs::File::open(&self.path) {
            Ok(f) => f,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(Error::io(&self.path, e)),
        };
        // Room for the format and the job's TOML (a vanilla job's is under a kilobyte), read in
        // place.
        let mut scratch = vec![0u8; 1 << 20];
        let head: Option<(Saved, String, String)> =
            postcard::from_io((std::io::BufReader::new(file), &mut scratch))
                .ok()
                .map(|(h, _): (Head, _)| {
                    let saved = Saved {
                        steps: h.steps,
                        seconds: h.seconds,
                    };
                    (saved, h.format, h.job)
                });
        match head {
            Some((saved, format, job))
                if (format == FORMAT || format == PBCS_FORMAT) && job == self.job =>
            {
                Ok(Some(saved))
            }
            _ => Err(self.refused("would be refused (run it to see why)")),
        }
    }

    /// Deletes the file (once the run's results are written); no file is not an error.
    pub fn remove(&self) -> Result<()> {
        match std::fs::remove_file(&self.path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(Error::io(&self.path, e)),
            _ => Ok(()),
        }
    }

    fn refused(&self, message: impl std::fmt::Display) -> Error {
        Error::parse(&self.path, format!("this checkpoint {message}"))
    }
}

/// SHA-256 of the learner's state followed by the run's, in hex.
fn checksum(learner: &[u8], progress: &[u8]) -> String {
    crate::record::sha256_hex_of(&[learner, progress])
}

/// [`super::train_vanilla`], saved to `checkpoint` every [`Checkpoint::every`] and resumed
/// from it where it holds a run of this job: the outcome is the same bytes as an uncut run's.
/// The outcome's `earlier_seconds` are the wall-clock seconds before this process resumed it
/// (up to the save it resumed from). A save that fails (a full disk) is reported on standard
/// error and the run goes on, the older file kept: the checkpoint only saves time. The
/// checkpoint is left in place (delete it, [`Checkpoint::remove`], once the results are
/// written).
///
/// With a deadline ([`Checkpoint::stop_at`]), the run stops at its first evaluation at or past
/// it, saved there, and `None` is returned: run it again to go on. A save that fails there is
/// an error (stopping unsaved would lose the work since the last save), the older file kept.
/// A run that ends at that evaluation (its last steps, or `stop_at_successes`) finishes.
pub fn train_vanilla_resumable<E: Env>(
    env: &E,
    learner: &LearnerConfig,
    train: &TrainConfig,
    seeds: &Seeds,
    kernel: Kernel,
    checkpoint: &Checkpoint,
    mut progress: impl FnMut(u64, f32),
) -> Result<Option<TrainOutcome>> {
    let mut run = match checkpoint.resume(env, learner, train, seeds, kernel)? {
        Some(run) => run,
        None => VanillaRun::new(env, learner, train, seeds, kernel)?,
    };
    let clock = Instant::now();
    let mut saved = Instant::now();
    let past_deadline = || checkpoint.stop_at.is_some_and(|t| Instant::now() >= t);
    let mut stopped = false;
    while !run.done() && !stopped {
        // To the next evaluation (`train_until` stops right after it).
        let next = (run.steps() / train.eval_every + 1) * train.eval_every;
        run.train_until(next, |run, steps, success| {
            progress(steps, success);
            if run.done() {
                return Ok(());
            }
            let seconds = run.earlier_seconds + clock.elapsed().as_secs_f64();
            if past_deadline() {
                stopped = true;
                return checkpoint.save(run, seconds);
            }
            if saved.elapsed() >= checkpoint.every {
                if let Err(e) = checkpoint.save(run, seconds) {
                    eprintln!("warning: the run goes on unsaved at {steps} steps: {e}");
                }
                saved = Instant::now();
            }
            Ok(())
        })?;
    }
    if stopped {
        return Ok(None);
    }
    run.finish().map(Some)
}
