//! Exploration noise added to the actor's actions: Gaussian or Ornstein–Uhlenbeck.

use crate::rng::Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

/// Which noise process.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NoiseKind {
    /// Independent N(0, σ²) per step and component.
    Gaussian,
    /// x ← x − θ·x + σ·N(0, 1), reset to 0 at each episode start (DDPG's original choice).
    OrnsteinUhlenbeck,
}

/// A noise process for `dim` action components; σ is absolute (already scaled to the action
/// bound).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Noise {
    kind: NoiseKind,
    sigma: f32,
    theta: f32,
    state: Vec<f32>,
}

impl Noise {
    /// A process with zero state.
    pub fn new(kind: NoiseKind, sigma: f32, theta: f32, dim: usize) -> Self {
        Noise {
            kind,
            sigma,
            theta,
            state: vec![0.0; dim],
        }
    }

    /// Resets the state (call at episode start).
    pub fn reset(&mut self) {
        self.state.fill(0.0);
    }

    /// Adds one noise sample to `action`.
    pub fn add(&mut self, rng: &mut Rng, action: &mut [f32]) {
        for (a, x) in action.iter_mut().zip(self.state.iter_mut()) {
            let z: f32 = StandardNormal.sample(rng);
            match self.kind {
                NoiseKind::Gaussian => *a += self.sigma * z,
                NoiseKind::OrnsteinUhlenbeck => {
                    *x += -self.theta * *x + self.sigma * z;
                    *a += *x;
                }
            }
        }
    }
}
