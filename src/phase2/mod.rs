//! Phase 2 of PBCS: Backplay, shaped training and skill chaining (the paper's Algorithms 1–3).
//!
//! * [`backplay::backplay`] — Algorithm 2, over the [`backplay::Backplayer`] interface;
//! * [`task::SkillTask`] — Algorithm 3 (training with the shaped reward) and Backplay's
//!   greedy tests, for one skill;
//! * [`goal::Goal`] — what a skill must reach (reached, terminal, reward and potential from
//!   one region), [`goal::BallMetric`] — what the balls measure (the position, or with
//!   momentum position and velocity, `phase2.velocity_scale`), and [`goal::Inputs`] — what its
//!   networks see (goal-relative observations, actions in [−1, 1]ᵈ);
//! * [`Between::step`] — Algorithm 1: Backplay on τ_0 … τ_T, then on τ_0 … τ_{K_s}, and so on,
//!   collecting skills backwards, then reversing them; [`Phase2Run`] runs it on τ one
//!   learning problem at a time, then verifies and repairs the chain ([`chain_skills`]: to
//!   the end);
//! * [`ArchiveStarts`] — Backplay's starts among phase 1's archived states in B_ε(τ_K)
//!   (`phase2.start = "archive"`, [`starts`]);
//! * [`SkillChain`] — the result: policies π_i with activation balls A_i = B_ε(τ_{K_i});
//!   executing it uses π_0 until the state enters A_1, then π_1, and so on ([`skill_chain`]: type,
//!   execution, persistence);
//! * [`Phase2Config`] — the procedure: the paper's settings and our [`Ideas`] ([`procedure`]),
//!   read from and written to files in the flat form of [`flat`].

pub mod algorithm1;
pub mod backplay;
pub mod flat;
pub mod goal;
pub mod goal_conditioned;
mod inputs;
pub mod lookahead;
mod manifest;
pub mod procedure;
mod ready;
mod repair;
pub mod run;
mod section;
pub mod skill_chain;
pub mod starts;
pub mod task;
mod trajectory;

pub use manifest::CHAIN_JOB;
pub use procedure::{
    ChainCheck, DeadWalk, EpisodeLimit, FastTests, Ideas, InputMode, KWalk, Phase2Config,
    SkillInit, Stopping,
};
pub use ready::Ready;
pub use skill_chain::{Ball, Rollout, Skill, SkillChain};

use crate::env::Env;
use crate::error::Result;
pub use algorithm1::{Between, Made, Problems};
pub use backplay::{handover, verified, MAX_HANDOVER_TRIES, MAX_VERIFIED_CANDIDATES};
pub use goal_conditioned::{chain_goal_conditioned, ChainStrategy};
pub use inputs::Phase2Inputs;
pub use run::{chain_skills, Found, OpenRepair, Phase2Run, Phase2State, RepairsAt};
use serde::{Deserialize, Serialize};
pub use starts::ArchiveStarts;
pub use trajectory::{phase2_trajectory, shorten};

/// Where Backplay's episodes start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, strum::IntoStaticStr)]
#[serde(rename_all = "snake_case")]
#[strum(serialize_all = "snake_case")]
pub enum StartMode {
    /// Uniformly in B_ε(τ_K), as the paper requires (appendix "Need for resetting in unseen
    /// states").
    Ball,
    /// Exactly at τ_K (the failure that appendix explains).
    Exact,
    /// In B_ε(τ_K), among the states phase 1's archive visited there ([`ArchiveStarts`]):
    /// states the environment reached, with their own velocities, instead of made-up ones.
    /// Needs the archive: [`Phase2Inputs::with_starts`] (`pbcs run` and experiments pass it).
    Archive,
}

/// Where the first skill's starts lie at K = 0, the chain's start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FirstStarts {
    /// In B_ε(τ_0), as at every other K (the paper).
    #[default]
    Ball,
    /// Ours, for a judge whose reset draws starts beyond B_ε(s_0) (gymnasium-robotics'
    /// AntMaze: ±1 m around the start cell's centre): drawn as the environment's reset draws
    /// them ([`crate::env::DrawStarts`]); the chain's verification and evaluation start there
    /// too.
    Drawn,
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
    /// Ours, for a judge whose reset draws each episode's goal (gymnasium-robotics' AntMaze,
    /// ±1 m around the goal cell's centre): the environment's success at a goal drawn as its
    /// reset draws it ([`crate::env::DrawGoals`]), one per episode of the last skill, whose
    /// networks see the position relative to that goal ([`goal::GoalKind::Drawn`]). Needs
    /// goal-relative inputs.
    Drawn,
}

impl Phase2Config {
    /// Who draws the first skill's starts at K = 0 and the chain's verification and
    /// evaluation starts: `None` for B_ε(τ_0) ([`FirstStarts::Ball`]), else `env`'s
    /// [`crate::env::DrawStarts`] (an environment without it is refused).
    pub fn first_starts<'e, E: Env>(
        &self,
        env: &'e E,
    ) -> Result<Option<&'e dyn crate::env::DrawStarts<E::State>>> {
        match self.first_starts {
            FirstStarts::Ball => Ok(None),
            FirstStarts::Drawn => env.drawn_starts().map(Some).ok_or_else(|| {
                crate::env::Capability::DrawStarts.missing("phase2.first_starts = \"drawn\"")
            }),
        }
    }

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

/// Environment steps spent, by purpose.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StepCounts {
    /// In training episodes (Algorithm 3).
    pub train: u64,
    /// In greedy test episodes (Backplay's tests).
    pub test: u64,
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
    /// A one-line status for a progress bar: `skill` skill attempts done (each a fresh learning
    /// problem: a skill saved, or one dropped by its verification or restarted), this report on
    /// the next, `total_steps` phase-2 environment steps so far at `steps_per_s`.
    pub fn status(&self, skill: usize, total_steps: u64, steps_per_s: f64) -> String {
        format!(
            "{skill} skill attempts done; attempt {}: K {} → T {}, {} {:.0} %, {total_steps} \
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
