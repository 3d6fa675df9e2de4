//! Environments by name: the registry the `pbcs` command, jobs and the Python package read.
//!
//! A job names its environment (`env = "rooms"`; none: the maze, so every config written
//! before the registry means what it meant). [`EnvName::visit`] builds the environment a name
//! stands for and hands it to generic code ([`Visit`]), which sees only [`Planar`] (an
//! [`crate::env::Env`] that can be drawn). Adding an environment is its own file, one variant
//! here and one arm in [`EnvName::visit`].
//!
//! ```
//! use pbcs::config::MazeConfig;
//! use pbcs::env::{Env, Planar};
//! use pbcs::envs::{EnvName, Visit};
//!
//! /// The start of whichever environment is named.
//! struct Start;
//! impl Visit for Start {
//!     type Output = (f32, f32);
//!     fn on<E: Planar>(self, env: E) -> pbcs::Result<(f32, f32)> {
//!         Ok(env.point(&env.start()))
//!     }
//! }
//! let maze = MazeConfig::default();
//! assert_eq!(EnvName::Maze.visit(&maze, Start).unwrap(), (0.5, 0.5));
//! assert_eq!(EnvName::Rooms.visit(&maze, Start).unwrap(), (0.3, 0.2));
//! assert_eq!("rooms".parse::<EnvName>().unwrap(), EnvName::Rooms);
//! ```

pub mod maze;
pub mod pendulum;
pub mod pointmaze;
pub mod rooms;
pub mod toy;

use crate::env::Planar;
use crate::envs::maze::{Maze, MazeConfig};
use crate::envs::pointmaze::MapName;
use crate::envs::rooms::TwoRooms;
use crate::error::Result;
use serde::{Deserialize, Serialize};

/// The environments PBCS runs on, by name.
#[derive(
    Debug,
    Clone,
    Copy,
    Default,
    PartialEq,
    Eq,
    PartialOrd,
    Ord,
    Hash,
    Serialize,
    Deserialize,
    clap::ValueEnum,
    strum::IntoStaticStr,
    strum::EnumString,
)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
#[value(rename_all = "snake_case")]
pub enum EnvName {
    /// The paper's continuous maze (`src/envs/maze/`), sized and laid out by the job's `[maze]`.
    #[default]
    Maze,
    /// Two rooms joined by a door (`src/envs/rooms.rs`); it has no parameters.
    Rooms,
    /// gymnasium-robotics' `PointMaze_UMaze-v3` (`src/envs/pointmaze/`, feature `mujoco`), from
    /// one of its two free cells farthest apart to the other; success where every goal its
    /// reset may draw counts one (`PointMaze::for_goal_noise`).
    PointmazeUmaze,
    /// gymnasium-robotics' `PointMaze_Open-v3`, the same way.
    PointmazeOpen,
    /// gymnasium-robotics' `PointMaze_Medium-v3`, the same way.
    PointmazeMedium,
    /// gymnasium-robotics' `PointMaze_Large-v3`, the same way.
    PointmazeLarge,
}

/// Generic work on whichever environment a name stands for ([`EnvName::visit`]).
pub trait Visit {
    /// What the work returns.
    type Output;
    /// The work on `env`.
    fn on<E: Planar>(self, env: E) -> Result<Self::Output>;
}

impl EnvName {
    /// The name as written in a job and on the command line (`maze`, `rooms`).
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// How titles and messages name the environment: `maze 5 (layout 0)`, `rooms`,
    /// `PointMaze Medium`.
    pub fn label(self, maze: &MazeConfig) -> String {
        match (self, self.point_map()) {
            (EnvName::Maze, _) => format!("maze {} (layout {})", maze.size, maze.seed),
            (_, Some(map)) => format!("PointMaze {}", <&str>::from(map)),
            (other, None) => other.name().to_string(),
        }
    }

    /// The names of the environments other than the maze, comma-separated (for messages).
    pub fn others() -> String {
        <EnvName as clap::ValueEnum>::value_variants()
            .iter()
            .filter(|e| !e.is_maze())
            .map(|e| e.name())
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Whether this is the maze (the default, left out of written jobs).
    pub fn is_maze(&self) -> bool {
        *self == EnvName::Maze
    }

    /// Builds the environment this name stands for (the maze from `maze`) and runs `work` on
    /// it.
    pub fn visit<V: Visit>(self, maze: &MazeConfig, work: V) -> Result<V::Output> {
        match self {
            EnvName::Maze => work.on(Maze::new(maze)?),
            EnvName::Rooms => work.on(TwoRooms),
            EnvName::PointmazeUmaze
            | EnvName::PointmazeOpen
            | EnvName::PointmazeMedium
            | EnvName::PointmazeLarge => point_maze(self.point_map().expect("a PointMaze"), work),
        }
    }

    /// The PointMaze map this name stands for (None for the maze and rooms). Needs no MuJoCo:
    /// the map, the task's cells and gymnasium-robotics' id and time limit are in
    /// [`crate::envs::pointmaze::model`].
    pub fn point_map(self) -> Option<MapName> {
        match self {
            EnvName::Maze | EnvName::Rooms => None,
            EnvName::PointmazeUmaze => Some(MapName::UMaze),
            EnvName::PointmazeOpen => Some(MapName::Open),
            EnvName::PointmazeMedium => Some(MapName::Medium),
            EnvName::PointmazeLarge => Some(MapName::Large),
        }
    }

    /// The cargo feature this environment needs and this build lacks (`mujoco` for PointMaze
    /// in a build without it), or None when this build runs it.
    ///
    /// ```
    /// use pbcs::envs::EnvName;
    /// assert_eq!(EnvName::Rooms.missing_feature(), None);
    /// let lacks = if cfg!(feature = "mujoco") { None } else { Some("mujoco") };
    /// assert_eq!(EnvName::PointmazeLarge.missing_feature(), lacks);
    /// ```
    pub fn missing_feature(self) -> Option<&'static str> {
        (self.point_map().is_some() && !cfg!(feature = "mujoco")).then_some("mujoco")
    }
}

/// What pictures draw of the registry's task on `map` (the same as its [`Planar::scene`],
/// without MuJoCo): the map, the start cell and the success region of [`point_maze`].
pub fn point_scene(map: MapName) -> crate::env::Scene {
    use crate::envs::pointmaze::{sure_radius, PointMap, GOAL_NOISE};
    let m = PointMap::named(map);
    let (start, goal) = m.farthest_cells();
    m.scene(start, goal, sure_radius(GOAL_NOISE) as f32)
}

/// A PointMaze task ([`crate::envs::pointmaze::PointMaze::named`]) whose success holds for every
/// goal gymnasium-robotics' reset may draw ([`crate::envs::pointmaze::GOAL_NOISE`]): one fixed chain
/// is judged there from the env's own resets, which move the goal up to 0.25 along each axis.
#[cfg(feature = "mujoco")]
fn point_maze<V: Visit>(map: MapName, work: V) -> Result<V::Output> {
    use crate::envs::pointmaze::{PointMaze, GOAL_NOISE};
    work.on(PointMaze::named(map)?.for_goal_noise(GOAL_NOISE)?)
}

/// Without MuJoCo: refused, saying how to build with it.
#[cfg(not(feature = "mujoco"))]
fn point_maze<V: Visit>(map: MapName, work: V) -> Result<V::Output> {
    let _ = work;
    Err(crate::error::Error::invalid(
        "env",
        format!(
            "{} runs on MuJoCo: `make mujoco`, then build with `--features mujoco`",
            map.gym_id()
        ),
    ))
}
