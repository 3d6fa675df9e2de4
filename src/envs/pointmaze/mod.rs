//! gymnasium-robotics' PointMaze (MuJoCo): a point mass with momentum in a maze of 1 m cells,
//! the benchmark the field uses for mazes, and an outside referee for PBCS beyond the paper's
//! displacement maze.
//!
//! * [`model`] — the maps (`UMaze`, `Open`, `Medium`, `Large`, or rows of 0/1), the cell ↔
//!   point conversion, the task (the two free cells farthest apart) and the MuJoCo model XML,
//!   as gymnasium-robotics 1.4.2 writes it; no MuJoCo needed.
//! * [`own`] — a map of one's own: the job's `[pointmaze]` (rows inline or from a file),
//!   checked into a [`PointMap`]; no MuJoCo needed.
//! * `PointMaze` (feature `mujoco`, `make mujoco` first) — the environment: gymnasium-robotics'
//!   step, reward and success on MuJoCo 3.17.0, as a pure [`crate::env::Env::step`] over the
//!   whole state (position, velocity and the solver's warm start, `PointState`).
//!   `python/tests/test_pointmaze.py` drives it and gymnasium-robotics' own `PointMaze_*-v3`
//!   from the same states with the same actions and requires the same numbers, bit for bit.

pub mod model;
pub mod own;
#[cfg(feature = "mujoco")]
mod sim;

pub use model::{sure_radius, MapName, PointMap, GOAL_NOISE, SUCCESS_DISTANCE};
pub use own::{PointMazeConfig, MAX_MAP_SIDE, OWN_TIME_LIMIT};
#[cfg(feature = "mujoco")]
pub use sim::{PointMaze, PointState, Resets, MAX_SPEED, RADIUS};

/// Without MuJoCo, PointMaze has no values: the registry refuses its names
/// ([`crate::envs::EnvSpec::build`]), and code generic over the registry's environments
/// ([`crate::with_env!`]) still compiles.
#[cfg(not(feature = "mujoco"))]
#[derive(Debug, Clone)]
pub enum PointMaze {}

#[cfg(not(feature = "mujoco"))]
impl crate::env::Env for PointMaze {
    type State = std::convert::Infallible;
    fn obs_dim(&self) -> usize {
        match *self {}
    }
    fn action_dim(&self) -> usize {
        match *self {}
    }
    fn action_bound(&self, _: usize) -> f32 {
        match *self {}
    }
    fn start(&self) -> Self::State {
        match *self {}
    }
    fn sample_start(&self, _: &mut crate::rng::Rng) -> Self::State {
        match *self {}
    }
    fn observe(&self, _: &Self::State, _: &mut [f32]) {
        match *self {}
    }
    fn step(&self, _: &Self::State, _: &[f32]) -> crate::env::Step<Self::State> {
        match *self {}
    }
}

#[cfg(not(feature = "mujoco"))]
impl crate::env::Planar for PointMaze {
    fn point(&self, _: &Self::State) -> (f32, f32) {
        match *self {}
    }
    fn scene(&self) -> crate::env::Scene {
        match *self {}
    }
    fn ball_point(&self, _: &[f32]) -> (f32, f32) {
        match *self {}
    }
}
