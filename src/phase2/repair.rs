//! The verification and repair of a finished chain (ours, `phase2.chain_verify_episodes` and
//! `phase2.chain_repairs`): the chain is executed from B_ε(s_0); a skill in whose section
//! episodes stall is learned again on its section τ_{K_i} … τ_{T_i}, half of the starts at
//! τ_{K_i} now being the states where the chain really entered its ball, and the result (one
//! skill, or several when Backplay cannot cover the section at once) replaces it.

use super::algorithm1::Between;
use super::inputs::{Along, Ledger};
use super::section::Section;
use super::{ChainCheck, EventKind, Failure, Progress, SkillChain, TraceRow};
use crate::env::{Capability, Env, SampleBall};
use crate::error::Result;
use crate::policy::Policy;
use crate::rng::{Rng, Stream};
use std::ops::ControlFlow;

/// What one verification of a chain found.
struct ChainTrial<S> {
    /// Episodes that reached the target.
    successes: usize,
    /// Failed episodes by the chain position of the skill in use when they stopped.
    stalled: Vec<usize>,
    /// By chain position: the states where episodes handed control to that skill.
    entries: Vec<Vec<S>>,
}

/// A skill as Algorithm 1 finds it: (K, T, π), its start and target indices and its policy.
pub type Found = (usize, usize, Box<dyn Policy>);

/// The chain's verification and repairs between two of their steps (a verification, or one
/// learning problem of a repair): what a run cut there goes on from.
#[derive(Debug, Clone)]
pub struct RepairsAt<S> {
    /// The chain so far, in execution order: (K, T, π), indices on the whole τ.
    pub chain: Vec<Found>,
    /// Repairs begun so far.
    pub repairs: usize,
    /// The stream the verifications draw their starts from, where it stands.
    pub rng: Rng,
    /// The repair under way, if one is.
    pub open: Option<OpenRepair<S>>,
}

/// A repair under way: Algorithm 1 again on the section τ_lo … τ_hi of the skill at chain
/// position `i`, half of the starts at τ_lo drawn from `entries`.
#[derive(Debug, Clone)]
pub struct OpenRepair<S> {
    /// The chain position it replaces.
    pub i: usize,
    /// The section's first index on τ: that skill's K.
    pub lo: usize,
    /// Its last: that skill's T.
    pub hi: usize,
    /// The states where the verification's episodes entered that skill.
    pub entries: Vec<S>,
    /// Algorithm 1 on the section (indices on it).
    pub at: Between<Box<dyn Policy>>,
}

impl<S> RepairsAt<S> {
    /// Before the first verification of `chain` (execution order, indices on τ): the
    /// verifications' starts from stream ChainVerify of `seeds`.
    pub fn new(chain: Vec<Found>, seeds: &crate::rng::Seeds) -> Self {
        RepairsAt {
            chain,
            repairs: 0,
            rng: seeds.stream(Stream::ChainVerify),
            open: None,
        }
    }
}

/// What a repair reads and writes: τ and the settings, the run's ledger, its progress.
pub(super) struct Repairs<'r, 'a, E: Env> {
    pub along: Along<'r, 'a, E>,
    pub ledger: &'r mut Ledger,
    pub progress: &'r mut dyn FnMut(usize, Progress),
}

impl<E: Env> Repairs<'_, '_, E> {
    /// One step of the verification and repair of a finished chain `at.chain`, which reads:
    ///
    /// ```text
    /// repeat:
    ///     run the chain from chain_verify_episodes starts in B_ε(s_0)   (a chain_verify trace row)
    ///     if every episode reached the target, or no repair is left: stop
    ///     i = the skill in use when the most failed episodes stopped (the first among ties)
    ///     E = the states where the episodes entered skill i
    ///     (π_i …) = Algorithm 1 on τ_{K_i} … τ_{T_i}, half of the starts at τ_{K_i} drawn from E
    ///     replace skill i by them (one skill, or several: a split)
    /// ```
    ///
    /// A step is one verification or one learning problem of a repair: `Continue` while steps
    /// are left (`at` copied out now goes on from there), `Break` with why the run failed, if it
    /// did, once they have ended. A repair that finds no skill leaves the chain as it was and
    /// ends the repairs; a verification or repair that runs out of the step budget ends the
    /// run with [`Failure::Budget`]. The chain_verify row's `skill` is the chain position of
    /// the skill blamed (the number of skills when the chain passed), its K and T that skill's
    /// (0 and N when it passed); the repair's own tests and training rounds follow as the rows
    /// of a new learning problem.
    pub fn step(
        &mut self,
        at: &mut RepairsAt<E::State>,
        spec: ChainCheck,
    ) -> Result<ControlFlow<Option<Failure>>> {
        let Some(mut open) = at.open.take() else {
            return self.verify(at, spec);
        };
        let config = self.along.config();
        let mut problems = Section {
            along: self.along,
            ledger: &mut *self.ledger,
            lo: open.lo,
            hi: open.hi,
            entries: &open.entries,
            progress: &mut *self.progress,
        };
        Ok(match open.at.step(config, &mut problems)? {
            ControlFlow::Continue(()) => {
                at.open = Some(open);
                ControlFlow::Continue(())
            }
            ControlFlow::Break(Some(Failure::Budget)) => ControlFlow::Break(Some(Failure::Budget)),
            ControlFlow::Break(Some(_)) => ControlFlow::Break(None),
            ControlFlow::Break(None) => {
                let lo = open.lo;
                let skills = open.at.into_skills().into_iter();
                let skills = skills.map(|(k, t, policy)| (lo + k, lo + t, policy));
                at.chain.splice(open.i..=open.i, skills);
                ControlFlow::Continue(())
            }
        })
    }

    /// A verification of `at.chain`, and where it fails and a repair is left, the repair of
    /// the skill blamed opened.
    fn verify(
        &mut self,
        at: &mut RepairsAt<E::State>,
        spec: ChainCheck,
    ) -> Result<ControlFlow<Option<Failure>>> {
        let setting = "phase2.chain_verify_episodes";
        let env = self.along.inputs.env;
        let ball = env
            .ball_starts()
            .ok_or_else(|| Capability::SampleBall.missing(setting))?;
        if self.exhausted() {
            return Ok(ControlFlow::Break(Some(Failure::Budget)));
        }
        let chain = SkillChain {
            skills: self.along.skills(0, at.chain.clone()),
            kernel: self.along.inputs.kernel,
        };
        let mut check = self.check(&chain, ball, spec.episodes, &mut at.rng);
        let success = check.successes as f32 / spec.episodes as f32;
        // The skill where the most failed episodes stopped (the first among ties).
        let blamed = (0..at.chain.len())
            .filter(|&i| check.stalled[i] > 0)
            .max_by_key(|&i| (check.stalled[i], std::cmp::Reverse(i)));
        let (skill, k, t) = match blamed {
            Some(i) => (i, at.chain[i].0, at.chain[i].1),
            None => (at.chain.len(), 0, self.along.inputs.tau.len() - 1),
        };
        self.report(skill, k, t, success);
        if self.exhausted() {
            // The verification itself used up the budget: as for any run that reaches it.
            return Ok(ControlFlow::Break(Some(Failure::Budget)));
        }
        let Some(i) = blamed else {
            return Ok(ControlFlow::Break(None));
        };
        if at.repairs >= spec.repairs {
            return Ok(ControlFlow::Break(None));
        }
        at.repairs += 1;
        at.open = Some(OpenRepair {
            i,
            lo: k,
            hi: t,
            entries: std::mem::take(&mut check.entries[i]),
            at: Between::start(t - k),
        });
        Ok(ControlFlow::Continue(()))
    }

    /// The chain_verify trace row and progress report of a verification.
    fn report(&mut self, skill: usize, k: usize, t: usize, success: f32) {
        let kind = EventKind::ChainVerify;
        let env_steps = self.ledger.spent;
        self.ledger.record(TraceRow {
            skill,
            k,
            t,
            event: kind,
            success,
            env_steps,
            seconds: 0.0,
        });
        let steps = self.ledger.steps;
        let n = self.ledger.made.saturating_sub(1);
        (self.progress)(
            n,
            Progress {
                k,
                t,
                kind,
                success,
                steps,
            },
        );
    }

    /// Runs `chain` greedily from `episodes` starts uniform in B_ε(s_0) (with
    /// `phase2.first_starts = "drawn"`, where the environment's reset draws them; each given a
    /// drawn goal where the chain aims at each episode's own), each skill allowed `max_steps`
    /// actions to hand over ([`SkillChain::run_limited`]); the steps are charged as test steps.
    fn check(
        &mut self,
        chain: &SkillChain,
        ball: &dyn SampleBall<E::State>,
        episodes: usize,
        rng: &mut Rng,
    ) -> ChainTrial<E::State> {
        let (env, tau, config) = (
            self.along.inputs.env,
            self.along.inputs.tau,
            self.along.config(),
        );
        let n = chain.skills.len();
        let mut out = ChainTrial {
            successes: 0,
            stalled: vec![0; n],
            entries: vec![Vec::new(); n],
        };
        let mut spent = 0;
        // `ready` checked the hook.
        let first = config.first_starts(env).ok().flatten();
        for _ in 0..episodes {
            let start = match first {
                Some(d) => d.drawn_start(&tau[0], rng),
                None => ball.sample_ball(&tau[0], config.epsilon, rng),
            };
            let start = chain.episode_start(env, start, rng);
            let r = chain.run_limited(env, start, config.eval_max_steps, Some(config.max_steps));
            spent += r.skill_used.len() as u64;
            let mut last = None;
            for (j, &i) in r.skill_used.iter().enumerate() {
                if last != Some(i) {
                    out.entries[i].push(r.states[j].clone());
                    last = Some(i);
                }
            }
            if r.success {
                out.successes += 1;
            } else if let Some(i) = last {
                out.stalled[i] += 1;
            }
        }
        self.ledger.steps.test += spent;
        self.ledger.spent += spent;
        out
    }

    fn exhausted(&self) -> bool {
        self.ledger.spent >= self.along.config().max_env_steps
    }
}
