//! The environment interface: a pure step function with reset-anywhere.
//!
//! PBCS needs to reset the environment to any state (phase 1 resets to archived states,
//! Backplay to states near τ_K). Here that is free: [`Env::step`] is a pure function of
//! `(&State, action)`, as in gymnax, so "resetting" is just passing another state. Implement
//! this trait for your own environment to run phase 1 and phase 2 on it.

use rand::Rng;
use serde::{Deserialize, Serialize};

/// The outcome of one environment step.
#[derive(Debug, Clone, PartialEq)]
pub struct Step<S> {
    /// The next state s'.
    pub state: S,
    /// The reward R(s, a, s').
    pub reward: f32,
    /// Whether s' ends the episode.
    pub terminal: bool,
}

/// An environment with continuous observations and actions and reset-anywhere.
///
/// Observations and actions are `f32` vectors of fixed length. The state is any cloneable
/// value; it must compare equal to itself so that phase 1 can recognise a step that did not
/// move.
pub trait Env {
    /// The full simulator state (a 2D point for the maze).
    type State: Clone + PartialEq + std::fmt::Debug;

    /// Length of the observation vector.
    fn obs_dim(&self) -> usize;

    /// Length of the action vector.
    fn action_dim(&self) -> usize;

    /// Bound `b_i` of the box action space: action component `i` lives in `[-b_i, b_i]`.
    fn action_bound(&self, i: usize) -> f32;

    /// The initial state s_0.
    fn start(&self) -> Self::State;

    /// A start state for a training or evaluation episode. Defaults to the fixed
    /// [`Env::start`]; environments with a start distribution override it.
    fn sample_start(&self, rng: &mut crate::rng::Rng) -> Self::State {
        let _ = rng;
        self.start()
    }

    /// A state drawn uniformly from the ball of radius `radius` around `center` (in
    /// observation space): Backplay's starts in B_ε(τ_K), which are usually states never
    /// visited. The default cannot make new states and returns `center`; environments that can
    /// should override it. The state may be one the agent cannot leave (inside a wall).
    fn sample_ball(
        &self,
        center: &Self::State,
        radius: f32,
        rng: &mut crate::rng::Rng,
    ) -> Self::State {
        let _ = (radius, rng);
        center.clone()
    }

    /// A short sequence of actions that takes `from` to (within rounding of) `to` while staying
    /// at least `clearance` away from anything that blocks, if the environment knows one (a
    /// straight line in the maze). Only used to shorten phase-1 trajectories before phase 2
    /// (an option of ours, off in the paper's preset). The default knows none.
    fn connect(
        &self,
        from: &Self::State,
        to: &Self::State,
        clearance: f32,
    ) -> Option<Vec<Vec<f32>>> {
        let _ = (from, to, clearance);
        None
    }

    /// Whether the ball of radius `radius` around `center` is clear of everything that blocks
    /// (`Some(true)`), touches something (`Some(false)`), or unknown (`None`, the default).
    /// Used by PBCS's `phase2.stop_at_failure` option: a partial failure from a clear ball
    /// is the policy's, not a wall's.
    fn ball_is_clear(&self, center: &Self::State, radius: f32) -> Option<bool> {
        let _ = (center, radius);
        None
    }

    /// The environment's success region as a ball in observation space, `(centre, radius)`,
    /// if it has one (the maze: the target and its 0.2 radius). PBCS's last skill aims at it:
    /// its potential is measured to this centre, so that the last skill is paid for reaching
    /// the region the environment rewards and for nothing else. Without one, the last skill's
    /// potential is measured to τ_N.
    fn success_region(&self) -> Option<(Vec<f32>, f32)> {
        None
    }

    /// Writes the observation of `state` into `out` (length [`Env::obs_dim`]).
    fn observe(&self, state: &Self::State, out: &mut [f32]);

    /// One step from `state` with `action`. Pure: the same inputs give the same output.
    fn step(&self, state: &Self::State, action: &[f32]) -> Step<Self::State>;

    /// Column names of the observation, for CSV headers.
    fn obs_names(&self) -> Vec<String> {
        (0..self.obs_dim()).map(|i| format!("o{i}")).collect()
    }
}

/// Fills `out` with an action drawn uniformly from the action box of `env`.
pub fn random_action<E: Env + ?Sized>(env: &E, rng: &mut impl Rng, out: &mut [f32]) {
    for (i, a) in out.iter_mut().enumerate() {
        let b = env.action_bound(i);
        *a = rng.random_range(-b..=b);
    }
}

/// One evaluation episode: whether it reached a positive terminal reward (the target), and in
/// how many steps. A PBCS run's chain (`evaluation.csv` of `pbcs run`, `s<seed>.evaluation.csv`
/// of a sweep, `eval-s<seed>.csv` of `pbcs eval`) and, when asked, a vanilla run's final greedy
/// policy are judged on these. The steps of the successful episodes are the path lengths.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct EvalEpisode {
    /// The episode reached the target.
    pub success: bool,
    /// Steps taken.
    pub steps: usize,
}

/// The start states of the evaluation protocol PBCS's chains are judged by: `episodes` states
/// uniform in B_ε(s_0) (radius `epsilon` around [`Env::start`]), drawn in order from the
/// [`crate::rng::Stream::Eval`] stream of `seeds`. The same seed gives every policy the same
/// starts, so a chain and a vanilla policy of one run seed are judged from the same states.
pub fn evaluation_starts<E: Env + ?Sized>(
    env: &E,
    epsilon: f32,
    episodes: usize,
    seeds: &crate::rng::Seeds,
) -> Vec<E::State> {
    let mut rng = seeds.stream(crate::rng::Stream::Eval);
    let start = env.start();
    (0..episodes)
        .map(|_| env.sample_ball(&start, epsilon, &mut rng))
        .collect()
}
