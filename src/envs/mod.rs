//! Environments by name: the registry the `pbcs` command, jobs and the Python package read, and
//! one module per environment.
//!
//! A job names its environment (`env = "rooms"`; none: the maze, so every config written
//! before the registry means what it meant). [`EnvSpec::build`] makes the environment a name
//! (with its parameters) stands for, once per run, as a [`Built`]; [`with_env!`](crate::with_env) hands it to generic
//! code, which sees only [`Planar`] (an [`crate::env::Env`] that can be drawn) and is compiled
//! once per environment, so the step loops inside stay monomorphic. A closure cannot be generic
//! over `E`, and a visitor struct per command (what this registry had) repeats each command's
//! arguments as fields; the macro is the one `match` over [`Built`].
//!
//! Adding an environment: its own module here (`three_rooms.rs` is the example), and in this
//! file its `mod` line, a variant of [`EnvName`], its arm in [`EnvSpec::build`], a variant of
//! [`Built`] and its arm in `with_env!`: five lines of code (and the variants' doc lines),
//! nothing else in the package.
//!
//! ```
//! use pbcs::env::{Env, Planar};
//! use pbcs::envs::{EnvName, EnvSpec};
//!
//! /// The start of whichever environment is named.
//! fn start(name: EnvName) -> pbcs::Result<(f32, f32)> {
//!     let built = EnvSpec::named(name).build()?;
//!     Ok(pbcs::with_env!(built, |env| env.point(&env.start())))
//! }
//! assert_eq!(start(EnvName::Maze).unwrap(), (0.5, 0.5));
//! assert_eq!(start(EnvName::Rooms).unwrap(), (0.3, 0.2));
//! assert_eq!("rooms".parse::<EnvName>().unwrap(), EnvName::Rooms);
//! ```

pub mod antmaze;
pub mod maze;
pub mod pendulum;
pub mod pointmaze;
pub mod rooms;
mod tasks;
pub mod three_rooms;
pub mod toy;
mod uninhabited;
mod walled;

use crate::error::{Error, Result};
use antmaze::AntMaze;
use maze::{Maze, MazeConfig};
use pointmaze::{MapName, PointMap, PointMaze, PointMazeConfig};
use rooms::TwoRooms;
use serde::{Deserialize, Serialize};

#[cfg_attr(feature = "mujoco", allow(unused_imports))]
pub(crate) use uninhabited::uninhabited_env;

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
    /// Three rooms in a row (`src/envs/three_rooms.rs`); it has no parameters.
    ThreeRooms,
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
    /// gymnasium-robotics' PointMaze on a map of one's own (the job's `[pointmaze]`,
    /// [`PointMazeConfig`]), the task and success as on the four named maps.
    Pointmaze,
    /// gymnasium-robotics' `PointMaze_UMaze-v3` with `continuing_task=False`, reset to the
    /// cells of PBCS's task (`reset(options={"reset_cell", "goal_cell"})`, as SB3's baseline
    /// and the judge play it): start and goal drawn per episode by its reset law (each ±0.25
    /// around its cell's centre), success within 0.45 of the episode's goal
    /// (`PointMaze::with_gym_resets`). A
    /// goal-conditioned task: runs on it train with `[train.her]`, so that the networks see
    /// the goal; PBCS, which needs one target, does not run on it.
    PointmazeUmazeGoals,
    /// gymnasium-robotics' `PointMaze_Open-v3`, the same way.
    PointmazeOpenGoals,
    /// gymnasium-robotics' `PointMaze_Medium-v3`, the same way.
    PointmazeMediumGoals,
    /// gymnasium-robotics' `PointMaze_Large-v3`, the same way.
    PointmazeLargeGoals,
    /// gymnasium-robotics' `AntMaze_UMaze-v5` (`src/envs/antmaze/`, feature `mujoco`) with
    /// `continuing_task=False` and the 27-number observation
    /// (`include_cfrc_ext_in_observation=False`), PBCS's fixed task: from rest at the centre of
    /// one of the two free cells farthest apart to within 0.45 of the other's centre. Phase 1
    /// never archives an ant on its back (`AntMaze::refusing_flipped`).
    AntmazeUmaze,
    /// gymnasium-robotics' `AntMaze_Open-v5`, the same way.
    AntmazeOpen,
    /// gymnasium-robotics' `AntMaze_Medium-v5`, the same way.
    AntmazeMedium,
    /// gymnasium-robotics' `AntMaze_Large-v5`, the same way.
    AntmazeLarge,
    /// `AntMaze_UMaze-v5` reset as the env resets the same cells: start and goal drawn per
    /// episode, each ±1 m around its cell's centre, success within 0.45 of the episode's goal.
    /// Goal-conditioned, as the `_goals` PointMazes: runs on it train with `[train.her]`.
    AntmazeUmazeGoals,
    /// `AntMaze_Open-v5`, the same way.
    AntmazeOpenGoals,
    /// `AntMaze_Medium-v5`, the same way.
    AntmazeMediumGoals,
    /// `AntMaze_Large-v5`, the same way.
    AntmazeLargeGoals,
    /// gymnasium-robotics' AntMaze on a map of one's own (the job's `[pointmaze]`: the same
    /// rows of 0 and 1, in cells of 4 m), the fixed task as on the four named maps.
    Antmaze,
    /// A Gymnasium environment of the user's, run from Python through the adapter
    /// (`pbcs.run(env=...)`, python/pbcs/adapter.py): what the record and the chain's job of
    /// such a run say. Not in the registry ([`EnvName::all`]): nothing here can build it.
    #[value(skip)]
    Gym,
}

/// An environment made from its name ([`EnvSpec::build`]); [`with_env!`](crate::with_env)
/// runs generic code on the one it holds.
#[derive(Debug)]
// Made once per run and matched at once (`with_env!`), each arm taking its environment by value:
// boxing the maze to even the sizes would put an indirection under every step.
#[allow(clippy::large_enum_variant)]
pub enum Built {
    /// [`EnvName::Maze`].
    Maze(Maze),
    /// [`EnvName::Rooms`].
    Rooms(TwoRooms),
    /// [`EnvName::ThreeRooms`].
    ThreeRooms(three_rooms::ThreeRooms),
    /// The PointMaze names, the four maps and `pointmaze` (with MuJoCo; a build without it refuses them in
    /// [`EnvSpec::build`], and its `PointMaze` has no values).
    PointMaze(PointMaze),
    /// The AntMaze names (with MuJoCo, as PointMaze).
    AntMaze(AntMaze),
}

/// Runs `$body` with `$env` bound to the environment a [`Built`] holds, as a value of its own
/// type: the body is compiled once per environment (`match` arms), so generic code inside it
/// runs monomorphic.
///
/// ```
/// use pbcs::env::Env;
/// use pbcs::envs::EnvName;
/// let rooms = pbcs::envs::EnvSpec::named(EnvName::Rooms).build().unwrap();
/// assert_eq!(pbcs::with_env!(rooms, |env| env.action_dim()), 2);
/// ```
#[macro_export]
macro_rules! with_env {
    ($built:expr, |$env:ident| $body:expr) => {
        match $built {
            $crate::envs::Built::Maze($env) => $body,
            $crate::envs::Built::Rooms($env) => $body,
            $crate::envs::Built::ThreeRooms($env) => $body,
            // Without MuJoCo this arm has no values (and its body is unreachable code).
            $crate::envs::Built::PointMaze($env) => {
                #[allow(unreachable_code, unused_variables)]
                let out = $body;
                out
            }
            $crate::envs::Built::AntMaze($env) => {
                #[allow(unreachable_code, unused_variables)]
                let out = $body;
                out
            }
        }
    };
}

impl EnvName {
    /// The name as written in a job and on the command line (`maze`, `rooms`).
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// Every environment of the registry, in order.
    pub fn all() -> &'static [EnvName] {
        <EnvName as clap::ValueEnum>::value_variants()
    }

    /// The names of the environments other than the maze, comma-separated (for messages).
    pub fn others() -> String {
        EnvName::all()
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

    /// The named PointMaze map this name stands for (None for the maze, the rooms and
    /// `pointmaze`, whose map is the job's: [`EnvSpec::point_map`]). Needs no MuJoCo:
    /// the map, the task's cells and gymnasium-robotics' id and time limit are in
    /// [`crate::envs::pointmaze::model`].
    pub fn point_map(self) -> Option<MapName> {
        match self {
            EnvName::PointmazeUmaze | EnvName::PointmazeUmazeGoals => Some(MapName::UMaze),
            EnvName::PointmazeOpen | EnvName::PointmazeOpenGoals => Some(MapName::Open),
            EnvName::PointmazeMedium | EnvName::PointmazeMediumGoals => Some(MapName::Medium),
            EnvName::PointmazeLarge | EnvName::PointmazeLargeGoals => Some(MapName::Large),
            _ => None,
        }
    }

    /// The named map of an AntMaze name (AntMaze runs on PointMaze's maps, in cells of 4 m).
    ///
    /// ```
    /// use pbcs::envs::{pointmaze::MapName, EnvName};
    /// assert_eq!(EnvName::AntmazeMedium.ant_map(), Some(MapName::Medium));
    /// assert_eq!(EnvName::PointmazeMedium.ant_map(), None);
    /// ```
    pub fn ant_map(self) -> Option<MapName> {
        match self {
            EnvName::AntmazeUmaze | EnvName::AntmazeUmazeGoals => Some(MapName::UMaze),
            EnvName::AntmazeOpen | EnvName::AntmazeOpenGoals => Some(MapName::Open),
            EnvName::AntmazeMedium | EnvName::AntmazeMediumGoals => Some(MapName::Medium),
            EnvName::AntmazeLarge | EnvName::AntmazeLargeGoals => Some(MapName::Large),
            _ => None,
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
        self.feature().filter(|_| !cfg!(feature = "mujoco"))
    }

    /// The cargo feature this environment needs in any build (`mujoco` for PointMaze and
    /// AntMaze), or None for the environments every build has.
    ///
    /// ```
    /// use pbcs::envs::EnvName;
    /// assert_eq!(EnvName::AntmazeUmaze.feature(), Some("mujoco"));
    /// assert_eq!(EnvName::Rooms.feature(), None);
    /// ```
    pub fn feature(self) -> Option<&'static str> {
        (self.is_pointmaze() || self.is_antmaze()).then_some("mujoco")
    }

    /// Whether this is an AntMaze: a named map (either task) or a map of one's own.
    pub fn is_antmaze(self) -> bool {
        self.ant_map().is_some() || self == EnvName::Antmaze
    }

    /// Whether the job's `[pointmaze]` gives this environment its map: `pointmaze` and
    /// `antmaze` (the others take none, and refuse one).
    pub fn takes_map(self) -> bool {
        matches!(self, EnvName::Pointmaze | EnvName::Antmaze)
    }

    /// Whether this is a PointMaze: one of the four named maps or a map of one's own.
    pub fn is_pointmaze(self) -> bool {
        self.point_map().is_some() || self == EnvName::Pointmaze
    }
}

/// Where a run runs: an environment's name and its parameters, as every job holds them
/// (`env`, `[maze]`, `[pointmaze]`) and [`crate::config::Located::env_spec`] gives them. The
/// one value that checks, builds, names and draws an environment.
///
/// ```
/// use pbcs::envs::{EnvName, EnvSpec};
/// let spec = EnvSpec::named(EnvName::Rooms);
/// assert_eq!(spec.label(), "rooms");
/// let mut maze = EnvSpec::default();
/// maze.maze.size = 4;
/// assert_eq!(maze.label(), "maze 4 (layout 0)");
/// let mut rooms_with_maze = maze.clone();
/// rooms_with_maze.name = EnvName::Rooms;
/// assert!(rooms_with_maze.check().unwrap_err().to_string().contains("[maze]"));
/// ```
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EnvSpec {
    /// The environment.
    pub name: EnvName,
    /// The maze's size and layout (the maze only; the defaults for any other).
    pub maze: MazeConfig,
    /// A map of one's own, in gymnasium-robotics' `maze_map` rows (`pointmaze` and `antmaze`
    /// only; the default, no map, for any other).
    pub pointmaze: PointMazeConfig,
}

impl EnvSpec {
    /// The environment `name` with default parameters.
    pub fn named(name: EnvName) -> EnvSpec {
        EnvSpec {
            name,
            ..EnvSpec::default()
        }
    }

    /// Checks the parameters against the name: the maze's for the maze, a map for
    /// `pointmaze` and `antmaze`; parameters of another environment are refused (they would be
    /// ignored).
    pub fn check(&self) -> Result<()> {
        let name = self.name.name();
        if !self.name.is_maze() && self.maze != MazeConfig::default() {
            return Err(Error::invalid(
                "maze",
                format!(
                    "sets the maze, but env = \"{name}\" runs another environment (leave \
                     [maze] out, or set env = \"maze\")"
                ),
            ));
        }
        if !self.name.takes_map() && !self.pointmaze.is_default() {
            return Err(Error::invalid(
                "pointmaze",
                format!(
                    "sets a map of one's own, but env = \"{name}\" (leave [pointmaze] out, \
                     or set env = \"pointmaze\" or \"antmaze\")"
                ),
            ));
        }
        crate::validate::Check::check(&self.maze)?;
        match self.name.takes_map() {
            true => self.pointmaze.check(),
            false => Ok(()),
        }
    }

    /// How titles and messages name the environment: `maze 5 (layout 0)`, `rooms`,
    /// `PointMaze Medium`, `PointMaze (own map, 10×12)`.
    pub fn label(&self) -> String {
        match (self.name, self.name.point_map()) {
            (EnvName::Maze, _) => format!("maze {} (layout {})", self.maze.size, self.maze.seed),
            (name, None) if name.ant_map().is_some() => {
                let map = name.ant_map().map_or("", <&str>::from);
                let drawn = if name.goal_resets() {
                    " (goals drawn per episode)"
                } else {
                    ""
                };
                format!("AntMaze {map}{drawn}")
            }
            (name, Some(map)) if name.goal_resets() => {
                format!("PointMaze {} (goals drawn per episode)", <&str>::from(map))
            }
            (_, Some(map)) => format!("PointMaze {}", <&str>::from(map)),
            (EnvName::Pointmaze | EnvName::Antmaze, None) => {
                let (h, w) = (
                    self.pointmaze.map.len(),
                    self.pointmaze.map.first().map_or(0, String::len),
                );
                let body = if self.name.is_antmaze() {
                    "AntMaze"
                } else {
                    "PointMaze"
                };
                format!("{body} (own map, {h}×{w})")
            }
            (other, None) => other.name().to_string(),
        }
    }

    /// How run folders name where they ran ([`crate::runs::explore_out`]): `maze<N>-m<layout>`
    /// for the maze, `pointmaze-<H>x<W>-<hash>` (`antmaze-…`) for a map of one's own (the
    /// first 8 hex digits of its rows' SHA-256, so that two maps do not share a folder; a clash
    /// of those 32 bits would be refused by the folder's claim, which compares the whole job),
    /// the name for another.
    ///
    /// ```
    /// use pbcs::envs::{EnvName, EnvSpec};
    /// let mut own = EnvSpec::named(EnvName::Pointmaze);
    /// own.pointmaze.map = vec!["111".into(), "101".into(), "111".into()];
    /// assert!(own.folder_name().starts_with("pointmaze-3x3-"));
    /// assert_eq!(EnvSpec::named(EnvName::PointmazeLarge).folder_name(), "pointmaze_large");
    /// ```
    pub fn folder_name(&self) -> String {
        match self.name {
            EnvName::Maze => format!("maze{}-m{}", self.maze.size, self.maze.seed),
            EnvName::Pointmaze | EnvName::Antmaze => {
                let rows = &self.pointmaze.map;
                let hex = crate::record::sha256_hex(rows.join("\n").as_bytes());
                let hex = &hex[..8];
                let w = rows.first().map_or(0, String::len);
                format!("{}-{}x{w}-{hex}", self.name.name(), rows.len())
            }
            other => other.name().to_string(),
        }
    }

    /// The maze's size and layout seed as records write them (`record.csv`'s `maze` and
    /// `maze_seed`): empty for any environment but the maze. The one place a record says
    /// where its run ran, with its `env` column.
    pub fn maze_columns(&self) -> (Option<usize>, Option<u64>) {
        match self.name {
            EnvName::Maze => (Some(self.maze.size), Some(self.maze.seed)),
            _ => (None, None),
        }
    }

    /// The PointMaze map, for a PointMaze (named or of one's own), else None.
    pub fn point_map(&self) -> Result<Option<PointMap>> {
        Ok(match (self.name, self.name.point_map()) {
            (_, Some(named)) => Some(PointMap::named(named)),
            (EnvName::Pointmaze, None) => Some(PointMap::from_config(&self.pointmaze)?),
            _ => None,
        })
    }

    /// The map of an AntMaze (named, or the job's own); an error for any other environment.
    pub fn ant_map(&self) -> Result<PointMap> {
        match (self.name, self.name.ant_map()) {
            (_, Some(named)) => Ok(PointMap::named(named)),
            (EnvName::Antmaze, None) => PointMap::from_config(&self.pointmaze),
            (other, None) => Err(Error::invalid(
                "env",
                format!("{} is not an AntMaze", other.name()),
            )),
        }
    }

    /// Makes the environment: once per run.
    pub fn build(&self) -> Result<Built> {
        Ok(match self.name {
            EnvName::Maze => Built::Maze(Maze::new(&self.maze)?),
            EnvName::Rooms => Built::Rooms(TwoRooms),
            EnvName::ThreeRooms => Built::ThreeRooms(three_rooms::ThreeRooms),
            EnvName::PointmazeUmaze
            | EnvName::PointmazeOpen
            | EnvName::PointmazeMedium
            | EnvName::PointmazeLarge
            | EnvName::Pointmaze
            | EnvName::PointmazeUmazeGoals
            | EnvName::PointmazeOpenGoals
            | EnvName::PointmazeMediumGoals
            | EnvName::PointmazeLargeGoals => {
                let map = self.point_map()?.expect("a PointMaze has a map");
                Built::PointMaze(point_maze(map, self.name)?)
            }
            EnvName::AntmazeUmaze
            | EnvName::AntmazeOpen
            | EnvName::AntmazeMedium
            | EnvName::AntmazeLarge
            | EnvName::AntmazeUmazeGoals
            | EnvName::AntmazeOpenGoals
            | EnvName::AntmazeMediumGoals
            | EnvName::AntmazeLargeGoals
            | EnvName::Antmaze => Built::AntMaze(ant_maze(self.ant_map()?, self.name)?),
            EnvName::Gym => {
                return Err(Error::invalid(
                    "env",
                    "`gym` is a Gymnasium environment of one's own, which runs from Python only \
                     (pbcs.run(env=...); its chain: pbcs.load_chain(path, adapter=...))",
                ))
            }
        })
    }

    /// What pictures draw under a run of this environment (its [`crate::env::Planar::scene`]):
    /// PointMaze's from its map, without MuJoCo, so that committed rows draw in any build.
    pub fn scene(&self) -> Result<crate::env::Scene> {
        match self.point_map()? {
            Some(map) if self.name.goal_resets() => {
                let (start, goal) = map.farthest_cells();
                let radius = pointmaze::SUCCESS_DISTANCE as f32;
                Ok(map.scene(start, goal, radius))
            }
            Some(map) => Ok(point_scene(&map)),
            None if self.name.is_antmaze() => {
                let map = self.ant_map()?;
                let (start, goal) = map.farthest_cells();
                let radius = pointmaze::SUCCESS_DISTANCE as f32;
                Ok(antmaze::model::scene(&map, start, goal, radius))
            }
            None => Ok(crate::with_env!(self.build()?, |env| {
                crate::env::Planar::scene(&env)
            })),
        }
    }
}

/// What pictures draw of the registry's task on `map` (the same as its [`Planar::scene`],
/// without MuJoCo): the map, the start cell and the success region of [`point_maze`].
pub fn point_scene(map: &PointMap) -> crate::env::Scene {
    use crate::envs::pointmaze::{sure_radius, GOAL_NOISE};
    let (start, goal) = map.farthest_cells();
    map.scene(start, goal, sure_radius(GOAL_NOISE) as f32)
}

/// A PointMaze task ([`crate::envs::pointmaze::PointMaze::named`]) whose success holds for
/// every goal gymnasium-robotics' reset may draw ([`pointmaze::GOAL_NOISE`]): one fixed chain
/// is judged there from the env's own resets, which move the goal up to 0.25 along each axis.
/// The `_goals` names: the same cells with those resets themselves
/// ([`crate::envs::pointmaze::PointMaze::with_gym_resets`]).
#[cfg(feature = "mujoco")]
fn point_maze(map: PointMap, name: EnvName) -> Result<PointMaze> {
    let env = PointMaze::on(map)?;
    if name.goal_resets() {
        env.with_gym_resets()
    } else {
        env.for_goal_noise(pointmaze::GOAL_NOISE)
    }
}

/// An AntMaze task: the map's two free cells farthest apart, with gymnasium-robotics' resets
/// ([`crate::envs::antmaze::AntMaze::on`]) for the `_goals` names, else from rest at the
/// start cell's centre to the goal cell's, phase 1 refusing an ant on its back.
#[cfg(feature = "mujoco")]
fn ant_maze(map: PointMap, name: EnvName) -> Result<AntMaze> {
    if name.goal_resets() {
        return AntMaze::on(map);
    }
    let (start, goal) = map.farthest_cells();
    Ok(AntMaze::new(map, start, goal, pointmaze::Resets::Fixed)?.refusing_flipped())
}

/// Without MuJoCo: refused, saying how to build with it.
#[cfg(not(feature = "mujoco"))]
fn point_maze(_map: PointMap, name: EnvName) -> Result<PointMaze> {
    Err(needs_mujoco(name))
}

/// Without MuJoCo: refused, saying how to build with it.
#[cfg(not(feature = "mujoco"))]
fn ant_maze(_map: PointMap, name: EnvName) -> Result<AntMaze> {
    Err(needs_mujoco(name))
}

/// The error for a MuJoCo environment in a build without it.
#[cfg(not(feature = "mujoco"))]
fn needs_mujoco(name: EnvName) -> Error {
    Error::invalid(
        "env",
        format!(
            "{} runs on MuJoCo: `make mujoco`, then build with `--features mujoco`",
            name.name()
        ),
    )
}
