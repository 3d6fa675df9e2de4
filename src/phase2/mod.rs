//! Phase 2 of PBCS: Backplay, shaped training and skill chaining (the paper's Algorithms 1–3).
//!
//! * [`backplay::backplay`] — Algorithm 2, over the [`backplay::Backplayer`] interface;
//! * [`task::SkillTask`] — Algorithm 3 (training with the shaped reward) and Backplay's
//!   greedy tests, for one skill;
//! * [`goal::Goal`] — what a skill must reach (reached, terminal, reward and potential from
//!   one region), and [`goal::Inputs`] — what its networks see (goal-relative observations,
//!   actions in [−1, 1]ᵈ);
//! * [`chain_skills`] — Algorithm 1: Backplay on τ_0 … τ_T, then on τ_0 … τ_{K_s}, and so on,
//!   collecting skills backwards, then reversing them;
//! * [`SkillChain`] — the result: policies π_i with activation balls A_i = B_ε(τ_{K_i});
//!   executing it uses π_0 until the state enters A_1, then π_1, and so on ([`skill_chain`]: type,
//!   execution, persistence).

pub mod backplay;
pub mod chaining;
pub mod goal;
pub mod skill_chain;
pub mod task;

pub use skill_chain::{Ball, Rollout, Skill, SkillChain};

use crate::env::Env;
use crate::error::{Error, Result};
use crate::validate::Check;
pub use chaining::{chain_skills, skill_chaining, verified, MAX_VERIFIED_CANDIDATES};
use goal::{Goal, Inputs};
use serde::{Deserialize, Serialize};
use task::StepCounts;

/// Where Backplay's episodes start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StartMode {
    /// Uniformly in B_ε(τ_K), as the paper requires (appendix "Need for resetting in unseen
    /// states").
    Ball,
    /// Exactly at τ_K (the failure that appendix explains).
    Exact,
}

/// The last skill's goal (the skill whose target is τ_N).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LastGoal {
    /// Our correction: the environment's own success region ([`goal::Goal::last`]), so the
    /// last skill is never paid for hovering in the part of B_ε(τ_N) outside the target disc.
    SuccessRegion,
    /// The paper as written: B_ε(τ_N), like every other skill.
    Ball,
}

/// What a skill's networks see and emit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InputMode {
    /// Our correction: observations relative to the centre of the skill's goal, actions in
    /// [−1, 1]ᵈ scaled to the environment's bounds ([`goal::Inputs::for_goal`]).
    GoalRelative,
    /// The paper as written: raw observations (maze coordinates in [0, N]²) and actions in the
    /// environment's own bounds (±0.1); exploration noise σ is still a fraction of the bound.
    Raw,
}

/// Phase-2 settings (α, β, ε, ...), validated by [`Check::check`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Phase2Config {
    /// α: consecutive non-improvements of the training success that end training at one K.
    pub alpha: usize,
    /// At most this many training rounds at one K (ours; 0 = no cap, the paper's "until
    /// performance stabilizes" alone): [`backplay::Walk::max_rounds`].
    pub max_rounds: usize,
    /// β: episodes per test and per training round.
    pub beta: usize,
    /// ε: radius of the start balls, target balls and activation balls.
    pub epsilon: f32,
    /// Step limit of a training or test episode.
    pub max_steps: usize,
    /// Skill chaining on (PBCS) or off (PBCS without skill chaining: fail when a second skill
    /// would be needed).
    pub chaining: bool,
    /// Starts in B_ε(τ_K) (the paper) or exactly at τ_K.
    pub start: StartMode,
    /// How far K moves back after each step of Backplay (1: the paper).
    pub k_step: usize,
    /// Shorten τ before phase 2 by cutting the random walk's detours
    /// ([`crate::explore::shorten`]); off in the paper's procedure.
    pub shorten: bool,
    /// End training at K as soon as a round at 100 % is confirmed by a 100 % greedy test
    /// ([`backplay::train_until_stable`]); off in the paper's procedure.
    pub early_stop: bool,
    /// Adaptive K steps ([`backplay::Walk::adaptive`]); off in the paper's procedure.
    pub adaptive_k: bool,
    /// End a skill at the first K that fails after training when its ball is clear of walls
    /// ([`backplay::Walk::stop_at_failure`]); off in the paper's procedure.
    pub stop_at_failure: bool,
    /// Restarts of a skill with a fresh learner (ours; 0 = the paper): while a skill has
    /// restarts left, a Backplay whose test after training fails before any K was saved gives
    /// up — at 0 %, or, with `stop_at_failure`, below 100 % from a ball clear of walls (its
    /// DDPG collapsed: walking K further from the goal cannot help) — and the skill starts
    /// again at T − 1 with new weights and an empty replay.
    pub restarts: usize,
    /// A bound on a dead walk (ours; 0 = off, the paper's procedure, whose Backplay walks K
    /// down to 0 however long it finds no success): a Backplay whose K is `dead_walk` indices
    /// below T without a single success in any test or training round gives up
    /// ([`backplay::Walk::dead_walk`]), writing a `dead_walk` trace row. Then the skill restarts (`restarts`), and once no
    /// restart is left the hand-over moves (`retargets`) or the run fails.
    pub dead_walk: usize,
    /// Moves of a hand-over (ours; 0 = off): when no attempt at a skill finds any K, the skill
    /// found before it (target T′, start K = T) is verified greedily from the balls of the
    /// indices after T (clear ones first, nearest first, at most
    /// [`chaining::MAX_HANDOVER_TRIES`] of the next `dead_walk`), and the first from which it
    /// passes every episode (`verify_episodes`, or β) becomes its start and the new skill's
    /// target, with fresh learners. At most `retargets` moves between two skills found; a
    /// `retarget` trace row records each try.
    pub retargets: usize,
    /// Greedy tests stop an episode as soon as it is stuck (a step that did not move: with a
    /// deterministic policy and a pure step it never will), and stop the whole test once it
    /// has both a success and a failure (Backplay only asks "100 %, 0 % or between"; the
    /// fraction reported for such a test is then a lower bound). Off in the paper's
    /// procedure, which counts every step of every test.
    pub fast_tests: bool,
    /// Verification of each finished skill (ours; 0 = off, the paper's procedure): its
    /// policy must reach its goal in all of `verify_episodes` greedy episodes from its
    /// activation ball, else Backplay's previous saved (K, π) — a shorter reach — is verified
    /// in its place. A skill that passes n of n episodes fails at most 3/n of the time (95 %
    /// confidence, the rule of three): β = 50 bounds it by 6 %, 500 episodes by 0.6 %.
    pub verify_episodes: usize,
    /// Warm start (ours; off in the paper's procedure, where each skill is "a new DDPG"): a
    /// learning problem whose target lies before the last problem's on τ — in Algorithm 1,
    /// the skill after a saved one — starts from the last problem's learner (actor, critic,
    /// their targets and optimiser state; the replay starts empty, its rewards being the
    /// previous goal's). The networks see goal-relative inputs, so "reach the goal from just
    /// behind τ_T" is the problem the previous skill solved from B_ε(τ_T). A restart (same
    /// target) starts fresh, and so does a chain repair whose section does not end before the
    /// last problem's target (always the first repair: the last problem was skill 0's). The
    /// learner's own update noise stream and update count carry over with it.
    pub warm_start: bool,
    /// Path-scaled episode limits (ours; 0 = off, the paper's procedure: every training and
    /// test episode may take `max_steps` steps): an episode from B_ε(τ_K) towards the goal of
    /// τ_T may take at most `path_limit × (L + 2ε) / a` steps (and never more than
    /// `max_steps`), L being τ's length from τ_K to τ_T and a the smallest action bound: a
    /// start near its goal does not spend `max_steps` steps to show that it fails.
    pub path_limit: f32,
    /// The same limit for greedy episodes only (ours; 0 = off): tests and verifications of
    /// a skill; training episodes keep `max_steps`. Not with `path_limit`, which limits every
    /// episode already (the check refuses both).
    pub test_path_limit: f32,
    /// Verification of the finished chain (ours; 0 = off, the paper's procedure): the chain
    /// runs greedily from `chain_verify_episodes` starts uniform in B_ε(s_0) (stream
    /// `ChainVerify`), each skill allowed `max_steps` steps to hand over. When
    /// an episode fails, the skill in use when it stopped is repaired ([`chaining`]), and
    /// the chain is verified again, at most `chain_repairs` times.
    pub chain_verify_episodes: usize,
    /// Repairs of the chain after a failed chain verification (see `chain_verify_episodes`).
    pub chain_repairs: usize,
    /// The last skill's goal: the environment's success region (our correction, the default)
    /// or B_ε(τ_N) (the paper as written).
    pub last_goal: LastGoal,
    /// What the networks see: goal-relative observations and actions in [−1, 1]ᵈ (our
    /// correction, the default) or raw coordinates and ±0.1 actions (the paper as written).
    pub inputs: InputMode,
    /// Budget of environment steps for the whole run (phase 1 included); the run fails when
    /// it is exceeded.
    pub max_env_steps: u64,
    /// Episodes of the final evaluation of the chain (from starts uniform in B_ε(s_0)).
    pub eval_episodes: usize,
    /// Step limit of an evaluation episode of the chain.
    pub eval_max_steps: usize,
}

impl Default for Phase2Config {
    fn default() -> Self {
        Phase2Config {
            alpha: 10,
            max_rounds: 0,
            beta: 50,
            epsilon: 0.1,
            max_steps: 50,
            chaining: true,
            start: StartMode::Ball,
            k_step: 1,
            shorten: false,
            early_stop: false,
            adaptive_k: false,
            stop_at_failure: false,
            restarts: 0,
            dead_walk: 0,
            retargets: 0,
            fast_tests: false,
            verify_episodes: 0,
            warm_start: false,
            path_limit: 0.0,
            test_path_limit: 0.0,
            chain_verify_episodes: 0,
            chain_repairs: 0,
            last_goal: LastGoal::SuccessRegion,
            inputs: InputMode::GoalRelative,
            max_env_steps: 50_000_000,
            eval_episodes: 100,
            eval_max_steps: 5_000,
        }
    }
}

impl Phase2Config {
    /// The PBCS variant these settings run: [`Variant::Pbcs`] with chaining, else
    /// [`Variant::PbcsNoChaining`] (the one rule; records, cells and messages use it).
    pub fn variant(&self) -> Variant {
        if self.chaining {
            Variant::Pbcs
        } else {
            Variant::PbcsNoChaining
        }
    }
}

/// Which PBCS a run is: with or without skill chaining ([`Phase2Config::variant`]).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, Serialize, serde::Deserialize, strum::IntoStaticStr,
)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum Variant {
    /// PBCS: skill chaining on.
    Pbcs,
    /// PBCS without skill chaining (the paper's ablation).
    PbcsNoChaining,
}

impl Variant {
    /// Its name in records and messages (its serde name): `pbcs`, `pbcs_no_chaining`.
    pub fn name(self) -> &'static str {
        self.into()
    }
}

impl Phase2Config {
    /// Refuses, naming the setting and the hook, a setting that needs a hook of [`Env`] that
    /// `env` does not offer: ball starts and the chain's verification need
    /// [`Env::ball_starts`], `stop_at_failure` and `retargets` [`Env::clear_balls`], `shorten`
    /// [`Env::connector`]. (Before, each silently did something else: exact starts, no stop,
    /// no shortening.)
    pub fn require_hooks<E: Env + ?Sized>(&self, env: &E) -> Result<()> {
        use crate::env::Capability;
        if self.start == StartMode::Ball {
            Capability::SampleBall.require(env, "phase2.start = \"ball\"")?;
        }
        if self.chain_verify_episodes > 0 {
            Capability::SampleBall.require(env, "phase2.chain_verify_episodes")?;
        }
        if self.stop_at_failure {
            Capability::BallIsClear.require(env, "phase2.stop_at_failure")?;
        }
        if self.retargets > 0 {
            // Moved hand-overs try clear balls first.
            Capability::BallIsClear.require(env, "phase2.retargets")?;
        }
        if self.shorten {
            Capability::Connect.require(env, "phase2.shorten")?;
        }
        Ok(())
    }
}

impl Check for Phase2Config {
    fn check(&self) -> Result<()> {
        for (field, v) in [
            ("phase2.alpha", self.alpha),
            ("phase2.beta", self.beta),
            ("phase2.max_steps", self.max_steps),
            ("phase2.k_step", self.k_step),
            ("phase2.eval_episodes", self.eval_episodes),
            ("phase2.eval_max_steps", self.eval_max_steps),
        ] {
            if v == 0 {
                return Err(Error::invalid(field, "must be at least 1"));
            }
        }
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
        if self.max_env_steps == 0 {
            return Err(Error::invalid("phase2.max_env_steps", "must be at least 1"));
        }
        self.check_combinations()
    }
}

impl Phase2Config {
    /// The switches that cannot combine, each refused naming both fields.
    fn check_combinations(&self) -> Result<()> {
        if self.retargets > 0 && self.dead_walk == 0 {
            return Err(Error::invalid(
                "phase2.retargets",
                "a hand-over moves after a walk bounded by phase2.dead_walk: set it too",
            ));
        }
        if self.retargets > 0 && !self.chaining {
            return Err(Error::invalid(
                "phase2.retargets",
                "moves the hand-over between two skills, which needs phase2.chaining = true",
            ));
        }
        if self.chain_repairs > 0 && !self.chaining {
            return Err(Error::invalid(
                "phase2.chain_repairs",
                "learns a failing skill's section of τ again as a chain of skills, which needs \
                 phase2.chaining = true (set phase2.chain_repairs = 0 without chaining)",
            ));
        }
        if self.warm_start && self.inputs == InputMode::Raw {
            return Err(Error::invalid(
                "phase2.warm_start",
                "hands a skill's learner to the next skill, whose goal lies elsewhere: only \
                 phase2.inputs = \"goal_relative\" makes that the same problem (with \
                 phase2.inputs = \"raw\" set phase2.warm_start = false)",
            ));
        }
        if self.path_limit > 0.0 && self.test_path_limit > 0.0 {
            return Err(Error::invalid(
                "phase2.test_path_limit",
                "limits greedy episodes only, while phase2.path_limit limits every episode: \
                 set one of the two (0 turns a limit off)",
            ));
        }
        if self.chain_repairs > 0 && self.chain_verify_episodes == 0 {
            return Err(Error::invalid(
                "phase2.chain_repairs",
                "repairs follow a failed chain verification: set phase2.chain_verify_episodes too",
            ));
        }
        Ok(())
    }
}

impl Phase2Config {
    /// The goal of the skill whose target is τ_t on a trajectory with observations `obs`
    /// (τ_0 … τ_N): [`Goal::for_target`], or B_ε(τ_N) for the last skill when
    /// [`LastGoal::Ball`].
    pub fn goal<E: Env>(&self, env: &E, obs: &[Vec<f32>], t: usize) -> Goal {
        match self.last_goal {
            LastGoal::SuccessRegion => Goal::for_target(env, obs, t, self.epsilon),
            LastGoal::Ball => Goal::ball(obs[t].clone(), self.epsilon),
        }
    }

    /// The path limit of greedy episodes: `path_limit` or `test_path_limit`, whichever is set
    /// (the check refuses both; 0: none).
    pub fn greedy_path_limit(&self) -> f32 {
        self.path_limit.max(self.test_path_limit)
    }

    /// What the networks of a skill aiming at `goal` see and emit ([`InputMode`]).
    pub fn inputs<E: Env>(&self, env: &E, goal: &Goal) -> Inputs {
        match self.inputs {
            InputMode::GoalRelative => Inputs::for_goal(env, goal),
            InputMode::Raw => Inputs::new(vec![0.0; env.obs_dim()], vec![1.0; env.action_dim()]),
        }
    }

    /// The bounds of the learner's actions: 1 per component with goal-relative inputs (the
    /// [`Inputs`] scale them), the environment's bounds with raw ones.
    pub fn learner_bounds<E: Env>(&self, env: &E) -> Vec<f32> {
        match self.inputs {
            InputMode::GoalRelative => vec![1.0; env.action_dim()],
            InputMode::Raw => (0..env.action_dim()).map(|i| env.action_bound(i)).collect(),
        }
    }

    /// Backplay's walk from these settings, for a skill that has restarts left or not (a walk
    /// that may restart gives up when dead: [`backplay::Walk::give_up_when_dead`]).
    pub fn walk(&self, restarts_left: bool) -> backplay::Walk {
        backplay::Walk {
            alpha: self.alpha,
            max_rounds: self.max_rounds,
            k_step: self.k_step,
            early_stop: self.early_stop,
            adaptive: self.adaptive_k,
            stop_at_failure: self.stop_at_failure,
            give_up_when_dead: restarts_left,
            dead_walk: (self.dead_walk > 0).then_some(self.dead_walk),
        }
    }
}

/// What a progress report is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, strum::IntoStaticStr)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum EventKind {
    /// A greedy test of β episodes (Backplay's).
    Test,
    /// A training round of β episodes (Algorithm 3).
    Train,
    /// The verification of a finished skill (`phase2.verify_episodes` greedy episodes).
    Verify,
    /// The verification of the finished chain from B_ε(s_0)
    /// (`phase2.chain_verify_episodes` episodes).
    ChainVerify,
    /// A try to move a hand-over after a dead walk (`phase2.retargets`): the skill found last
    /// (target T) verified greedily from a later ball B_ε(τ_K).
    Retarget,
    /// A Backplay walk that gave up at K (`phase2.dead_walk`): K was that many indices below
    /// T and no test or training round had reached the goal once (success 0, no steps).
    DeadWalk,
}

impl EventKind {
    /// Its name in `trace.csv` and in messages (its serde name): `test`, `train`, `verify`,
    /// `chain_verify`, `retarget`, `dead_walk`.
    pub fn name(self) -> &'static str {
        self.into()
    }
}

/// A progress report from inside Backplay.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Current K.
    pub k: usize,
    /// Current T.
    pub t: usize,
    /// A test, a training round or a verification.
    pub kind: EventKind,
    /// Its success fraction.
    pub success: f32,
    /// Steps spent by the current skill so far.
    pub steps: StepCounts,
}

impl Progress {
    /// A one-line status for a progress bar: `skill` skills found, this report on the next,
    /// `total_steps` phase-2 environment steps so far at `steps_per_s`.
    pub fn status(&self, skill: usize, total_steps: u64, steps_per_s: f64) -> String {
        format!(
            "{skill} skills found; building skill {}: K {} → T {}, {} {:.0} %, {total_steps} \
             phase-2 env steps ({steps_per_s:.0} steps/s)",
            skill + 1,
            self.k,
            self.t,
            self.kind.name(),
            100.0 * self.success,
        )
    }
}

/// Why phase 2 did not produce a chain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, strum::IntoStaticStr)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum Failure {
    /// Backplay solved no K at all for some skill.
    BackplayFailed,
    /// A second skill would have been needed with chaining off.
    NoChaining,
    /// The step budget `phase2.max_env_steps` ran out.
    Budget,
}

impl Failure {
    /// Its name in records and messages (its serde name): `backplay_failed`, `no_chaining`,
    /// `budget`.
    pub fn name(self) -> &'static str {
        self.into()
    }
}

/// The output of phase 2.
#[derive(Debug, Clone)]
pub struct Phase2Outcome {
    /// The chain (complete when `failure` is `None`; the skills found so far otherwise).
    pub chain: SkillChain,
    /// Why it stopped early, if it did.
    pub failure: Option<Failure>,
    /// Environment steps of training and of tests.
    pub steps: StepCounts,
    /// Every test, training round and verification, in order: how Backplay walked.
    pub trace: Vec<TraceRow>,
}

/// One row of a run's trace (`trace.csv`): a test, training round or verification of one
/// skill at one K. Deterministic per seed; the wall clock of each row is `seconds`, kept out
/// of the CSV (written beside it).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TraceRow {
    /// The learning problem: skills in the order built (0 = the one that ends at τ_N), a
    /// restarted skill taking the next number (`phase2.restarts`).
    pub skill: usize,
    /// K: start index on τ.
    pub k: usize,
    /// T: target index on τ.
    pub t: usize,
    /// Test, training round or verification.
    pub event: EventKind,
    /// Its success fraction.
    pub success: f32,
    /// Environment steps of the whole run so far (phase 1 included), after this event.
    pub env_steps: u64,
    /// Wall-clock seconds since phase 2 began (not in the CSV).
    #[serde(skip)]
    pub seconds: f64,
}

/// The trajectory phase 2 works on: τ itself, or τ shortened with clearance ε when
/// `config.shorten` is on.
pub fn phase2_trajectory<E: Env>(
    env: &E,
    tau: &crate::explore::Trajectory<E::State>,
    config: &Phase2Config,
) -> Result<crate::explore::Trajectory<E::State>> {
    if config.shorten {
        crate::explore::shorten(env, tau, config.epsilon)
    } else {
        Ok(tau.clone())
    }
}
