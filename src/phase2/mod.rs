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
pub mod goal;
pub mod shaped;

use crate::config::Check;
use crate::env::Env;
use crate::error::{Error, Result};
use crate::learner::{Learner, LearnerConfig};
use crate::nn::Mlp;
use crate::rng::{Seeds, Stream};
use goal::{Goal, Inputs};
use serde::{Deserialize, Serialize};
use shaped::{dist, SkillTask, StepCounts};
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
        Ok(())
    }
}

impl Phase2Config {
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
        let mut raw = vec![0.0; env.obs_dim()];
        let mut obs = vec![0.0; env.obs_dim()];
        let mut action = vec![0.0; env.action_dim()];
        let mut ws = crate::nn::Workspace::default();
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
            }
            let skill = &self.skills[i];
            skill.inputs.observation(&raw, &mut obs);
            let a = skill.policy.forward(&obs, 1, &mut ws);
            skill.inputs.env_action(a, &mut action);
            let step = env.step(&s, &action);
            out.skill_used.push(i);
            s = step.state;
            out.states.push(s.clone());
            if step.reward > 0.0 && step.terminal {
                out.success = true;
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
        let text = toml::to_string(&manifest).map_err(|e| Error::Parse {
            path: dir.join("manifest.toml"),
            message: e.to_string(),
        })?;
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

    /// Loads a chain saved by [`SkillChain::save`].
    pub fn load(dir: &Path) -> Result<Self> {
        let path = dir.join("manifest.toml");
        let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
        let manifest: Manifest = toml::from_str(&text).map_err(|e| Error::Parse {
            path: path.clone(),
            message: e.to_string(),
        })?;
        let mut skills = Vec::new();
        for (i, m) in manifest.skills.into_iter().enumerate() {
            let bad = |field: &str, why: String| Error::Parse {
                path: path.clone(),
                message: format!("skills[{i}].{field}: {why}"),
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
        Ok(SkillChain { skills })
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

/// Phase 2 on a trajectory τ: [`skill_chaining`] with a [`SkillTask`] (fresh learner, shaped
/// reward, starts in B_ε(τ_K)) per skill.
///
/// Skill n's learner is initialised from the run's seeds for sub-run n, and its starts, noise
/// and replay sampling read substream n; `spent` is the step count already used (phase 1),
/// charged against `config.max_env_steps`.
pub fn chain_skills<E: Env>(
    env: &E,
    tau: &[E::State],
    learner: &LearnerConfig,
    config: &Phase2Config,
    seeds: &Seeds,
    spent: u64,
    mut progress: impl FnMut(usize, Progress),
) -> Result<Phase2Outcome> {
    config.check()?;
    // The learner acts in [−1, 1]ᵈ; each skill's Inputs scale its actions to the bounds.
    let unit = vec![1.0; env.action_dim()];
    let obs: Vec<Vec<f32>> = tau
        .iter()
        .map(|s| {
            let mut o = vec![0.0; env.obs_dim()];
            env.observe(s, &mut o);
            o
        })
        .collect();
    let mut steps = StepCounts::default();
    let spent_cell = std::cell::Cell::new(spent);
    let clock = std::time::Instant::now();
    let trace = std::cell::RefCell::new(Vec::new());
    let progress = std::cell::RefCell::new(&mut progress);
    let (found, failure) = skill_chaining(
        tau.len() - 1,
        config,
        |n, t| {
            let n32 = n as u32;
            let learner = Learner::new(learner, env.obs_dim(), &unit, &seeds.skill(n32))?;
            let rngs = [
                seeds.substream(Stream::Start, n32),
                seeds.substream(Stream::Noise, n32),
                seeds.substream(Stream::Replay, n32),
            ];
            let budget = config.max_env_steps.saturating_sub(spent_cell.get());
            let mut task = SkillTask::new(env, config, tau, &obs, t, learner, rngs, budget);
            let (progress, trace, before) = (&progress, &trace, spent_cell.get());
            task.on_event = Some(Box::new(move |p: Progress| {
                trace.borrow_mut().push(TraceRow {
                    skill: n,
                    k: p.k,
                    t: p.t,
                    event: p.kind,
                    success: p.success,
                    env_steps: before + p.steps.train + p.steps.test,
                    seconds: clock.elapsed().as_secs_f64(),
                });
                (progress.borrow_mut())(n, p)
            }));
            Ok(task)
        },
        |task| {
            steps.train += task.steps.train;
            steps.test += task.steps.test;
            spent_cell.set(spent_cell.get() + task.steps.train + task.steps.test);
        },
    )?;
    let skills = found
        .into_iter()
        .map(|(k, t, policy)| Skill {
            policy,
            activation: Ball {
                center: obs[k].clone(),
                radius: config.epsilon,
            },
            start_index: k,
            target_index: t,
            inputs: Inputs::for_goal(env, &Goal::for_target(env, &obs, t, config.epsilon)),
        })
        .collect();
    Ok(Phase2Outcome {
        chain: SkillChain { skills },
        failure,
        steps,
        trace: trace.into_inner(),
    })
}
