//! gymnasium-robotics' AntMaze (MuJoCo): gymnasium's ant — a torso on four legs of two hinges
//! each, 8 motors, contacts with the floor and the walls, a body that can flip over — in
//! PointMaze's maps with cells of 4 m. Where PointMaze's action pushes a point, here the agent
//! has to walk before it can go anywhere.
//!
//! * [`model`] — the model XML, as gymnasium-robotics 1.4.2 writes it around gymnasium's
//!   `ant.xml`, and the cell ↔ point conversion in metres; no MuJoCo needed.
//! * `AntMaze` (feature `mujoco`, `make mujoco` first) — the environment:
//!   `AntMaze_<map>-v5`'s step, observation, reward and success (with
//!   `include_cfrc_ext_in_observation=False` and `continuing_task=False`) on MuJoCo 3.17.0,
//!   as a pure [`crate::env::Env::step`] over the whole state (`AntState`).
//!   `python/tests/test_antmaze.py` drives it and gymnasium-robotics' own env from the same
//!   states with the same actions and requires the same numbers, bit for bit.

pub mod model;
#[cfg(feature = "mujoco")]
mod sim;

#[cfg(feature = "mujoco")]
pub use sim::{AntMaze, AntState, FRAME_SKIP, NQ, NU, NV};

#[cfg(not(feature = "mujoco"))]
crate::envs::uninhabited_env!(AntMaze, "AntMaze");
