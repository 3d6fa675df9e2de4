//! Phase 2's settings as a preset file writes them: one flat `[phase2]` table of numbers,
//! booleans and names, where 0 or `false` turns one of our ideas off. This is the form every
//! committed preset, experiment and run folder holds; [`super::Phase2Config`] is the typed
//! procedure read from it (and written back to it, field for field), in which combinations
//! that make no sense cannot be written. The conversions both ways are here.

use super::goal::BallMetric;
use super::goal_conditioned::settings::{ChainName, ChainStrategy, GoalConditioned};
use super::{
    ChainCheck, DeadWalk, EpisodeLimit, FastTests, FirstStarts, Ideas, InputMode, KWalk, LastGoal,
    Phase2Config, SkillInit, StartMode, Stopping,
};
use crate::error::{Error, Result};
use crate::validate::Check;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

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
    /// λ of [`super::goal::BallMetric::PositionVelocity`] (0: balls in position, the
    /// default, not written).
    #[serde(skip_serializing_if = "crate::validate::is_zero")]
    pub velocity_scale: f32,
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
    /// [`super::Ideas::patience`] (0: none, the default, not written).
    #[serde(skip_serializing_if = "is_zero_usize")]
    pub patience: usize,
    /// [`super::Ideas::lookahead`] (0: none, the default, not written).
    #[serde(skip_serializing_if = "is_zero_usize")]
    pub lookahead: usize,
    /// [`super::Ideas::fast_tests`].
    pub fast_tests: bool,
    /// [`super::FastTests::lanes`] (0: all β at once, the default, not written; needs
    /// `fast_tests`).
    #[serde(skip_serializing_if = "is_zero_usize")]
    pub test_lanes: usize,
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
    /// [`Phase2Config::first_starts`] (`ball`, the default, not written).
    #[serde(skip_serializing_if = "is_ball")]
    pub first_starts: FirstStarts,
    /// [`Phase2Config::inputs`].
    pub inputs: FlatInputs,
    /// [`Phase2Config::max_env_steps`].
    pub max_env_steps: u64,
    /// [`Phase2Config::eval_episodes`].
    pub eval_episodes: usize,
    /// [`Phase2Config::eval_max_steps`].
    pub eval_max_steps: usize,
    /// [`Phase2Config::chain`] (`per_skill`, the default, not written).
    #[serde(skip_serializing_if = "ChainName::is_per_skill")]
    pub chain: ChainName,
    /// The settings of `chain = "goal_conditioned"` (`[phase2.goal_conditioned]`; absent: its
    /// defaults; refused with the per-skill chain).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub goal_conditioned: Option<GoalConditioned>,
}

impl Default for FlatPhase2 {
    /// The defaults of the typed procedure ([`Phase2Config::default`]), written flat.
    fn default() -> Self {
        Phase2Config::default().into()
    }
}

/// An unset `phase2.patience`, `phase2.lookahead` or `phase2.test_lanes`, left out of written files (those written
/// before it existed keep their bytes).
fn is_zero_usize(n: &usize) -> bool {
    *n == 0
}

/// Unset `phase2.first_starts`, left out of written files (those written before it existed keep
/// their bytes).
fn is_ball(f: &FirstStarts) -> bool {
    *f == FirstStarts::Ball
}

/// `0` as "off" in the flat form.
fn nonzero(n: usize) -> Option<usize> {
    (n > 0).then_some(n)
}

/// A positive limit as "on" in the flat form (0: off).
fn positive(p: f32) -> Option<f32> {
    (p > 0.0).then_some(p)
}

impl FlatPhase2 {
    /// The chaining strategy the flat form names; refuses its settings' table without it.
    fn typed_chain(&self) -> Result<ChainStrategy> {
        match (self.chain, &self.goal_conditioned) {
            (ChainName::PerSkill, None) => Ok(ChainStrategy::PerSkill),
            (ChainName::PerSkill, Some(_)) => Err(Error::invalid(
                "phase2.goal_conditioned",
                "sets the goal-conditioned chain, while phase2.chain is \"per_skill\": set \
                 phase2.chain = \"goal_conditioned\", or leave the table out",
            )),
            (ChainName::GoalConditioned, s) => Ok(ChainStrategy::GoalConditioned(Box::new(
                s.clone().unwrap_or_default(),
            ))),
        }
    }

    /// The episode limit the flat form writes; refuses, naming both fields, what the typed
    /// form cannot hold (a setting without the one it needs, or both path limits).
    fn typed_limit(&self) -> Result<Option<EpisodeLimit>> {
        if self.retargets > 0 && self.dead_walk == 0 {
            return Err(Error::invalid(
                "phase2.retargets",
                "a hand-over moves after a walk bounded by phase2.dead_walk: set it too",
            ));
        }
        if self.chain_repairs > 0 && self.chain_verify_episodes == 0 {
            return Err(Error::invalid(
                "phase2.chain_repairs",
                "repairs follow a failed chain verification: set phase2.chain_verify_episodes too",
            ));
        }
        if self.warm_start && self.inputs == FlatInputs::Raw {
            return Err(Error::invalid(
                "phase2.warm_start",
                "hands a skill's learner to the next skill, whose goal lies elsewhere: only \
                 phase2.inputs = \"goal_relative\" makes that the same problem (with \
                 phase2.inputs = \"raw\" set phase2.warm_start = false)",
            ));
        }
        for (field, p) in [
            ("phase2.path_limit", self.path_limit),
            ("phase2.test_path_limit", self.test_path_limit),
        ] {
            if !(p.is_finite() && p >= 0.0) {
                return Err(Error::invalid(
                    field,
                    format!("must be 0 (off) or positive, got {p}"),
                ));
            }
        }
        match (positive(self.path_limit), positive(self.test_path_limit)) {
            (Some(_), Some(_)) => Err(Error::invalid(
                "phase2.test_path_limit",
                "limits greedy episodes only, while phase2.path_limit limits every episode: \
                 set one of the two (0 turns a limit off)",
            )),
            (Some(p), None) => Ok(Some(EpisodeLimit::Every(p))),
            (None, Some(p)) => Ok(Some(EpisodeLimit::Greedy(p))),
            (None, None) => Ok(None),
        }
    }
}

/// Phase 2's settings are read in their flat form, then checked as one typed procedure (what
/// `#[serde(try_from = "FlatPhase2")]` would derive).
impl<'de> Deserialize<'de> for Phase2Config {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        Phase2Config::try_from(FlatPhase2::deserialize(d)?).map_err(serde::de::Error::custom)
    }
}

/// Phase 2's settings are written in their flat form (what `#[serde(into = "FlatPhase2")]`
/// would derive).
impl Serialize for Phase2Config {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        FlatPhase2::from(self.clone()).serialize(s)
    }
}

impl TryFrom<FlatPhase2> for Phase2Config {
    type Error = Error;

    /// Reads the flat form, refusing, with both fields named, what the typed form cannot hold;
    /// then [`Check::check`].
    fn try_from(f: FlatPhase2) -> Result<Self> {
        let episode_limit = f.typed_limit()?;
        let ball = match f.velocity_scale {
            0.0 => BallMetric::Position,
            scale => BallMetric::PositionVelocity { scale },
        };
        let config = Phase2Config {
            alpha: f.alpha,
            beta: f.beta,
            epsilon: f.epsilon,
            max_steps: f.max_steps,
            chaining: f.chaining,
            start: f.start,
            ball,
            last_goal: f.last_goal,
            first_starts: f.first_starts,
            inputs: match (f.inputs, f.warm_start) {
                (FlatInputs::Raw, _) => InputMode::Raw,
                (FlatInputs::GoalRelative, warm) => InputMode::GoalRelative {
                    init: if warm {
                        SkillInit::Warm
                    } else {
                        SkillInit::Fresh
                    },
                },
            },
            max_env_steps: f.max_env_steps,
            eval_episodes: f.eval_episodes,
            eval_max_steps: f.eval_max_steps,
            ideas: Ideas {
                k_walk: if f.adaptive_k {
                    KWalk::Adaptive { first: f.k_step }
                } else {
                    KWalk::Fixed { step: f.k_step }
                },
                stopping: Stopping {
                    early_stop: f.early_stop,
                    max_rounds: nonzero(f.max_rounds),
                },
                stop_at_failure: f.stop_at_failure,
                restarts: f.restarts,
                dead_walk: nonzero(f.dead_walk).map(|after| DeadWalk {
                    after,
                    retargets: f.retargets,
                }),
                patience: nonzero(f.patience),
                lookahead: nonzero(f.lookahead),
                fast_tests: match (f.fast_tests, nonzero(f.test_lanes)) {
                    (false, Some(_)) => {
                        return Err(Error::invalid(
                            "phase2.test_lanes",
                            "groups the episodes of fast tests, while phase2.fast_tests is \
                             false: turn fast_tests on, or leave test_lanes out (0)",
                        ))
                    }
                    (false, None) => None,
                    (true, lanes) => Some(FastTests { lanes }),
                },
                verify_skills: nonzero(f.verify_episodes),
                episode_limit,
                chain_check: nonzero(f.chain_verify_episodes).map(|episodes| ChainCheck {
                    episodes,
                    repairs: f.chain_repairs,
                }),
                shorten: f.shorten,
            },
            chain: f.typed_chain()?,
        };
        config.check()?;
        Ok(config)
    }
}

impl From<Phase2Config> for FlatPhase2 {
    /// Writes the typed form flat, field for field (an idea that is off as 0 or `false`).
    fn from(c: Phase2Config) -> Self {
        let i = c.ideas;
        let (path_limit, test_path_limit) = match i.episode_limit {
            None => (0.0, 0.0),
            Some(EpisodeLimit::Every(p)) => (p, 0.0),
            Some(EpisodeLimit::Greedy(p)) => (0.0, p),
        };
        FlatPhase2 {
            alpha: c.alpha,
            max_rounds: i.stopping.max_rounds.unwrap_or(0),
            beta: c.beta,
            epsilon: c.epsilon,
            max_steps: c.max_steps,
            chaining: c.chaining,
            start: c.start,
            velocity_scale: c.ball.scale(),
            k_step: i.k_walk.first_step(),
            shorten: i.shorten,
            early_stop: i.stopping.early_stop,
            adaptive_k: matches!(i.k_walk, KWalk::Adaptive { .. }),
            stop_at_failure: i.stop_at_failure,
            restarts: i.restarts,
            dead_walk: i.dead_walk.map_or(0, |d| d.after),
            retargets: i.dead_walk.map_or(0, |d| d.retargets),
            patience: i.patience.unwrap_or(0),
            lookahead: i.lookahead.unwrap_or(0),
            fast_tests: i.fast_tests.is_some(),
            test_lanes: i.fast_tests.and_then(|f| f.lanes).unwrap_or(0),
            verify_episodes: i.verify_skills.unwrap_or(0),
            warm_start: c.warm_start(),
            path_limit,
            test_path_limit,
            chain_verify_episodes: i.chain_check.map_or(0, |v| v.episodes),
            chain_repairs: i.chain_check.map_or(0, |v| v.repairs),
            last_goal: c.last_goal,
            first_starts: c.first_starts,
            inputs: match c.inputs {
                InputMode::GoalRelative { .. } => FlatInputs::GoalRelative,
                InputMode::Raw => FlatInputs::Raw,
            },
            max_env_steps: c.max_env_steps,
            eval_episodes: c.eval_episodes,
            eval_max_steps: c.eval_max_steps,
            chain: match c.chain {
                ChainStrategy::PerSkill => ChainName::PerSkill,
                ChainStrategy::GoalConditioned(_) => ChainName::GoalConditioned,
            },
            goal_conditioned: match c.chain {
                ChainStrategy::PerSkill => None,
                ChainStrategy::GoalConditioned(s) => Some(*s),
            },
        }
    }
}
