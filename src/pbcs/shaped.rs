//! The learning problem of one skill: reach B_ε(τ_T) from starts in B_ε(τ_K), with the
//! paper's shaped reward (Algorithm 3) — the [`Backplayer`] that Backplay drives.

use super::backplay::Backplayer;
use super::{Phase2Config, StartMode};
use crate::env::Env;
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

/// L2 distance between two observations.
#[inline]
pub fn dist(a: &[f32], b: &[f32]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f32>()
        .sqrt()
}

/// The shaped reward of Algorithm 3: 10 when s' ∈ B_ε(τ_T), else Φ(s') − Φ(s) with the
/// potential Φ(s) = 1 / d(s, τ_T). (The episode loop also gives 10 when the last skill reaches
/// the environment's reward.)
#[inline]
pub fn shaped_reward(d_s: f32, d_next: f32, epsilon: f32) -> f32 {
    if d_next <= epsilon {
        10.0
    } else {
        1.0 / d_next.max(1e-6) - 1.0 / d_s.max(1e-6)
    }
}

/// One skill's learning problem on a trajectory section τ_0 … τ_T.
pub struct SkillTask<'a, E: Env> {
    env: &'a E,
    config: &'a Phase2Config,
    /// τ_0 … τ_T (states) and their observations.
    states: &'a [E::State],
    obs: &'a [Vec<f32>],
    t: usize,
    /// The learner being trained (a fresh DDPG for each skill).
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
    /// Called after each test and training round.
    pub on_event: Option<Box<dyn FnMut(super::Progress) + 'a>>,
}

impl<'a, E: Env> SkillTask<'a, E> {
    /// The task of reaching τ_T (`t`) along `states` with `learner`; random streams for
    /// starts, noise and replay sampling are passed in.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        env: &'a E,
        config: &'a Phase2Config,
        states: &'a [E::State],
        obs: &'a [Vec<f32>],
        t: usize,
        learner: Learner,
        rngs: [Rng; 3],
        budget: u64,
    ) -> Self {
        let lc = learner.config().clone();
        let bound = env.action_bound(0);
        let [rng_start, rng_noise, rng_replay] = rngs;
        SkillTask {
            env,
            config,
            states,
            obs,
            t,
            replay: Replay::new(lc.replay_size, env.obs_dim(), env.action_dim()),
            batch: Batch::default(),
            noise: (0..config.beta)
                .map(|_| {
                    Noise::new(
                        lc.noise,
                        lc.noise_sigma * bound,
                        lc.noise_theta,
                        env.action_dim(),
                    )
                })
                .collect(),
            learner,
            rng_start,
            rng_noise,
            rng_replay,
            steps: StepCounts::default(),
            budget,
            on_event: None,
        }
    }

    fn spent_budget(&self) -> bool {
        self.steps.train + self.steps.test >= self.budget
    }

    /// β start states around τ_k: uniform in B_ε(τ_k), or τ_k itself ([`StartMode::Exact`]).
    fn starts(&mut self, k: usize) -> Vec<E::State> {
        (0..self.config.beta)
            .map(|_| match self.config.start {
                StartMode::Ball => {
                    self.env
                        .sample_ball(&self.states[k], self.config.epsilon, &mut self.rng_start)
                }
                StartMode::Exact => self.states[k].clone(),
            })
            .collect()
    }

    /// β episodes in lockstep from starts around τ_k, at most `max_steps` steps each; each step
    /// the actions of all running episodes come from one batched forward pass. With
    /// `learn`, noise is added, transitions are stored with the shaped reward and every step
    /// makes one learner update (Algorithm 3); without, the policy is greedy (a test).
    /// Returns the fraction of episodes that reached B_ε(τ_T).
    fn episodes(&mut self, k: usize, learn: bool) -> f32 {
        let (eps, obs_dim, act_dim) = (
            self.config.epsilon,
            self.env.obs_dim(),
            self.env.action_dim(),
        );
        let bounds: Vec<f32> = (0..act_dim).map(|i| self.env.action_bound(i)).collect();
        let target = &self.obs[self.t];
        let final_skill = self.t + 1 == self.states.len();
        let mut states = self.starts(k);
        let mut running: Vec<usize> = (0..states.len()).collect();
        let mut successes = 0usize;
        let mut obs = vec![0.0; obs_dim * running.len()];
        let mut next_obs = vec![0.0; obs_dim];
        for n in &mut self.noise {
            n.reset();
        }
        for _ in 0..self.config.max_steps {
            if running.is_empty() {
                break;
            }
            obs.resize(obs_dim * running.len(), 0.0);
            for (row, &lane) in obs.chunks_exact_mut(obs_dim).zip(&running) {
                self.env.observe(&states[lane], row);
            }
            let mut actions = self.learner.act(&obs, running.len()).to_vec();
            let mut still = Vec::with_capacity(running.len());
            for (j, &lane) in running.iter().enumerate() {
                let a = &mut actions[j * act_dim..(j + 1) * act_dim];
                if learn {
                    self.noise[lane].add(&mut self.rng_noise, a);
                    for (x, &b) in a.iter_mut().zip(&bounds) {
                        *x = x.clamp(-b, b);
                    }
                }
                let o = &obs[j * obs_dim..(j + 1) * obs_dim];
                let step = self.env.step(&states[lane], a);
                self.env.observe(&step.state, &mut next_obs);
                let (d_s, d_next) = (dist(o, target), dist(&next_obs, target));
                // The goal is B_ε(τ_T); for the last skill (T = N) it is the environment's own
                // reward, because B_ε(τ_N) can stick out of the rewarded region (τ_N is merely
                // the first state found inside it). Reaching the reward ends any episode, and
                // so does any other terminal state (as a failure).
                let rewarded = step.terminal && step.reward > 0.0;
                let reached = if final_skill {
                    rewarded
                } else {
                    d_next <= eps || rewarded
                };
                if learn {
                    self.steps.train += 1;
                    let r = if reached {
                        10.0
                    } else {
                        shaped_reward(d_s, d_next, eps)
                    };
                    self.replay
                        .push(o, a, r, &next_obs, reached || step.terminal);
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
                let ended = step.terminal;
                states[lane] = step.state;
                if reached {
                    successes += 1;
                } else if !ended {
                    still.push(lane);
                }
            }
            running = still;
        }
        successes as f32 / self.config.beta as f32
    }

    fn report(&mut self, k: usize, test: bool, success: f32) {
        let steps = self.steps;
        if let Some(f) = self.on_event.as_mut() {
            f(super::Progress {
                k,
                t: self.t,
                test,
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
        let p = self.episodes(k, false);
        self.report(k, true, p);
        p
    }

    fn train(&mut self, k: usize) -> f32 {
        if self.spent_budget() {
            return 0.0;
        }
        let p = self.episodes(k, true);
        self.report(k, false, p);
        p
    }

    fn policy(&self) -> Mlp {
        self.learner.actor.clone()
    }

    fn exhausted(&self) -> bool {
        self.spent_budget()
    }
}
