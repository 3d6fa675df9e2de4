//! The learning problem of one skill: reach its [`Goal`] (B_ε(τ_T), or the environment's
//! success for the last skill) from starts in B_ε(τ_K), with the paper's shaped reward
//! (Algorithm 3) — the [`Backplayer`] that Backplay drives. The networks see the skill's
//! [`Inputs`]: observations relative to the goal's centre, actions in [−1, 1]ᵈ.

use super::backplay::Backplayer;
use super::goal::{dist, Goal, Inputs};
use super::{EventKind, Phase2Config, StartMode};
use crate::env::{Env, SampleBall};
use crate::learner::noise::Noise;
use crate::learner::replay::{Batch, Replay};
use crate::learner::Learner;
use crate::nn::Mlp;
use crate::rng::Rng;

/// Environment steps spent, by purpose.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StepCounts {
    /// In training episodes (Algorithm 3).
    pub train: u64,
    /// In greedy test episodes (Backplay's tests).
    pub test: u64,
}

/// L_k for each of `states` = τ_0 … τ_T: τ's length from τ_k to τ_T (in observations).
fn lengths_to_goal<E: Env>(env: &E, states: &[E::State]) -> Vec<f32> {
    let obs: Vec<Vec<f32>> = states
        .iter()
        .map(|s| {
            let mut o = vec![0.0; env.obs_dim()];
            env.observe(s, &mut o);
            o
        })
        .collect();
    let mut lengths = vec![0.0; obs.len()];
    for k in (0..obs.len().saturating_sub(1)).rev() {
        lengths[k] = lengths[k + 1] + dist(&obs[k], &obs[k + 1]);
    }
    lengths
}

/// The step limit of an episode from each τ_k towards the goal of τ_T, given L_k
/// ([`lengths_to_goal`]): `max_steps`, or with a path limit p > 0
/// ([`Phase2Config::path_limit`], [`Phase2Config::greedy_path_limit`]) at most
/// ⌈p (L_k + 2ε) / a⌉, a being the smallest action bound.
fn episode_limits<E: Env>(env: &E, config: &Phase2Config, p: f32, lengths: &[f32]) -> Vec<usize> {
    if p <= 0.0 {
        return vec![config.max_steps; lengths.len()];
    }
    let a = (0..env.action_dim())
        .map(|i| env.action_bound(i))
        .fold(f32::INFINITY, f32::min);
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
    /// [`StartMode::Ball`] (required by [`SkillTask::new`]), `None` with exact starts.
    ball: Option<&'a dyn SampleBall<E::State>>,
    config: &'a Phase2Config,
    /// τ_0 … τ_T (states) and their observations.
    states: &'a [E::State],
    t: usize,
    /// The region this skill must reach (decides reached, terminal, reward and Φ).
    pub goal: Goal,
    /// What the networks see and emit.
    pub inputs: Inputs,
    /// The learner being trained: a fresh one for each skill, as in the paper, or the previous
    /// problem's with `phase2.warm_start`.
    pub learner: Learner,
    replay: Replay,
    batch: Batch,
    noise: Vec<Noise>,
    rng_start: Rng,
    rng_noise: Rng,
    rng_replay: Rng,
    /// Environment steps spent so far.
    pub steps: StepCounts,
    /// Steps this task may spend; once spent, tests and rounds return 0 without running.
    budget: u64,
    /// The learner's action bounds (1 with goal-relative inputs, the environment's with raw
    /// ones): noise is added in units of the bound and actions are clipped to it.
    bounds: Vec<f32>,
    /// States where an executed chain entered this skill's section (chain repair): half of
    /// the starts at K = 0 are drawn from them, half uniformly in B_ε(τ_0). Empty otherwise.
    entries: Vec<E::State>,
    /// The step limit of a training episode from each τ_k (`max_steps`, or less with
    /// [`Phase2Config::path_limit`]), and of a greedy one (tests, verification; less also
    /// with [`Phase2Config::test_path_limit`]).
    limits: Vec<usize>,
    test_limits: Vec<usize>,
    /// Called after each test and training round.
    pub on_event: Option<Box<dyn FnMut(super::Progress) + 'a>>,
}

impl<'a, E: Env> SkillTask<'a, E> {
    /// The task of reaching `goal` (the goal of τ_T, `t`: [`Phase2Config::goal`]) along
    /// `states` with `learner`, whose actions live in [`Phase2Config::learner_bounds`]; random
    /// streams for starts, noise and replay sampling are passed in.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        env: &'a E,
        config: &'a Phase2Config,
        states: &'a [E::State],
        goal: Goal,
        t: usize,
        learner: Learner,
        rngs: [Rng; 3],
        budget: u64,
    ) -> crate::error::Result<Self> {
        config.require_hooks(env)?;
        let lc = learner.config().clone();
        let [rng_start, rng_noise, rng_replay] = rngs;
        let inputs = config.inputs(env, &goal);
        let lengths = lengths_to_goal(env, &states[..=t]);
        Ok(SkillTask {
            env,
            ball: match config.start {
                StartMode::Ball => env.ball_starts(),
                StartMode::Exact => None,
            },
            config,
            states,
            t,
            goal,
            inputs,
            replay: Replay::new(lc.replay_size, env.obs_dim(), env.action_dim()),
            batch: Batch::default(),
            noise: (0..config.beta)
                .map(|_| {
                    // σ in the learner's [−1, 1] action space.
                    Noise::new(lc.noise, lc.noise_sigma, lc.noise_theta, env.action_dim())
                })
                .collect(),
            learner,
            rng_start,
            rng_noise,
            rng_replay,
            steps: StepCounts::default(),
            budget,
            bounds: config.learner_bounds(env),
            entries: Vec::new(),
            limits: episode_limits(env, config, config.path_limit, &lengths),
            test_limits: episode_limits(env, config, config.greedy_path_limit(), &lengths),
            on_event: None,
        })
    }

    /// Draws half of the starts at K = 0 from `entries` (where an executed chain entered
    /// this section) instead of uniformly in B_ε(τ_0): chain repair.
    pub fn with_entries(mut self, entries: Vec<E::State>) -> Self {
        self.entries = entries;
        self
    }

    /// The index of the goal's state in this task's section (τ_T).
    pub fn target(&self) -> usize {
        self.t
    }

    fn spent_budget(&self) -> bool {
        self.steps.train + self.steps.test >= self.budget
    }

    /// `n` start states around τ_k: uniform in B_ε(τ_k), or τ_k itself
    /// ([`StartMode::Exact`]).
    fn starts(&mut self, k: usize, n: usize) -> Vec<E::State> {
        use rand::Rng as _;
        (0..n)
            .map(|_| match self.config.start {
                _ if k == 0 && !self.entries.is_empty() && self.rng_start.random::<bool>() => {
                    let i = self.rng_start.random_range(0..self.entries.len());
                    self.entries[i].clone()
                }
                _ => match self.ball {
                    Some(ball) => {
                        ball.sample_ball(&self.states[k], self.config.epsilon, &mut self.rng_start)
                    }
                    None => self.states[k].clone(),
                },
            })
            .collect()
    }

    /// `n` episodes in lockstep from starts around τ_k, at most `max_steps` steps each (fewer
    /// with [`Phase2Config::path_limit`], and for greedy ones `test_path_limit`); each
    /// step the actions of all running episodes come from one batched forward pass. With
    /// `learn`, noise is added, transitions are stored with the shaped reward and every step
    /// makes one learner update (Algorithm 3); without, the policy is greedy (a test).
    /// Returns the fraction of episodes that reached the goal (a lower bound for a test cut
    /// short by [`Phase2Config::fast_tests`]).
    fn episodes(&mut self, k: usize, n: usize, learn: bool) -> f32 {
        let (obs_dim, act_dim) = (self.env.obs_dim(), self.env.action_dim());
        let mut states = self.starts(k, n);
        let mut running: Vec<usize> = (0..states.len()).collect();
        let (mut successes, mut failures) = (0usize, 0usize);
        let fast = !learn && self.config.fast_tests;
        // Raw observations of the running states and the networks' view of them; one next
        // state's raw observation and view.
        let (mut raw, mut obs) = (Vec::new(), Vec::new());
        let (mut raw_next, mut next_obs) = (vec![0.0; obs_dim], vec![0.0; obs_dim]);
        let mut env_action = vec![0.0; act_dim];
        if learn {
            for noise in &mut self.noise {
                noise.reset();
            }
        }
        let limit = if learn {
            self.limits[k]
        } else {
            self.test_limits[k]
        };
        for _ in 0..limit {
            if running.is_empty() {
                break;
            }
            raw.resize(obs_dim * running.len(), 0.0);
            obs.resize(obs_dim * running.len(), 0.0);
            for ((r, o), &lane) in raw
                .chunks_exact_mut(obs_dim)
                .zip(obs.chunks_exact_mut(obs_dim))
                .zip(&running)
            {
                self.env.observe(&states[lane], r);
                self.inputs.observation(r, o);
            }
            let mut actions = self.learner.act(&obs, running.len()).to_vec();
            let mut still = Vec::with_capacity(running.len());
            for (j, &lane) in running.iter().enumerate() {
                let a = &mut actions[j * act_dim..(j + 1) * act_dim];
                if learn {
                    // σ is a fraction of the bound: noise is added in units of the bound.
                    for (x, b) in a.iter_mut().zip(&self.bounds) {
                        *x /= b;
                    }
                    self.noise[lane].add(&mut self.rng_noise, a);
                    for (x, b) in a.iter_mut().zip(&self.bounds) {
                        *x = x.clamp(-1.0, 1.0) * b;
                    }
                }
                self.inputs.env_action(a, &mut env_action);
                let raw_s = &raw[j * obs_dim..(j + 1) * obs_dim];
                let step = self.env.step(&states[lane], &env_action);
                self.env.observe(&step.state, &mut raw_next);
                let reached = self.goal.reached(&raw_next, step.terminal, step.reward);
                if learn {
                    self.steps.train += 1;
                    let r = self.goal.reward(raw_s, &raw_next, reached);
                    self.inputs.observation(&raw_next, &mut next_obs);
                    let o = &obs[j * obs_dim..(j + 1) * obs_dim];
                    let done = self.goal.terminal(reached, step.terminal);
                    self.replay.push(o, a, r, &next_obs, done);
                    if self.replay.len() >= self.learner.config().batch_size {
                        self.replay.sample(
                            self.learner.config().batch_size,
                            &mut self.rng_replay,
                            &mut self.batch,
                        );
                        self.learner.update(&self.batch);
                    }
                } else {
                    self.steps.test += 1;
                }
                // A greedy episode that did not move is stuck for good (deterministic policy,
                // pure step): with fast tests it ends as a failure now.
                let stuck = fast && step.state == states[lane];
                let ended = step.terminal || stuck;
                states[lane] = step.state;
                if reached {
                    successes += 1;
                } else if ended {
                    failures += 1;
                } else {
                    still.push(lane);
                }
            }
            running = still;
            if fast && successes > 0 && failures > 0 {
                break; // neither 0 % nor 100 %: all Backplay needs to know
            }
        }
        successes as f32 / n as f32
    }

    /// `episodes` greedy episodes of a saved `policy` from B_ε(τ_k) (swapped in for π, then
    /// swapped back), reported as `kind`.
    fn greedy_with(&mut self, k: usize, policy: &Mlp, episodes: usize, kind: EventKind) -> f32 {
        if self.spent_budget() {
            return 0.0;
        }
        let current = std::mem::replace(&mut self.learner.actor, policy.clone());
        let p = self.episodes(k, episodes, false);
        self.learner.actor = current;
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
    type Policy = Mlp;

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

    fn policy(&self) -> Mlp {
        self.learner.actor.clone()
    }

    /// Runs `episodes` greedy episodes of `policy` (swapped in for π, then swapped back).
    fn verify(&mut self, k: usize, policy: &Mlp, episodes: usize) -> f32 {
        self.greedy_with(k, policy, episodes, EventKind::Verify)
    }

    /// [`Self::verify`], reported as a `retarget` row.
    fn verify_handover(&mut self, k: usize, policy: &Mlp, episodes: usize) -> f32 {
        self.greedy_with(k, policy, episodes, EventKind::Retarget)
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
