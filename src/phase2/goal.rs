//! A skill's goal and what its networks see: the two places where Algorithm 3 meets the
//! environment.
//!
//! * [`Goal`] decides, from one region, whether a step reached the goal, whether it ends the
//!   episode, what shaped reward it earns and the potential Φ behind that reward. For every
//!   skill but the last the region is B_ε(τ_T); for the last skill (T = N) it is the
//!   environment's own success region, so that the last skill is never paid for hovering in
//!   the part of B_ε(τ_N) that lies outside the rewarded disc.
//! * [`Inputs`] maps observations and actions between the environment and a skill's networks:
//!   observations relative to the centre of the skill's goal (the same skill is the same
//!   learning problem wherever it lies in the maze), actions in [−1, 1]ᵈ scaled to the
//!   environment's bounds (Stable-Baselines3's convention; exploration noise σ lives in that
//!   space).
//!
//! ```
//! use pbcs::phase2::goal::{Goal, Inputs, REACHED_REWARD};
//!
//! // Skill goal B_ε(τ_T) with τ_T = (1, 1), ε = 0.1.
//! let goal = Goal::ball(vec![1.0, 1.0], 0.1);
//! assert!(goal.reached(&[1.05, 1.0], false, 0.0));
//! assert_eq!(goal.reward(&[1.5, 1.0], &[1.05, 1.0], true), REACHED_REWARD);
//! // Φ(s) = 1 / d(s, centre): moving from d = 0.5 to d = 0.25 earns 4 − 2 = 2.
//! assert!((goal.reward(&[1.5, 1.0], &[1.25, 1.0], false) - 2.0).abs() < 1e-5);
//!
//! // The networks see s − centre and act in [−1, 1]²; the environment gets ±0.1.
//! let inputs = Inputs::new(vec![1.0, 1.0], vec![0.1, 0.1]);
//! let mut obs = [0.0; 2];
//! inputs.observation(&[1.5, 0.5], &mut obs);
//! assert_eq!(obs, [0.5, -0.5]);
//! let mut act = [0.0; 2];
//! inputs.env_action(&[1.0, -0.5], &mut act);
//! assert_eq!(act, [0.1, -0.05]);
//! ```

use crate::env::Env;
use serde::{Deserialize, Serialize};

/// L2 distance between two observations.
#[inline]
pub fn dist(a: &[f32], b: &[f32]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f32>()
        .sqrt()
}

/// The distance d(a, c) = √(Σ w_i² (a_i − c_i)²) over the coordinates of `c` (a ball's
/// centre), with weights `w` (empty: all 1, [`dist`]).
#[inline]
pub fn weighted_dist(a: &[f32], c: &[f32], w: &[f32]) -> f32 {
    if w.is_empty() {
        return dist(a, c);
    }
    a.iter()
        .zip(c)
        .zip(w)
        .map(|((x, y), w)| (w * (x - y)) * (w * (x - y)))
        .sum::<f32>()
        .sqrt()
}

/// A ball's centre at the observation `obs` of `env`: its position ([`Env::position`]), the
/// centre of a ball in position ([`BallMetric::Position`]).
pub fn ball_center<E: Env>(env: &E, obs: &[f32]) -> Vec<f32> {
    BallMetric::Position.center(env, obs)
}

/// What PBCS's balls — the goals B_ε(τ_T), the activation sets A_i and Backplay's starts —
/// measure: the position (the paper, and the default), or, for an environment with momentum,
/// position and velocity under d² = ‖Δx‖² + λ²‖Δv‖² (`phase2.velocity_scale` = λ, in
/// seconds; needs [`crate::env::Env::velocity_balls`]).
///
/// ```
/// use pbcs::phase2::goal::{weighted_dist, BallMetric};
///
/// // λ = 0.5 s: a velocity 0.4 off weighs as 0.2 of distance.
/// let w = [1.0, 1.0, 0.5, 0.5];
/// let d = weighted_dist(&[0.3, 0.0, 0.4, 0.0], &[0.0, 0.0, 0.0, 0.0], &w);
/// assert!((d - (0.3f32 * 0.3 + 0.2 * 0.2).sqrt()).abs() < 1e-6);
/// assert_eq!(BallMetric::default(), BallMetric::Position);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum BallMetric {
    /// Position only: a ball is reached at any velocity.
    #[default]
    Position,
    /// Position and velocity, a velocity difference weighed by λ = `scale` (> 0).
    PositionVelocity {
        /// λ, in seconds.
        scale: f32,
    },
}

impl BallMetric {
    /// λ, or 0 for [`BallMetric::Position`] (the file's `phase2.velocity_scale`).
    pub fn scale(self) -> f32 {
        match self {
            BallMetric::Position => 0.0,
            BallMetric::PositionVelocity { scale } => scale,
        }
    }

    /// How many velocity components the ball measures in `env` (0 for the position only, or
    /// where `env` has no [`crate::env::VelocityBalls`]: refused before a run starts).
    fn velocity_dims<E: Env>(self, env: &E) -> usize {
        match self {
            BallMetric::Position => 0,
            BallMetric::PositionVelocity { .. } => {
                env.velocity_balls().map_or(0, |v| v.velocity_dims())
            }
        }
    }

    /// The centre of the ball around the observation `obs`: its position, then (with
    /// velocity) the velocity components that follow it.
    pub fn center<E: Env>(self, env: &E, obs: &[f32]) -> Vec<f32> {
        let position = env.position(obs).len();
        obs[..(position + self.velocity_dims(env)).min(obs.len())].to_vec()
    }

    /// The weights of [`weighted_dist`] for those coordinates: none (all 1) for the position
    /// (also where `env` measures no velocity), else 1 per position component and λ per
    /// velocity component.
    pub fn weights<E: Env>(self, env: &E) -> Vec<f32> {
        match (self, self.velocity_dims(env)) {
            (BallMetric::PositionVelocity { scale }, v) if v > 0 => {
                let mut w = vec![1.0; env.position_dims()];
                w.resize(w.len() + v, scale);
                w
            }
            _ => Vec::new(),
        }
    }
}

/// The shaped reward of a step that reaches the goal (the paper's 10).
pub const REACHED_REWARD: f32 = 10.0;

/// How a [`Goal`] is reached.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GoalKind {
    /// d(s′, centre) ≤ radius: the ball B_ε(τ_T) of every skill but the last. Reaching the
    /// environment's reward on the way counts too.
    Ball,
    /// The environment's own success (a positive reward on a terminal step): the last skill.
    /// `centre` and `radius` describe the success region for the potential.
    EnvSuccess,
    /// The environment's own success at the goal each episode draws
    /// (`phase2.last_goal = "drawn"`, [`crate::env::DrawGoals`]): the last skill. `centre` is
    /// the task's goal; an episode measures its potential to its own goal ([`Goal::toward`]).
    Drawn,
}

/// One skill's goal: the region that decides reached, terminal, reward and potential together.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Goal {
    /// How it is reached.
    pub kind: GoalKind,
    /// Centre of the region (τ_T, or the environment's success region).
    pub center: Vec<f32>,
    /// Radius of the region (ε, or the success radius). Φ is bounded by 1 / radius.
    pub radius: f32,
    /// Weights of the distance to the centre ([`weighted_dist`]; empty: all 1, a ball in
    /// position; [`BallMetric::weights`] with velocity).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub weights: Vec<f32>,
}

impl Goal {
    /// B_ε(τ_T): the goal of every skill but the last.
    pub fn ball(center: Vec<f32>, epsilon: f32) -> Self {
        Goal {
            kind: GoalKind::Ball,
            center,
            radius: epsilon,
            weights: Vec::new(),
        }
    }

    /// B_ε around the observation `obs` of `env`, measured by `metric`.
    pub fn ball_in<E: Env>(env: &E, obs: &[f32], epsilon: f32, metric: BallMetric) -> Self {
        Goal {
            weights: metric.weights(env),
            ..Goal::ball(metric.center(env, obs), epsilon)
        }
    }

    /// The last skill's goal: the environment's success region ([`Env::success_region`]), or,
    /// for an environment that does not describe one, its success with Φ measured to τ_N
    /// (`tau_n`) and bounded by 1/ε. (PBCS's runs ask for it with
    /// `phase2.last_goal = "success_region"`, which such an environment refuses before any
    /// work: [`crate::env::Capability::SuccessRegion`].)
    pub fn last<E: Env>(env: &E, tau_n: &[f32], epsilon: f32) -> Self {
        let (center, radius) = env
            .success_region()
            .unwrap_or_else(|| (ball_center(env, tau_n), epsilon));
        Goal {
            kind: GoalKind::EnvSuccess,
            center,
            radius,
            weights: Vec::new(),
        }
    }

    /// The last skill's goal when each episode draws its own ([`GoalKind::Drawn`]):
    /// [`Goal::last`]'s region (the success region; for an environment without one, τ_N and
    /// ε, which then bound Φ by 1/ε), reached by the environment's success at the drawn goal.
    pub fn drawn<E: Env>(env: &E, tau_n: &[f32], epsilon: f32) -> Self {
        Goal {
            kind: GoalKind::Drawn,
            ..Goal::last(env, tau_n, epsilon)
        }
    }

    /// This goal moved to an episode's own goal `goal` (its first `goal.len()` coordinates, the
    /// position, replaced): what a [`GoalKind::Drawn`] episode measures its potential to.
    pub fn toward(&self, goal: &[f32]) -> Goal {
        let mut moved = self.clone();
        for (c, g) in moved.center.iter_mut().zip(goal) {
            *c = *g;
        }
        moved
    }

    /// The goal of the skill whose target is τ_t on a trajectory with observations `obs`
    /// (τ_0 … τ_N): [`Goal::last`] when t = N, else B_ε(τ_t) measured by `metric`.
    pub fn for_target<E: Env>(
        env: &E,
        obs: &[Vec<f32>],
        t: usize,
        epsilon: f32,
        metric: BallMetric,
    ) -> Self {
        if t + 1 == obs.len() {
            Goal::last(env, &obs[t], epsilon)
        } else {
            Goal::ball_in(env, &obs[t], epsilon, metric)
        }
    }

    /// Whether the step to `next_obs` (with the environment's `terminal` flag and `reward`)
    /// reached the goal.
    #[inline]
    pub fn reached(&self, next_obs: &[f32], terminal: bool, reward: f32) -> bool {
        let env_success = terminal && reward > 0.0;
        match self.kind {
            GoalKind::Ball => env_success || self.distance(next_obs) <= self.radius,
            GoalKind::EnvSuccess | GoalKind::Drawn => env_success,
        }
    }

    /// Whether the transition ends the episode: the goal was reached, or the environment
    /// ended it (a terminal state that is not the goal counts as a failure).
    #[inline]
    pub fn terminal(&self, reached: bool, env_terminal: bool) -> bool {
        reached || env_terminal
    }

    /// The potential Φ(s) = 1 / d(s, centre), bounded by 1 / radius (equation (1) of the
    /// paper, with the bound that keeps it finite inside the region).
    #[inline]
    pub fn potential(&self, obs: &[f32]) -> f32 {
        1.0 / self.distance(obs).max(self.radius)
    }

    /// d(obs, centre) in the goal's metric ([`weighted_dist`]).
    #[inline]
    pub fn distance(&self, obs: &[f32]) -> f32 {
        weighted_dist(obs, &self.center, &self.weights)
    }

    /// The shaped reward of Algorithm 3: [`REACHED_REWARD`] when the step reached the goal,
    /// else Φ(s′) − Φ(s). Standing still pays 0, wherever it stands.
    #[inline]
    pub fn reward(&self, obs: &[f32], next_obs: &[f32], reached: bool) -> f32 {
        if reached {
            REACHED_REWARD
        } else {
            self.potential(next_obs) - self.potential(obs)
        }
    }
}

/// What a skill's networks see and emit. Saved with the chain, so that executing a saved or
/// reloaded chain computes the same inputs as training did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Inputs {
    /// Subtracted from every observation: the centre of the skill's goal.
    pub origin: Vec<f32>,
    /// Multiplies each action component in [−1, 1]: the environment's bound b_i.
    pub action_scale: Vec<f32>,
    /// Whether the position is seen relative to the episode's own goal instead of `origin`'s
    /// (the last skill of `phase2.last_goal = "drawn"`, [`GoalKind::Drawn`]): the skill is
    /// told the goal through where it stands from it. Absent in a manifest: `false`.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub episode_goal: bool,
    /// A sub-goal the networks see after the observation, as its offset from the position
    /// (goal − position; a goal-conditioned chain's skill, [`super::goal_conditioned`]): empty
    /// for a skill that sees the observation alone (every per-skill chain's). With
    /// [`Inputs::episode_goal`] the episode's own goal takes its place (the last sub-goal).
    /// Absent in a manifest: empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub goal: Vec<f32>,
    /// Divides each observation number once `origin` is subtracted, the result clipped to
    /// ±[`Inputs::CLIP`] (a goal-conditioned chain's observation normalisation,
    /// `phase2.goal_conditioned.normalise`): empty for observations seen unscaled (every
    /// chain's before it). Absent in a manifest: empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub scale: Vec<f32>,
}

impl Inputs {
    /// Observations relative to `origin`; actions in [−1, 1] scaled by `action_scale`.
    pub fn new(origin: Vec<f32>, action_scale: Vec<f32>) -> Self {
        Inputs {
            origin,
            action_scale,
            episode_goal: false,
            goal: Vec::new(),
            scale: Vec::new(),
        }
    }

    /// Where a scaled observation number is clipped ([`Inputs::scale`]), as Stable-Baselines3's
    /// `VecNormalize` clips its normalised observations (`clip_obs = 10`).
    pub const CLIP: f32 = 10.0;

    /// These inputs seeing each observation number x as (x − `shift`) / `scale` clipped to
    /// ±[`Inputs::CLIP`] (`shift` replaces the origin).
    ///
    /// ```
    /// use pbcs::phase2::goal::Inputs;
    /// let inputs = Inputs::toward_goal(2, vec![3.0, 1.0], false, vec![0.1, 0.1])
    ///     .scaled(vec![1.0, 1.0], vec![2.0, 0.1]);
    /// let mut seen = Vec::new();
    /// inputs.observation_toward(&[2.0, 3.0], None, &mut seen);
    /// // (2 − 1) / 2 and (3 − 1) / 0.1 = 20, clipped; the sub-goal minus the raw position.
    /// assert_eq!(seen, [0.5, 10.0, 1.0, -2.0]);
    /// ```
    pub fn scaled(self, shift: Vec<f32>, scale: Vec<f32>) -> Self {
        Inputs {
            origin: shift,
            scale,
            ..self
        }
    }

    /// [`Inputs::observation`] in place on the first [`Inputs::origin`]`.len()` numbers of
    /// each row of `rows` (rows of `width` numbers): what a batch of raw observations becomes.
    pub fn observe_rows(&self, rows: &mut [f32], width: usize) {
        for row in rows.chunks_mut(width) {
            let seen = &mut row[..self.origin.len()];
            for (i, x) in seen.iter_mut().enumerate() {
                *x = self.seen(i, *x);
            }
        }
    }

    /// Observation number `i` as the networks see it: x − origin_i, scaled where
    /// [`Inputs::scale`] is given.
    #[inline]
    fn seen(&self, i: usize, x: f32) -> f32 {
        let moved = x - self.origin[i];
        match self.scale.get(i) {
            Some(s) => (moved / s).clamp(-Inputs::CLIP, Inputs::CLIP),
            None => moved,
        }
    }

    /// The inputs of a goal-conditioned skill aiming at `goal` (a point of the position space):
    /// the observation as it is, then `goal` − position; with `episode_goal`, each episode's
    /// own goal instead of `goal` (the last sub-goal). Actions in [−1, 1] scaled by
    /// `action_scale`.
    ///
    /// ```
    /// use pbcs::phase2::goal::Inputs;
    /// let inputs = Inputs::toward_goal(2, vec![3.0, 1.0], false, vec![0.1, 0.1]);
    /// let mut seen = Vec::new();
    /// inputs.observation_toward(&[1.0, 1.5], None, &mut seen);
    /// assert_eq!(seen, [1.0, 1.5, 2.0, -0.5]);
    /// // The last sub-goal sees each episode's own goal.
    /// let last = Inputs::toward_goal(2, vec![3.0, 1.0], true, vec![0.1, 0.1]);
    /// last.observation_toward(&[1.0, 1.5], Some(&[4.0, 2.0]), &mut seen);
    /// assert_eq!(seen, [1.0, 1.5, 3.0, 0.5]);
    /// ```
    pub fn toward_goal(
        obs_dim: usize,
        goal: Vec<f32>,
        episode_goal: bool,
        action_scale: Vec<f32>,
    ) -> Self {
        Inputs {
            episode_goal,
            goal,
            ..Inputs::new(vec![0.0; obs_dim], action_scale)
        }
    }

    /// How many numbers the networks see: the observation's, and the sub-goal's where there
    /// is one.
    pub fn input_dim(&self) -> usize {
        self.origin.len() + self.goal.len()
    }

    /// These inputs for an episode whose goal is `goal` (its position): with
    /// [`Inputs::episode_goal`], the origin's position moved there; otherwise unchanged.
    pub fn toward(&self, goal: &[f32]) -> Inputs {
        let mut moved = self.clone();
        if self.episode_goal && !self.goal.is_empty() {
            moved.goal = goal.to_vec();
        } else if self.episode_goal {
            for (o, g) in moved.origin.iter_mut().zip(goal) {
                *o = *g;
            }
        }
        moved
    }

    /// The inputs of a skill aiming at `goal` in `env`: observations relative to the goal's
    /// centre in the position ([`Env::position`]), the rest (a velocity) as it is (also where
    /// the goal measures the velocity, [`BallMetric::PositionVelocity`]).
    pub fn for_goal<E: Env>(env: &E, goal: &Goal) -> Self {
        let mut origin = goal.center.clone();
        origin.truncate(env.position_dims());
        origin.resize(env.obs_dim(), 0.0);
        Inputs {
            episode_goal: goal.kind == GoalKind::Drawn,
            ..Inputs::new(
                origin,
                (0..env.action_dim()).map(|i| env.action_bound(i)).collect(),
            )
        }
    }

    /// Writes the network's view of the environment observation `raw` into `out`:
    /// `raw − origin` (divided by [`Inputs::scale`] and clipped, where it is given).
    #[inline]
    pub fn observation(&self, raw: &[f32], out: &mut [f32]) {
        if !self.scale.is_empty() {
            for (i, (o, r)) in out.iter_mut().zip(raw).enumerate().take(self.origin.len()) {
                *o = self.seen(i, *r);
            }
            return;
        }
        for ((o, r), c) in out.iter_mut().zip(raw).zip(&self.origin) {
            *o = r - c;
        }
    }

    /// [`Inputs::observation`] in an episode whose goal is `goal`: with
    /// [`Inputs::episode_goal`] and a goal, the position relative to it; otherwise (no goal
    /// given: the task's own, `origin`) the same.
    ///
    /// A goal-conditioned skill ([`Inputs::toward_goal`]) sees the observation, then its
    /// sub-goal (with [`Inputs::episode_goal`] and a goal: that goal) minus the position.
    /// `out` is resized to [`Inputs::input_dim`].
    #[inline]
    pub fn observation_toward(&self, raw: &[f32], goal: Option<&[f32]>, out: &mut Vec<f32>) {
        out.resize(self.input_dim(), 0.0);
        let (seen, sub_goal) = out.split_at_mut(self.origin.len());
        self.observation(raw, seen);
        let episode = goal.filter(|_| self.episode_goal);
        if self.goal.is_empty() {
            if let Some(goal) = episode {
                for ((o, r), g) in seen.iter_mut().zip(raw).zip(goal) {
                    *o = r - g;
                }
            }
            return;
        }
        let aim = episode.unwrap_or(&self.goal);
        for ((o, g), x) in sub_goal.iter_mut().zip(aim).zip(raw) {
            *o = g - x;
        }
    }

    /// Writes the environment action of the network action `a` ∈ [−1, 1]ᵈ into `out`:
    /// `a_i · b_i`.
    #[inline]
    pub fn env_action(&self, a: &[f32], out: &mut [f32]) {
        for ((o, x), b) in out.iter_mut().zip(a).zip(&self.action_scale) {
            *o = x * b;
        }
    }
}
