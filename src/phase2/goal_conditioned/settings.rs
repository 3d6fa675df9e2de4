//! The settings of the goal-conditioned chain (`[phase2.goal_conditioned]`), validated as
//! linfa validates its hyper-parameters: each bad value names its field.

use crate::error::{Error, Result};
use crate::learner::her::HerConfig;
use crate::validate::{bounds, count, Check};
use serde::{Deserialize, Serialize};

/// How phase 2 turns τ into a chain (`phase2.chain`).
#[derive(Debug, Clone, PartialEq, Default)]
pub enum ChainStrategy {
    /// The paper's: Backplay walks K back along τ and a new skill is trained, with its own
    /// networks, wherever DDPG stops improving (Algorithms 1–3).
    #[default]
    PerSkill,
    /// One goal-conditioned learner for every sub-goal cut from τ, with overshoot and value
    /// chaining (DCIL-II's mechanisms, [`super`]).
    GoalConditioned(Box<GoalConditioned>),
}

/// `phase2.chain` as the file names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ChainName {
    /// [`ChainStrategy::PerSkill`].
    #[default]
    PerSkill,
    /// [`ChainStrategy::GoalConditioned`].
    GoalConditioned,
}

impl ChainName {
    /// The default, left out of written files (those written before it existed keep their
    /// bytes).
    pub fn is_per_skill(&self) -> bool {
        *self == ChainName::PerSkill
    }
}

/// Where a goal-conditioned chain's training episodes start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Curriculum {
    /// DCIL-II's: at sub-goal j with weight 1 / (success rate of its last `window` tries),
    /// 10 while that rate is at most 0.1 (and before any try); a try from j succeeds when it
    /// reaches sub-goal j + 1.
    FailureWeighted,
    /// Backplay's order (the paper's idea): uniformly at or after a frontier that begins at
    /// the last sub-goal and moves one back once `advance_at` of the frontier's last `window`
    /// tries reached the final goal.
    Backplay,
}

/// The reward a goal-conditioned learner is trained on (`phase2.goal_conditioned.reward`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GoalReward {
    /// DCIL-II's: 1 where a step reaches its goal, else 0 (and a failure's penalty).
    #[default]
    Sparse,
    /// The paper's Algorithm 3 (its Equations 1–2) toward the transition's own goal g (the
    /// sub-goal it aimed at, or the one HER gave it): 10 where the step reaches g, else
    /// Φ(s′) − Φ(s) with Φ(s) = 1 / max(d(position, g), radius) (and a failure's penalty).
    Shaped,
    /// Toward the transition's own goal g, the linear potential Φ(s) = −d(position, g), the
    /// goal-space analogue of the forward-velocity reward a MuJoCo body learns to walk on: 1
    /// where the step reaches g, else d(s, g) − d(s′, g), the metres it came closer (and a
    /// failure's penalty). The paper's 1/d pays 0.026 for a 0.1 m step toward a goal 2 m
    /// away; this, 0.1.
    Progress,
}

impl GoalReward {
    /// The default, left out of written files (those written before it existed keep their
    /// bytes).
    pub fn is_sparse(&self) -> bool {
        *self == GoalReward::Sparse
    }
}

/// The goal-conditioned chain's settings (`[phase2.goal_conditioned]`). Distances are in the
/// units of the environment's goal space (the maze's cells are 1 wide; PointMaze's and
/// AntMaze's in metres).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GoalConditioned {
    /// Distance between two sub-goals cut from τ (the first at least this far from τ_0).
    pub spacing: f32,
    /// A sub-goal is reached within this distance of it.
    pub radius: f32,
    /// Steps an episode may spend on one sub-goal; the episode ends (truncated, not terminal)
    /// when they run out.
    pub steps_per_goal: usize,
    /// Where training episodes start.
    pub curriculum: Curriculum,
    /// Training episodes from a sub-goal start with the body at rest as the env's reset leaves
    /// it, where τ stands at that sub-goal ([`crate::env::DrawStarts::at_rest_like`]), then
    /// moved in B_ε; the episodes from τ_0 start as `phase2.first_starts` says (`false`: τ's
    /// whole saved state, its joints and velocities).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub rest_starts: bool,
    /// Tries per start that the curriculum remembers.
    pub window: usize,
    /// Backplay's frontier moves back once this fraction of its last tries succeeded.
    pub advance_at: f32,
    /// Value chaining: a step that reaches sub-goal i bootstraps through Q(s′, g_{i+1})
    /// instead of ending (`false`: it ends there, reward 1, as the final goal does).
    pub value_chaining: bool,
    /// Overshoot: once sub-goal i is reached the episode goes on toward g_{i+1} from the state
    /// it reached (`false`: it ends there, as one skill's episode would; the ablation).
    #[serde(skip_serializing_if = "is_true")]
    pub overshoot: bool,
    /// A failure of the body (the environment's: the ant on its back) ends a training episode,
    /// a terminal of value 0 (`false`: the episode goes on; an environment's own terminal
    /// always ends it). Greedy tests and the judges never end an episode for it.
    #[serde(skip_serializing_if = "is_true")]
    pub end_on_failure: bool,
    /// The reward of a training step where the body fails (with `end_on_failure`; 0: the
    /// terminal is worth nothing, as DCIL-II's; below 0, a penalty its relabelled copies keep).
    #[serde(skip_serializing_if = "crate::validate::is_zero")]
    pub failure_reward: f32,
    /// The reward the learner is trained on: sparse (DCIL-II's) or the paper's shaped one.
    #[serde(skip_serializing_if = "GoalReward::is_sparse")]
    pub reward: GoalReward,
    /// Observation normalisation: the networks see each observation number x as
    /// (x − μ) / σ clipped to ±10, μ and σ its mean and standard deviation along τ (σ at least
    /// [`super::MIN_SCALE`]), fixed for the run and saved with the chain; the sub-goal minus the
    /// position stays in the env's units (`false`: the observation as it is).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub normalise: bool,
    /// Updates of the learner per training step, once `learning_starts` have passed.
    #[serde(skip_serializing_if = "is_one")]
    pub updates_per_step: usize,
    /// Training steps of uniformly random actions before the learner acts and learns.
    pub learning_starts: u64,
    /// A greedy test of the chain after every this many training steps.
    pub test_every: u64,
    /// Episodes of a test (from B_ε(s_0), or drawn starts); the test stops at its first
    /// failure, and phase 2 ends at the first test they all pass.
    pub test_episodes: usize,
    /// Hindsight relabelling of the learner's replay.
    pub her: HerConfig,
}

impl Default for GoalConditioned {
    fn default() -> Self {
        GoalConditioned {
            spacing: 0.5,
            radius: 0.1,
            steps_per_goal: 50,
            curriculum: Curriculum::FailureWeighted,
            rest_starts: false,
            window: 10,
            advance_at: 0.5,
            value_chaining: true,
            overshoot: true,
            end_on_failure: true,
            failure_reward: 0.0,
            reward: GoalReward::Sparse,
            normalise: false,
            updates_per_step: 1,
            learning_starts: 1_000,
            test_every: 5_000,
            test_episodes: 20,
            her: HerConfig::default(),
        }
    }
}

impl Check for GoalConditioned {
    fn check(&self) -> Result<()> {
        let field = |f: &str| format!("phase2.goal_conditioned.{f}");
        for (name, v) in [("spacing", self.spacing), ("radius", self.radius)] {
            crate::validate::positive_finite(&field(name), v, 1e6)?;
        }
        if self.radius >= self.spacing {
            return Err(Error::invalid(
                field("radius"),
                format!(
                    "{} is not below phase2.goal_conditioned.spacing = {}: a sub-goal's ball \
                     would hold the next one",
                    self.radius, self.spacing
                ),
            ));
        }
        for (name, v, max) in [
            (
                "steps_per_goal",
                self.steps_per_goal as u64,
                bounds::EPISODE_STEPS,
            ),
            ("window", self.window as u64, bounds::EPISODES),
            ("test_every", self.test_every, bounds::ENV_STEPS),
            ("test_episodes", self.test_episodes as u64, bounds::EPISODES),
            (
                "updates_per_step",
                self.updates_per_step as u64,
                bounds::UPDATES_PER_STEP,
            ),
        ] {
            count(&field(name), v, max)?;
        }
        crate::validate::at_most(
            &field("learning_starts"),
            self.learning_starts,
            bounds::ENV_STEPS,
        )?;
        if !(self.advance_at > 0.0 && self.advance_at <= 1.0) {
            return Err(Error::invalid(
                field("advance_at"),
                format!("must be in (0, 1], got {}", self.advance_at),
            ));
        }
        if !(self.failure_reward.is_finite() && (-1e3..=0.0).contains(&self.failure_reward)) {
            return Err(Error::invalid(
                field("failure_reward"),
                format!("must be in [-1000, 0], got {}", self.failure_reward),
            ));
        }
        if !self.overshoot && self.curriculum == Curriculum::Backplay {
            return Err(Error::invalid(
                field("overshoot"),
                "is false, but curriculum = \"backplay\" counts a try only when it reaches the \
                 final goal, which an episode that ends at its first sub-goal never does \
                 (use curriculum = \"failure_weighted\", or overshoot)",
            ));
        }
        if self.her.goal_frame != crate::learner::her::GoalFrame::World {
            return Err(Error::invalid(
                field("her.goal_frame"),
                "is not \"world\": the goal-conditioned chain's networks see the sub-goal minus \
                 the position, and its saved chain acts so (leave goal_frame out)",
            ));
        }
        self.her.check()
    }
}

fn is_true(b: &bool) -> bool {
    *b
}

fn is_one(n: &usize) -> bool {
    *n == 1
}
