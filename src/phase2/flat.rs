//! Phase 2's settings as a preset file writes them: one flat `[phase2]` table of numbers,
//! booleans and names, where 0 or `false` turns one of our ideas off. This is the form every
//! committed preset, experiment and run folder holds; [`super::Phase2Config`] is the typed
//! procedure read from it (and written back to it, field for field), in which combinations
//! that make no sense cannot be written.

use super::{LastGoal, Phase2Config, StartMode};
use serde::{Deserialize, Serialize};

/// The networks' inputs as the file names them (`inputs = "goal_relative"` or `"raw"`);
/// [`super::InputMode`] adds where warm starts are possible.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FlatInputs {
    /// [`super::InputMode::GoalRelative`].
    GoalRelative,
    /// [`super::InputMode::Raw`].
    Raw,
}

/// The `[phase2]` table of a preset file, field by field, each the part of
/// [`Phase2Config`] it becomes (0 or `false` where that part is off).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FlatPhase2 {
    /// [`Phase2Config::alpha`].
    pub alpha: usize,
    /// [`super::Stopping::max_rounds`] (0: none).
    pub max_rounds: usize,
    /// [`Phase2Config::beta`].
    pub beta: usize,
    /// [`Phase2Config::epsilon`].
    pub epsilon: f32,
    /// [`Phase2Config::max_steps`].
    pub max_steps: usize,
    /// [`Phase2Config::chaining`].
    pub chaining: bool,
    /// [`Phase2Config::start`].
    pub start: StartMode,
    /// The step of [`super::KWalk`] (its first step when adaptive).
    pub k_step: usize,
    /// [`super::Ideas::shorten`].
    pub shorten: bool,
    /// [`super::Stopping::early_stop`].
    pub early_stop: bool,
    /// [`super::KWalk::Adaptive`] (else [`super::KWalk::Fixed`]).
    pub adaptive_k: bool,
    /// [`super::Ideas::stop_at_failure`].
    pub stop_at_failure: bool,
    /// [`super::Ideas::restarts`].
    pub restarts: usize,
    /// [`super::DeadWalk::after`] (0: no [`super::DeadWalk`]).
    pub dead_walk: usize,
    /// [`super::DeadWalk::retargets`] (needs `dead_walk`).
    pub retargets: usize,
    /// [`super::Ideas::fast_tests`].
    pub fast_tests: bool,
    /// [`super::Ideas::verify_skills`] (0: none).
    pub verify_episodes: usize,
    /// [`super::SkillInit::Warm`] (needs `inputs = "goal_relative"`).
    pub warm_start: bool,
    /// [`super::EpisodeLimit::Every`] (0: none; not with `test_path_limit`).
    pub path_limit: f32,
    /// [`super::EpisodeLimit::Greedy`] (0: none; not with `path_limit`).
    pub test_path_limit: f32,
    /// [`super::ChainCheck::episodes`] (0: no [`super::ChainCheck`]).
    pub chain_verify_episodes: usize,
    /// [`super::ChainCheck::repairs`] (needs `chain_verify_episodes`).
    pub chain_repairs: usize,
    /// [`Phase2Config::last_goal`].
    pub last_goal: LastGoal,
    /// [`Phase2Config::inputs`].
    pub inputs: FlatInputs,
    /// [`Phase2Config::max_env_steps`].
    pub max_env_steps: u64,
    /// [`Phase2Config::eval_episodes`].
    pub eval_episodes: usize,
    /// [`Phase2Config::eval_max_steps`].
    pub eval_max_steps: usize,
}

impl Default for FlatPhase2 {
    /// The defaults of the typed procedure ([`Phase2Config::default`]), written flat.
    fn default() -> Self {
        Phase2Config::default().into()
    }
}
