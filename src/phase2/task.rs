//! The learning problem of one skill: reach its [`Goal`] (B_ε(τ_T), or the environment's
//! success for the last skill) from starts in B_ε(τ_K), with the paper's shaped reward
//! (Algorithm 3) — the [`Backplayer`] that Backplay drives. The networks see the skill's
//! [`Inputs`]: observations relative to the goal's centre, actions in [−1, 1]ᵈ.

use super::backplay::Backplayer;
use super::goal::{dist, BallMetric, Goal, GoalKind, Inputs};
use super::{EventKind, Phase2Config, StartMode, StepCounts};
use crate::env::{DrawGoals, DrawStarts, Env, SampleBall, VelocityBalls};
use crate::learner::replay::{Batch, Replay};
use crate::learner::Learner;
use crate::policy::Policy;
use crate::rng::Rng;
use crate::rollout::{lockstep, Agent, Tally, Verdict};

/// L_k for each of `states` = τ_0 … τ_T: τ's length from τ_k to τ_T (in position,
/// [`Env::position`]).
fn lengths_to_goal<E: Env>(env: &E, states: &[E::State]) -> Vec<f32> {
    let obs = crate::env::observations(env, states);
    let mut lengths = vec![0.0; obs.len()];
    for k in (0..obs.len().saturating_sub(1)).rev() {
        lengths[k] = lengths[k + 1] + dist(env.position(&obs[k]), env.position(&obs[k + 1]));
    }
    lengths
}

/// The step limit of an episode from each τ_k towards the goal of τ_T, given L_k
/// ([`lengths_to_goal`]): `max_steps`, or with a path limit p > 0
/// ([`crate::phase2::EpisodeLimit`], [`Phase2Config::path_limits`]) at most
/// ⌈p (L_k + 2ε) / a⌉, a being how far one step can go ([`Env::step_reach`], as `ready`
/// took it from the environment it checked).
fn episode_limits<E: Env>(
    ready: super::Ready<'_, E>,
    p: Option<f32>,
    lengths: &[f32],
) -> Vec<usize> {
    let config = ready.settings();
    // With a path limit, `Ready` holds the reach (its construction refuses the settings
    // otherwise, `Capability::StepReach`); without one, no reach is needed.
    let (Some(p), Some(a)) = (p, ready.step_reach()) else {
        return vec![config.max_steps; lengths.len()];
    };
    lengths
        .iter()
        .map(|l| {
            let steps = (p * (l + 2.0 * config.epsilon) / a).ceil();
            (steps as usize).clamp(1, config.max_steps)
        })
        .collect()
}

/// One skill's learning problem on a trajectory section τ_0 … τ_T.
pub struct SkillTask<'a, E: Env> {
    env: &'a E,
    /// Where starts in B_ε(τ_k) come from: the environment's [`SampleBall`] with
    /// [`StartMode::Ball`] (required by [`SkillTask::new`]) — and with [`StartMode::Archive`]
    /// until [`SkillTask::with_starts`] gives the archive's —, `None` with exact starts.
    ball: Option<&'a dyn SampleBall<E::State>>,
    /// With balls in position and velocity ([`crate::phase2::goal::BallMetric`]) and
    /// [`StartMode::Ball`], the environment's [`VelocityBalls`], which then draw the starts.
    velocity: Option<&'a dyn VelocityBalls<E::State>>,
    /// With a goal each episode draws ([`GoalKind::Drawn`]), the environment's [`DrawGoals`],
    /// which gives every start its goal.
    drawn: Option<&'a dyn DrawGoals<E::State>>,
    /// With `phase2.first_starts = "drawn"`, the environment's [`DrawStarts`], which draws
    /// the starts at K = 0 (on a section from τ_0: [`SkillTask::at_offset`]).
    first: Option<&'a dyn DrawStarts<E::State>>,
    config: &'a Phase2Config,
    /// τ_0 … τ_T (states) and their observations.
    states: &'a [E::State],
    t: usize,
    /// The region this skill must reach (decides reached, terminal, reward and Φ).
    pub goal: Goal,
    /// What the networks see and emit.
    pub inputs: Inputs,
    /// The learner being trained: a fresh one for each skill, as in the paper, or the previous
    /// problem's with a warm start ([`crate::phase2::SkillInit::Warm`]).
    pub learner: Box<dyn Learner>,
    replay: Replay,
    batch: Batch,
    rng_start: Rng,
    rng_noise: Rng,
    rng_replay: Rng,
    /// Environment steps spent so far.
    pub steps: StepCounts,
    /// Steps this task may spend; once spent, tests and rounds return 0 without running.
    budget: u64,
    /// States where an executed chain entered this skill's section (chain repair): half of
    /// the starts at K = 0 are drawn from them, half uniformly in B_ε(τ_0). Empty otherwise.
    entries: Vec<E::State>,
    /// The step limit of a training episode from each τ_k (`max_steps`, or less with
    /// [`crate::phase2::EpisodeLimit`]), and of a greedy one (tests, verification; less also
    /// with [`Phase2Config::test_path_limit`]).
    limits: Vec<usize>,
    test_limits: Vec<usize>,
    /// The skills found after this one, looked ahead to at its goal (`phase2.lookahead`).
    lookahead: Option<super::lookahead::Lookahead>,
    /// Called after each test and training round.
    pub on_event: Option<Box<dyn FnMut(super::Progress) + 'a>>,
}

impl<'a, E: Env> SkillTask<'a, E> {
    /// The task of reaching `goal` (the goal of τ_T, `t`: [`Phase2Config::goal`]) along
    /// `states` with `learner`, whose actions live in [`Phase2Config::learner_bounds`]; random
    /// streams for starts, noise and replay sampling are passed in. The settings come checked
    /// against `env` ([`super::Ready`]). Its step budget is unbounded until
    /// [`SkillTask::with_budget`] sets it.
    pub fn new(
        env: &'a E,
        ready: super::Ready<'a, E>,
        states: &'a [E::State],
        goal: Goal,
        t: usize,
        learner: Box<dyn Learner>,
        rngs: [Rng; 3],
    ) -> Self {
        let config = ready.settings();
        let [rng_start, rng_noise, rng_replay] = rngs;
        let inputs = config.inputs(env, &goal);
        let lengths = lengths_to_goal(env, &states[..=t]);
        let (train_limit, greedy_limit) = config.path_limits();
        SkillTask {
            env,
            ball: match config.start {
                // Archive starts replace it ([`SkillTask::with_starts`]).
                StartMode::Ball | StartMode::Archive => env.ball_starts(),
                StartMode::Exact => None,
            },
            velocity: match (config.start, config.ball) {
                (StartMode::Ball, BallMetric::PositionVelocity { .. }) => env.velocity_balls(),
                _ => None,
            },
            drawn: match goal.kind {
                GoalKind::Drawn => env.drawn_goals(),
                GoalKind::Ball | GoalKind::EnvSuccess => None,
            },
            // `ready` checked the hook.
            first: config.first_starts(env).ok().flatten(),
            config,
            states,
            t,
            goal,
            inputs,
            replay: Replay::new(
                learner.config().replay_size(),
                env.obs_dim(),
                env.action_dim(),
            ),
            batch: Batch::default(),
            learner,
            rng_start,
            rng_noise,
            rng_replay,
            steps: StepCounts::default(),
            budget: u64::MAX,
            entries: Vec::new(),
            limits: episode_limits(ready, train_limit, &lengths),
            test_limits: episode_limits(ready, greedy_limit, &lengths),
            lookahead: None,
            on_event: None,
        }
    }

    /// Spends at most `budget` environment steps: once spent, tests and rounds return 0 without
    /// running.
    pub fn with_budget(mut self, budget: u64) -> Self {
        self.budget = budget;
        self
    }

    /// Draws half of the starts at K = 0 from `entries` (where an executed chain entered
    /// this section) instead of uniformly in B_ε(τ_0): chain repair.
    pub fn with_entries(mut self, entries: Vec<E::State>) -> Self {
        self.entries = entries;
        self
    }

    /// Looks ahead at the goal ([`super::Ideas::lookahead`]): its ball is reached only where
    /// `lookahead`'s skills carry the entry to their target. `None` (no skill found after this
    /// one yet) changes nothing.
    pub fn with_lookahead(mut self, lookahead: Option<super::lookahead::Lookahead>) -> Self {
        self.lookahead = lookahead;
        self
    }

    /// For a section τ_lo … τ_T of τ (a chain repair's, `lo` > 0): its K = 0 is τ_lo, not the
    /// chain's start, so `phase2.first_starts = "drawn"` does not draw its starts there.
    pub fn at_offset(mut self, lo: usize) -> Self {
        if lo > 0 {
            self.first = None;
        }
        self
    }

    /// With [`StartMode::Archive`], draws the starts in B_ε(τ_k) with `starts` (phase 1's
    /// archive, [`crate::phase2::ArchiveStarts`]); otherwise (or with `None`) changes nothing:
    /// a task with archive starts that is not given them draws from the environment's ball
    /// ([`crate::phase2::Phase2Run::new`] refuses that case).
    pub fn with_starts(mut self, starts: Option<&'a dyn SampleBall<E::State>>) -> Self {
        if let (StartMode::Archive, Some(starts)) = (self.config.start, starts) {
            self.ball = Some(starts);
        }
        self
    }

    /// The index of the goal's state in this task's section (τ_T).
    pub fn target(&self) -> usize {
        self.t
    }

    /// The steps it spent and its learner (the next skill's, with `phase2.warm_start`).
    pub fn into_parts(self) -> (StepCounts, Box<dyn Learner>) {
        (self.steps, self.learner)
    }

    fn spent_budget(&self) -> bool {
        self.steps.train + self.steps.test >= self.budget
    }

    /// `n` start states around τ_k (at K = 0 with `phase2.first_starts = "drawn"`, where the
    /// environment's reset draws them): uniform in B_ε(τ_k) (made by the environment, in position
    /// or in position and velocity, or drawn from phase 1's archive: [`StartMode::Archive`]),
    /// or τ_k itself ([`StartMode::Exact`]); with a drawn goal ([`GoalKind::Drawn`]), each
    /// then given a goal drawn as the environment's reset draws it.
    fn starts(&mut self, k: usize, n: usize) -> Vec<E::State> {
        use rand::Rng as _;
        // At K = 0 with `first_starts = "drawn"`, the environment's reset draws them.
        let first = self.first.filter(|_| k == 0);
        let starts: Vec<E::State> = (0..n)
            .map(|_| match first {
                _ if k == 0 && !self.entries.is_empty() && self.rng_start.random::<bool>() => {
                    let i = self.rng_start.random_range(0..self.entries.len());
                    self.entries[i].clone()
                }
                Some(d) => d.drawn_start(&self.states[0], &mut self.rng_start),
                None => match (self.velocity, self.ball) {
                    (Some(v), _) => v.sample_velocity_ball(
                        &self.states[k],
                        self.config.epsilon,
                        self.config.ball.scale(),
                        &mut self.rng_start,
                    ),
                    (None, Some(ball)) => {
                        ball.sample_ball(&self.states[k], self.config.epsilon, &mut self.rng_start)
                    }
                    (None, None) => self.states[k].clone(),
                },
            })
            .collect();
        match self.drawn {
            Some(d) => starts
                .iter()
                .map(|s| d.with_drawn_goal(s, &mut self.rng_start))
                .collect(),
            None => starts,
        }
    }

    /// `n` episodes in lockstep ([`crate::rollout::lockstep`]) from starts around τ_k, at
    /// most `max_steps` steps each (fewer with an [`crate::phase2::EpisodeLimit`], and for greedy
    /// ones `test_path_limit`); each step the actions of all running episodes come from one
    /// batched forward pass. With `learn`, noise is added, transitions are stored with the
    /// shaped reward and every step makes one learner update (Algorithm 3); without, the
    /// policy is greedy (a test). Returns the fraction of episodes that reached the goal (a
    /// lower bound for a test cut short by [`crate::phase2::Ideas::fast_tests`]).
    fn episodes(&mut self, k: usize, n: usize, learn: bool) -> f32 {
        self.episodes_of(k, n, learn, None)
    }

    /// [`Self::episodes`], greedy episodes acted by `policy` instead of the learner's π when
    /// one is given (a saved skill's policy, verified: the learner is not touched).
    fn episodes_of(&mut self, k: usize, n: usize, learn: bool, policy: Option<&dyn Policy>) -> f32 {
        debug_assert!(
            !(learn && policy.is_some()),
            "a saved policy is only verified"
        );
        let starts = self.starts(k, n);
        if learn {
            self.learner.begin_episodes(n);
        }
        let limit = if learn {
            self.limits[k]
        } else {
            self.test_limits[k]
        };
        let fast = self.config.ideas.fast_tests.filter(|_| !learn);
        let env = self.env;
        let ws = crate::nn::Workspace::with_kernel(self.learner.kernel());
        let mut agent = Episodes {
            task: self,
            policy,
            ws,
            learn,
            fast: fast.is_some(),
            view: Vec::new(),
            actions: Vec::new(),
            next_view: vec![0.0; env.obs_dim()],
            toward: Vec::new(),
        };
        // Neither 0 % nor 100 % is all Backplay needs to know of a fast test: it stops there,
        // within a group of episodes run side by side or between two.
        let mixed = |t: Tally| fast.is_some() && t.successes > 0 && t.failures > 0;
        // Groups for Backplay's tests of π only: a saved policy's verification keeps its
        // fraction whole (`verified` compares them).
        let grouped = fast.and_then(|f| f.lanes).filter(|_| policy.is_none());
        let lanes = grouped.unwrap_or(n).max(1);
        let (mut starts, mut tally) = (starts, Tally::default());
        while !starts.is_empty() && !mixed(tally) {
            let rest = starts.split_off(lanes.min(starts.len()));
            let (before, len) = (tally, starts.len());
            let with = |t: Tally| Tally {
                successes: before.successes + t.successes,
                failures: before.failures + t.failures,
            };
            agent.aim(&starts);
            let group = lockstep(env, &mut agent, starts, limit, |t: Tally| mixed(with(t)));
            // A group that ran to its end: an episode still running at the step limit failed
            // too (lockstep counts it neither way).
            tally = match mixed(with(group)) {
                true => with(group),
                false => with(Tally {
                    successes: group.successes,
                    failures: len - group.successes,
                }),
            };
            starts = rest;
        }
        tally.successes as f32 / n as f32
    }

    /// `episodes` greedy episodes of a saved `policy` from B_ε(τ_k), acted by that policy
    /// (the learner is not touched), reported as `kind`.
    fn greedy_with(
        &mut self,
        k: usize,
        policy: &dyn Policy,
        episodes: usize,
        kind: EventKind,
    ) -> f32 {
        if self.spent_budget() {
            return 0.0;
        }
        let p = self.episodes_of(k, episodes, false, Some(policy));
        self.report(k, kind, p);
        p
    }

    fn report(&mut self, k: usize, kind: EventKind, success: f32) {
        let steps = self.steps;
        if let Some(f) = self.on_event.as_mut() {
            f(super::Progress {
                k,
                t: self.t,
                kind,
                success,
                steps,
            });
        }
    }
}

impl<E: Env> Backplayer for SkillTask<'_, E> {
    type Policy = Box<dyn Policy>;

    fn test(&mut self, k: usize) -> f32 {
        if self.spent_budget() {
            return 0.0;
        }
        let p = self.episodes(k, self.config.beta, false);
        self.report(k, EventKind::Test, p);
        p
    }

    fn train(&mut self, k: usize) -> f32 {
        if self.spent_budget() {
            return 0.0;
        }
        let p = self.episodes(k, self.config.beta, true);
        self.report(k, EventKind::Train, p);
        p
    }

    fn policy(&self) -> Box<dyn Policy> {
        self.learner.policy()
    }

    /// Runs `episodes` greedy episodes of `policy` (acted by it; the learner is not touched).
    fn verify(&mut self, k: usize, policy: &Box<dyn Policy>, episodes: usize) -> f32 {
        self.greedy_with(k, policy.as_ref(), episodes, EventKind::Verify)
    }

    /// [`Self::verify`], reported as a `retarget` row.
    fn verify_handover(&mut self, k: usize, policy: &Box<dyn Policy>, episodes: usize) -> f32 {
        self.greedy_with(k, policy.as_ref(), episodes, EventKind::Retarget)
    }

    /// A `dead_walk` trace row at K, success 0.
    fn gave_up(&mut self, k: usize) {
        self.report(k, EventKind::DeadWalk, 0.0);
    }

    fn exhausted(&self) -> bool {
        self.spent_budget()
    }

    /// Whether B_ε(τ_k) is clear; `false` where the environment cannot tell (the settings that
    /// read it, `stop_at_failure` and `retargets`, are refused before the task is made).
    fn ball_is_clear(&self, k: usize) -> bool {
        self.env
            .clear_balls()
            .is_some_and(|c| c.ball_is_clear(&self.states[k], self.config.epsilon))
    }
}

/// [`SkillTask::episodes`]' agent: the task's learner acting on the skill's view of the
/// observations ([`Inputs`]), with noise and learning when training, judged by the skill's
/// goal.
struct Episodes<'t, 'a, 'p, E: Env> {
    task: &'t mut SkillTask<'a, E>,
    /// Who acts in greedy episodes: a saved policy being verified, or (None) the learner's π.
    policy: Option<&'p dyn Policy>,
    /// The saved policy's scratch, on the learner's kernel.
    ws: crate::nn::Workspace,
    learn: bool,
    /// A greedy episode that does not move is stuck for good (deterministic policy, pure
    /// step): with fast tests it ends as a failure at once.
    fast: bool,
    /// The networks' view of this step's observations, and the learner's actions (in its
    /// bounds, noise added when learning), one row per running episode.
    view: Vec<f32>,
    actions: Vec<f32>,
    next_view: Vec<f32>,
    /// With a drawn goal, each lane's goal and inputs moved to the goal its start drew
    /// ([`Goal::toward`], [`Inputs::toward`]); empty otherwise (the task's own).
    toward: Vec<(Goal, Inputs)>,
}

impl<E: Env> Episodes<'_, '_, '_, E> {
    /// Aims each lane of the episodes from `starts` at its start's own goal, with a drawn goal.
    fn aim(&mut self, starts: &[E::State]) {
        self.toward.clear();
        let Some(drawn) = self.task.drawn else {
            return;
        };
        let mut goal = vec![0.0; drawn.goal_dim()];
        for s in starts {
            drawn.desired_goal(s, &mut goal);
            let t = &*self.task;
            self.toward
                .push((t.goal.toward(&goal), t.inputs.toward(&goal)));
        }
    }
}

impl<E: Env> Agent<E> for Episodes<'_, '_, '_, E> {
    fn act(&mut self, lanes: &[usize], obs: &[f32], env_actions: &mut [f32]) {
        let t = &mut *self.task;
        let (obs_dim, act_dim) = (t.env.obs_dim(), t.env.action_dim());
        self.view.resize(obs.len(), 0.0);
        for ((r, o), lane) in obs
            .chunks_exact(obs_dim)
            .zip(self.view.chunks_exact_mut(obs_dim))
            .zip(lanes)
        {
            let inputs = self.toward.get(*lane).map_or(&t.inputs, |(_, i)| i);
            inputs.observation(r, o);
        }
        self.actions.clear();
        let actions = match (self.policy, self.learn) {
            (Some(p), _) => p.act(&self.view, lanes.len(), &mut self.ws),
            // Exploration within the learner's bounds (TD3's noise, SAC's sampling).
            (None, true) => t.learner.explore(&self.view, lanes, &mut t.rng_noise),
            (None, false) => t.learner.act(&self.view, lanes.len()),
        };
        self.actions.extend_from_slice(actions);
        for j in 0..lanes.len() {
            let a = &mut self.actions[j * act_dim..(j + 1) * act_dim];
            t.inputs
                .env_action(a, &mut env_actions[j * act_dim..(j + 1) * act_dim]);
        }
    }

    fn after(
        &mut self,
        j: usize,
        lane: usize,
        state: &E::State,
        obs: &[f32],
        step: &crate::env::Step<E::State>,
        next_obs: &[f32],
    ) -> Verdict {
        let t = &mut *self.task;
        let (goal, inputs) = match self.toward.get(lane) {
            Some((g, i)) => (g, i),
            None => (&t.goal, &t.inputs),
        };
        let mut reached = goal.reached(next_obs, step.terminal, step.reward);
        // With a lookahead, an entry into the goal ball (not the environment's own success)
        // counts only if the next skills carry it on; either way the episode ends there.
        let mut handed = false;
        let env_success = step.terminal && step.reward > 0.0;
        if let Some(l) = t.lookahead.as_ref().filter(|_| reached && !env_success) {
            // No skill takes over from a state the environment ended.
            let (carried, steps) = match step.terminal {
                true => (false, 0),
                false => l.carries(t.env, step.state.clone()),
            };
            (reached, handed) = (carried, true);
            match self.learn {
                true => t.steps.train += steps,
                false => t.steps.test += steps,
            }
        }
        if self.learn {
            t.steps.train += 1;
            let (obs_dim, act_dim) = (t.env.obs_dim(), t.env.action_dim());
            let r = goal.reward(obs, next_obs, reached);
            inputs.observation(next_obs, &mut self.next_view);
            let o = &self.view[j * obs_dim..(j + 1) * obs_dim];
            let a = &self.actions[j * act_dim..(j + 1) * act_dim];
            let done = goal.terminal(reached, step.terminal) || handed;
            t.replay.push(o, a, r, &self.next_view, done);
            let batch_size = t.learner.batch_size();
            if t.replay.len() >= batch_size {
                t.replay.sample(batch_size, &mut t.rng_replay, &mut t.batch);
                t.learner.update(&t.batch);
            }
        } else {
            t.steps.test += 1;
        }
        let stuck = self.fast && step.state == *state;
        if reached {
            Verdict::Success
        } else if step.terminal || stuck || handed {
            Verdict::Failure
        } else {
            Verdict::Running
        }
    }
}
