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

#[cfg(not(feature = "mujoco"))]
crate::envs::uninhabited_env!(PointMaze, "PointMaze");
