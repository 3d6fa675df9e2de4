//! The jobs a run is computed from (`pbcs explore`, `train`, `run`), assembled from each
//! module's own validated config, and the named presets.
//!
//! Each struct rejects unknown keys when parsed and has a `check()` that names the offending
//! field in its error (`invalid \`maze.size\`: ...`). Every field has a default, so a config
//! file only states what it changes.
//!
//! ```
//! use pbcs::config::{Check, ExploreJob};
//!
//! let job: ExploreJob = toml::from_str("seed = 3\n[maze]\nsize = 7\n").unwrap();
//! job.check().unwrap();
//! assert_eq!((job.seed, job.maze.size, job.explore.bin_side), (3, 7, 0.05));
//!
//! let bad: ExploreJob = toml::from_str("[maze]\nsize = 1\n").unwrap();
//! assert!(bad.check().unwrap_err().to_string().contains("maze.size"));
//! ```

use crate::envs::pointmaze::PointMazeConfig;
use crate::envs::{EnvName, EnvSpec};
use crate::error::{Error, Result};
use crate::learner::td3::Td3Config;
use crate::learner::LearnerConfig;
use crate::phase2::Phase2Config;
use crate::validate::parse_toml;
use crate::vanilla::TrainConfig;
use serde::{Deserialize, Serialize};
use std::path::Path;

pub use crate::envs::maze::{MazeConfig, MAX_MAZE_SIZE};
pub use crate::phase1::ExploreConfig;
pub use crate::validate::{load, Check};

/// What `pbcs explore` runs: phase 1 on one environment (the maze unless `env` names another)
/// with one run seed.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExploreJob {
    /// The run seed; every random stream of the run derives from it (see [`crate::rng`]).
    pub seed: u64,
    /// The environment ([`crate::envs::EnvName`]): the maze unless named (and then left out
    /// of the written job).
    #[serde(skip_serializing_if = "EnvName::is_maze")]
    pub env: EnvName,
    /// The maze (when `env` is the maze; left at its defaults otherwise).
    pub maze: MazeConfig,
    /// A map of one's own (when `env` is `pointmaze` or `antmaze`; left out otherwise).
    #[serde(skip_serializing_if = "PointMazeConfig::is_default")]
    pub pointmaze: PointMazeConfig,
    /// Phase 1 settings.
    pub explore: ExploreConfig,
}

impl Check for ExploreJob {
    fn check(&self) -> Result<()> {
        self.env_spec().check()?;
        self.env.check_fixed_task("phase 1's exploration")?;
        self.explore.check()
    }
}

/// Where a job runs: its run seed and its environment with its parameters (`env`, `[maze]`,
/// `[pointmaze]`), read and set as one [`EnvSpec`]. Every job has them; a grid's cell, the
/// command's flags and Python's arguments set them through this.
pub trait Located {
    /// The run seed.
    fn seed(&self) -> u64;
    /// The run seed, to set.
    fn seed_mut(&mut self) -> &mut u64;
    /// The environment and its parameters.
    fn env_spec(&self) -> EnvSpec;
    /// Sets the environment and its parameters.
    fn set_env_spec(&mut self, spec: EnvSpec);
}

macro_rules! located {
    ($($job:ty),*) => {$(
        impl Located for $job {
            fn seed(&self) -> u64 {
                self.seed
            }
            fn seed_mut(&mut self) -> &mut u64 {
                &mut self.seed
            }
            fn env_spec(&self) -> EnvSpec {
                EnvSpec {
                    name: self.env,
                    maze: self.maze.clone(),
                    pointmaze: self.pointmaze.clone(),
                }
            }
            fn set_env_spec(&mut self, spec: EnvSpec) {
                (self.env, self.maze, self.pointmaze) = (spec.name, spec.maze, spec.pointmaze);
            }
        }
    )*};
}
located!(ExploreJob, TrainJob, PbcsJob);

/// What `pbcs train` runs: a vanilla baseline (DDPG, TD3, or the argmax actor) on one
/// environment's own reward (the maze unless `env` names another).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrainJob {
    /// The run seed.
    pub seed: u64,
    /// The environment ([`crate::envs::EnvName`]): the maze unless named (and then left out
    /// of the written job).
    #[serde(skip_serializing_if = "EnvName::is_maze")]
    pub env: EnvName,
    /// The maze (when `env` is the maze; left at its defaults otherwise).
    pub maze: MazeConfig,
    /// A map of one's own (when `env` is `pointmaze` or `antmaze`; left out otherwise).
    #[serde(skip_serializing_if = "PointMazeConfig::is_default")]
    pub pointmaze: PointMazeConfig,
    /// The learner's hyper-parameters.
    pub learner: LearnerConfig,
    /// The training schedule.
    pub train: TrainConfig,
}

impl TrainJob {
    /// The learner's name in result rows: [`LearnerConfig::record_name`], with `_her` when
    /// it trains with hindsight experience replay (`sac_her`, `td3_her`).
    pub fn learner_name(&self) -> crate::learner::LearnerName {
        let her = if self.train.her.is_some() { "_her" } else { "" };
        crate::learner::LearnerName::of_family(&format!("{}{her}", self.learner.record_name()))
    }
}

impl Check for TrainJob {
    fn check(&self) -> Result<()> {
        self.env_spec().check()?;
        if self.train.her.is_none() {
            self.env.check_fixed_task("a run without [train.her]")?;
        }
        self.learner.check()?;
        self.train.check()?;
        let batch = self.learner.batch_size() as u64;
        if batch > self.train.steps {
            // The learner updates once its replay holds a batch, which never happens.
            return Err(Error::invalid(
                "learner.batch_size",
                format!(
                    "{batch} is more than train.steps = {}: the replay never holds a batch, so \
                     the learner would never update",
                    self.train.steps
                ),
            ));
        }
        Ok(())
    }
}

/// What `pbcs run` runs: PBCS on one maze — phase 1, then phase 2 — and the evaluation of the
/// resulting chain.
///
/// The learner defaults to DDPG with γ = 0.9 (the other settings as [`LearnerConfig`]'s
/// defaults). Measured on maze 2, seed 0 (`examples/phase2_trace.rs`): with γ = 0.99 DDPG's
/// training success at the very first K rose to 0.86–0.90 and then collapsed to 0.02–0.06
/// within six rounds, and no skill was found in 2.2M steps; with γ = 0.9 training stayed at
/// 0.88–1.0 and the maze was solved with 2 skills in 253k steps. The paper's appendix on γ
/// reports the same direction.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PbcsJob {
    /// The run seed.
    pub seed: u64,
    /// The environment ([`crate::envs::EnvName`]): the maze unless named (and then left out
    /// of the written job, so a maze job reads as before the registry).
    #[serde(skip_serializing_if = "EnvName::is_maze")]
    pub env: EnvName,
    /// The maze (the environment's size and layout when `env` is the maze; left at its
    /// defaults otherwise).
    pub maze: MazeConfig,
    /// A map of one's own (when `env` is `pointmaze` or `antmaze`; left out otherwise).
    #[serde(skip_serializing_if = "PointMazeConfig::is_default")]
    pub pointmaze: PointMazeConfig,
    /// Phase 1.
    pub explore: ExploreConfig,
    /// The learner trained by each Backplay (DDPG by default, as in the paper).
    pub learner: LearnerConfig,
    /// Phase 2: α, β, ε, chaining, starts, budget, evaluation.
    pub phase2: Phase2Config,
}

impl Default for PbcsJob {
    fn default() -> Self {
        PbcsJob {
            seed: 0,
            env: EnvName::Maze,
            maze: MazeConfig::default(),
            pointmaze: PointMazeConfig::default(),
            explore: ExploreConfig::default(),
            learner: Td3Config {
                gamma: 0.9,
                ..Td3Config::ddpg()
            }
            .into(),
            phase2: Phase2Config::default(),
        }
    }
}

impl Check for PbcsJob {
    fn check(&self) -> Result<()> {
        self.env_spec().check()?;
        self.env.check_fixed_task("PBCS")?;
        self.explore.check()?;
        self.learner.check()?;
        self.phase2.check()
    }
}

impl PbcsJob {
    /// PBCS without chaining (`pbcs run --no-chaining`): one skill, so what acts between
    /// skills goes with it. Returns the settings set to 0 for it (`phase2.retargets`,
    /// `phase2.chain_repairs`), to be said.
    pub fn without_chaining(&mut self) -> Vec<&'static str> {
        self.phase2.chaining = false;
        let ideas = &mut self.phase2.ideas;
        let between = [
            (
                "phase2.retargets",
                ideas.dead_walk.as_mut().map(|d| &mut d.retargets),
            ),
            (
                "phase2.chain_repairs",
                ideas.chain_check.as_mut().map(|c| &mut c.repairs),
            ),
        ];
        let mut zeroed = Vec::new();
        for (field, value) in between {
            if let Some(value) = value.filter(|v| **v > 0) {
                *value = 0;
                zeroed.push(field);
            }
        }
        zeroed
    }
}

/// What a command line or a Python call changes in a job before it runs: where it runs and
/// its seed, each left as the job has it when `None` (the same call in both, so a job means
/// the same from either). [`Place::apply`] refuses a maze size or layout for a job on another
/// environment, and a map for any but `pointmaze` and `antmaze`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Place {
    /// The environment (`--env`, `env=`).
    pub env: Option<EnvName>,
    /// The maze's size (`--maze`, `size=`).
    pub maze_size: Option<usize>,
    /// The maze's layout seed (`--maze-seed`, `layout=`).
    pub maze_seed: Option<u64>,
    /// The run seed (`--seed`, `seed=`).
    pub seed: Option<u64>,
    /// The rows of a map of one's own (`--map FILE`, `map=`, `map_file=`), for `pointmaze`
    /// and `antmaze` (its time limit stays the job's).
    pub map: Option<Vec<String>>,
}

impl Place {
    /// Sets the fields given into `job`; a maze size or layout with an environment other
    /// than the maze is refused, naming the environment.
    ///
    /// ```
    /// use pbcs::config::{Place, ExploreJob};
    /// use pbcs::envs::EnvName;
    /// let mut job = ExploreJob::default();
    /// let place = Place { env: Some(EnvName::Rooms), seed: Some(3), ..Place::default() };
    /// place.apply(&mut job).unwrap();
    /// assert_eq!((job.env, job.seed), (EnvName::Rooms, 3));
    /// let maze = Place { maze_size: Some(4), ..place };
    /// assert!(maze.apply(&mut job).unwrap_err().to_string().contains("rooms"));
    /// ```
    pub fn apply(&self, job: &mut impl Located) -> Result<()> {
        let mut spec = job.env_spec();
        spec.name = self.env.unwrap_or(spec.name);
        let env = spec.name.name();
        if !spec.name.is_maze() && (self.maze_size.is_some() || self.maze_seed.is_some()) {
            return Err(crate::error::Error::invalid(
                "maze",
                format!(
                    "a maze size or layout (--maze, --maze-seed; Python's size=, layout=) sets \
                     the maze, but the run's environment is `{env}`",
                ),
            ));
        }
        if !spec.name.takes_map() && self.map.is_some() {
            return Err(crate::error::Error::invalid(
                "pointmaze.map",
                format!(
                    "a map (--map; Python's map=, map_file=) is for env `pointmaze` or \
                     `antmaze`, but the run's environment is `{env}`"
                ),
            ));
        }
        spec.maze.size = self.maze_size.unwrap_or(spec.maze.size);
        spec.maze.seed = self.maze_seed.unwrap_or(spec.maze.seed);
        if let Some(map) = &self.map {
            spec.pointmaze.map = map.clone();
        }
        job.set_env_spec(spec);
        let seed = job.seed_mut();
        *seed = self.seed.unwrap_or(*seed);
        Ok(())
    }
}

/// The named PBCS procedures, each a complete TOML file in `experiments/` (embedded in the
/// library, so `pbcs run --preset NAME` needs no file).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum, strum::IntoStaticStr,
)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum Preset {
    /// The paper's procedure (Algorithms 1–3 as written, K − 1 at a time, α rounds of
    /// training), with our corrections and our choices of the settings it leaves open:
    /// `experiments/pbcs_paper.toml`.
    Paper,
    /// The paper's procedure with switches of ours (shortened τ, early stop, adaptive K
    /// steps, capped training rounds, restarts, bounded walks and moved hand-overs,
    /// warm-started skills, path-limited tests, verified skills and a verified, repaired
    /// chain; which are kept on evidence: `experiments/settings.toml`):
    /// `experiments/pbcs_fast.toml`.
    Fast,
}

impl Preset {
    /// The preset's name on the command line (`fast`, `paper`).
    pub fn name(self) -> &'static str {
        self.into()
    }

    /// The preset called `name` (`fast`, `paper`), or an error listing the presets.
    ///
    /// ```
    /// use pbcs::config::Preset;
    /// assert_eq!(Preset::named("paper").unwrap(), Preset::Paper);
    /// assert!(Preset::named("slow").unwrap_err().to_string().contains("`paper`, `fast`"));
    /// ```
    pub fn named(name: &str) -> Result<Preset> {
        let all = <Preset as clap::ValueEnum>::value_variants();
        all.iter()
            .copied()
            .find(|p| p.name() == name)
            .ok_or_else(|| {
                let names: Vec<String> = all.iter().map(|p| format!("`{}`", p.name())).collect();
                crate::Error::invalid(
                    "preset",
                    format!("must be one of {}, got `{name}`", names.join(", ")),
                )
            })
    }

    /// The preset's file name in `experiments/`.
    pub fn file_name(self) -> &'static str {
        match self {
            Preset::Paper => "pbcs_paper.toml",
            Preset::Fast => "pbcs_fast.toml",
        }
    }

    /// The preset's TOML text (the file in `experiments/`, embedded at build time).
    pub fn text(self) -> &'static str {
        match self {
            Preset::Paper => include_str!("../experiments/pbcs_paper.toml"),
            Preset::Fast => include_str!("../experiments/pbcs_fast.toml"),
        }
    }

    /// The preset as a validated job (maze 5, seed 0: set them for your run).
    pub fn job(self) -> Result<PbcsJob> {
        let job: PbcsJob = parse_toml(
            self.text(),
            &Path::new("experiments").join(self.file_name()),
        )?;
        job.check()?;
        Ok(job)
    }
}
