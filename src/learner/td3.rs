//! TD3 (Fujimoto et al. 2018), with DDPG as a preset and the argmax actor as a variant of the
//! same update.
//!
//! As in Stable-Baselines3, DDPG is TD3 with three knobs turned off: one critic instead of
//! two (no clipped double-Q), a policy delay of 1, and no target-policy smoothing. The argmax
//! actor ("(am)" in the paper, from "The problem with DDPG", Matheron et al. 2019) replaces
//! the deterministic policy gradient by a regression of π(s) onto argmax_a Q(s, a) estimated
//! from uniformly sampled actions. [`Td3::update`] is the whole algorithm on one screen.
//! Exploration adds Gaussian or Ornstein–Uhlenbeck noise ([`super::noise`]) to π(s).

mod update;

use super::noise::{Noise, NoiseKind};
use super::replay::Batch;
use super::{check_common, concat_rows, Family, Learner, LearnerConfig, Losses};
use crate::error::{Error, Result};
use crate::nn::kernel::Kernel;
use crate::nn::{Adam, Head, Mlp, Workspace};
use crate::policy::Policy;
use crate::rng::{Rng, Seeds, Stream};
use crate::validate::Check;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The base algorithm.
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    PartialOrd,
    Ord,
    Serialize,
    Deserialize,
    strum::IntoStaticStr,
    strum::Display,
    strum::EnumString,
    clap::ValueEnum,
)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum Algo {
    /// DDPG (Lillicrap et al. 2015): TD3 with 1 critic, policy delay 1, no target smoothing.
    Ddpg,
    /// TD3 (Fujimoto et al. 2018): 2 critics, policy delay 2, target smoothing 0.2 / 0.5.
    Td3,
}

impl Algo {
    /// The config spelling: `ddpg` or `td3`.
    pub fn name(&self) -> &'static str {
        (*self).into()
    }
}

/// How the actor is trained.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, strum::IntoStaticStr, clap::ValueEnum,
)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum ActorUpdate {
    /// Deterministic policy gradient: ascend Q(s, π(s)).
    Gradient,
    /// Regress π(s) onto argmax over `argmax_samples` uniform actions of Q(s, a).
    Argmax,
}

impl ActorUpdate {
    /// The config spelling: `gradient` or `argmax`.
    pub fn name(&self) -> &'static str {
        (*self).into()
    }
}

/// Hyper-parameters of the learner (validated by [`Check::check`]). Noise levels are
/// fractions of the action bound.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Td3Config {
    /// DDPG or TD3: sets the defaults of the four TD3 knobs below when they are left unset.
    pub algo: Algo,
    /// Hidden layer widths of actor and critics.
    pub hidden: Vec<usize>,
    /// Adam learning rate of the actor.
    pub actor_lr: f32,
    /// Adam learning rate of the critics.
    pub critic_lr: f32,
    /// Discount γ ∈ [0, 1).
    pub gamma: f32,
    /// Target networks' soft-update rate τ ∈ (0, 1].
    pub tau: f32,
    /// Mini-batch size.
    pub batch_size: usize,
    /// Replay capacity (transitions).
    pub replay_size: usize,
    /// Critics (1: DDPG, 2: TD3's clipped double-Q).
    pub n_critics: Option<usize>,
    /// Critic updates per actor and target update (1: DDPG, 2: TD3).
    pub policy_delay: Option<usize>,
    /// σ of the target-policy smoothing noise (0: DDPG, 0.2: TD3).
    pub target_noise: Option<f32>,
    /// Clip of the target-policy smoothing noise (TD3: 0.5).
    pub target_noise_clip: Option<f32>,
    /// Gradient (DDPG/TD3) or argmax actor update.
    pub actor_update: ActorUpdate,
    /// Uniform action samples per state for the argmax actor.
    pub argmax_samples: usize,
    /// Exploration noise process.
    pub noise: NoiseKind,
    /// σ of the exploration noise.
    pub noise_sigma: f32,
    /// θ of the Ornstein–Uhlenbeck process.
    pub noise_theta: f32,
    /// λ of a penalty on the actor's actions: λ · mean over the batch and the action's
    /// components of (π(s)_i / b_i)², added to the actor's loss (OpenAI baselines' DDPG+HER,
    /// `action_l2 = 1`). It keeps π(s) off the bounds, where the tanh head saturates and the
    /// actor's gradient vanishes. 0 (the default, not written): none.
    #[serde(skip_serializing_if = "crate::validate::is_zero")]
    pub action_l2: f32,
}

impl Default for Td3Config {
    fn default() -> Self {
        Td3Config {
            algo: Algo::Ddpg,
            hidden: vec![64, 64],
            actor_lr: 1e-3,
            critic_lr: 1e-3,
            gamma: 0.99,
            tau: 0.005,
            batch_size: 64,
            replay_size: 1_000_000,
            n_critics: None,
            policy_delay: None,
            target_noise: None,
            target_noise_clip: None,
            actor_update: ActorUpdate::Gradient,
            argmax_samples: 64,
            noise: NoiseKind::Gaussian,
            noise_sigma: 0.1,
            noise_theta: 0.15,
            action_l2: 0.0,
        }
    }
}

impl Td3Config {
    /// The learner's name in result rows: `ddpg` or `td3`, with `_am` for the argmax actor.
    pub fn record_name(&self) -> String {
        let suffix = match self.actor_update {
            ActorUpdate::Argmax => "_am",
            ActorUpdate::Gradient => "",
        };
        format!("{}{suffix}", self.algo.name())
    }

    /// The DDPG preset.
    pub fn ddpg() -> Self {
        Td3Config::default()
    }

    /// The TD3 preset.
    pub fn td3() -> Self {
        Td3Config {
            algo: Algo::Td3,
            ..Td3Config::default()
        }
    }

    /// The four TD3 knobs, from the preset where unset:
    /// `(n_critics, policy_delay, target_noise, target_noise_clip)`.
    pub fn knobs(&self) -> (usize, usize, f32, f32) {
        let (c, d, s, k) = match self.algo {
            Algo::Ddpg => (1, 1, 0.0, 0.0),
            Algo::Td3 => (2, 2, 0.2, 0.5),
        };
        (
            self.n_critics.unwrap_or(c),
            self.policy_delay.unwrap_or(d),
            self.target_noise.unwrap_or(s),
            self.target_noise_clip.unwrap_or(k),
        )
    }
}

impl Check for Td3Config {
    fn check(&self) -> Result<()> {
        check_common(
            &[
                ("learner.actor_lr", self.actor_lr),
                ("learner.critic_lr", self.critic_lr),
            ],
            self.gamma,
            self.tau,
            self.batch_size,
            self.replay_size,
            &self.hidden,
        )?;
        let (critics, delay, smooth, clip) = self.knobs();
        if !(1..=2).contains(&critics) {
            return Err(Error::invalid("learner.n_critics", "must be 1 or 2"));
        }
        if delay == 0 {
            return Err(Error::invalid("learner.policy_delay", "must be at least 1"));
        }
        for (field, v) in [
            ("learner.target_noise", smooth),
            ("learner.target_noise_clip", clip),
            ("learner.noise_sigma", self.noise_sigma),
            ("learner.noise_theta", self.noise_theta),
            ("learner.action_l2", self.action_l2),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(field, format!("must be ≥ 0, got {v}")));
            }
        }
        // Unused by the gradient actor, but a job that says 0 (or a typo's count) says
        // something it cannot mean: refused whatever the actor, so switching the actor never
        // makes it bad.
        crate::validate::count(
            "learner.argmax_samples",
            self.argmax_samples as u64,
            crate::validate::bounds::SAMPLES,
        )
    }
}

/// Scratch buffers of the update, kept to allocate nothing per step.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct Scratch {
    ws_actor: Workspace,
    ws_actor_target: Workspace,
    ws_critic: Workspace,
    ws_act: Workspace,
    sa: Vec<f32>,
    y: Vec<f32>,
    q_next: Vec<f32>,
    dq: Vec<f32>,
    dsa: Vec<f32>,
    da: Vec<f32>,
    grad_actor: Vec<f32>,
    grad_critic: Vec<f32>,
    target_a: Vec<f32>,
    pi: Vec<f32>,
}

impl Scratch {
    fn new(kernel: Kernel) -> Self {
        Scratch {
            ws_actor: Workspace::with_kernel(kernel),
            ws_actor_target: Workspace::with_kernel(kernel),
            ws_critic: Workspace::with_kernel(kernel),
            ws_act: Workspace::with_kernel(kernel),
            sa: Vec::new(),
            y: Vec::new(),
            q_next: Vec::new(),
            dq: Vec::new(),
            dsa: Vec::new(),
            da: Vec::new(),
            grad_actor: Vec::new(),
            grad_critic: Vec::new(),
            target_a: Vec::new(),
            pi: Vec::new(),
        }
    }
}

/// Actor, critics, their targets and optimisers.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Td3 {
    #[serde(with = "super::settings_as_toml")]
    config: Td3Config,
    obs_dim: usize,
    bounds: Vec<f32>,
    /// The policy π.
    pub actor: Mlp,
    actor_target: Mlp,
    actor_opt: Adam,
    /// The critics Q_1 (and Q_2 for TD3).
    pub critics: Vec<Mlp>,
    critic_targets: Vec<Mlp>,
    critic_opts: Vec<Adam>,
    rng: Rng,
    updates: u64,
    s: Scratch,
    /// The kernel of every product, Adam step and soft update.
    kernel: Kernel,
    /// Exploration noise, one process per lane.
    noise: Vec<Noise>,
    /// Exploratory actions of the running lanes.
    explored: Vec<f32>,
}

impl Td3 {
    /// A fresh learner for observations of `obs_dim` and actions in `[-bounds_i, bounds_i]`,
    /// whose layer arithmetic runs on `kernel` (an input of the run like the seed: kernels
    /// other than AVX2/AVX-512 give other bytes). All weights come from the [`Stream::Init`]
    /// stream of `seeds`; the update's own noise from [`Stream::Update`].
    pub fn new(
        config: &Td3Config,
        obs_dim: usize,
        bounds: &[f32],
        seeds: &Seeds,
        kernel: Kernel,
    ) -> Result<Self> {
        config.check()?;
        let act_dim = bounds.len();
        let mut init = seeds.stream(Stream::Init);
        let mut sizes = vec![obs_dim];
        sizes.extend(&config.hidden);
        sizes.push(act_dim);
        let actor = Mlp::new(&sizes, Head::Tanh(bounds.to_vec()), &mut init);
        sizes[0] = obs_dim + act_dim;
        *sizes.last_mut().unwrap() = 1;
        let (n_critics, ..) = config.knobs();
        let critics: Vec<Mlp> = (0..n_critics)
            .map(|_| Mlp::new(&sizes, Head::Linear, &mut init))
            .collect();
        Ok(Td3 {
            config: config.clone(),
            obs_dim,
            bounds: bounds.to_vec(),
            actor_target: actor.clone(),
            actor_opt: Adam::new(actor.params.len(), config.actor_lr, kernel),
            critic_targets: critics.clone(),
            critic_opts: critics
                .iter()
                .map(|c| Adam::new(c.params.len(), config.critic_lr, kernel))
                .collect(),
            actor,
            critics,
            rng: seeds.stream(Stream::Update),
            updates: 0,
            s: Scratch::new(kernel),
            kernel,
            noise: Vec::new(),
            explored: Vec::new(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &Td3Config {
        &self.config
    }

    /// Updates done so far.
    pub fn updates(&self) -> u64 {
        self.updates
    }

    /// Subnormal values among all Adam moments (0 while the flush works; see [`Adam`]).
    pub fn subnormal_moments(&self) -> usize {
        self.actor_opt.subnormal_moments()
            + self
                .critic_opts
                .iter()
                .map(Adam::subnormal_moments)
                .sum::<usize>()
    }

    /// Runs every later product, optimiser step and soft update on `kernel` (AVX-512 and
    /// AVX2 give the same bytes; `portable` and `matrixmultiply` round differently; see
    /// [`crate::nn::kernel`]).
    ///
    /// # Panics
    /// If this CPU cannot run `kernel` (see [`Kernel::available`]).
    pub fn set_kernel(&mut self, kernel: Kernel) {
        assert!(
            kernel.available(),
            "the {} kernel does not run here",
            kernel.name()
        );
        let s = &mut self.s;
        for ws in [
            &mut s.ws_actor,
            &mut s.ws_actor_target,
            &mut s.ws_critic,
            &mut s.ws_act,
        ] {
            ws.set_kernel(kernel);
        }
        self.actor_opt.kernel = kernel;
        for o in &mut self.critic_opts {
            o.kernel = kernel;
        }
        self.kernel = kernel;
    }

    /// The kernel the update runs on (products, optimiser steps and soft updates alike).
    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    /// Greedy actions π(s) for a batch of `n` observations (one forward pass).
    pub fn act(&mut self, obs: &[f32], n: usize) -> &[f32] {
        self.actor.forward(obs, n, &mut self.s.ws_act)
    }

    /// TD3's target actions for a batch of next observations: π'(s') plus the smoothing
    /// noise clip(σ·b·z, −c·b, c·b) per component (b the bound), clipped to the bounds. With
    /// σ = 0 (DDPG) this is π'(s').
    pub fn smoothed_target_actions(&mut self, next_obs: &[f32], n: usize) -> &[f32] {
        let (_, _, sigma, clip) = self.config.knobs();
        let s = &mut self.s;
        s.target_a.clear();
        s.target_a.extend_from_slice(self.actor_target.forward(
            next_obs,
            n,
            &mut s.ws_actor_target,
        ));
        if sigma > 0.0 {
            for row in s.target_a.chunks_exact_mut(self.bounds.len()) {
                for (x, &b) in row.iter_mut().zip(&self.bounds) {
                    let z: f32 = StandardNormal.sample(&mut self.rng);
                    *x = (*x + (sigma * b * z).clamp(-clip * b, clip * b)).clamp(-b, b);
                }
            }
        }
        &s.target_a
    }

    /// Fills the scratch `y` with y = r + γ·(1 − done)·min_i Q'_i(s', a'), where a' are the
    /// smoothed target actions (`smooth`) or plain π'(s').
    fn compute_td_targets(&mut self, b: &Batch, smooth: bool) {
        let (n, o, a) = (b.len, self.obs_dim, self.bounds.len());
        if smooth {
            self.smoothed_target_actions(&b.next_obs, n);
        } else {
            let s = &mut self.s;
            s.target_a.clear();
            s.target_a.extend_from_slice(self.actor_target.forward(
                &b.next_obs,
                n,
                &mut s.ws_actor_target,
            ));
        }
        let s = &mut self.s;
        concat_rows(&b.next_obs, o, &s.target_a, a, &mut s.sa);
        s.q_next.clear();
        s.q_next.resize(n, f32::INFINITY);
        for target in &self.critic_targets {
            let q = target.forward(&s.sa, n, &mut s.ws_critic);
            for (m, q) in s.q_next.iter_mut().zip(q) {
                *m = m.min(*q);
            }
        }
        let gamma = self.config.gamma;
        s.y.clear();
        s.y.extend((0..n).map(|i| b.rew[i] + gamma * (1.0 - b.done[i]) * s.q_next[i]));
    }

    /// The TD targets y of a batch under the current target networks, without smoothing
    /// noise (exposed for tests of the terminal mask).
    pub fn td_targets(&mut self, b: &Batch) -> Vec<f32> {
        self.compute_td_targets(b, false);
        self.s.y.clone()
    }
}

impl Family for Td3Config {
    const ALGOS: &'static [&'static str] = &["ddpg", "td3"];
    const POLICY: &'static str = "mlp";

    fn algo(&self) -> &'static str {
        self.algo.name()
    }
    fn preset(algo: &str) -> Self {
        match algo {
            "td3" => Td3Config::td3(),
            _ => Td3Config::ddpg(),
        }
    }
    fn record_name(&self) -> String {
        Td3Config::record_name(self)
    }
    fn gamma(&self) -> f32 {
        self.gamma
    }
    fn gamma_mut(&mut self) -> &mut f32 {
        &mut self.gamma
    }
    fn replay_size(&self) -> usize {
        self.replay_size
    }
    fn batch_size(&self) -> usize {
        self.batch_size
    }
    fn build(
        &self,
        obs_dim: usize,
        bounds: &[f32],
        seeds: &Seeds,
        kernel: Kernel,
    ) -> Result<Box<dyn Learner>> {
        Ok(Box::new(Td3::new(self, obs_dim, bounds, seeds, kernel)?))
    }
    /// The actor: a deterministic MLP whose tanh head is scaled to `bounds` (a linear head
    /// where `bounds` is empty).
    fn load_policy(sizes: &[usize], bounds: &[f32], path: &Path) -> Result<Box<dyn Policy>> {
        let head = if bounds.is_empty() {
            Head::Linear
        } else {
            Head::Tanh(bounds.to_vec())
        };
        if sizes.len() < 2 || sizes.contains(&0) || (!bounds.is_empty() && bounds.len() != sizes[sizes.len() - 1]) {
            return Err(Error::parse(path, "the manifest's sizes and action bounds do not fit an mlp policy"));
        }
        let mut mlp = Mlp::new(sizes, head, &mut Seeds::new(0).stream(Stream::Init));
        mlp.load(path)?;
        Ok(Box::new(mlp))
    }
    fn policy_action_dim(sizes: &[usize]) -> usize {
        Td3Config::actor_outputs(sizes)
    }
}

impl Td3Config {
    /// [`Family::policy_action_dim`]: the actor's output.
    fn actor_outputs(sizes: &[usize]) -> usize {
        sizes[sizes.len() - 1]
    }
}

impl Learner for Td3 {
    fn config(&self) -> LearnerConfig {
        self.config.clone().into()
    }
    fn act(&mut self, obs: &[f32], n: usize) -> &[f32] {
        Td3::act(self, obs, n)
    }
    fn begin_episodes(&mut self, lanes: usize) {
        let (c, dim) = (&self.config, self.bounds.len());
        // σ in units of the bound.
        self.noise
            .resize_with(lanes, || Noise::new(c.noise, c.noise_sigma, c.noise_theta, dim));
        for noise in &mut self.noise {
            noise.reset();
        }
    }
    /// π(s) plus each lane's noise in units of the bound, clipped to the bounds.
    fn explore(&mut self, obs: &[f32], lanes: &[usize], rng: &mut Rng) -> &[f32] {
        let dim = self.bounds.len();
        if let Some(&most) = lanes.iter().max() {
            if most >= self.noise.len() {
                self.begin_episodes(most + 1);
            }
        }
        self.explored.clear();
        self.explored
            .extend_from_slice(self.actor.forward(obs, lanes.len(), &mut self.s.ws_act));
        for (a, &lane) in self.explored.chunks_exact_mut(dim).zip(lanes) {
            for (x, b) in a.iter_mut().zip(&self.bounds) {
                *x /= b;
            }
            self.noise[lane].add(rng, a);
            for (x, b) in a.iter_mut().zip(&self.bounds) {
                *x = x.clamp(-1.0, 1.0) * b;
            }
        }
        &self.explored
    }
    fn update(&mut self, batch: &Batch) -> Losses {
        Td3::update(self, batch)
    }
    fn policy(&self) -> Box<dyn Policy> {
        Box::new(self.actor.clone())
    }
    fn batch_size(&self) -> usize {
        self.config.batch_size
    }
    fn updates(&self) -> u64 {
        self.updates
    }
    fn kernel(&self) -> Kernel {
        self.kernel
    }
    fn set_kernel(&mut self, kernel: Kernel) {
        Td3::set_kernel(self, kernel)
    }
    fn subnormal_moments(&self) -> usize {
        Td3::subnormal_moments(self)
    }
    fn boxed(&self) -> Box<dyn Learner> {
        Box::new(self.clone())
    }
    fn save_state(&self) -> Result<Vec<u8>> {
        super::save_whole(self)
    }
    fn restore_state(&mut self, bytes: &[u8]) -> Result<()> {
        let same = |saved: &Self| (&saved.config, saved.obs_dim) == (&self.config, self.obs_dim);
        *self = super::restore_whole(bytes, same)?;
        Ok(())
    }
    fn as_any_mut(&mut self) -> &mut dyn std::any::Any {
        self
    }
}
