//! SAC (Haarnoja et al. 2018) as Stable-Baselines3 runs it: a tanh-Gaussian actor, twin
//! critics with target networks, and an entropy coefficient α learned towards a target
//! entropy of −dim(A).
//!
//! The actor is one ReLU MLP whose output row is [μ | ℓ] (Stable-Baselines3's two linear
//! heads on one latent, side by side); σ = exp(clamp(ℓ, −20, 2)), u = μ + σ·ε with ε ~ N(0, I)
//! (the reparameterisation), a = tanh(u) ∈ [−1, 1]ᵈ, and the learner's action is b ⊙ a (b the
//! bounds it was made with). log π(a|s) is the Gaussian's log density at u less
//! Σ log(1 − a² + 10⁻⁶) (the tanh's change of variables). The greedy policy is b ⊙ tanh(μ).
//! [`Sac::update`] is the whole algorithm on one screen; its hand-written gradients are
//! checked against candle's autograd (tests/sac.rs).
//!
//! Where this differs from Stable-Baselines3: the replay, the warm-up (`learning_starts`) and
//! the update schedule are the caller's (a vanilla run's `[train]`, a skill's task), as for
//! TD3; α's optimiser is the same Adam as the networks' (Stable-Baselines3's too), run on
//! one parameter.

mod update;

use super::replay::Batch;
use super::{check_common, Family, Learner, LearnerConfig, Losses};
pub use update::SacGradients;
use update::Scratch;
use crate::error::{Error, Result};
use crate::nn::kernel::Kernel;
use crate::nn::{Adam, Head, Mlp, Workspace};
use crate::policy::Policy;
use crate::rng::{Rng, Seeds, Stream};
use crate::validate::Check;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use std::any::Any;
use std::path::Path;

/// Bounds of the log standard deviation ℓ (Stable-Baselines3's `LOG_STD_MIN`, `LOG_STD_MAX`).
pub const LOG_STD_BOUNDS: (f32, f32) = (-20.0, 2.0);
/// δ in the tanh correction log(1 − a² + δ) (Stable-Baselines3's `TanhBijector.epsilon`).
pub const TANH_EPS: f32 = 1e-6;

/// The `algo` of SAC's settings.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SacAlgo {
    /// SAC.
    #[default]
    Sac,
}

/// The entropy coefficient α: `"auto"` (learned, from 1), `"auto_<α₀>"` (learned, from α₀),
/// or a number (fixed), as Stable-Baselines3's `ent_coef`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum EntCoef {
    /// A fixed α ≥ 0.
    Fixed(f32),
    /// `auto` or `auto_<α₀>`.
    Learned(String),
}

impl EntCoef {
    /// The starting α and whether it is learned; an error naming the field for a bad value.
    pub fn start(&self) -> Result<(f32, bool)> {
        let bad = |why: String| Err(Error::invalid("learner.ent_coef", why));
        match self {
            EntCoef::Fixed(a) if a.is_finite() && *a >= 0.0 => Ok((*a, false)),
            EntCoef::Fixed(a) => bad(format!("a fixed coefficient must be ≥ 0, got {a}")),
            EntCoef::Learned(s) if s == "auto" => Ok((1.0, true)),
            EntCoef::Learned(s) => match s.strip_prefix("auto_").map(str::parse::<f32>) {
                Some(Ok(a)) if a.is_finite() && a > 0.0 => Ok((a, true)),
                _ => bad(format!(
                    "`{s}`: say \"auto\", \"auto_<positive start>\" or a number ≥ 0"
                )),
            },
        }
    }
}

/// SAC's hyper-parameters (validated by [`Check::check`]): Stable-Baselines3's defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SacConfig {
    /// `sac`.
    pub algo: SacAlgo,
    /// Hidden layer widths of the actor and of each critic.
    pub hidden: Vec<usize>,
    /// Adam learning rate of the actor, the critics and α.
    pub learning_rate: f32,
    /// Discount γ ∈ [0, 1).
    pub gamma: f32,
    /// Target networks' soft-update rate τ ∈ (0, 1].
    pub tau: f32,
    /// Mini-batch size.
    pub batch_size: usize,
    /// Replay capacity (transitions).
    pub replay_size: usize,
    /// The entropy coefficient α.
    pub ent_coef: EntCoef,
    /// The entropy a learned α aims at (absent: −dim(A)); only with a learned α.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_entropy: Option<f32>,
}

impl Default for SacConfig {
    fn default() -> Self {
        SacConfig {
            algo: SacAlgo::Sac,
            hidden: vec![256, 256],
            learning_rate: 3e-4,
            gamma: 0.99,
            tau: 0.005,
            batch_size: 256,
            replay_size: 1_000_000,
            ent_coef: EntCoef::Learned("auto".into()),
            target_entropy: None,
        }
    }
}

impl Check for SacConfig {
    fn check(&self) -> Result<()> {
        check_common(
            &[("learner.learning_rate", self.learning_rate)],
            self.gamma,
            self.tau,
            self.batch_size,
            self.replay_size,
            &self.hidden,
        )?;
        let (_, learned) = self.ent_coef.start()?;
        match self.target_entropy {
            Some(_) if !learned => Err(Error::invalid(
                "learner.target_entropy",
                "is the aim of a learned α: only with ent_coef = \"auto\" or \"auto_<start>\"",
            )),
            Some(h) if !h.is_finite() => Err(Error::invalid(
                "learner.target_entropy",
                format!("must be finite, got {h}"),
            )),
            _ => Ok(()),
        }
    }
}

impl Family for SacConfig {
    const ALGOS: &'static [&'static str] = &["sac"];
    const POLICY: &'static str = "sac";

    fn algo(&self) -> &'static str {
        "sac"
    }
    fn preset(_: &str) -> Self {
        SacConfig::default()
    }
    fn record_name(&self) -> String {
        "sac".into()
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
        Ok(Box::new(Sac::new(self, obs_dim, bounds, seeds, kernel)?))
    }
    fn load_policy(sizes: &[usize], bounds: &[f32], path: &Path) -> Result<Box<dyn Policy>> {
        if sizes.len() < 2 || sizes.contains(&0) || sizes[sizes.len() - 1] != 2 * bounds.len() {
            return Err(Error::parse(
                path,
                "a sac policy's network gives 2 outputs (μ, ℓ) per action bound",
            ));
        }
        let mut net = Mlp::new(sizes, Head::Linear, &mut Seeds::new(0).stream(Stream::Init));
        net.load(path)?;
        Ok(Box::new(SacPolicy {
            net,
            bounds: bounds.to_vec(),
        }))
    }
    /// Half the network's output: μ and ℓ per action.
    fn policy_action_dim(sizes: &[usize]) -> usize {
        sizes[sizes.len() - 1] / 2
    }
}

/// SAC's greedy policy b ⊙ tanh(μ(s)); its network's output row is [μ | ℓ].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SacPolicy {
    /// The actor network (linear output, 2·dim(A) wide).
    pub net: Mlp,
    /// The action bounds b.
    pub bounds: Vec<f32>,
}

impl SacPolicy {
    /// The actions b ⊙ tanh(μ + σ·ε) of the stochastic policy π that training explores with
    /// (`Learner::explore`), σ = exp(clamp(ℓ)), for `n` observations and the given standard
    /// normal draws `eps` (n × dim(A), row-major).
    ///
    /// ```
    /// use pbcs::learner::sac::SacPolicy;
    /// use pbcs::nn::{Head, Mlp, Workspace};
    /// use pbcs::rng::{Seeds, Stream};
    /// let net = Mlp::new(&[2, 4, 2], Head::Linear, &mut Seeds::new(0).stream(Stream::Init));
    /// let pi = SacPolicy { net, bounds: vec![0.5] };
    /// let mut ws = Workspace::with_kernel(pbcs::nn::kernel::Kernel::detect());
    /// // With ε = 0 the sample is the greedy action b ⊙ tanh(μ).
    /// let greedy = pbcs::policy::Policy::act(&pi, &[0.3, -0.2], 1, &mut ws).to_vec();
    /// assert_eq!(pi.sample(&[0.3, -0.2], &[0.0], 1, &mut ws), &greedy[..]);
    /// assert!(pi.sample(&[0.3, -0.2], &[3.0], 1, &mut ws)[0] > greedy[0]);
    /// ```
    pub fn sample<'w>(&self, obs: &[f32], eps: &[f32], n: usize, ws: &'w mut Workspace) -> &'w [f32] {
        let d = self.bounds.len();
        assert_eq!(eps.len(), n * d, "one draw per action component");
        let (lo, hi) = LOG_STD_BOUNDS;
        self.net.forward(obs, n, ws);
        let (out, actions) = ws.output_and_buffer();
        actions.clear();
        for (row, e) in out.chunks_exact(2 * d).zip(eps.chunks_exact(d)) {
            for (j, b) in self.bounds.iter().enumerate() {
                let sigma = row[d + j].clamp(lo, hi).exp();
                actions.push(b * (row[j] + sigma * e[j]).tanh());
            }
        }
        actions
    }
}

impl Policy for SacPolicy {
    fn kind(&self) -> &'static str {
        "sac"
    }
    fn sizes(&self) -> &[usize] {
        self.net.sizes()
    }
    fn action_bounds(&self) -> &[f32] {
        &self.bounds
    }
    fn action_dim(&self) -> usize {
        self.bounds.len()
    }
    fn act<'w>(&self, obs: &[f32], n: usize, ws: &'w mut Workspace) -> &'w [f32] {
        let d = self.bounds.len();
        self.net.forward(obs, n, ws);
        let (out, actions) = ws.output_and_buffer();
        actions.clear();
        for row in out.chunks_exact(2 * d) {
            actions.extend(row[..d].iter().zip(&self.bounds).map(|(m, b)| b * m.tanh()));
        }
        actions
    }
    fn save(&self, path: &Path) -> Result<()> {
        self.net.save(path)
    }
    fn boxed(&self) -> Box<dyn Policy> {
        Box::new(self.clone())
    }
    fn same(&self, other: &dyn Policy) -> bool {
        other.as_any().downcast_ref::<SacPolicy>() == Some(self)
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
}

/// SAC's actor, twin critics, their targets, α and their optimisers.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Sac {
    #[serde(with = "super::settings_as_toml")]
    config: SacConfig,
    obs_dim: usize,
    /// The policy π (its greedy part and the network of μ and ℓ).
    pub actor: SacPolicy,
    actor_opt: Adam,
    /// The critics Q_1, Q_2.
    pub critics: [Mlp; 2],
    critic_targets: [Mlp; 2],
    critic_opts: [Adam; 2],
    /// log α, learned when `alpha_opt` is some.
    pub log_alpha: f32,
    alpha_opt: Option<Adam>,
    /// H̄.
    pub target_entropy: f32,
    rng: Rng,
    updates: u64,
    s: Scratch,
    kernel: Kernel,
    /// ε of the last [`Learner::explore`] (scratch).
    explored: Vec<f32>,
}

impl Sac {
    /// A fresh learner for observations of `obs_dim` and actions in `[-bounds_i, bounds_i]`
    /// on `kernel`. Weights come from the [`Stream::Init`] stream of `seeds` (actor, then the
    /// two critics); the update's samples from [`Stream::Update`].
    pub fn new(
        config: &SacConfig,
        obs_dim: usize,
        bounds: &[f32],
        seeds: &Seeds,
        kernel: Kernel,
    ) -> Result<Self> {
        config.check()?;
        let d = bounds.len();
        let mut init = seeds.stream(Stream::Init);
        let mut sizes = vec![obs_dim];
        sizes.extend(&config.hidden);
        sizes.push(2 * d);
        let net = Mlp::new(&sizes, Head::Linear, &mut init);
        sizes[0] = obs_dim + d;
        *sizes.last_mut().unwrap() = 1;
        let critics = [
            Mlp::new(&sizes, Head::Linear, &mut init),
            Mlp::new(&sizes, Head::Linear, &mut init),
        ];
        let lr = config.learning_rate;
        let (alpha, learned) = config.ent_coef.start()?;
        Ok(Sac {
            config: config.clone(),
            obs_dim,
            actor_opt: Adam::new(net.params.len(), lr, kernel),
            actor: SacPolicy {
                net,
                bounds: bounds.to_vec(),
            },
            critic_opts: [
                Adam::new(critics[0].params.len(), lr, kernel),
                Adam::new(critics[1].params.len(), lr, kernel),
            ],
            critic_targets: critics.clone(),
            critics,
            log_alpha: alpha.ln(),
            alpha_opt: learned.then(|| Adam::new(1, lr, kernel)),
            target_entropy: config.target_entropy.unwrap_or(-(d as f32)),
            rng: seeds.stream(Stream::Update),
            updates: 0,
            s: Scratch::new(kernel),
            kernel,
            explored: Vec::new(),
        })
    }

    /// The entropy coefficient α.
    pub fn alpha(&self) -> f32 {
        self.log_alpha.exp()
    }

    fn dim(&self) -> usize {
        self.actor.bounds.len()
    }

    /// n × d standard normal draws from the update's stream into `s.eps`.
    fn draw(&mut self, n: usize) {
        let d = self.dim();
        self.s.eps.clear();
        self.s
            .eps
            .extend((0..n * d).map(|_| -> f32 { StandardNormal.sample(&mut self.rng) }));
    }
}

impl Learner for Sac {
    fn config(&self) -> LearnerConfig {
        self.config.clone().into()
    }
    fn act(&mut self, obs: &[f32], n: usize) -> &[f32] {
        self.actor.act(obs, n, &mut self.s.ws_act)
    }
    /// SAC keeps no exploration state.
    fn begin_episodes(&mut self, _lanes: usize) {}
    /// b ⊙ tanh(μ + σ·ε) ([`SacPolicy::sample`]), ε drawn from `rng`, row by row.
    fn explore(&mut self, obs: &[f32], lanes: &[usize], rng: &mut Rng) -> &[f32] {
        let draws = lanes.len() * self.dim();
        self.explored.clear();
        self.explored
            .extend((0..draws).map(|_| -> f32 { StandardNormal.sample(rng) }));
        self.actor
            .sample(obs, &self.explored, lanes.len(), &mut self.s.ws_act)
    }
    fn update(&mut self, batch: &Batch) -> Losses {
        Sac::update(self, batch)
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
        assert!(
            kernel.available(),
            "the {} kernel does not run here",
            kernel.name()
        );
        let s = &mut self.s;
        for ws in [&mut s.ws_actor, &mut s.ws_next, &mut s.ws_act]
            .into_iter()
            .chain(s.ws_critics.iter_mut())
        {
            ws.set_kernel(kernel);
        }
        for o in [&mut self.actor_opt]
            .into_iter()
            .chain(self.critic_opts.iter_mut())
            .chain(self.alpha_opt.as_mut())
        {
            o.kernel = kernel;
        }
        self.kernel = kernel;
    }
    fn subnormal_moments(&self) -> usize {
        self.actor_opt.subnormal_moments()
            + self.critic_opts.iter().map(Adam::subnormal_moments).sum::<usize>()
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
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}
