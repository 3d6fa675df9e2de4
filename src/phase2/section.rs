//! Algorithm 1's learning problems on a section τ_lo … τ_hi of τ ([`Section`]: one
//! [`SkillTask`] each, charged to the run's [`Ledger`]).

use super::algorithm1::{Between, Problems};
use super::backplay::Backplayer;
use super::inputs::{stamp, Along, Ledger};
use super::lookahead::Lookahead;
use super::task::SkillTask;
use super::{Progress, TraceRow};
use crate::env::Env;
use crate::error::Result;
use crate::learner::Learner;
use crate::policy::Policy;
use crate::rng::Stream;

/// The learning problems of Algorithm 1 on τ_lo … τ_hi with the goal of τ_hi: each a
/// [`SkillTask`] (a learner fresh from the seeds or the last one, the shaped reward, starts in
/// B_ε(τ_K)), its steps and trace rows charged to `ledger`, its tests and rounds reported to
/// `progress(n, report)` with indices on the whole τ.
pub(super) struct Section<'r, 'a, E: Env> {
    pub along: Along<'r, 'a, E>,
    pub ledger: &'r mut Ledger,
    pub lo: usize,
    pub hi: usize,
    /// Start states at τ_lo drawn for half of the starts there (chain repair; empty otherwise).
    pub entries: &'r [E::State],
    pub progress: &'r mut dyn FnMut(usize, Progress),
}

impl<E: Env> Problems for Section<'_, '_, E> {
    type Policy = Box<dyn Policy>;

    fn pose<R>(
        &mut self,
        at: &Between<Box<dyn Policy>>,
        t: usize,
        solve: impl FnOnce(&mut dyn Backplayer<Policy = Box<dyn Policy>>) -> R,
    ) -> Result<(R, bool)> {
        let lookahead = self
            .along
            .config()
            .ideas
            .lookahead
            .and_then(|n| Lookahead::after(self.along, &at.found, self.lo, t, n));
        let mut task = self.task(t, lookahead)?;
        let r = solve(&mut task);
        let exhausted = task.exhausted();
        let (steps, learner) = task.into_parts();
        self.ledger.charge(steps);
        if self.along.config().warm_start() {
            self.ledger.last = Some((self.lo + t, learner));
        }
        Ok((r, exhausted))
    }
}

impl<E: Env> Section<'_, '_, E> {
    /// The next learning problem: reach the goal of τ_{lo+t} along τ_lo ….
    fn task(&mut self, t: usize, lookahead: Option<Lookahead>) -> Result<SkillTask<'_, E>> {
        let (inputs, lo) = (self.along.inputs, self.lo);
        let (env, config) = (inputs.env, inputs.config());
        let n = self.ledger.made;
        self.ledger.made += 1;
        let n32 = n as u32;
        let last = self.ledger.last.take();
        let learner = warm_or_fresh(last, config.warm_start(), lo + t, || {
            inputs.learner.build(
                env.obs_dim(),
                &config.learner_bounds(env),
                &inputs.seeds.skill(n32),
                inputs.kernel,
            )
        })?;
        let rngs = [
            inputs.seeds.substream(Stream::Start, n32),
            inputs.seeds.substream(Stream::Noise, n32),
            inputs.seeds.substream(Stream::Replay, n32),
        ];
        let budget = config.max_env_steps.saturating_sub(self.ledger.spent);
        let states = &inputs.tau[lo..=self.hi];
        let goal = self.along.goal(lo + t);
        let mut task = SkillTask::new(env, inputs.ready, states, goal, t, learner, rngs)
            .with_budget(budget)
            .with_entries(self.entries.to_vec())
            .with_starts(inputs.starts)
            .with_lookahead(lookahead)
            .at_offset(lo);
        let before = self.ledger.spent;
        let (clock, earlier) = (self.ledger.clock, self.ledger.earlier_seconds);
        let trace = &mut self.ledger.trace;
        let progress = &mut *self.progress;
        task.on_event = Some(Box::new(move |p: Progress| {
            let row = TraceRow {
                skill: n,
                k: lo + p.k,
                t: lo + p.t,
                event: p.kind,
                success: p.success,
                env_steps: before + p.steps.train + p.steps.test,
                seconds: 0.0,
            };
            stamp(trace, row, clock, earlier);
            let (k, t) = (lo + p.k, lo + p.t);
            progress(n, Progress { k, t, ..p });
        }));
        Ok(task)
    }
}

/// The learner of a new problem whose target is τ_`target`: with `warm_start`, a problem whose
/// target lies before the `last` one's (the next skill of the chain) takes over the last
/// learner; a restart (same target), a repair of a later section, and every problem without
/// the switch start from `fresh()`.
fn warm_or_fresh(
    last: Option<(usize, Box<dyn Learner>)>,
    warm_start: bool,
    target: usize,
    fresh: impl FnOnce() -> Result<Box<dyn Learner>>,
) -> Result<Box<dyn Learner>> {
    match last {
        Some((last_t, learner)) if warm_start && last_t > target => Ok(learner),
        _ => fresh(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::learner::LearnerConfig;
    use crate::nn::kernel::Kernel;
    use crate::rng::Seeds;

    /// With `warm_start`, the problem after a saved skill (an earlier target on τ) takes over
    /// the last learner; a restart (same target) or a repair of a later section starts from
    /// the seeds, as every problem does without the switch.
    #[test]
    fn warm_start_takes_over_the_last_learner_only_for_the_next_skill() {
        let lc = LearnerConfig::ddpg();
        let seeds = Seeds::new(5);
        let kernel = Kernel::detect();
        let fresh = || lc.build(1, &[1.0], &seeds.skill(0), kernel);
        // A learner unlike any fresh one: the weights of sub-run 99.
        let trained = lc.build(1, &[1.0], &seeds.skill(99), kernel).unwrap();
        let fresh_params = fresh().unwrap().policy();
        assert!(fresh_params != trained.policy());
        for warm in [false, true] {
            // (last target, new target, whether the last learner is taken over when warm)
            for (last_t, t, takes_over) in [(6, 3, true), (6, 6, false), (6, 8, false)] {
                let got = warm_or_fresh(Some((last_t, trained.clone())), warm, t, fresh).unwrap();
                let expected = if warm && takes_over {
                    &trained.policy()
                } else {
                    &fresh_params
                };
                assert!(
                    &got.policy() == expected,
                    "warm {warm}, T {last_t} → {t}: took over {}",
                    got.policy() == trained.policy()
                );
            }
            // The first problem has no last learner: fresh, warm or not.
            let first = warm_or_fresh(None, warm, 3, fresh).unwrap();
            assert!(
                first.policy().same(fresh_params.as_ref()),
                "warm {warm}, first problem"
            );
        }
    }
}
