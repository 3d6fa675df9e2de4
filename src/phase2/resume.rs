//! Phase 2 cut between two learning problems and resumed there ([`chain_skills_resumable`]):
//! a PBCS run of hours (AntMaze) outlives a session or a cluster job's time limit, and ends
//! with the bytes of a run never cut.
//!
//! Between two learning problems of the main section, phase 2 is Algorithm 1's loop state
//! ([`Between`]: the skills found so far, T, the problems made, restarts and hand-over moves)
//! and the [`Chainer`]'s (env steps spent, step counts, the trace, and with
//! `phase2.warm_start` the learner the next skill takes over). Each learning problem's random
//! streams are substream n of the run's seeds and its replay starts empty, so nothing else
//! carries over. [`Phase2State`] holds it; a checkpoint writes it
//! ([`crate::runs::pbcs_resume`]). The chain's verification and repairs, which follow the main
//! section, are not cut.
//!
//! ```
//! use pbcs::config::PbcsJob;
//! use pbcs::envs::maze::Maze;
//! use pbcs::phase1::explore;
//! use pbcs::phase2::{chain_skills, chain_skills_resumable, Pause, TraceRow};
//! use pbcs::rng::{Seeds, Stream};
//! let mut job = PbcsJob::default();
//! (job.maze.size, job.seed) = (2, 0);
//! let maze = Maze::new(&job.maze).unwrap();
//! let seeds = Seeds::new(job.seed);
//! let found = explore(&maze, &job.explore, &mut seeds.stream(Stream::Explore), |_, _| {}).unwrap();
//! let tau = &found.trajectory.states;
//! let (ready, kernel) = (job.phase2.ready(&maze).unwrap(), pbcs::nn::kernel::Kernel::detect());
//! let run = |from, pause: &mut dyn FnMut(Pause) -> bool| {
//!     chain_skills_resumable(&maze, tau, None, &job.learner, ready, &seeds, found.env_steps,
//!                            kernel, |_, _| {}, from, |p| Ok(pause(p))).unwrap()
//! };
//! // Cut after its first learning problem, its state kept...
//! let mut kept = None;
//! let cut = run(None, &mut |p| { kept = Some(p.state().unwrap()); true });
//! assert!(cut.is_none() && kept.as_ref().unwrap().between.made == 1);
//! // ...it goes on to the outcome of the run never cut.
//! let resumed = run(kept, &mut |_| false).unwrap();
//! let whole = chain_skills(&maze, tau, &job.learner, ready, &seeds, found.env_steps, kernel,
//!                          |_, _| {}).unwrap();
//! assert_eq!((resumed.chain, resumed.failure, resumed.steps), (whole.chain, whole.failure, whole.steps));
//! let clockless = |t: Vec<TraceRow>| -> Vec<TraceRow> {
//!     t.into_iter().map(|r| TraceRow { seconds: 0.0, ..r }).collect()
//! };
//! assert_eq!(clockless(resumed.trace), clockless(whole.trace));
//! ```

use super::chaining::{repair_chain, Chainer};
use super::task::StepCounts;
use super::Failure;
use super::{Phase2Outcome, Progress, Ready, SkillChain, TraceRow};
use crate::env::{Env, SampleBall};
use crate::error::{Error, Result};
use crate::learner::{Learner, LearnerConfig};
use crate::nn::kernel::Kernel;
use crate::policy::Policy;
use crate::rng::Seeds;
use std::cell::RefCell;

/// Phase 2 between two learning problems of its main section: what a run cut there goes on
/// from ([`chain_skills_resumable`]).
#[derive(Debug, Clone)]
pub struct Phase2State {
    /// Algorithm 1's loop.
    pub between: Between<Box<dyn Policy>>,
    /// Environment steps of the whole run so far (phase 1 included).
    pub spent: u64,
    /// Phase 2's steps so far, by purpose.
    pub steps: StepCounts,
    /// The trace so far, wall clock included.
    pub trace: Vec<TraceRow>,
    /// With `phase2.warm_start`, the learner the next skill takes over: its last target's
    /// index on τ and its [`Learner::save_state`].
    pub warm: Option<(usize, Vec<u8>)>,
}

/// Phase 2 between two learning problems, as its `pause` sees it: [`Pause::state`] copies it
/// out (only when it is to be saved: that serialises the learner).
pub struct Pause<'s> {
    /// Algorithm 1's loop.
    pub between: &'s Between<Box<dyn Policy>>,
    /// Environment steps of the whole run so far (phase 1 included).
    pub spent: u64,
    steps: StepCounts,
    trace: &'s RefCell<Vec<TraceRow>>,
    last: &'s RefCell<Option<(usize, Box<dyn Learner>)>>,
}

impl Pause<'_> {
    /// The kernel of the learner the next skill takes over, if one is handed over.
    pub fn warm_kernel(&self) -> Option<Kernel> {
        self.last.borrow().as_ref().map(|(_, l)| l.kernel())
    }

    /// The state a resumed run goes on from.
    pub fn state(&self) -> Result<Phase2State> {
        let warm = match &*self.last.borrow() {
            Some((t, learner)) => Some((*t, learner.save_state()?)),
            None => None,
        };
        Ok(Phase2State {
            between: self.between.clone(),
            spent: self.spent,
            steps: self.steps,
            trace: self.trace.borrow().clone(),
            warm,
        })
    }
}

/// [`super::chain_skills_with_starts`] from `from` (a [`Phase2State`] a `pause` copied out of
/// a run of the same settings, seeds and τ; `None`: from the start), asking `pause` after
/// each learning problem of the main section that leaves work to do whether to stop there:
/// `Ok(None)` when it did. A run resumed from where it stopped ends with the outcome of the
/// run never cut: the same chain, failure, step counts and trace (its wall clock aside).
/// A state that does not fit τ or the learner is refused.
#[allow(clippy::too_many_arguments)]
pub fn chain_skills_resumable<E: Env>(
    env: &E,
    tau: &[E::State],
    starts: Option<&dyn SampleBall<E::State>>,
    learner: &LearnerConfig,
    ready: Ready<'_, E>,
    seeds: &Seeds,
    spent: u64,
    kernel: Kernel,
    mut progress: impl FnMut(usize, Progress),
    from: Option<Phase2State>,
    mut pause: impl FnMut(Pause<'_>) -> Result<bool>,
) -> Result<Option<Phase2Outcome>> {
    let config = ready.settings();
    let starts = super::starts::archive_starts(config, starts)?;
    let n = tau.len() - 1;
    let chainer = Chainer::new(
        env,
        tau,
        starts,
        learner,
        ready,
        seeds,
        spent,
        kernel,
        &mut progress,
    );
    let between = match from {
        None => Between::start(n),
        Some(state) => restore(&chainer, state)?,
    };
    let looked = chainer.section_from(0, n, &[], between, |between| {
        pause(Pause {
            between,
            spent: chainer.spent.get(),
            steps: chainer.steps.get(),
            trace: &chainer.trace,
            last: &chainer.last,
        })
    })?;
    let Chained::Done(found, mut failure) = looked else {
        return Ok(None);
    };
    let mut chain = SkillChain {
        skills: chainer.skills(0, found),
        kernel,
    };
    if let (None, Some(check)) = (failure, config.ideas.chain_check) {
        failure = repair_chain(&chainer, &mut chain, check)?;
    }
    Ok(Some(Phase2Outcome {
        chain,
        failure,
        steps: chainer.steps.get(),
        trace: chainer.trace.into_inner(),
    }))
}

/// Puts `state` into a new `chainer` and returns its loop; refuses a state that cannot be
/// this run's (indices past τ, a learner of other settings or sizes).
fn restore<E: Env, P: FnMut(usize, Progress)>(
    chainer: &Chainer<'_, E, P>,
    state: Phase2State,
) -> Result<Between<Box<dyn Policy>>> {
    let n = chainer.tau.len() - 1;
    let b = &state.between;
    let past = b.t > n || b.found.iter().any(|&(k, t, _)| k > t || t > n);
    let (obs_dim, action_dim) = (chainer.env.obs_dim(), chainer.env.action_dim());
    let wrong_sizes = b
        .found
        .iter()
        .any(|(_, _, p)| p.obs_dim() != obs_dim || p.action_dim() != action_dim);
    if past || wrong_sizes || state.spent < chainer.spent.get() {
        return Err(Error::invalid(
            "phase 2 state",
            format!(
                "it does not fit this run (τ of {} states, observations of {obs_dim}, actions \
                 of {action_dim}): it is another run's",
                n + 1
            ),
        ));
    }
    if let Some((t, bytes)) = &state.warm {
        let config = chainer.config;
        let mut learner = chainer.learner.build(
            chainer.env.obs_dim(),
            &config.learner_bounds(chainer.env),
            &chainer.seeds.skill(0),
            chainer.kernel,
        )?;
        learner.restore_state(bytes)?;
        // The saved state names the kernel it was computed on; this run computes on its own
        // (one of the same bytes, `Kernel::same_bytes`, which the checkpoint checked).
        learner.set_kernel(chainer.kernel);
        *chainer.last.borrow_mut() = Some((*t, learner));
    }
    chainer.spent.set(state.spent);
    chainer.made.set(b.made);
    chainer.steps.set(state.steps);
    chainer
        .earlier_seconds
        .set(state.trace.last().map_or(0.0, |r| r.seconds));
    *chainer.trace.borrow_mut() = state.trace;
    Ok(state.between)
}

/// Where Algorithm 1 stands between two learning problems: what a run cut there goes on from
/// ([`super::skill_chaining_from`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Between<P> {
    /// The skills found so far, in the order found (backwards from τ_N): (K, T, π).
    pub found: Vec<(usize, usize, P)>,
    /// T of the next learning problem.
    pub t: usize,
    /// Learning problems made so far (skills, restarts, hand-over tries).
    pub made: usize,
    /// Restarts of the current skill.
    pub restarts: usize,
    /// Moves of the hand-over of the skill found last.
    pub moves: usize,
}

impl<P> Between<P> {
    /// Before the first learning problem on τ_0 … τ_n.
    pub fn start(n: usize) -> Self {
        Between {
            found: Vec::new(),
            t: n,
            made: 0,
            restarts: 0,
            moves: 0,
        }
    }
}

/// How [`skill_chaining_from`] ended.
#[derive(Debug)]
pub enum Chained<P> {
    /// The skills in execution order as `(K_i, T_i, π_i)`, and why it stopped early, if it did.
    Done(Vec<(usize, usize, P)>, Option<Failure>),
    /// Its `pause` asked it to stop between two learning problems, here.
    Paused(Between<P>),
}
