//! Checkpoints of a PBCS run: phase 2 saved between two of its steps ([`crate::phase2::run`]:
//! a learning problem of Algorithm 1, a verification of the chain or a learning problem of its
//! repair), or with the goal-conditioned chain between two of its tests
//! ([`crate::phase2::goal_conditioned::GoalConditionedRun`], format [`GOAL_CONDITIONED`]: its
//! learner, replay, streams, curriculum and episode in flight), so that a run of hours
//! (AntMaze) cut by a session's end or a cluster job's limit goes on from its last save and
//! ends with the bytes of a run never cut.
//!
//! The file is a [`Checkpoint`] (`s<seed>.resume` in an experiment, as a vanilla run's: the
//! same envelope of format, job, wall clock and env steps, which `pbcs exp list` reads, and a
//! checksum), with its own format and body: for the per-skill chain ([`FORMAT`]) Algorithm 1's
//! loop, the skills found so far (each its policy's kind, sizes, bounds and the chain's own
//! safetensors bytes), the repairs' state once begun, the step counts, the trace, the learner
//! the next skill takes over; for either, the SHA-256 of τ's observations. A resumed run does
//! phase 1 again (deterministic, and cheap beside phase 2) and refuses a checkpoint whose τ is
//! not the τ it found. Saved at the end of a step ten minutes or more after the last save or the
//! (re)start, and at the first one at or past the deadline ([`Checkpoint::stop_at`]) that
//! leaves another to make, where the run stops.

use crate::checkpoint::{Checkpoint, Saves};
use crate::error::{Error, Result};
use crate::learner::load_policy;
use crate::nn::kernel::Kernel;
use crate::phase2::goal_conditioned::{GoalConditionedRun, GoalConditionedState};
use crate::phase2::{
    Between, Found, OpenRepair, Phase2Inputs, Phase2Outcome, Phase2Run, Phase2State, Progress,
    RepairsAt, StepCounts, TraceRow,
};
use crate::policy::Policy;
use crate::rng::Rng;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// The format of a PBCS run's checkpoint ([`crate::checkpoint::PBCS`]).
pub use crate::checkpoint::PBCS as FORMAT;

/// The format of a PBCS run's checkpoint with the goal-conditioned chain
/// ([`crate::checkpoint::PBCS_GOAL_CONDITIONED`]).
pub use crate::checkpoint::PBCS_GOAL_CONDITIONED as GOAL_CONDITIONED;

/// One skill found so far.
#[derive(Serialize, Deserialize)]
struct SavedSkill {
    k: usize,
    t: usize,
    kind: String,
    sizes: Vec<usize>,
    bounds: Vec<f32>,
    /// The policy as a chain saves it (safetensors).
    weights: Vec<u8>,
}

/// [`Phase2State`] as saved.
#[derive(Serialize, Deserialize)]
struct Saved {
    /// SHA-256 of τ's observations (f32, little-endian): a resumed run must have found it.
    tau_sha256: String,
    /// The layer kernel the run computed on ([`Kernel::name`]): a resumed run must compute the
    /// same bytes ([`Kernel::same_bytes`]).
    kernel: String,
    /// Algorithm 1 on the whole τ.
    between: SavedBetween,
    /// The chain's verification and repairs, once begun.
    repairs: Option<SavedRepairs>,
    /// Learning problems made so far.
    made: usize,
    spent: u64,
    train: u64,
    test: u64,
    trace: Vec<TraceRow>,
    /// Each trace row's wall clock (not in `trace`'s encoding).
    trace_seconds: Vec<f64>,
    warm: Option<(usize, Vec<u8>)>,
}

/// [`Between`] as saved: the skills found so far and the loop's counters.
#[derive(Serialize, Deserialize)]
struct SavedBetween {
    found: Vec<SavedSkill>,
    t: usize,
    made: usize,
    restarts: usize,
    moves: usize,
}

/// [`RepairsAt`] as saved.
#[derive(Serialize, Deserialize)]
struct SavedRepairs {
    /// The chain so far (execution order, indices on τ).
    chain: Vec<SavedSkill>,
    repairs: usize,
    rng: Rng,
    open: Option<SavedOpenRepair>,
}

/// [`OpenRepair`] as saved.
#[derive(Serialize, Deserialize)]
struct SavedOpenRepair {
    i: usize,
    lo: usize,
    hi: usize,
    /// The entry states (postcard).
    entries: Vec<u8>,
    at: SavedBetween,
}

/// [`GoalConditionedState`] as saved.
#[derive(Serialize, Deserialize)]
struct SavedGoalConditioned {
    /// As [`Saved`]'s.
    tau_sha256: String,
    kernel: String,
    learner: Vec<u8>,
    progress: Vec<u8>,
    spent: u64,
    train: u64,
    test: u64,
    trace: Vec<TraceRow>,
    trace_seconds: Vec<f64>,
}

/// The SHA-256 of τ's observations: what a checkpoint is checked against.
pub fn tau_sha256(observations: &[Vec<f32>]) -> String {
    let bytes: Vec<u8> = observations
        .iter()
        .flatten()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    crate::record::sha256_hex(&bytes)
}

/// A policy's safetensors bytes, as [`Policy::save`] writes its file.
fn policy_bytes(policy: &dyn Policy) -> Result<Vec<u8>> {
    let dir = tempfile::tempdir().map_err(|e| Error::io(std::env::temp_dir(), e))?;
    let path = dir.path().join("policy.safetensors");
    policy.save(&path)?;
    std::fs::read(&path).map_err(|e| Error::io(&path, e))
}

/// The policy [`policy_bytes`] gave, read back by its kind.
fn policy_from(skill: &SavedSkill) -> Result<Box<dyn Policy>> {
    let dir = tempfile::tempdir().map_err(|e| Error::io(std::env::temp_dir(), e))?;
    let path = dir.path().join("policy.safetensors");
    std::fs::write(&path, &skill.weights).map_err(|e| Error::io(&path, e))?;
    load_policy(&skill.kind, &skill.sizes, &skill.bounds, &path)
}

/// Saves `state` (τ's hash `tau`, `seconds` of wall clock so far) to `checkpoint`'s file,
/// replacing it at once and whole.
pub fn save<S: Serialize>(
    checkpoint: &Checkpoint,
    state: &Phase2State<S>,
    tau: &str,
    kernel: Kernel,
    seconds: f64,
) -> Result<()> {
    let repairs = match &state.repairs {
        None => None,
        Some(r) => Some(SavedRepairs {
            chain: saved_skills(&r.chain)?,
            repairs: r.repairs,
            rng: r.rng.clone(),
            open: match &r.open {
                None => None,
                Some(o) => Some(SavedOpenRepair {
                    i: o.i,
                    lo: o.lo,
                    hi: o.hi,
                    entries: postcard::to_stdvec(&o.entries)
                        .map_err(|e| Error::invalid("phase 2 state", e.to_string()))?,
                    at: SavedBetween::of(&o.at)?,
                }),
            },
        }),
    };
    let saved = Saved {
        tau_sha256: tau.into(),
        kernel: kernel.name().into(),
        between: SavedBetween::of(&state.between)?,
        repairs,
        made: state.made,
        spent: state.spent,
        train: state.steps.train,
        test: state.steps.test,
        trace: state.trace.clone(),
        trace_seconds: state.trace.iter().map(|r| r.seconds).collect(),
        warm: state.warm.clone(),
    };
    let body =
        postcard::to_stdvec(&saved).map_err(|e| Error::invalid("phase 2 state", e.to_string()))?;
    checkpoint.write(FORMAT, state.spent, seconds, &body)
}

/// Skills (K, T, π) as saved.
fn saved_skills(skills: &[Found]) -> Result<Vec<SavedSkill>> {
    skills
        .iter()
        .map(|(k, t, p)| {
            Ok(SavedSkill {
                k: *k,
                t: *t,
                kind: p.kind().into(),
                sizes: p.sizes().to_vec(),
                bounds: p.action_bounds().to_vec(),
                weights: policy_bytes(p.as_ref())?,
            })
        })
        .collect()
}

/// Saved skills read back.
fn skills_from(saved: &[SavedSkill]) -> Result<Vec<Found>> {
    saved
        .iter()
        .map(|s| Ok((s.k, s.t, policy_from(s)?)))
        .collect()
}

impl SavedBetween {
    fn of(b: &Between<Box<dyn Policy>>) -> Result<Self> {
        Ok(SavedBetween {
            found: saved_skills(&b.found)?,
            t: b.t,
            made: b.made,
            restarts: b.restarts,
            moves: b.moves,
        })
    }

    fn read(&self) -> Result<Between<Box<dyn Policy>>> {
        Ok(Between {
            found: skills_from(&self.found)?,
            t: self.t,
            made: self.made,
            restarts: self.restarts,
            moves: self.moves,
        })
    }
}

impl SavedRepairs {
    fn read<S: DeserializeOwned>(&self) -> Result<RepairsAt<S>> {
        let open = match &self.open {
            None => None,
            Some(o) => Some(OpenRepair {
                i: o.i,
                lo: o.lo,
                hi: o.hi,
                entries: postcard::from_bytes(&o.entries)
                    .map_err(|e| Error::invalid("the repair's entry states", e.to_string()))?,
                at: o.at.read()?,
            }),
        };
        Ok(RepairsAt {
            chain: skills_from(&self.chain)?,
            repairs: self.repairs,
            rng: self.rng.clone(),
            open,
        })
    }
}

/// The PBCS run saved at `checkpoint`'s file, with its wall-clock seconds, or `None` where
/// there is no file. A file that does not decode, is damaged, is another job's, was saved on
/// another τ than `tau` or computed on a kernel whose bytes `kernel`'s are not is refused,
/// naming it; it is left as it is.
pub fn load<S: DeserializeOwned>(
    checkpoint: &Checkpoint,
    tau: &str,
    kernel: Kernel,
) -> Result<Option<(Phase2State<S>, f64)>> {
    let Some(opened) = checkpoint.read(FORMAT)? else {
        return Ok(None);
    };
    let refused = |m: String| checkpoint.refused(m);
    let saved: Saved = postcard::from_bytes(&opened.body)
        .map_err(|e| refused(format!("does not decode ({e})")))?;
    same_origin(checkpoint, (&saved.tau_sha256, &saved.kernel), tau, kernel)?;
    let trace = with_seconds(checkpoint, saved.trace, saved.trace_seconds)?;
    let skill = |e: Error| refused(format!("holds a skill that does not load ({e})"));
    let repairs = saved.repairs.as_ref().map(SavedRepairs::read).transpose();
    let state = Phase2State {
        between: saved.between.read().map_err(skill)?,
        repairs: repairs.map_err(skill)?,
        made: saved.made,
        spent: saved.spent,
        steps: StepCounts {
            train: saved.train,
            test: saved.test,
        },
        trace,
        warm: saved.warm,
    };
    Ok(Some((state, opened.seconds)))
}

/// Refuses a checkpoint saved (`saved`: τ's hash, the kernel's name) on another τ than `tau`
/// or on a kernel whose bytes `kernel`'s are not.
fn same_origin(
    checkpoint: &Checkpoint,
    saved: (&str, &str),
    tau: &str,
    kernel: Kernel,
) -> Result<()> {
    let (saved_tau, saved_kernel) = saved;
    if saved_tau != tau {
        return Err(checkpoint
            .refused("was saved on another τ than phase 1 found now (another build or machine?)"));
    }
    if !Kernel::same_bytes(saved_kernel, kernel.name()) {
        return Err(Error::parse(
            &checkpoint.path,
            format!(
                "this checkpoint was computed on the `{saved_kernel}` kernel, whose bytes the \
                 `{}` kernel does not compute: go on with PBCS_KERNEL={saved_kernel}, or delete \
                 it to start the run afresh",
                kernel.name(),
            ),
        ));
    }
    Ok(())
}

/// The saved trace with each row's wall clock put back; refused where they do not match.
fn with_seconds(
    checkpoint: &Checkpoint,
    trace: Vec<TraceRow>,
    seconds: Vec<f64>,
) -> Result<Vec<TraceRow>> {
    if seconds.len() != trace.len() {
        return Err(checkpoint.refused("holds a trace whose wall clock does not match it"));
    }
    Ok(trace
        .into_iter()
        .zip(seconds)
        .map(|(r, seconds)| TraceRow { seconds, ..r })
        .collect())
}

/// Saves a goal-conditioned `state` as [`save`] saves Algorithm 1's (format
/// [`GOAL_CONDITIONED`]).
pub fn save_goal_conditioned(
    checkpoint: &Checkpoint,
    state: GoalConditionedState,
    tau: &str,
    kernel: Kernel,
    seconds: f64,
) -> Result<()> {
    let saved = SavedGoalConditioned {
        tau_sha256: tau.into(),
        kernel: kernel.name().into(),
        trace_seconds: state.trace.iter().map(|r| r.seconds).collect(),
        learner: state.learner,
        progress: state.progress,
        spent: state.spent,
        train: state.steps.train,
        test: state.steps.test,
        trace: state.trace,
    };
    let body = postcard::to_stdvec(&saved)
        .map_err(|e| Error::invalid("goal-conditioned run state", e.to_string()))?;
    checkpoint.write(GOAL_CONDITIONED, saved.spent, seconds, &body)
}

/// The goal-conditioned PBCS run saved at `checkpoint`'s file, with its wall-clock seconds,
/// refused as [`load`] refuses; whether the state fits the run is
/// [`GoalConditionedRun::resume`]'s check.
pub fn load_goal_conditioned(
    checkpoint: &Checkpoint,
    tau: &str,
    kernel: Kernel,
) -> Result<Option<(GoalConditionedState, f64)>> {
    let Some(opened) = checkpoint.read(GOAL_CONDITIONED)? else {
        return Ok(None);
    };
    let saved: SavedGoalConditioned = postcard::from_bytes(&opened.body)
        .map_err(|e| checkpoint.refused(format!("does not decode ({e})")))?;
    same_origin(checkpoint, (&saved.tau_sha256, &saved.kernel), tau, kernel)?;
    let state = GoalConditionedState {
        learner: saved.learner,
        progress: saved.progress,
        spent: saved.spent,
        steps: StepCounts {
            train: saved.train,
            test: saved.test,
        },
        trace: with_seconds(checkpoint, saved.trace, saved.trace_seconds)?,
    };
    Ok(Some((state, opened.seconds)))
}

/// The saves of a PBCS run to `checkpoint` between phase 2's steps ([`crate::phase2::Phase2Run`]'s
/// learning problems and verifications, [`GoalConditionedRun`]'s tests;
/// [`crate::checkpoint::Saves`]: at the end of a step [`Checkpoint::every`] or more after the
/// last save or the start, and at the first one at or past the deadline, where the run stops).
pub struct Saver<'c> {
    saves: Saves<'c>,
    checkpoint: &'c Checkpoint,
    tau: String,
    kernel: Kernel,
    earlier_seconds: f64,
    clock: Instant,
}

impl<'c> Saver<'c> {
    /// Saving to `checkpoint` a run on τ of hash `tau`, computing on `kernel`, that had run
    /// `earlier_seconds` up to its last save before this process, which began at `clock`.
    pub fn new(
        checkpoint: &'c Checkpoint,
        tau: String,
        kernel: Kernel,
        earlier_seconds: f64,
        clock: Instant,
    ) -> Self {
        Saver {
            saves: checkpoint.saves(),
            checkpoint,
            tau,
            kernel,
            earlier_seconds,
            clock,
        }
    }

    /// Wall-clock seconds of the run so far: this process's since it began (its phase 1
    /// included) and the earlier processes' up to their last save (what a cut process ran
    /// after its last save is lost, as its work is).
    pub fn seconds(&self) -> f64 {
        self.earlier_seconds + self.clock.elapsed().as_secs_f64()
    }

    /// Whether the run stops here (saved).
    pub fn pause<E: crate::env::Env>(&mut self, run: &Phase2Run<'_, E>) -> Result<bool> {
        let seconds = self.seconds();
        let (checkpoint, tau, kernel) = (self.checkpoint, &self.tau, self.kernel);
        self.saves.due("", || {
            let state = run.state()?;
            save(checkpoint, &state, tau, kernel, seconds)
        })
    }

    /// Whether the goal-conditioned run stops here (saved), between two of its tests.
    pub fn pause_goal_conditioned<E: crate::env::Env>(
        &mut self,
        run: &GoalConditionedRun<'_, E>,
    ) -> Result<bool> {
        let seconds = self.seconds();
        let (checkpoint, tau, kernel) = (self.checkpoint, &self.tau, self.kernel);
        self.saves.due("", || {
            save_goal_conditioned(checkpoint, run.state()?, tau, kernel, seconds)
        })
    }
}

/// The state `load` reads from `checkpoint` (τ's hash `hash`) and the wall-clock seconds saved
/// with it: none and 0 without a checkpoint or a file.
pub(super) fn loaded<T>(
    checkpoint: Option<&Checkpoint>,
    hash: &Option<String>,
    load: impl FnOnce(&Checkpoint, &str) -> Result<Option<(T, f64)>>,
) -> Result<(Option<T>, f64)> {
    let (Some(c), Some(hash)) = (checkpoint, hash) else {
        return Ok((None, 0.0));
    };
    Ok(match load(c, hash)? {
        Some((state, seconds)) => (Some(state), seconds),
        None => (None, 0.0),
    })
}

/// The saver of a run with a checkpoint (τ's hash `hash`), none without one.
pub(super) fn saver_for<'c>(
    checkpoint: Option<&'c Checkpoint>,
    hash: &Option<String>,
    kernel: Kernel,
    earlier_seconds: f64,
    clock: Instant,
) -> Option<Saver<'c>> {
    let (c, hash) = (checkpoint?, hash.clone()?);
    Some(Saver::new(c, hash, kernel, earlier_seconds, clock))
}

/// The goal-conditioned phase 2, from `from` where a checkpoint held one, paused by `saver`
/// between two of its tests: `None` where it stopped there, saved.
pub(super) fn goal_conditioned<E: crate::env::Env>(
    inputs: Phase2Inputs<'_, E>,
    settings: &crate::phase2::goal_conditioned::GoalConditioned,
    from: Option<crate::phase2::goal_conditioned::GoalConditionedState>,
    mut saver: Option<&mut Saver<'_>>,
    progress: &mut dyn FnMut(usize, Progress),
) -> Result<Option<Phase2Outcome>> {
    use crate::phase2::goal_conditioned::GoalConditionedRun;
    let mut run = match from {
        None => GoalConditionedRun::start(inputs, settings)?,
        Some(state) => GoalConditionedRun::resume(inputs, settings, state)?,
    };
    while run.next_test(progress).is_continue() {
        if let Some(saver) = saver.as_mut() {
            if saver.pause_goal_conditioned(&run)? {
                return Ok(None);
            }
        }
    }
    Ok(Some(run.finish(progress)))
}

/// The paper's per-skill phase 2 ([`Phase2Run`]) from `from` (a saved state) or from its start,
/// saved by `saver` between learning problems: `None` where it stopped at the checkpoint's
/// deadline.
pub(super) fn per_skill<E: crate::env::Env>(
    inputs: Phase2Inputs<'_, E>,
    from: Option<crate::phase2::Phase2State<E::State>>,
    mut saver: Option<&mut Saver<'_>>,
    progress: &mut dyn FnMut(usize, Progress),
) -> Result<Option<Phase2Outcome>> {
    let mut run = match from {
        None => Phase2Run::new(inputs)?,
        Some(state) => Phase2Run::resume(inputs, state)?,
    };
    while run.next_problem(progress)?.is_continue() {
        if let Some(saver) = saver.as_mut() {
            if saver.pause(&run)? {
                return Ok(None);
            }
        }
    }
    run.finish(progress).map(Some)
}
