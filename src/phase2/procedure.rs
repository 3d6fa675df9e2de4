//! Phase 2 as a typed procedure: the paper's settings (α, β, ε, the episode limit, where
//! episodes start, the last skill's goal, what the networks see, chaining on or off), and
//! each idea of ours as an `Option` or an enum of its own in [`Ideas`], so that the paper's
//! procedure is its settings with [`Ideas::NONE`], and a new Backplay idea is one variant.
//!
//! Combinations that make no sense cannot be written: a warm start lives in
//! [`InputMode::GoalRelative`] (raw inputs have none), moves of a hand-over in the
//! [`DeadWalk`] they follow, repairs of the chain in the [`ChainCheck`] whose failures they
//! answer, and the two episode limits are one [`EpisodeLimit`]. What still involves two parts
//! (repairs and hand-over moves act between skills, so they need chaining) is refused by
//! [`Check::check`] naming both fields, and a part that needs a hook the environment lacks by
//! [`Phase2Config::require_hooks`].
//!
//! Files hold the flat form ([`super::flat::FlatPhase2`], today's `[phase2]` table): reading one converts
//! it, refusing what the typed form cannot hold with a message naming the fields; writing
//! one converts back field for field, so committed presets, rows and run folders read and
//! write the same bytes.
//!
//! ```
//! use pbcs::config::Preset;
//! use pbcs::phase2::{Ideas, InputMode, KWalk, SkillInit};
//!
//! // The paper's procedure: its settings, and none of our ideas.
//! let paper = Preset::Paper.job().unwrap().phase2;
//! assert_eq!(paper.ideas, Ideas::NONE);
//! assert_eq!(paper.ideas.k_walk, KWalk::Fixed { step: 1 });
//! // `fast` warms each skill from the one before: only goal-relative inputs can say so.
//! let fast = Preset::Fast.job().unwrap().phase2;
//! assert_eq!(fast.inputs, InputMode::GoalRelative { init: SkillInit::Warm });
//! ```

use super::goal::{BallMetric, Goal, Inputs};
use super::goal_conditioned::settings::ChainStrategy;
use super::{FirstStarts, LastGoal, StartMode};
use crate::env::Env;
use crate::error::{Error, Result};
use crate::validate::Check;

/// Phase-2 settings: the paper's procedure and our [`Ideas`], validated by [`Check::check`].
/// Read from and written to files in the flat form ([`super::flat::FlatPhase2`], which implements
/// its `Serialize` and `Deserialize`).
#[derive(Debug, Clone, PartialEq)]
pub struct Phase2Config {
    /// α: consecutive non-improvements of the training success that end training at one K.
    pub alpha: usize,
    /// β: episodes per test and per training round.
    pub beta: usize,
    /// ε: radius of the start balls, target balls and activation balls.
    pub epsilon: f32,
    /// Step limit of a training or test episode.
    pub max_steps: usize,
    /// Skill chaining on (PBCS) or off (PBCS without skill chaining: fail when a second skill
    /// would be needed).
    pub chaining: bool,
    /// Starts in B_ε(τ_K) (the paper), exactly at τ_K, or among phase 1's archived states in
    /// B_ε(τ_K) (ours).
    pub start: StartMode,
    /// What the balls measure — goals, activation sets, Backplay's starts: the position (the
    /// paper) or, with momentum, position and velocity ([`BallMetric`]).
    pub ball: BallMetric,
    /// The last skill's goal: the environment's success region (our correction, the default)
    /// or B_ε(τ_N) (the paper as written).
    pub last_goal: LastGoal,
    /// Where the first skill's starts lie at K = 0: B_ε(τ_0) (the paper, the default) or
    /// where the environment's reset draws them (ours).
    pub first_starts: FirstStarts,
    /// What the networks see, and, with goal-relative inputs, how a skill's learner starts.
    pub inputs: InputMode,
    /// Budget of environment steps for the whole run (phase 1 included); the run fails when
    /// it is exceeded.
    pub max_env_steps: u64,
    /// Episodes of the final evaluation of the chain (from starts uniform in B_ε(s_0)).
    pub eval_episodes: usize,
    /// Step limit of an evaluation episode of the chain.
    pub eval_max_steps: usize,
    /// Our ideas, each off ([`Ideas::NONE`]) in the paper's procedure.
    pub ideas: Ideas,
    /// How τ becomes a chain: the paper's skills, one per Backplay stall (the default), or
    /// one goal-conditioned learner along τ ([`super::goal_conditioned`]).
    pub chain: ChainStrategy,
}

/// What a skill's networks see and emit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputMode {
    /// Our correction: observations relative to the centre of the skill's goal, actions in
    /// [−1, 1]ᵈ scaled to the environment's bounds ([`Inputs::for_goal`]); a skill's learner
    /// starts as `init` says.
    GoalRelative {
        /// Fresh networks per skill (the paper) or the previous skill's (ours).
        init: SkillInit,
    },
    /// The paper as written: raw observations (maze coordinates in [0, N]²) and actions in the
    /// environment's own bounds (±0.1); exploration noise σ is still a fraction of the bound.
    /// Every skill starts fresh (another goal's learner would see another problem).
    Raw,
}

/// How the learner of a new skill starts (goal-relative inputs only).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SkillInit {
    /// "A new DDPG" per skill, as in the paper.
    Fresh,
    /// Warm start (ours): a learning problem whose target lies before the last problem's on
    /// τ — in Algorithm 1, the skill after a saved one — starts from the last problem's
    /// learner (actor, critic, their targets and optimiser state; the replay starts empty, its
    /// rewards being the previous goal's). With goal-relative inputs "reach the goal from just
    /// behind τ_T" is the problem the previous skill solved from B_ε(τ_T). A restart (same
    /// target) starts fresh, and so does a chain repair whose section does not end before the
    /// last problem's target (always the first repair: the last problem was skill 0's). The
    /// learner's own update noise stream and update count carry over with it.
    Warm,
}

/// Fast greedy tests ([`Ideas::fast_tests`]): how many of a Backplay test's β episodes run side
/// by side.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FastTests {
    /// Episodes of Backplay's tests of π run side by side (in lockstep, one batch through the
    /// networks) in groups of this many, the test stopping within a group or between two once
    /// it has a success and a failure, a group that ran to its end counting an episode still
    /// running at the step limit as a failure; `None`: all β at once, where a failure by the
    /// step limit shows only when every episode has run to it (`phase2.test_lanes`, ours; 0 in
    /// the flat form). The starts are drawn as before: a test's verdict (100 %, 0 % or
    /// between) does not depend on it, its reported fraction (a lower bound) does. The
    /// verification of a saved skill and a hand-over's tries, whose fractions
    /// [`crate::phase2::verified`] compares, run all their episodes at once.
    pub lanes: Option<usize>,
}

impl FastTests {
    /// All of a test's episodes side by side (the `fast` preset's).
    pub const ALL: FastTests = FastTests { lanes: None };
}

/// Our ideas, each an `Option` or an enum whose first variant is the paper's procedure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ideas {
    /// How K walks back from T.
    pub k_walk: KWalk,
    /// When training at one K ends.
    pub stopping: Stopping,
    /// End a skill at the first K that fails after training when its ball is clear of walls
    /// ([`super::backplay::Walk::stop_at_failure`]; needs [`crate::env::Env::clear_balls`]).
    pub stop_at_failure: bool,
    /// Restarts of a skill with a fresh learner (0: the paper): while a skill has restarts
    /// left, a Backplay whose test after training fails before any K was saved gives up — at
    /// 0 %, or, with `stop_at_failure`, below 100 % from a ball clear of walls (its DDPG
    /// collapsed: walking K further from the goal cannot help) — and the skill starts again at
    /// T − 1 with new weights and an empty replay.
    pub restarts: usize,
    /// A bound on a walk without any success, and what follows it.
    pub dead_walk: Option<DeadWalk>,
    /// Once a K is saved, a walk ends after this many Ks in a row trained without another
    /// save ([`super::backplay::Walk::patience`]; the paper walks on until a test after
    /// training reads 0 %).
    pub patience: Option<usize>,
    /// Hand-over lookahead (ours; `None`: the paper): a skill's goal ball counts as reached
    /// only where the next `n` skills already found carry the entry on to the n-th one's
    /// target ([`super::lookahead`]); the paper's Backplay never looks past its own goal.
    pub lookahead: Option<usize>,
    /// Greedy tests stop an episode as soon as it is stuck (a step that did not move: with a
    /// deterministic policy and a pure step it never will), and stop the whole test once it
    /// has both a success and a failure (Backplay only asks "100 %, 0 % or between"; the
    /// fraction reported for such a test is then a lower bound). The paper counts every step
    /// of every test. `None`: off.
    pub fast_tests: Option<FastTests>,
    /// Verification of each finished skill: its policy must reach its goal in all of these
    /// greedy episodes from its activation ball, else Backplay's previous saved (K, π) — a
    /// shorter reach — is verified in its place. A skill that passes n of n episodes fails at
    /// most 3/n of the time (95 % confidence, the rule of three): β = 50 bounds it by 6 %, 500
    /// episodes by 0.6 %.
    pub verify_skills: Option<usize>,
    /// Episode limits scaled by the path left to the goal (the paper: `max_steps` for every
    /// episode).
    pub episode_limit: Option<EpisodeLimit>,
    /// Verification, and repair, of the finished chain.
    pub chain_check: Option<ChainCheck>,
    /// Shorten τ before phase 2 by cutting the random walk's detours
    /// ([`super::shorten`]; needs [`crate::env::Env::connector`]).
    pub shorten: bool,
}

impl Ideas {
    /// None of our ideas: the paper's procedure.
    pub const NONE: Ideas = Ideas {
        k_walk: KWalk::Fixed { step: 1 },
        stopping: Stopping::UNTIL_STABLE,
        stop_at_failure: false,
        restarts: 0,
        dead_walk: None,
        patience: None,
        lookahead: None,
        fast_tests: None,
        verify_skills: None,
        episode_limit: None,
        chain_check: None,
        shorten: false,
    };
}

/// How Backplay's K walks back from T.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KWalk {
    /// K moves back `step` indices after each K (1: the paper).
    Fixed {
        /// Indices per move.
        step: usize,
    },
    /// Adaptive steps (ours), starting at `first`: the step doubles after each K that ends at
    /// 100 % (up to [`super::backplay::MAX_ADAPTIVE_STEP`]); a jump whose first test fails is
    /// not trained but halved, K going back halfway towards the last saved K; at step 1 the
    /// walk is the paper's.
    Adaptive {
        /// The first step.
        first: usize,
    },
}

impl KWalk {
    /// The first step of the walk.
    pub fn first_step(self) -> usize {
        match self {
            KWalk::Fixed { step } => step,
            KWalk::Adaptive { first } => first,
        }
    }
}

/// When training at one K ends: the paper's "until performance stabilizes" (α misses in a
/// row), and our two ways to end it sooner.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stopping {
    /// End as soon as a round at 100 % is confirmed by a 100 % greedy test (ours): DDPG trained
    /// on past success tends to drift away from it during the α further rounds
    /// ([`super::backplay::train_until_stable`]).
    pub early_stop: bool,
    /// At most this many rounds (ours): a K that needs more is rarely solved at all.
    pub max_rounds: Option<usize>,
}

impl Stopping {
    /// The paper's: α misses in a row, and nothing else.
    pub const UNTIL_STABLE: Stopping = Stopping {
        early_stop: false,
        max_rounds: None,
    };
}

/// A bound on a dead walk (ours; the paper's Backplay walks K down to 0 however long it finds
/// no success).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DeadWalk {
    /// A Backplay whose K is this many indices below T without a single success in any test
    /// or training round gives up ([`super::backplay::Walk::dead_walk`]), writing a
    /// `dead_walk` trace row. Then the skill restarts ([`Ideas::restarts`]), and once no
    /// restart is left the hand-over moves (`retargets`) or the run fails.
    pub after: usize,
    /// Moves of a hand-over (0: none): when no attempt at a skill finds any K, the skill found
    /// before it (target T′, start K = T) is verified greedily from the balls of the indices
    /// after T (clear ones first, nearest first, at most
    /// [`super::MAX_HANDOVER_TRIES`] of the next `after`), and the first from which
    /// it passes every episode (`verify_skills`, or β) becomes its start and the new skill's
    /// target, with fresh learners. At most `retargets` moves between two skills found; a
    /// `retarget` trace row records each try. Needs [`crate::env::Env::clear_balls`] and
    /// chaining.
    pub retargets: usize,
}

/// Path-scaled episode limits (ours): an episode from B_ε(τ_K) towards the goal of τ_T may
/// take at most `p × (L + 2ε) / a` steps (and never more than `max_steps`), L being τ's length
/// from τ_K to τ_T and a the smallest action bound: a start near its goal does not spend
/// `max_steps` steps to show that it fails.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EpisodeLimit {
    /// Every training and greedy episode (`phase2.path_limit` in files).
    Every(f32),
    /// Greedy episodes only — tests and verifications; training episodes keep `max_steps`
    /// (`phase2.test_path_limit` in files).
    Greedy(f32),
}

/// Verification of the finished chain (ours): the chain runs greedily from `episodes` starts
/// uniform in B_ε(s_0) (stream `ChainVerify`), each skill allowed `max_steps` steps to hand
/// over. When an episode fails, the skill in use when it stopped is repaired
/// ([`super::chaining`]), and the chain is verified again, at most `repairs` times (repairs
/// need chaining). Needs [`crate::env::Env::ball_starts`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ChainCheck {
    /// Episodes of one verification.
    pub episodes: usize,
    /// Repairs after failed verifications.
    pub repairs: usize,
}

impl Default for Phase2Config {
    /// The paper's settings with our corrections (goal-relative inputs, the success region as
    /// the last goal) and none of our ideas.
    fn default() -> Self {
        Phase2Config {
            alpha: 10,
            beta: 50,
            epsilon: 0.1,
            max_steps: 50,
            chaining: true,
            start: StartMode::Ball,
            ball: BallMetric::Position,
            last_goal: LastGoal::SuccessRegion,
            first_starts: FirstStarts::Ball,
            inputs: InputMode::GoalRelative {
                init: SkillInit::Fresh,
            },
            max_env_steps: 50_000_000,
            eval_episodes: 100,
            eval_max_steps: 5_000,
            ideas: Ideas::NONE,
            chain: ChainStrategy::PerSkill,
        }
    }
}

impl Check for Phase2Config {
    /// Every number in range, and the two parts that act between skills only with chaining.
    fn check(&self) -> Result<()> {
        self.check_counts()?;
        if !(self.epsilon.is_finite() && self.epsilon > 0.0) {
            return Err(Error::invalid(
                "phase2.epsilon",
                format!("must be positive, got {}", self.epsilon),
            ));
        }
        if self.epsilon > 1.0 {
            return Err(Error::invalid(
                "phase2.epsilon",
                format!(
                    "is a radius in the environment's units (the maze's cells are 1 wide), \
                     at most 1, got {}",
                    self.epsilon
                ),
            ));
        }
        let limit = match self.ideas.episode_limit {
            Some(EpisodeLimit::Every(p)) => Some(("phase2.path_limit", p)),
            Some(EpisodeLimit::Greedy(p)) => Some(("phase2.test_path_limit", p)),
            None => None,
        };
        if let Some((field, p)) = limit {
            if !(p.is_finite() && p > 0.0) {
                return Err(Error::invalid(field, format!("must be positive, got {p}")));
            }
        }
        self.check_repeats()?;
        self.check_ball()?;
        if let ChainStrategy::GoalConditioned(settings) = &self.chain {
            settings.check()?;
        }
        self.check_combinations()
    }
}

impl Phase2Config {
    /// Each count of the procedure at least 1 and at most its bound.
    fn check_counts(&self) -> Result<()> {
        use crate::validate::bounds::{EPISODES as EP, EPISODE_STEPS as ST, REPEATS as RE};
        let i = &self.ideas;
        // Each count: its field, its value (1 where the switch is off) and its upper bound.
        for (field, v, max) in [
            ("alpha", self.alpha, RE),
            ("beta", self.beta, EP),
            ("max_steps", self.max_steps, ST),
            ("k_step", i.k_walk.first_step(), RE),
            ("eval_episodes", self.eval_episodes, EP),
            ("eval_max_steps", self.eval_max_steps, ST),
            ("max_rounds", i.stopping.max_rounds.unwrap_or(1), RE),
            ("dead_walk", i.dead_walk.map_or(1, |d| d.after), RE),
            ("patience", i.patience.unwrap_or(1), RE),
            ("lookahead", i.lookahead.unwrap_or(1), EP),
            (
                "test_lanes",
                i.fast_tests.and_then(|f| f.lanes).unwrap_or(1),
                EP,
            ),
            ("verify_episodes", i.verify_skills.unwrap_or(1), EP),
            (
                "chain_verify_episodes",
                i.chain_check.map_or(1, |v| v.episodes),
                EP,
            ),
        ] {
            crate::validate::count(&format!("phase2.{field}"), v as u64, max)?;
        }
        Ok(())
    }

    /// The step budget and the repeats (restarts, hand-over moves, repairs) at most their
    /// bounds.
    fn check_repeats(&self) -> Result<()> {
        use crate::validate::bounds::REPEATS as RE;
        let i = &self.ideas;
        crate::validate::count(
            "phase2.max_env_steps",
            self.max_env_steps,
            crate::validate::bounds::ENV_STEPS,
        )?;
        for (field, v) in [
            ("phase2.restarts", i.restarts),
            ("phase2.retargets", i.dead_walk.map_or(0, |d| d.retargets)),
            (
                "phase2.chain_repairs",
                i.chain_check.map_or(0, |v| v.repairs),
            ),
        ] {
            crate::validate::at_most(field, v as u64, RE)?;
        }
        Ok(())
    }

    /// The parts that act between skills only with chaining, and drawn last goals only with
    /// goal-relative inputs.
    fn check_combinations(&self) -> Result<()> {
        let i = &self.ideas;
        if !self.chaining && i.dead_walk.is_some_and(|d| d.retargets > 0) {
            return Err(Error::invalid(
                "phase2.retargets",
                "moves the hand-over between two skills, which needs phase2.chaining = true",
            ));
        }
        if self.last_goal == LastGoal::Drawn && self.inputs == InputMode::Raw {
            return Err(Error::invalid(
                "phase2.last_goal",
                "\"drawn\" tells the last skill each episode's goal through its position \
                 relative to it, which needs phase2.inputs = \"goal_relative\"",
            ));
        }
        if !self.chaining && i.chain_check.is_some_and(|v| v.repairs > 0) {
            return Err(Error::invalid(
                "phase2.chain_repairs",
                "learns a failing skill's section of τ again as a chain of skills, which needs \
                 phase2.chaining = true (set phase2.chain_repairs = 0 without chaining)",
            ));
        }
        Ok(())
    }
}

impl Phase2Config {
    /// λ positive and finite; archive starts only with balls in position (they are looked up
    /// by position, [`super::ArchiveStarts`]).
    fn check_ball(&self) -> Result<()> {
        let BallMetric::PositionVelocity { scale } = self.ball else {
            return Ok(());
        };
        if !(scale.is_finite() && scale > 0.0) {
            return Err(Error::invalid(
                "phase2.velocity_scale",
                format!("must be 0 (balls in position) or positive, got {scale}"),
            ));
        }
        if self.start == StartMode::Archive {
            return Err(Error::invalid(
                "phase2.velocity_scale",
                "measures velocities too, while phase2.start = \"archive\" looks its starts \
                 up by position: set phase2.start = \"ball\" or phase2.velocity_scale = 0",
            ));
        }
        Ok(())
    }

    /// Whether a skill's learner starts from the last problem's ([`SkillInit::Warm`]).
    pub fn warm_start(&self) -> bool {
        self.inputs
            == InputMode::GoalRelative {
                init: SkillInit::Warm,
            }
    }

    /// The goal of the skill whose target is τ_t on a trajectory with observations `obs`
    /// (τ_0 … τ_N): [`Goal::for_target`], or B_ε(τ_N) for the last skill when
    /// [`LastGoal::Ball`].
    pub fn goal<E: Env>(&self, env: &E, obs: &[Vec<f32>], t: usize) -> Goal {
        match self.last_goal {
            LastGoal::SuccessRegion => Goal::for_target(env, obs, t, self.epsilon, self.ball),
            LastGoal::Ball => Goal::ball_in(env, &obs[t], self.epsilon, self.ball),
            LastGoal::Drawn if t + 1 == obs.len() => Goal::drawn(env, &obs[t], self.epsilon),
            LastGoal::Drawn => Goal::ball_in(env, &obs[t], self.epsilon, self.ball),
        }
    }

    /// The path limits of (training, greedy) episodes ([`EpisodeLimit`]; `None`: `max_steps`).
    pub fn path_limits(&self) -> (Option<f32>, Option<f32>) {
        match self.ideas.episode_limit {
            None => (None, None),
            Some(EpisodeLimit::Every(p)) => (Some(p), Some(p)),
            Some(EpisodeLimit::Greedy(p)) => (None, Some(p)),
        }
    }

    /// What the networks of a skill aiming at `goal` see and emit ([`InputMode`]).
    pub fn inputs<E: Env>(&self, env: &E, goal: &Goal) -> Inputs {
        match self.inputs {
            InputMode::GoalRelative { .. } => Inputs::for_goal(env, goal),
            InputMode::Raw => Inputs::new(vec![0.0; env.obs_dim()], vec![1.0; env.action_dim()]),
        }
    }

    /// The bounds of the learner's actions: 1 per component with goal-relative inputs (the
    /// [`Inputs`] scale them), the environment's bounds with raw ones.
    pub fn learner_bounds<E: Env>(&self, env: &E) -> Vec<f32> {
        match self.inputs {
            InputMode::GoalRelative { .. } => vec![1.0; env.action_dim()],
            InputMode::Raw => (0..env.action_dim()).map(|i| env.action_bound(i)).collect(),
        }
    }

    /// Greedy episodes of a hand-over try: `verify_skills`, or β.
    pub fn handover_episodes(&self) -> usize {
        self.ideas.verify_skills.unwrap_or(self.beta)
    }
}
