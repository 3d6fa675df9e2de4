//! The verification and repair of a finished chain (ours, `phase2.chain_verify_episodes` and
//! `phase2.chain_repairs`): the chain is executed from B_ε(s_0); a skill in whose section
//! episodes stall is learned again on its section τ_{K_i} … τ_{T_i}, half of the starts at
//! τ_{K_i} now being the states where the chain really entered its ball, and the result (one
//! skill, or several when Backplay cannot cover the section at once) replaces it.

use super::algorithm1::Between;
use super::inputs::{Along, Ledger};
use super::section::Section;
use super::{ChainCheck, EventKind, Failure, Progress, Skill, SkillChain, TraceRow};
use crate::env::{Capability, Env, SampleBall};
use crate::error::Result;
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

/// What a repair reads and writes: τ and the settings, the run's ledger, its progress.
pub(super) struct Repairs<'r, 'a, E: Env> {
    pub along: Along<'r, 'a, E>,
    pub ledger: &'r mut Ledger,
    pub progress: &'r mut dyn FnMut(usize, Progress),
}

impl<E: Env> Repairs<'_, '_, E> {
    /// Verification and repair of a finished `chain`:
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
    /// A repair that finds no skill leaves the chain as it was and ends the repairs; a
    /// verification or repair that runs out of the step budget ends the run with
    /// [`Failure::Budget`]. The chain_verify row's `skill` is the chain position of the skill
    /// blamed (the number of skills when the chain passed), its K and T that skill's (0 and N
    /// when it passed); the repair's own tests and training rounds follow as the rows of a new
    /// learning problem.
    pub fn repair(&mut self, chain: &mut SkillChain, spec: ChainCheck) -> Result<Option<Failure>> {
        let setting = "phase2.chain_verify_episodes";
        let env = self.along.inputs.env;
        let ball = env
            .ball_starts()
            .ok_or_else(|| Capability::SampleBall.missing(setting))?;
        let mut rng = self.along.inputs.seeds.stream(Stream::ChainVerify);
        let mut repairs = 0;
        loop {
            if self.exhausted() {
                return Ok(Some(Failure::Budget));
            }
            let check = self.check(chain, ball, spec.episodes, &mut rng);
            let success = check.successes as f32 / spec.episodes as f32;
            // The skill where the most failed episodes stopped (the first among ties).
            let blamed = (0..chain.skills.len())
                .filter(|&i| check.stalled[i] > 0)
                .max_by_key(|&i| (check.stalled[i], std::cmp::Reverse(i)));
            let (skill, k, t) = match blamed {
                Some(i) => {
                    let s = &chain.skills[i];
                    (i, s.start_index, s.target_index)
                }
                None => (chain.skills.len(), 0, self.along.inputs.tau.len() - 1),
            };
            self.report(skill, k, t, success);
            if self.exhausted() {
                // The verification itself used up the budget: as for any run that reaches it.
                return Ok(Some(Failure::Budget));
            }
            let Some(i) = blamed else {
                return Ok(None);
            };
            if repairs == spec.repairs {
                return Ok(None);
            }
            repairs += 1;
            match self.section(k, t, &check.entries[i])? {
                (_, Some(Failure::Budget)) => return Ok(Some(Failure::Budget)),
                (_, Some(_)) => return Ok(None),
                (skills, None) => {
                    chain.skills.splice(i..=i, skills);
                }
            }
        }
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

    /// Algorithm 1 on the section τ_lo … τ_hi with the goal of τ_hi, `entries` drawn for half of
    /// the starts at τ_lo: the skills in execution order, with indices on the whole τ.
    fn section(
        &mut self,
        lo: usize,
        hi: usize,
        entries: &[E::State],
    ) -> Result<(Vec<Skill>, Option<Failure>)> {
        let config = self.along.config();
        let mut problems = Section {
            along: self.along,
            ledger: &mut *self.ledger,
            lo,
            hi,
            entries,
            progress: &mut *self.progress,
        };
        let mut at = Between::start(hi - lo);
        let failure = loop {
            if let ControlFlow::Break(failure) = at.step(config, &mut problems)? {
                break failure;
            }
        };
        Ok((self.along.skills(lo, at.into_skills()), failure))
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
