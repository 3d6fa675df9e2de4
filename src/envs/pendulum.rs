//! Gymnasium's Pendulum-v1, ported step for step: a task with published numbers, on which our
//! learners are checked against Stable-Baselines3 and RL-Zoo's figure (issue 25).
//!
//! The state is (θ, θ̇) in f64, as gymnasium keeps it; observations are (cos θ, sin θ, θ̇) in
//! f32; the action is a torque u clipped to [−2, 2]. One step (g = 10, m = l = 1, dt = 0.05):
//! cost = norm(θ)² + 0.1 θ̇² + 0.001 u², θ̇′ = clip(θ̇ + (15 sin θ + 3u) dt, ±8),
//! θ′ = θ + θ̇′ dt, reward −cost; never terminal (gymnasium's 200-step limit is the trainer's
//! `max_episode_steps`). Gymnasium computes `0.001 u²` and `3u` in float32 (u is a float32 and
//! numpy keeps Python floats weak), everything else in float64; this port does the same, so
//! its steps equal gymnasium's for the same actions (`python/tests/test_pendulum.py`).
//! Episodes start uniformly in θ ∈ [−π, π], θ̇ ∈ [−1, 1].
//!
//! ```
//! use pbcs::env::Env;
//! use pbcs::envs::pendulum::Pendulum;
//! // Hanging straight down and still: no torque keeps it there, at the largest angle cost.
//! let s = Pendulum.step(&[std::f64::consts::PI, 0.0], &[0.0]);
//! assert_eq!(s.state[1], 15.0 * std::f64::consts::PI.sin() * 0.05);
//! assert!((s.reward + std::f32::consts::PI.powi(2)).abs() < 1e-5);
//! ```

use crate::env::{Env, Step};
use crate::rng::Rng;
use rand::Rng as _;
use std::f64::consts::PI;

/// Gymnasium's Pendulum-v1; the state is `[θ, θ̇]`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Pendulum;

/// Largest torque.
pub const MAX_TORQUE: f32 = 2.0;
/// Largest angular speed.
pub const MAX_SPEED: f64 = 8.0;
/// Gymnasium's episode length for Pendulum-v1.
pub const EPISODE_STEPS: usize = 200;

/// θ wrapped into [−π, π), as gymnasium's `angle_normalize` (Python's `%` takes the sign of
/// the divisor: `rem_euclid`).
pub fn angle_normalize(x: f64) -> f64 {
    (x + PI).rem_euclid(2.0 * PI) - PI
}

impl Env for Pendulum {
    type State = [f64; 2];

    fn obs_dim(&self) -> usize {
        3
    }

    fn action_dim(&self) -> usize {
        1
    }

    fn action_bound(&self, _i: usize) -> f32 {
        MAX_TORQUE
    }

    fn start(&self) -> [f64; 2] {
        [PI, 0.0]
    }

    fn sample_start(&self, rng: &mut Rng) -> [f64; 2] {
        [rng.random_range(-PI..=PI), rng.random_range(-1.0..=1.0)]
    }

    fn observe(&self, state: &[f64; 2], out: &mut [f32]) {
        out[0] = state[0].cos() as f32;
        out[1] = state[0].sin() as f32;
        out[2] = state[1] as f32;
    }

    fn step(&self, state: &[f64; 2], action: &[f32]) -> Step<[f64; 2]> {
        let [th, thdot] = *state;
        let u = if action[0].is_nan() {
            0.0
        } else {
            action[0].clamp(-MAX_TORQUE, MAX_TORQUE)
        };
        let cost =
            angle_normalize(th).powi(2) + 0.1 * (thdot * thdot) + f64::from(0.001f32 * (u * u));
        let newthdot = thdot + (15.0 * th.sin() + f64::from(3.0f32 * u)) * 0.05;
        let newthdot = newthdot.clamp(-MAX_SPEED, MAX_SPEED);
        let newth = th + newthdot * 0.05;
        Step {
            state: [newth, newthdot],
            reward: -cost as f32,
            terminal: false,
        }
    }

    fn obs_names(&self) -> Vec<String> {
        vec!["cos".into(), "sin".into(), "thdot".into()]
    }
}
