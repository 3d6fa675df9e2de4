//! Typed, validated configurations, read from TOML.
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

use crate::error::{Error, Result};
use crate::learner::LearnerConfig;
use crate::phase2::Phase2Config;
use crate::train::TrainConfig;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Largest maze size accepted. Phase 1 and the wall grid scale with N², so the bound keeps a
/// typo (`size = 1000`) from turning into hours of work; the paper's largest maze is 15.
pub const MAX_MAZE_SIZE: usize = 100;

/// A validated configuration.
pub trait Check {
    /// Ok if every field is in range; otherwise an [`Error::Invalid`] naming the field.
    fn check(&self) -> Result<()>;
}

/// Reads a TOML file into a config and validates it. Unknown keys, syntax errors and
/// unreadable files are errors that name the file (and the key, for parse errors).
pub fn load<T: DeserializeOwned + Check>(path: &Path) -> Result<T> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let config: T = toml::from_str(&text).map_err(|e| Error::Parse {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    config.check()?;
    Ok(config)
}

fn positive_finite(field: &str, value: f32, max: f32) -> Result<()> {
    if !(value.is_finite() && value > 0.0 && value <= max) {
        return Err(Error::invalid(
            field,
            format!("must be in (0, {max}], got {value}"),
        ));
    }
    Ok(())
}

/// The maze environment (appendix "Experimental Setup"): a layout named by its size and its
/// own maze seed, and the constants of the MDP.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MazeConfig {
    /// N: the maze has N×N cells and the state space is [0, N]². 2 ≤ N ≤ 100.
    pub size: usize,
    /// Seed of the layout, independent of the run seed, so that one layout can be held fixed
    /// while runs vary. Ignored for N = 2, whose layout is the fixed U-shape.
    pub seed: u64,
    /// Wall thickness (0.1 in the paper).
    pub wall_thickness: f32,
    /// Success radius around the target (0.2 in the paper).
    pub target_radius: f32,
    /// Largest absolute action component (0.1 in the paper).
    pub max_action: f32,
}

impl Default for MazeConfig {
    fn default() -> Self {
        MazeConfig {
            size: 5,
            seed: 0,
            wall_thickness: 0.1,
            target_radius: 0.2,
            max_action: 0.1,
        }
    }
}

impl Check for MazeConfig {
    fn check(&self) -> Result<()> {
        if !(2..=MAX_MAZE_SIZE).contains(&self.size) {
            return Err(Error::invalid(
                "maze.size",
                format!(
                    "must be between 2 and {MAX_MAZE_SIZE} cells, got {}",
                    self.size
                ),
            ));
        }
        positive_finite("maze.wall_thickness", self.wall_thickness, 0.5)?;
        positive_finite("maze.target_radius", self.target_radius, 0.5)?;
        positive_finite("maze.max_action", self.max_action, 0.5)?;
        Ok(())
    }
}

/// Phase 1 (appendix algorithm "Exploration algorithm").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExploreConfig {
    /// Side of the square state-space bins of the archive (0.05 in the paper).
    pub bin_side: f32,
    /// Budget of environment steps in all; phase 1 fails with an error if the reward is not
    /// found within it. (The paper runs until the reward is found.) Called `max_steps` before
    /// (still read, so stored configs compare equal); `phase2.max_steps` is a different thing,
    /// the length limit of one Backplay episode.
    #[serde(alias = "max_steps")]
    pub budget: u64,
}

impl Default for ExploreConfig {
    fn default() -> Self {
        ExploreConfig {
            bin_side: 0.05,
            budget: 100_000_000,
        }
    }
}

impl Check for ExploreConfig {
    fn check(&self) -> Result<()> {
        positive_finite("explore.bin_side", self.bin_side, 1.0)?;
        if self.budget == 0 {
            return Err(Error::invalid("explore.budget", "must be at least 1"));
        }
        Ok(())
    }
}

/// What `pbcs explore` runs: phase 1 on one maze with one run seed.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExploreJob {
    /// The run seed; every random stream of the run derives from it (see [`crate::rng`]).
    pub seed: u64,
    /// The maze.
    pub maze: MazeConfig,
    /// Phase 1 settings.
    pub explore: ExploreConfig,
}

impl Check for ExploreJob {
    fn check(&self) -> Result<()> {
        self.maze.check()?;
        self.explore.check()
    }
}

/// What `pbcs train` runs: a vanilla baseline (DDPG, TD3, or the argmax actor) on one maze's
/// own reward.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrainJob {
    /// The run seed.
    pub seed: u64,
    /// The maze.
    pub maze: MazeConfig,
    /// The learner's hyper-parameters.
    pub learner: LearnerConfig,
    /// The training schedule.
    pub train: TrainConfig,
}

impl Check for TrainJob {
    fn check(&self) -> Result<()> {
        self.maze.check()?;
        self.learner.check()?;
        self.train.check()
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
pub struct RunJob {
    /// The run seed.
    pub seed: u64,
    /// The maze.
    pub maze: MazeConfig,
    /// Phase 1.
    pub explore: ExploreConfig,
    /// The learner trained by each Backplay (DDPG by default, as in the paper).
    pub learner: LearnerConfig,
    /// Phase 2: α, β, ε, chaining, starts, budget, evaluation.
    pub phase2: Phase2Config,
}

impl Default for RunJob {
    fn default() -> Self {
        RunJob {
            seed: 0,
            maze: MazeConfig::default(),
            explore: ExploreConfig::default(),
            learner: LearnerConfig {
                gamma: 0.9,
                ..LearnerConfig::ddpg()
            },
            phase2: Phase2Config::default(),
        }
    }
}

impl Check for RunJob {
    fn check(&self) -> Result<()> {
        self.maze.check()?;
        self.explore.check()?;
        self.learner.check()?;
        self.phase2.check()
    }
}

/// The named PBCS procedures, each a complete TOML file in `experiments/` (embedded in the
/// library, so `pbcs run --preset NAME` needs no file).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "snake_case")]
pub enum Preset {
    /// The paper's procedure (Algorithms 1–3 as written, K − 1 at a time, α rounds of
    /// training), with our corrections and our choices of the settings it leaves open:
    /// `experiments/pbcs_paper.toml`.
    Paper,
    /// Everything of ours that measured better (shortened τ, early stop, adaptive K steps,
    /// verified skills): `experiments/pbcs_fast.toml`.
    Fast,
}

impl Preset {
    /// The preset's name on the command line (`fast`, `paper`).
    pub fn name(self) -> &'static str {
        match self {
            Preset::Paper => "paper",
            Preset::Fast => "fast",
        }
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
    pub fn job(self) -> Result<RunJob> {
        let job: RunJob = toml::from_str(self.text()).map_err(|e| Error::Parse {
            path: Path::new("experiments").join(self.file_name()),
            message: e.to_string(),
        })?;
        job.check()?;
        Ok(job)
    }
}
