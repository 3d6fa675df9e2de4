//! Algorithm 1 on an environment's learning problems ([`chain_skills`]), and the verification and
//! repair of the finished chain (`repair_chain`, ours).
//!
//! Each skill is one learning problem ([`SkillTask`]: a learner, the shaped reward, starts in
//! B_ε(τ_K)) — a new DDPG as in the paper, or, with `phase2.warm_start`, the learner of the
//! skill saved before it; [`skill_chaining`] walks them backwards from τ_N. With
//! `phase2.chain_verify_episodes` the finished chain is then executed from B_ε(s_0); a skill in
//! whose section episodes stall is learned again on its section τ_{K_i} … τ_{T_i}, half of the
//! starts at τ_{K_i} now being the states where the chain really entered its ball, and the
//! result (one skill, or several when Backplay cannot cover the section at once) replaces it.

use super::backplay::{self, handover, verified};
use super::resume::{Between, Chained};
use super::task::{SkillTask, StepCounts};
use super::{
    Ball, EventKind, Failure, Phase2Config, Phase2Outcome, Progress, Ready, Skill, SkillChain,
    TraceRow,
};
use crate::env::{Capability, Env, SampleBall};
use crate::error::Result;
use crate::learner::{Learner, LearnerConfig};
use crate::nn::kernel::Kernel;
use crate::policy::Policy;
use crate::rng::{Rng, Seeds, Stream};
use std::cell::{Cell, RefCell};
use std::time::Instant;

/// Phase 2 on a trajectory τ: [`skill_chaining`] with a [`SkillTask`] (fresh learner, shaped
/// reward, starts in B_ε(τ_K)) per skill, then, with `phase2.chain_verify_episodes`, the
/// chain's verification and repair (`repair_chain`, in this module).
///
/// Learning problem n's learner is initialised from the run's seeds for sub-run n (or, with
/// `phase2.warm_start`, taken over from the skill before it), and its
/// starts, noise and replay sampling read substream n (n counts restarts and repairs too, so
/// it equals the skill's index when nothing restarts); `spent` is the step count already used
/// (phase 1), charged against `config.max_env_steps`. Archive starts need phase 1's archive
/// ([`chain_skills_with_starts`]): refused here.
#[allow(clippy::too_many_arguments)]
pub fn chain_skills<E: Env>(
    env: &E,
    tau: &[E::State],
    learner: &LearnerConfig,
    config: Ready<'_, E>,
    seeds: &Seeds,
    spent: u64,
    kernel: Kernel,
    progress: impl FnMut(usize, Progress),
) -> Result<Phase2Outcome> {
    chain_skills_with_starts(
        env, tau, None, learner, config, seeds, spent, kernel, progress,
    )
}

/// [`chain_skills`], with Backplay's starts in B_ε(τ_K) drawn by `starts` where
/// `phase2.start = "archive"` asks for them (phase 1's archive, [`super::ArchiveStarts`]);
/// that setting without `starts` is refused.
#[allow(clippy::too_many_arguments)]
pub fn chain_skills_with_starts<E: Env>(
    env: &E,
    tau: &[E::State],
    starts: Option<&dyn SampleBall<E::State>>,
    learner: &LearnerConfig,
    ready: Ready<'_, E>,
    seeds: &Seeds,
    spent: u64,
    kernel: Kernel,
    mut progress: impl FnMut(usize, Progress),
) -> Result<Phase2Outcome> {
    let outcome = super::resume::chain_skills_resumable(
        env,
        tau,
        starts,
        learner,
        ready,
        seeds,
        spent,
        kernel,
        &mut progress,
        None,
        |_| Ok(false),
    )?;
    Ok(outcome.expect("a pause that never asks to stop"))
}

/// The state of one phase 2: τ, the settings, the step count and the trace, shared by the
/// learning problems it makes.
pub(crate) struct Chainer<'a, E: Env, P: FnMut(usize, Progress)> {
    pub(super) env: &'a E,
    pub(super) tau: &'a [E::State],
    /// Backplay's starts where they are not the environment's ball ([`super::StartMode::Archive`]).
    pub(super) starts: Option<&'a dyn SampleBall<E::State>>,
    pub(super) obs: Vec<Vec<f32>>,
    pub(super) learner: &'a LearnerConfig,
    pub(super) config: &'a Phase2Config,
    /// `config`, checked against `env`, for each learning problem ([`SkillTask::new`]).
    pub(super) ready: Ready<'a, E>,
    pub(super) seeds: &'a Seeds,
    /// The layer kernel of every learner and of the chain.
    pub(super) kernel: Kernel,
    /// Environment steps of the whole run so far (phase 1 included).
    pub(super) spent: Cell<u64>,
    /// Learning problems made so far (skills, restarts, repairs).
    pub(super) made: Cell<usize>,
    /// The last learning problem's learner and its target's index on τ (warm start).
    pub(super) last: RefCell<Option<(usize, Box<dyn Learner>)>>,
    pub(super) steps: Cell<StepCounts>,
    pub(super) trace: RefCell<Vec<TraceRow>>,
    pub(super) clock: Instant,
    /// Wall-clock seconds of the run before this process resumed it (trace rows count on).
    pub(super) earlier_seconds: Cell<f64>,
    pub(super) progress: RefCell<&'a mut P>,
    /// The skills found so far on the section being chained, as Algorithm 1 holds them (for
    /// `phase2.lookahead`).
    #[allow(clippy::type_complexity)]
    pub(super) found: RefCell<Vec<(usize, usize, Box<dyn Policy>)>>,
}

impl<'a, E: Env, P: FnMut(usize, Progress)> Chainer<'a, E, P> {
    #[allow(clippy::too_many_arguments)]
    pub(super) fn new(
        env: &'a E,
        tau: &'a [E::State],
        starts: Option<&'a dyn SampleBall<E::State>>,
        learner: &'a LearnerConfig,
        ready: Ready<'a, E>,
        seeds: &'a Seeds,
        spent: u64,
        kernel: Kernel,
        progress: &'a mut P,
    ) -> Self {
        Chainer {
            env,
            tau,
            starts,
            obs: crate::env::observations(env, tau),
            learner,
            config: ready.settings(),
            ready,
            seeds,
            kernel,
            spent: Cell::new(spent),
            made: Cell::new(0),
            last: RefCell::new(None),
            steps: Cell::new(StepCounts::default()),
            trace: RefCell::new(Vec::new()),
            clock: Instant::now(),
            earlier_seconds: Cell::new(0.0),
            progress: RefCell::new(progress),
            found: RefCell::new(Vec::new()),
        }
    }

    /// Algorithm 1 on the section τ_lo … τ_hi with the goal of τ_hi
    /// ([`Phase2Config::goal`]): the skills in execution order, with indices on the whole τ.
    /// `entries` (chain repair) are start states at τ_lo drawn for half of the starts there.
    fn section(
        &self,
        lo: usize,
        hi: usize,
        entries: &[E::State],
    ) -> Result<(Vec<Skill>, Option<Failure>)> {
        match self.section_from(lo, hi, entries, Between::start(hi - lo), |_| Ok(false))? {
            Chained::Done(found, failure) => Ok((self.skills(lo, found), failure)),
            Chained::Paused(_) => unreachable!("a pause that never asks to stop"),
        }
    }

    /// [`Chainer::section`] from `from`, asking `pause` after each learning problem
    /// ([`skill_chaining_from`]); the skills found, with indices on the section.
    pub(super) fn section_from(
        &self,
        lo: usize,
        hi: usize,
        entries: &[E::State],
        from: Between<Box<dyn Policy>>,
        mut pause: impl FnMut(&Between<Box<dyn Policy>>) -> Result<bool>,
    ) -> Result<Chained<Box<dyn Policy>>> {
        let states = &self.tau[lo..=hi];
        let looks = self.config.ideas.lookahead.is_some();
        if looks {
            *self.found.borrow_mut() = from.found.clone();
        }
        skill_chaining_from(
            from,
            self.config,
            |_, t| self.task(states, lo, t, entries),
            |task| {
                let mut steps = self.steps.get();
                steps.train += task.steps.train;
                steps.test += task.steps.test;
                self.steps.set(steps);
                self.spent
                    .set(self.spent.get() + task.steps.train + task.steps.test);
                if self.config.warm_start() {
                    *self.last.borrow_mut() = Some((lo + task.target(), task.learner));
                }
            },
            |at| {
                if looks {
                    *self.found.borrow_mut() = at.found.clone();
                }
                pause(at)
            },
        )
    }

    /// The skills of `found` (execution order, indices on the section from τ_lo).
    pub(super) fn skills(
        &self,
        lo: usize,
        found: Vec<(usize, usize, Box<dyn Policy>)>,
    ) -> Vec<Skill> {
        found
            .into_iter()
            .map(|(k, t, policy)| {
                let goal = self.config.goal(self.env, &self.obs, lo + t);
                Skill {
                    policy,
                    activation: Ball::around(
                        self.env,
                        &self.obs[lo + k],
                        self.config.epsilon,
                        self.config.ball,
                    ),
                    start_index: lo + k,
                    target_index: lo + t,
                    inputs: self.config.inputs(self.env, &goal),
                }
            })
            .collect()
    }

    /// The next fresh learning problem: reach the goal of τ_{lo+t} along `states` = τ_lo ….
    fn task<'s>(
        &'s self,
        states: &'s [E::State],
        lo: usize,
        t: usize,
        entries: &[E::State],
    ) -> Result<SkillTask<'s, E>> {
        let n = self.made.get();
        self.made.set(n + 1);
        let n32 = n as u32;
        let (env, config) = (self.env, self.config);
        let last = self.last.borrow_mut().take();
        let learner = warm_or_fresh(last, config.warm_start(), lo + t, || {
            self.learner.build(
                env.obs_dim(),
                &config.learner_bounds(env),
                &self.seeds.skill(n32),
                self.kernel,
            )
        })?;
        let rngs = [
            self.seeds.substream(Stream::Start, n32),
            self.seeds.substream(Stream::Noise, n32),
            self.seeds.substream(Stream::Replay, n32),
        ];
        let budget = config.max_env_steps.saturating_sub(self.spent.get());
        let goal = config.goal(env, &self.obs, lo + t);
        let mut task = SkillTask::new(env, self.ready, states, goal, t, learner, rngs, budget)
            .with_entries(entries.to_vec())
            .with_starts(self.starts)
            .with_lookahead(
                config
                    .ideas
                    .lookahead
                    .and_then(|n| self.lookahead(lo, t, n)),
            )
            .at_offset(lo);
        let before = self.spent.get();
        task.on_event = Some(Box::new(move |p: Progress| {
            self.record(TraceRow {
                skill: n,
                k: lo + p.k,
                t: lo + p.t,
                event: p.kind,
                success: p.success,
                env_steps: before + p.steps.train + p.steps.test,
                seconds: 0.0,
            });
            (self.progress.borrow_mut())(
                n,
                Progress {
                    k: lo + p.k,
                    t: lo + p.t,
                    ..p
                },
            );
        }));
        Ok(task)
    }

    fn record(&self, mut row: TraceRow) {
        row.seconds = self.earlier_seconds.get() + self.clock.elapsed().as_secs_f64();
        self.trace.borrow_mut().push(row);
    }

    fn exhausted(&self) -> bool {
        self.spent.get() >= self.config.max_env_steps
    }
}

/// What one verification of a chain found.
struct ChainTrial<S> {
    /// Episodes that reached the target.
    successes: usize,
    /// Failed episodes by the chain position of the skill in use when they stopped.
    stalled: Vec<usize>,
    /// By chain position: the states where episodes handed control to that skill.
    entries: Vec<Vec<S>>,
}

/// Runs `chain` greedily from `episodes` starts uniform in B_ε(s_0) (with
/// `phase2.first_starts = "drawn"`, where the environment's reset draws them; each given a
/// drawn goal where the chain aims at each episode's own), each skill allowed
/// `max_steps` actions to hand over ([`SkillChain::run_limited`]); the steps are charged as
/// test steps.
fn check_chain<E: Env, P: FnMut(usize, Progress)>(
    c: &Chainer<'_, E, P>,
    chain: &SkillChain,
    ball: &dyn SampleBall<E::State>,
    episodes: usize,
    rng: &mut Rng,
) -> ChainTrial<E::State> {
    let n = chain.skills.len();
    let mut out = ChainTrial {
        successes: 0,
        stalled: vec![0; n],
        entries: vec![Vec::new(); n],
    };
    let mut spent = 0;
    // `ready` checked the hook.
    let first = c.config.first_starts(c.env).ok().flatten();
    for _ in 0..episodes {
        let start = match first {
            Some(d) => d.drawn_start(&c.tau[0], rng),
            None => ball.sample_ball(&c.tau[0], c.config.epsilon, rng),
        };
        let start = chain.episode_start(c.env, start, rng);
        let r = chain.run_limited(
            c.env,
            start,
            c.config.eval_max_steps,
            Some(c.config.max_steps),
        );
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
    let mut steps = c.steps.get();
    steps.test += spent;
    c.steps.set(steps);
    c.spent.set(c.spent.get() + spent);
    out
}

/// Verification and repair of a finished chain (ours, `phase2.chain_verify_episodes` and
/// `phase2.chain_repairs`):
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
/// [`Failure::Budget`]. The chain_verify row's
/// `skill` is the chain position of the skill blamed (the number of skills when the chain
/// passed), its K and T that skill's (0 and N when it passed); the repair's own tests and
/// training rounds follow as the rows of a new learning problem.
pub(crate) fn repair_chain<E: Env, P: FnMut(usize, Progress)>(
    c: &Chainer<'_, E, P>,
    chain: &mut SkillChain,
    spec: super::ChainCheck,
) -> Result<Option<Failure>> {
    let setting = "phase2.chain_verify_episodes";
    let ball = c
        .env
        .ball_starts()
        .ok_or_else(|| Capability::SampleBall.missing(setting))?;
    let mut rng = c.seeds.stream(Stream::ChainVerify);
    let mut repairs = 0;
    loop {
        if c.exhausted() {
            return Ok(Some(Failure::Budget));
        }
        let check = check_chain(c, chain, ball, spec.episodes, &mut rng);
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
            None => (chain.skills.len(), 0, c.tau.len() - 1),
        };
        c.record(TraceRow {
            skill,
            k,
            t,
            event: EventKind::ChainVerify,
            success,
            env_steps: c.spent.get(),
            seconds: 0.0,
        });
        let steps = c.steps.get();
        (c.progress.borrow_mut())(
            c.made.get().saturating_sub(1),
            Progress {
                k,
                t,
                kind: EventKind::ChainVerify,
                success,
                steps,
            },
        );
        if c.exhausted() {
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
        let (skills, failure) = c.section(k, t, &check.entries[i])?;
        match failure {
            Some(Failure::Budget) => return Ok(Some(Failure::Budget)),
            Some(_) => return Ok(None),
            None => {
                chain.skills.splice(i..=i, skills);
            }
        }
    }
}

/// Algorithm 1 on any [`backplay::Backplayer`]: skills are found backwards from T = N and
/// returned in execution order as `(K_i, T_i, π_i)` ([`skill_chaining_from`] from the start,
/// never paused).
#[allow(clippy::type_complexity)]
pub fn skill_chaining<B: backplay::Backplayer>(
    n: usize,
    config: &Phase2Config,
    next: impl FnMut(usize, usize) -> Result<B>,
    finished: impl FnMut(B),
) -> Result<(Vec<(usize, usize, B::Policy)>, Option<Failure>)> {
    match skill_chaining_from(Between::start(n), config, next, finished, |_| Ok(false))? {
        Chained::Done(skills, failure) => Ok((skills, failure)),
        Chained::Paused(_) => unreachable!("a pause that never asks to stop"),
    }
}

/// Algorithm 1 from `from` (the start, [`Between::start`], or where a cut run stood):
///
/// ```text
/// T = N
/// while T > 0:
///     (π_n, T) = Backplay(τ_0 … τ_T);  A_n = B_ε(τ_T);  n += 1
/// reverse π and A
/// ```
///
/// α, the K walk, early stopping, verification, restarts and chaining come from `config`.
/// `next(n, T)` makes the n-th learning problem (its learner fresh from the seeds, or, with
/// `warm_start`, the last saved skill's; n counts restarts too, so it equals the skill's index
/// when nothing restarts);
/// `finished(b)` receives it back after its Backplay (to collect step counts). A problem whose
/// [`backplay::Backplayer::exhausted`] is true after Backplay ends the run with
/// [`Failure::Budget`]. Without chaining, a first skill that does not start at τ_0 ends the run
/// with [`Failure::NoChaining`]. After each learning problem that leaves work to do,
/// `pause(&between)` is asked whether to stop there: `true` returns [`Chained::Paused`] with
/// it, from which the same calls go on to the same result.
#[allow(clippy::type_complexity)]
pub fn skill_chaining_from<B: backplay::Backplayer>(
    from: Between<B::Policy>,
    config: &Phase2Config,
    mut next: impl FnMut(usize, usize) -> Result<B>,
    mut finished: impl FnMut(B),
    mut pause: impl FnMut(&Between<B::Policy>) -> Result<bool>,
) -> Result<Chained<B::Policy>> {
    let mut at = from;
    let mut failure = None;
    // Hand-over moves follow a dead walk (`phase2.dead_walk`, `phase2.retargets`).
    let (dead_walk, retargets) = config
        .ideas
        .dead_walk
        .map_or((0, 0), |d| (d.after, d.retargets));
    while at.t > 0 {
        let mut b = next(at.made, at.t)?;
        at.made += 1;
        let walk = backplay::Walk::of(config, at.restarts < config.ideas.restarts);
        let candidates = backplay::backplay_candidates(&mut b, at.t, &walk);
        let found = verified(&mut b, candidates, config.ideas.verify_skills);
        let exhausted = b.exhausted();
        finished(b);
        match found {
            _ if exhausted => {
                failure = Some(Failure::Budget);
                break;
            }
            None if at.restarts < config.ideas.restarts => at.restarts += 1,
            None if at.moves < retargets && !at.found.is_empty() => {
                // No attempt found any K towards τ_T: move the hand-over of the skill found
                // last (start T, target T′) to a later index of τ, if it passes from there.
                let (_, t_last, policy) = at.found.last().expect("not empty");
                let mut b = next(at.made, *t_last)?;
                at.made += 1;
                let episodes = config.handover_episodes();
                let moved = handover(&mut b, at.t, *t_last, policy, episodes, dead_walk);
                let exhausted = b.exhausted();
                finished(b);
                match moved {
                    _ if exhausted => {
                        failure = Some(Failure::Budget);
                        break;
                    }
                    Some(k) => {
                        at.found.last_mut().expect("not empty").0 = k;
                        at.t = k;
                        (at.restarts, at.moves) = (0, at.moves + 1);
                    }
                    None => {
                        failure = Some(Failure::BackplayFailed);
                        break;
                    }
                }
            }
            None => {
                failure = Some(Failure::BackplayFailed);
                break;
            }
            Some((k, policy)) => {
                (at.restarts, at.moves) = (0, 0);
                at.found.push((k, at.t, policy));
                if k > 0 && !config.chaining {
                    failure = Some(Failure::NoChaining);
                    break;
                }
                at.t = k;
            }
        }
        if at.t > 0 && pause(&at)? {
            return Ok(Chained::Paused(at));
        }
    }
    let mut skills = at.found;
    skills.reverse();
    Ok(Chained::Done(skills, failure))
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
#[path = "chaining_tests.rs"]
mod tests;
