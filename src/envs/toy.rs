//! A 1-D toy task to check that the learners learn, close to the 1-D toy of "The problem
//! with DDPG" (Matheron, Perrin, Sigaud 2019): a point x ∈ [0, 1], actions in [−0.1, 0.1],
//! reward 1 and termination when x + a ≤ 0; the right end clips. Episodes start uniformly in
//! [0, 1], so "success" of a policy is a fraction over start states.
//!
//! ```
//! use pbcs::env::Env;
//! use pbcs::envs::toy::Toy1D;
//! let toy = Toy1D;
//! let step = toy.step(&0.05, &[-0.1]);
//! assert_eq!((step.reward, step.terminal), (1.0, true));
//! assert_eq!(toy.step(&0.95, &[0.1]).state, 1.0);
//! ```

use crate::env::{Env, Step};
use crate::rng::Rng;
use rand::Rng as _;

/// The 1-D toy environment; the state is x.
#[derive(Debug, Clone, Copy, Default)]
pub struct Toy1D;

impl Env for Toy1D {
    type State = f32;

    fn obs_dim(&self) -> usize {
        1
    }

    fn action_dim(&self) -> usize {
        1
    }

    fn action_bound(&self, _i: usize) -> f32 {
        0.1
    }

    fn start(&self) -> f32 {
        0.5
    }

    fn sample_start(&self, rng: &mut Rng) -> f32 {
        rng.random_range(0.0..1.0)
    }

    fn observe(&self, state: &f32, out: &mut [f32]) {
        out[0] = *state;
    }

    fn step(&self, state: &f32, action: &[f32]) -> Step<f32> {
        let a = if action[0].is_nan() {
            0.0
        } else {
            action[0].clamp(-0.1, 0.1)
        };
        let next = state + a;
        if next <= 0.0 {
            Step {
                state: 0.0,
                reward: 1.0,
                terminal: true,
            }
        } else {
            Step {
                state: next.min(1.0),
                reward: 0.0,
                terminal: false,
            }
        }
    }
}
