//! Phase 2 of PBCS: Backplay, shaped training and skill chaining (the paper's Algorithms 1–3).
//!
//! * [`backplay::backplay`] — Algorithm 2, over the [`backplay::Backplayer`] interface;
//! * [`shaped::SkillTask`] — Algorithm 3 (training with the shaped reward) and Backplay's
//!   greedy tests, for one skill;
//! * [`goal::Goal`] — what a skill must reach (reached, terminal, reward and potential from
//!   one region), and [`goal::Inputs`] — what its networks see (goal-relative observations,
//!   actions in [−1, 1]ᵈ);
//! * [`chain_skills`] — Algorithm 1: Backplay on τ_0 … τ_T, then on τ_0 … τ_{K_s}, and so on,
//!   collecting skills backwards, then reversing them;
//! * [`SkillChain`] — the result: policies π_i with activation balls A_i = B_ε(τ_{K_i});
//!   executing it uses π_0 until the state enters A_1, then π_1, and so on.

pub mod backplay;
pub mod chaining;
pub mod goal;
pub mod shaped;

pub use chaining::chain_skills;

use crate::env::Env;
use crate::error::{Error, Result};
use crate::nn::kernel::Kernel;
use crate::nn::Mlp;
use crate::rng::{Seeds, Stream};
use crate::validate::Check;
use goal::{Goal, Inputs};
use serde::{Deserialize, Serialize};
use shaped::{dist, StepCounts};
use std::path::Path;

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
    /// restarts left, a Backplay whose test after training is 0 % before any K was saved gives
    /// up (its DDPG collapsed: walking K further from the goal cannot help), and the skill
    /// starts again at T − 1 with new weights and an empty replay.
    pub restarts: usize,
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
    /// Verification of the finished chain (ours; 0 = off, the paper's procedure): the chain
    /// runs greedily from `chain_verify_episodes` starts uniform in B_ε(s_0) (stream
    /// `ChainVerify`), each skill allowed `max_steps` steps to hand over, as in its tests. When
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
            fast_tests: false,
            verify_episodes: 0,
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
        if self.max_env_steps == 0 {
            return Err(Error::invalid("phase2.max_env_steps", "must be at least 1"));
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

    /// Backplay's walk from these settings.
    pub fn walk(&self) -> backplay::Walk {
        backplay::Walk {
            alpha: self.alpha,
            k_step: self.k_step,
            early_stop: self.early_stop,
            adaptive: self.adaptive_k,
            stop_at_failure: self.stop_at_failure,
            give_up_when_dead: false,
        }
    }
}

/// What a progress report is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
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

/// A closed ball in observation space.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Ball {
    /// Centre.
    pub center: Vec<f32>,
    /// Radius.
    pub radius: f32,
}

impl Ball {
    /// Whether `obs` is in the ball (d ≤ radius).
    pub fn contains(&self, obs: &[f32]) -> bool {
        dist(&self.center, obs) <= self.radius
    }
}

/// A skill: a policy and its activation set.
#[derive(Debug, Clone, PartialEq)]
pub struct Skill {
    /// π_i.
    pub policy: Mlp,
    /// A_i = B_ε(τ_{K_i}).
    pub activation: Ball,
    /// K_i: the index on τ of the ball's centre.
    pub start_index: usize,
    /// The index on τ of the skill's target (the next skill's K, or N for the last one).
    pub target_index: usize,
    /// What π_i sees and emits (goal-relative observations, actions in [−1, 1]ᵈ).
    pub inputs: Inputs,
}

/// A chain of skills in execution order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SkillChain {
    /// π_0 … π_n with A_0 … A_n.
    pub skills: Vec<Skill>,
    /// The layer kernel the policies run on (not saved: [`SkillChain::load`] is told it).
    pub kernel: Kernel,
}

/// One execution of a chain.
#[derive(Debug, Clone, PartialEq)]
pub struct Rollout<S> {
    /// Visited states, start included.
    pub states: Vec<S>,
    /// Index of the skill that chose each action (one per step).
    pub skill_used: Vec<usize>,
    /// Whether the environment's reward was reached.
    pub success: bool,
}

#[derive(Serialize, Deserialize)]
struct Manifest {
    skills: Vec<ManifestSkill>,
}

#[derive(Serialize, Deserialize)]
struct ManifestSkill {
    file: String,
    center: Vec<f32>,
    radius: f32,
    start_index: usize,
    target_index: usize,
    sizes: Vec<usize>,
    /// The policy's tanh scale (1 for actions in [−1, 1]).
    action_bounds: Vec<f32>,
    /// [`Inputs::origin`]: subtracted from observations.
    origin: Vec<f32>,
    /// [`Inputs::action_scale`]: multiplies the policy's actions.
    action_scale: Vec<f32>,
}

impl SkillChain {
    /// Executes the chain from `start`: π_0 until the state enters A_1, then π_1, and so on,
    /// until the environment's positive reward or `max_steps` steps. When a state lies in
    /// several later activation balls, the chain switches to the last of them (a skill that
    /// overshoots its goal into a later ball hands over there). Each skill sees its own
    /// [`Inputs`]. An empty chain takes no step.
    pub fn run<E: Env>(&self, env: &E, start: E::State, max_steps: usize) -> Rollout<E::State> {
        self.run_limited(env, start, max_steps, None)
    }

    /// [`SkillChain::run`], and with `per_skill = Some(m)` the episode also ends (a failure)
    /// when one skill has acted `m` times without handing over, or when a step does not move
    /// the state (a greedy chain on a pure step is then stuck for good): the limits of a
    /// skill's own tests, used by the chain's verification.
    pub fn run_limited<E: Env>(
        &self,
        env: &E,
        start: E::State,
        max_steps: usize,
        per_skill: Option<usize>,
    ) -> Rollout<E::State> {
        let mut acted = 0;
        let mut raw = vec![0.0; env.obs_dim()];
        let mut obs = vec![0.0; env.obs_dim()];
        let mut action = vec![0.0; env.action_dim()];
        let mut ws = crate::nn::Workspace::with_kernel(self.kernel);
        let mut i = 0;
        let mut s = start;
        let mut out = Rollout {
            states: vec![s.clone()],
            skill_used: Vec::new(),
            success: false,
        };
        if self.skills.is_empty() {
            return out;
        }
        for _ in 0..max_steps {
            env.observe(&s, &mut raw);
            if let Some(j) = (i + 1..self.skills.len())
                .rev()
                .find(|&j| self.skills[j].activation.contains(&raw))
            {
                i = j;
                acted = 0;
            }
            if per_skill.is_some_and(|m| acted >= m) {
                break;
            }
            acted += 1;
            let skill = &self.skills[i];
            skill.inputs.observation(&raw, &mut obs);
            let a = skill.policy.forward(&obs, 1, &mut ws);
            skill.inputs.env_action(a, &mut action);
            let step = env.step(&s, &action);
            out.skill_used.push(i);
            let stuck = per_skill.is_some() && step.state == s;
            s = step.state;
            out.states.push(s.clone());
            if step.reward > 0.0 && step.terminal {
                out.success = true;
                break;
            }
            if stuck {
                break;
            }
        }
        out
    }

    /// Saves the chain into `dir`: `skill{i}.safetensors` per policy and `manifest.toml`
    /// (activation balls, trajectory indices, network shapes).
    pub fn save(&self, dir: &Path) -> Result<()> {
        let mut manifest = Manifest { skills: Vec::new() };
        for (i, skill) in self.skills.iter().enumerate() {
            let file = format!("skill{i}.safetensors");
            skill.policy.save(&dir.join(&file))?;
            let bounds = match skill.policy.head() {
                crate::nn::Head::Tanh(b) => b.clone(),
                crate::nn::Head::Linear => Vec::new(),
            };
            manifest.skills.push(ManifestSkill {
                file,
                center: skill.activation.center.clone(),
                radius: skill.activation.radius,
                start_index: skill.start_index,
                target_index: skill.target_index,
                sizes: skill.policy.sizes().to_vec(),
                action_bounds: bounds,
                origin: skill.inputs.origin.clone(),
                action_scale: skill.inputs.action_scale.clone(),
            });
        }
        let text = crate::validate::to_toml(&manifest, &dir.join("manifest.toml"))?;
        crate::record::write_atomic(&dir.join("manifest.toml"), |w| w.write_all(text.as_bytes()))?;
        // A chain saved here before may have had more skills: its extra policy files go, so the
        // folder holds exactly what the manifest lists.
        for entry in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
            let path = entry.map_err(|e| Error::io(dir, e))?.path();
            let name = path.file_name().unwrap_or_default().to_string_lossy();
            let listed = manifest.skills.iter().any(|s| s.file == name);
            if name.starts_with("skill") && name.ends_with(".safetensors") && !listed {
                std::fs::remove_file(&path).map_err(|e| Error::io(&path, e))?;
            }
        }
        Ok(())
    }

    /// Loads a chain saved by [`SkillChain::save`], its policies to run on `kernel`.
    pub fn load(dir: &Path, kernel: Kernel) -> Result<Self> {
        let path = dir.join("manifest.toml");
        let manifest: Manifest = crate::validate::read_toml(&path)?;
        let mut skills = Vec::new();
        for (i, m) in manifest.skills.into_iter().enumerate() {
            let bad = |field: &str, why: String| {
                Error::parse(&path, format!("skills[{i}].{field}: {why}"))
            };
            if m.sizes.len() < 2 || m.sizes.contains(&0) {
                return Err(bad(
                    "sizes",
                    format!(
                        "needs an input, an output and no empty layer, got {:?}",
                        m.sizes
                    ),
                ));
            }
            let (input, output) = (m.sizes[0], *m.sizes.last().unwrap_or(&0));
            for (field, len, want) in [
                ("center", m.center.len(), input),
                ("origin", m.origin.len(), input),
                ("action_scale", m.action_scale.len(), output),
            ] {
                if len != want {
                    return Err(bad(
                        field,
                        format!("has {len} values, the network needs {want}"),
                    ));
                }
            }
            if !m.action_bounds.is_empty() && m.action_bounds.len() != output {
                return Err(bad(
                    "action_bounds",
                    format!(
                        "has {} values, the network has {output} outputs",
                        m.action_bounds.len()
                    ),
                ));
            }
            if !(m.radius.is_finite() && m.radius > 0.0) {
                return Err(bad("radius", format!("must be positive, got {}", m.radius)));
            }
            let mut rng = Seeds::new(0).stream(Stream::Init);
            let head = if m.action_bounds.is_empty() {
                crate::nn::Head::Linear
            } else {
                crate::nn::Head::Tanh(m.action_bounds.clone())
            };
            let mut policy = Mlp::new(&m.sizes, head, &mut rng);
            policy.load(&dir.join(&m.file))?;
            skills.push(Skill {
                policy,
                activation: Ball {
                    center: m.center,
                    radius: m.radius,
                },
                start_index: m.start_index,
                target_index: m.target_index,
                inputs: Inputs::new(m.origin, m.action_scale),
            });
        }
        Ok(SkillChain { skills, kernel })
    }
}

/// Why phase 2 did not produce a chain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
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
        match self {
            Failure::BackplayFailed => "backplay_failed",
            Failure::NoChaining => "no_chaining",
            Failure::Budget => "budget",
        }
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
) -> crate::explore::Trajectory<E::State> {
    if config.shorten {
        crate::explore::shorten(env, tau, config.epsilon)
    } else {
        tau.clone()
    }
}

/// Algorithm 1 on any [`backplay::Backplayer`]: skills are found backwards from T = N and
/// returned in execution order as `(K_i, T_i, π_i)`.
///
/// ```text
/// T = N
/// while T > 0:
///     (π_n, T) = Backplay(τ_0 … τ_T);  A_n = B_ε(τ_T);  n += 1
/// reverse π and A
/// ```
///
/// α, the K walk, early stopping, verification, restarts and chaining come from `config`.
/// `next(n, T)` makes the n-th fresh learning problem (a new DDPG each time; n counts
/// restarts too, so it equals the skill's index when nothing restarts);
/// `finished(b)` receives it back after its Backplay (to collect step counts). A problem whose
/// [`backplay::Backplayer::exhausted`] is true after Backplay ends the run with
/// [`Failure::Budget`]. Without chaining, a first skill that does not start at τ_0 ends the run
/// with [`Failure::NoChaining`].
#[allow(clippy::type_complexity)]
pub fn skill_chaining<B: backplay::Backplayer>(
    n: usize,
    config: &Phase2Config,
    mut next: impl FnMut(usize, usize) -> Result<B>,
    mut finished: impl FnMut(B),
) -> Result<(Vec<(usize, usize, B::Policy)>, Option<Failure>)> {
    let mut skills = Vec::new();
    let mut t = n;
    let mut failure = None;
    // Learning problems made so far (skills plus restarts) and restarts of the current skill.
    let (mut made, mut restarts) = (0, 0);
    while t > 0 {
        let mut b = next(made, t)?;
        made += 1;
        let walk = backplay::Walk {
            give_up_when_dead: restarts < config.restarts,
            ..config.walk()
        };
        let candidates = backplay::backplay_candidates(&mut b, t, &walk);
        let found = verified(&mut b, candidates, config.verify_episodes);
        let exhausted = b.exhausted();
        finished(b);
        match found {
            _ if exhausted => {
                failure = Some(Failure::Budget);
                break;
            }
            None if restarts < config.restarts => restarts += 1,
            None => {
                failure = Some(Failure::BackplayFailed);
                break;
            }
            Some((k, policy)) => {
                restarts = 0;
                skills.push((k, t, policy));
                if k > 0 && !config.chaining {
                    failure = Some(Failure::NoChaining);
                    break;
                }
                t = k;
            }
        }
    }
    skills.reverse();
    Ok((skills, failure))
}

/// Most saved (K, π) of one Backplay that a failed verification falls back through.
pub const MAX_VERIFIED_CANDIDATES: usize = 4;

/// The skill kept from Backplay's saved `candidates` (in the order saved, decreasing K).
/// Without verification (`episodes` = 0) the last one, as in the paper. With it, the last
/// one whose policy reaches the goal in all `episodes` greedy episodes from its ball, trying
/// at most [`MAX_VERIFIED_CANDIDATES`] from the last; if none passes, the one with the best
/// verified success (the farthest-reaching among ties).
pub fn verified<B: backplay::Backplayer>(
    b: &mut B,
    mut candidates: Vec<(usize, B::Policy)>,
    episodes: usize,
) -> Option<(usize, B::Policy)> {
    if episodes == 0 {
        return candidates.pop();
    }
    let mut best: Option<(f32, usize)> = None;
    let first = candidates.len().saturating_sub(MAX_VERIFIED_CANDIDATES);
    for i in (first..candidates.len()).rev() {
        let (k, policy) = &candidates[i];
        let p = b.verify(*k, policy, episodes);
        if p >= 1.0 {
            return Some(candidates.swap_remove(i));
        }
        if best.is_none_or(|(bp, _)| p > bp) {
            best = Some((p, i));
        }
        if b.exhausted() {
            break;
        }
    }
    best.map(|(_, i)| candidates.swap_remove(i))
}
