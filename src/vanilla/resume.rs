//! Checkpoints of a vanilla run: its whole state saved now and then, so that a run cut short
//! (a session's end, a killed process) goes on where it was saved and ends with the same bytes
//! as a run never cut.
//!
//! A checkpoint holds the learner's state ([`crate::learner::Learner::save_state`]: weights,
//! targets, optimiser moments, the update stream's position) and the rest of the run's (the
//! replay buffer, the generators' positions, the environment's state, the episode so far, the
//! evaluations and visited bins), postcard-encoded, in the envelope every checkpoint has
//! ([`crate::checkpoint`]: the job it belongs to, the wall-clock seconds so far and a SHA-256 of
//! the state, which catches a damaged file; the job is compared whole). It is saved after an
//! evaluation, atomically; a file of another job or
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
//! use pbcs::checkpoint::Checkpoint;
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
//! cut.save(&checkpoint, 1.5).unwrap();
//! // ...goes on from there, and ends as the run never cut.
//! let mut resumed = VanillaRun::resume(&checkpoint, &Toy1D, &learner, &train, &seeds, kernel)
//!     .unwrap().unwrap();
//! assert_eq!(resumed.steps(), 200);
//! resumed.train_until(u64::MAX, |_, _, _| Ok(())).unwrap();
//! let whole = train_vanilla(&Toy1D, &learner, &train, &seeds, kernel, |_, _| {}).unwrap();
//! assert_eq!(resumed.finish().unwrap().evals, whole.evals);
//! // A checkpoint is resumed only by its own job.
//! let other = Checkpoint::new(checkpoint.path.clone(), "toy, seed 1");
//! let err = VanillaRun::resume(&other, &Toy1D, &learner, &train, &seeds, kernel).err().unwrap();
//! assert!(err.to_string().contains("another job"), "{err}");
//! ```

use super::{TrainConfig, TrainOutcome, VanillaRun};
pub use crate::checkpoint::{Checkpoint, Saved, EVERY};
use crate::env::Env;
use crate::error::{Error, Result};
use crate::learner::LearnerConfig;
use crate::nn::kernel::Kernel;
use crate::rng::Seeds;
use std::time::Instant;

/// The format of a vanilla run's checkpoint ([`crate::checkpoint::VANILLA`]).
pub use crate::checkpoint::VANILLA as FORMAT;

impl<'a, E: Env> VanillaRun<'a, E> {
    /// Saves this run to `checkpoint`, `seconds` of wall clock into it, replacing the file at
    /// once and whole.
    pub fn save(&self, checkpoint: &Checkpoint, seconds: f64) -> Result<()> {
        let (learner, progress) = self.saved()?;
        let body = postcard::to_stdvec(&(learner, progress))
            .map_err(|e| Error::invalid("vanilla run state", e.to_string()))?;
        checkpoint.write(FORMAT, self.steps(), seconds, &body)
    }

    /// The run saved at `checkpoint`, or `None` where there is no file. A file that does not
    /// decode, is damaged, is another job's or does not fit the run that `env`, `learner`,
    /// `train`, `seeds` and `kernel` make is refused, naming it; it is left as it is.
    pub fn resume(
        checkpoint: &Checkpoint,
        env: &'a E,
        learner: &LearnerConfig,
        train: &'a TrainConfig,
        seeds: &'a Seeds,
        kernel: Kernel,
    ) -> Result<Option<Self>> {
        let Some(saved) = checkpoint.read(FORMAT)? else {
            return Ok(None);
        };
        let (learner_state, progress): (Vec<u8>, Vec<u8>) = postcard::from_bytes(&saved.body)
            .map_err(|e| checkpoint.refused(format!("does not decode ({e})")))?;
        let mut run = VanillaRun::new(env, learner, train, seeds, kernel)?;
        run.restore(&learner_state, &progress, saved.steps)
            .map_err(|e| checkpoint.refused(format!("does not fit this run: {e}")))?;
        run.earlier_seconds = saved.seconds;
        Ok(Some(run))
    }
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
    let mut run = match VanillaRun::resume(checkpoint, env, learner, train, seeds, kernel)? {
        Some(run) => run,
        None => VanillaRun::new(env, learner, train, seeds, kernel)?,
    };
    let clock = Instant::now();
    let mut saves = checkpoint.saves();
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
            let at = format!(" at {steps} steps");
            stopped = saves.due(&at, || run.save(checkpoint, seconds))?;
            Ok(())
        })?;
    }
    if stopped {
        return Ok(None);
    }
    run.finish().map(Some)
}
