//! Phase 2 as one owned run ([`Phase2Run`]): Algorithm 1 on the whole τ, one learning problem
//! at a time, then the chain's verification and repair; [`chain_skills`] runs it to the end.
//!
//! Between two learning problems, a run is Algorithm 1's loop state ([`Between`]: the skills
//! found so far, T, the problems made, restarts and hand-over moves), once the chain's
//! verification has begun the repairs' ([`RepairsAt`]: the chain so far, the repairs made, the
//! verifications' stream and the repair under way with its own Algorithm 1), and its ledger's
//! (env steps spent, step counts, the trace, and with `phase2.warm_start` the learner the next
//! skill takes over). Each learning problem's random streams are substream n of the run's seeds
//! and its replay starts empty, so nothing else carries over.
//! [`Phase2Run::state`] copies it out ([`Phase2State`]), [`Phase2Run::resume`] goes on from it,
//! and the caller decides when to save (a checkpoint writes it: [`crate::runs::pbcs_resume`]):
//! a PBCS run of hours (AntMaze) outlives a session or a cluster job's time limit, and ends with
//! the bytes of a run never cut, wherever it was cut: in Algorithm 1, between two
//! verifications of the chain, or in the middle of a repair.
//!
//! ```
//! use pbcs::config::PbcsJob;
//! use pbcs::envs::maze::Maze;
//! use pbcs::phase1::explore;
//! use pbcs::phase2::{chain_skills, Phase2Inputs, Phase2Run, TraceRow};
//! use pbcs::rng::{Seeds, Stream};
//! let mut job = PbcsJob::default();
//! (job.maze.size, job.seed) = (2, 0);
//! let maze = Maze::new(&job.maze).unwrap();
//! let seeds = Seeds::new(job.seed);
//! let found = explore(&maze, &job.explore, &mut seeds.stream(Stream::Explore), |_, _| {}).unwrap();
//! let tau = &found.trajectory.states;
//! let (ready, kernel) = (job.phase2.ready(&maze).unwrap(), pbcs::nn::kernel::Kernel::detect());
//! let inputs = || Phase2Inputs::new(&maze, tau, ready, &job.learner, &seeds, kernel)
//!     .after(found.env_steps);
//! // Cut after its first learning problem, its state kept...
//! let mut run = Phase2Run::new(inputs()).unwrap();
//! assert!(run.next_problem(&mut |_, _| {}).unwrap().is_continue());
//! let kept = run.state().unwrap();
//! assert_eq!(kept.between.made, 1);
//! // ...it goes on to the outcome of the run never cut.
//! let resumed = Phase2Run::resume(inputs(), kept).unwrap().finish(&mut |_, _| {}).unwrap();
//! let whole = chain_skills(inputs(), |_, _| {}).unwrap();
//! assert_eq!((resumed.chain, resumed.failure, resumed.steps), (whole.chain, whole.failure, whole.steps));
//! let clockless = |t: Vec<TraceRow>| -> Vec<TraceRow> {
//!     t.into_iter().map(|r| TraceRow { seconds: 0.0, ..r }).collect()
//! };
//! assert_eq!(clockless(resumed.trace), clockless(whole.trace));
//! ```

use super::algorithm1::Between;
use super::inputs::{Along, Ledger, Phase2Inputs};
use super::repair::Repairs;
pub use super::repair::{Found, OpenRepair, RepairsAt};
use super::section::Section;
use super::{Failure, Phase2Outcome, Progress, SkillChain, StepCounts, TraceRow};
use crate::env::Env;
use crate::error::{Error, Result};
use crate::nn::kernel::Kernel;
use crate::policy::Policy;
use std::ops::ControlFlow;

/// Phase 2 on τ: [`Phase2Run::new`], then [`Phase2Run::finish`] (every learning problem of
/// Algorithm 1, then, with `phase2.chain_verify_episodes`, the chain's verification and
/// repair). `progress(n, report)` is told of each test and training round of learning problem n.
pub fn chain_skills<E: Env>(
    inputs: Phase2Inputs<'_, E>,
    mut progress: impl FnMut(usize, Progress),
) -> Result<Phase2Outcome> {
    Phase2Run::new(inputs)?.finish(&mut progress)
}

/// Phase 2 between two of its learning problems (or the chain's verifications): what a run cut
/// there goes on from ([`Phase2Run::resume`]).
#[derive(Debug, Clone)]
pub struct Phase2State<S> {
    /// Algorithm 1's loop on the whole τ.
    pub between: Between<Box<dyn Policy>>,
    /// Once Algorithm 1 has found a whole chain and `phase2.chain_verify_episodes` asks for it:
    /// the chain's verification and repairs.
    pub repairs: Option<RepairsAt<S>>,
    /// Learning problems made so far (Algorithm 1's and the repairs'): problem n draws from
    /// substream n of the run's seeds.
    pub made: usize,
    /// Environment steps of the whole run so far (phase 1 included).
    pub spent: u64,
    /// Phase 2's steps so far, by purpose.
    pub steps: StepCounts,
    /// The trace so far, wall clock included.
    pub trace: Vec<TraceRow>,
    /// With `phase2.warm_start`, the learner the next skill takes over: its last target's
    /// index on τ and its [`crate::learner::Learner::save_state`].
    pub warm: Option<(usize, Vec<u8>)>,
}

/// One phase 2 on τ, owning what it has found and spent: Algorithm 1 advanced one learning
/// problem at a time ([`Phase2Run::next_problem`]), copied out between two of them
/// ([`Phase2Run::state`]) and resumed from the copy ([`Phase2Run::resume`]), then finished
/// ([`Phase2Run::finish`]).
pub struct Phase2Run<'a, E: Env> {
    inputs: Phase2Inputs<'a, E>,
    /// The observations of τ.
    obs: Vec<Vec<f32>>,
    ledger: Ledger,
    /// Algorithm 1 on the whole τ.
    at: Between<Box<dyn Policy>>,
    /// The chain's verification and repairs, once Algorithm 1 has found a whole chain.
    repairs: Option<RepairsAt<E::State>>,
    /// Once phase 2 has ended: why it failed, if it did.
    ended: Option<Option<Failure>>,
}

impl<'a, E: Env> Phase2Run<'a, E> {
    /// Phase 2 before its first learning problem; archive starts asked for without
    /// [`Phase2Inputs::starts`] are refused.
    pub fn new(inputs: Phase2Inputs<'a, E>) -> Result<Self> {
        let starts = super::starts::archive_starts(inputs.config(), inputs.starts)?;
        let inputs = inputs.with_starts(starts);
        Ok(Phase2Run {
            obs: crate::env::observations(inputs.env, inputs.tau),
            ledger: Ledger::new(inputs.spent),
            at: Between::start(inputs.tau.len() - 1),
            repairs: None,
            ended: None,
            inputs,
        })
    }

    /// Phase 2 where a run of the same inputs stood when `state` was copied out of it: it goes
    /// on to the outcome of the run never cut (the same chain, failure, step counts and trace,
    /// its wall clock aside). A state that cannot be this run's (indices past τ, policies or a
    /// learner of other sizes or settings) is refused.
    pub fn resume(inputs: Phase2Inputs<'a, E>, state: Phase2State<E::State>) -> Result<Self> {
        let mut run = Phase2Run::new(inputs)?;
        run.restore(state)?;
        Ok(run)
    }

    /// Runs the next learning problem of Algorithm 1 on the whole τ, or once it has found a
    /// whole chain (with `phase2.chain_verify_episodes`) the next verification of the chain or
    /// learning problem of its repair: `Continue` while steps are left (a state copied out now
    /// goes on from there), `Break` once phase 2 has ended (at once when it had).
    pub fn next_problem(
        &mut self,
        progress: &mut dyn FnMut(usize, Progress),
    ) -> Result<ControlFlow<()>> {
        if self.ended.is_some() {
            return Ok(ControlFlow::Break(()));
        }
        let along = Along {
            inputs: &self.inputs,
            obs: &self.obs,
        };
        let config = self.inputs.config();
        let flow = match (&mut self.repairs, config.ideas.chain_check) {
            (Some(at), Some(check)) => {
                let mut repairs = Repairs {
                    along,
                    ledger: &mut self.ledger,
                    progress,
                };
                repairs.step(at, check)?
            }
            _ => {
                let mut problems = Section {
                    along,
                    ledger: &mut self.ledger,
                    lo: 0,
                    hi: self.inputs.tau.len() - 1,
                    entries: &[],
                    progress,
                };
                self.at.step(config, &mut problems)?
            }
        };
        let ControlFlow::Break(failure) = flow else {
            return Ok(ControlFlow::Continue(()));
        };
        if let (None, Some(_), None) = (failure, config.ideas.chain_check, &self.repairs) {
            // A whole chain: its verification and repairs follow.
            let chain = self.at.clone().into_skills();
            self.repairs = Some(RepairsAt::new(chain, self.inputs.seeds));
            return Ok(ControlFlow::Continue(()));
        }
        self.ended = Some(failure);
        Ok(ControlFlow::Break(()))
    }

    /// Runs what is left of phase 2 (Algorithm 1, then with `phase2.chain_verify_episodes` the
    /// chain's verification and repair): the outcome.
    pub fn finish(mut self, progress: &mut dyn FnMut(usize, Progress)) -> Result<Phase2Outcome> {
        while self.next_problem(progress)?.is_continue() {}
        let along = Along {
            inputs: &self.inputs,
            obs: &self.obs,
        };
        let found = match self.repairs {
            Some(repairs) => repairs.chain,
            None => self.at.into_skills(),
        };
        Ok(Phase2Outcome {
            chain: SkillChain {
                skills: along.skills(0, found),
                kernel: self.inputs.kernel,
            },
            failure: self.ended.flatten(),
            steps: self.ledger.steps,
            trace: self.ledger.trace,
        })
    }

    /// The run as it stands between two of its steps, for [`Phase2Run::resume`] (serialises the
    /// learner the next skill takes over, if one is).
    pub fn state(&self) -> Result<Phase2State<E::State>> {
        let warm = match &self.ledger.last {
            Some((t, learner)) => Some((*t, learner.save_state()?)),
            None => None,
        };
        Ok(Phase2State {
            between: self.at.clone(),
            repairs: self.repairs.clone(),
            made: self.ledger.made,
            spent: self.ledger.spent,
            steps: self.ledger.steps,
            trace: self.ledger.trace.clone(),
            warm,
        })
    }

    /// The kernel of the learner the next skill takes over, if one is handed over.
    pub fn warm_kernel(&self) -> Option<Kernel> {
        self.ledger.last.as_ref().map(|(_, l)| l.kernel())
    }

    /// Puts `state` into this new run; refuses a state that cannot be this run's.
    fn restore(&mut self, state: Phase2State<E::State>) -> Result<()> {
        let (env, inputs) = (self.inputs.env, &self.inputs);
        let n = inputs.tau.len() - 1;
        let b = &state.between;
        let (obs_dim, action_dim) = (env.obs_dim(), env.action_dim());
        // Skills (K, T, π) on τ_0 … τ_n: within it, of this run's sizes.
        let fit = |skills: &[Found], n: usize| {
            skills.iter().all(|(k, t, p)| {
                k <= t && *t <= n && p.obs_dim() == obs_dim && p.action_dim() == action_dim
            })
        };
        let check = inputs.config().ideas.chain_check;
        let repairs_fit = state.repairs.as_ref().is_none_or(|r| {
            // Repairs begin once Algorithm 1 has found a whole chain, with the check asked for.
            b.t == 0
                && check.is_some_and(|c| r.repairs <= c.repairs)
                && fit(&r.chain, n)
                && r.open.as_ref().is_none_or(|o| {
                    o.i < r.chain.len()
                        && o.lo < o.hi
                        && o.hi <= n
                        && o.at.t <= o.hi - o.lo
                        && fit(&o.at.found, o.hi - o.lo)
                })
        });
        let past = b.t > n || !repairs_fit || state.made < b.made;
        let wrong_sizes = !fit(&b.found, n);
        if past || wrong_sizes || state.spent < self.ledger.spent {
            return Err(Error::invalid(
                "phase 2 state",
                format!(
                    "it does not fit this run (τ of {} states, observations of {obs_dim}, \
                     actions of {action_dim}): it is another run's",
                    n + 1
                ),
            ));
        }
        if let Some((t, bytes)) = &state.warm {
            let config = inputs.config();
            let bounds = config.learner_bounds(env);
            let mut learner =
                inputs
                    .learner
                    .build(obs_dim, &bounds, &inputs.seeds.skill(0), inputs.kernel)?;
            learner.restore_state(bytes)?;
            // The saved state names the kernel it was computed on; this run computes on its own
            // (one of the same bytes, `Kernel::same_bytes`, which the checkpoint checked).
            learner.set_kernel(inputs.kernel);
            self.ledger.last = Some((*t, learner));
        }
        self.ledger.spent = state.spent;
        self.ledger.made = state.made;
        self.ledger.steps = state.steps;
        self.ledger.earlier_seconds = state.trace.last().map_or(0.0, |r| r.seconds);
        self.ledger.trace = state.trace;
        self.at = state.between;
        self.repairs = state.repairs;
        Ok(())
    }
}
