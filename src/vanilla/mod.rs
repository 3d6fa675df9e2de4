//! Vanilla off-policy training on an environment's own reward (the paper's DDPG and TD3
//! baselines): episodes with a step limit, one update per environment step, periodic greedy
//! evaluation, the set of visited state bins for the "explored area" picture, and optionally
//! PBCS's evaluation protocol after training. With `[train.her]`, hindsight experience replay
//! ([`crate::learner::her`]) on an environment that offers goals: the networks see the
//! observation followed by the episode's goal.
//!
//! A run is a [`VanillaRun`] driven to its end; [`resume`] saves one now and then and goes on
//! from where it was saved, to the same bytes.

pub mod resume;
mod run;

pub use run::VanillaRun;

use crate::env::{Env, EvalEpisode, Goals};
use crate::error::{Error, Result};
use crate::learner::her::HerConfig;
use crate::learner::{Learner, LearnerConfig};
use crate::nn::kernel::Kernel;
use crate::rng::{Seeds, Stream};
use crate::rollout::Greedy;
use crate::validate::Check;
use serde::{Deserialize, Serialize};

/// The training schedule (validated by [`Check::check`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrainConfig {
    /// Environment steps in all (1M for the paper's baselines).
    pub steps: u64,
    /// Episode step limit; reaching it truncates the episode (not a terminal transition).
    pub max_episode_steps: usize,
    /// Steps of uniformly random actions before the policy acts and learning starts.
    pub learning_starts: u64,
    /// Greedy evaluation every this many environment steps.
    pub eval_every: u64,
    /// Greedy episodes per evaluation (1 is enough when the start state is fixed).
    pub eval_episodes: usize,
    /// Side of the bins in which visited states are recorded.
    pub visit_bin: f32,
    /// PBCS's protocol, when at least 1: after training, the greedy policy runs this many
    /// episodes from the starts PBCS's chains are evaluated from (uniform in B_ε(s_0),
    /// [`crate::env::evaluation_starts`]), and the run is judged on them instead of on its last
    /// periodic evaluation. 0 (the default, and the paper's baselines): off.
    pub final_eval_episodes: usize,
    /// ε of that protocol: the radius of the start ball around s_0 (PBCS's ε).
    pub final_eval_epsilon: f32,
    /// Step limit of each of those episodes (PBCS's `phase2.eval_max_steps`).
    pub final_eval_max_steps: usize,
    /// When the learner updates (after `learning_starts`).
    pub updates: Updates,
    /// Hindsight experience replay (`[train.her]`; absent: off). Needs an environment that
    /// offers goals ([`crate::env::Env::goals`]: the maze, the rooms, PointMaze, AntMaze).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub her: Option<HerConfig>,
    /// Stop training after the first periodic evaluation with at least this many successful
    /// episodes of its `eval_episodes` (Stable-Baselines3's PointMaze protocol: 95 of 100);
    /// absent: train all `steps`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stop_at_successes: Option<usize>,
}

/// When a vanilla learner updates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Updates {
    /// One update after every environment step (the paper's baselines, ours).
    #[default]
    Step,
    /// After each episode, as many updates as it had steps (RL-Zoo's `train_freq = [1,
    /// "episode"], gradient_steps = -1`, for the Pendulum check).
    Episode,
}

impl Default for TrainConfig {
    fn default() -> Self {
        TrainConfig {
            steps: 1_000_000,
            max_episode_steps: 1000,
            learning_starts: 10_000,
            eval_every: 10_000,
            eval_episodes: 1,
            visit_bin: 0.05,
            final_eval_episodes: 0,
            final_eval_epsilon: 0.1,
            final_eval_max_steps: 5000,
            updates: Updates::Step,
            her: None,
            stop_at_successes: None,
        }
    }
}

impl Check for TrainConfig {
    fn check(&self) -> Result<()> {
        use crate::validate::{bounds, count};
        for (field, v) in [
            ("train.steps", self.steps),
            ("train.eval_every", self.eval_every),
        ] {
            count(field, v, bounds::ENV_STEPS)?;
        }
        for (field, v, max) in [
            (
                "train.max_episode_steps",
                self.max_episode_steps,
                bounds::EPISODE_STEPS,
            ),
            ("train.eval_episodes", self.eval_episodes, bounds::EPISODES),
            (
                "train.final_eval_max_steps",
                self.final_eval_max_steps,
                bounds::EPISODE_STEPS,
            ),
        ] {
            count(field, v as u64, max)?;
        }
        crate::validate::at_most(
            "train.final_eval_episodes",
            self.final_eval_episodes as u64,
            bounds::EPISODES,
        )?;
        // A bin of the visited states' picture: at most the largest maze's side.
        crate::validate::positive_finite("train.visit_bin", self.visit_bin, 100.0)?;
        if self.learning_starts > self.steps {
            return Err(Error::invalid(
                "train.learning_starts",
                format!(
                    "{} of train.steps = {}: the learner would never update (its first update \
                     comes after learning_starts steps; equal to train.steps: random actions \
                     only)",
                    self.learning_starts, self.steps
                ),
            ));
        }
        if !(self.final_eval_epsilon.is_finite() && self.final_eval_epsilon > 0.0) {
            return Err(Error::invalid(
                "train.final_eval_epsilon",
                format!("must be positive, got {}", self.final_eval_epsilon),
            ));
        }
        if let Some(n) = self.stop_at_successes {
            // A stopped run is a solved run: its row says so ([`crate::stats::SOLVED_AT`]).
            let least = crate::stats::least_successes(self.eval_episodes as u64) as usize;
            if n < least.max(1) || n > self.eval_episodes {
                return Err(Error::invalid(
                    "train.stop_at_successes",
                    format!(
                        "must be between {} (the {} % that counts a run solved) and \
                         train.eval_episodes = {}, got {n}",
                        least.max(1),
                        (crate::stats::SOLVED_AT * 100.0).round(),
                        self.eval_episodes
                    ),
                ));
            }
            if self.final_eval_episodes > 0 {
                return Err(Error::invalid(
                    "train.stop_at_successes",
                    "cannot combine with train.final_eval_episodes: a run stopped at a solving \
                     evaluation would be judged again on other episodes",
                ));
            }
        }
        match &self.her {
            Some(her) => her.check(),
            None => Ok(()),
        }
    }
}

/// One evaluation of the greedy policy (a row of a vanilla run's `evals.csv`).
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct EvalRow {
    /// Environment steps of training so far.
    pub steps: u64,
    /// Training episodes begun so far.
    pub episodes: u64,
    /// Fraction of greedy episodes that reached a positive reward.
    pub success: f32,
    /// Mean return of the greedy episodes.
    pub mean_return: f32,
    /// Mean length of the greedy episodes.
    pub mean_length: f32,
}

/// What a training run produced.
#[derive(Debug, Clone)]
pub struct TrainOutcome {
    /// Environment steps trained: `train.steps`, or fewer where `train.stop_at_successes`
    /// stopped the run.
    pub steps: u64,
    /// The evaluations, in order.
    pub evals: Vec<EvalRow>,
    /// Bins (of side `visit_bin`) of every observation met in training, sorted.
    pub visited: Vec<Vec<i32>>,
    /// Training episodes begun.
    pub episodes: u64,
    /// Transitions stored as terminal (positive or negative, as the environment says).
    pub terminal_transitions: u64,
    /// Episodes cut by the step limit (their last transition is stored as non-terminal).
    pub truncated_episodes: u64,
    /// The trained learner.
    pub learner: Box<dyn Learner>,
    /// PBCS's protocol after training (`train.final_eval_episodes` episodes; empty when off).
    pub final_eval: Vec<EvalEpisode>,
    /// Wall-clock seconds of the run before it was resumed from a checkpoint ([`resume`]; 0
    /// for a run never cut).
    pub earlier_seconds: f64,
}

/// What a policy sees beside each observation: with `goals` (a learner trained with HER) the
/// episode's goal, rewritten by `frame` when given ([`crate::env::Goals::body_frame`]). `NONE`:
/// the observation alone.
pub struct GoalInputs<'g, S> {
    /// The environment's goals, for a learner trained with HER.
    pub goals: Option<&'g dyn Goals<S>>,
    /// The rewrite of the inputs into the body's frame.
    pub frame: Option<fn(&mut [f32])>,
}

impl<S> Clone for GoalInputs<'_, S> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<S> Copy for GoalInputs<'_, S> {}

impl<S> GoalInputs<'_, S> {
    /// The observation alone.
    pub const NONE: Self = GoalInputs {
        goals: None,
        frame: None,
    };
}

/// Runs the greedy policy for `episodes` episodes from [`Env::sample_start`] (stream
/// [`Stream::Eval`], substream `round`, so evaluation never shifts training's randomness): the
/// fraction that reached a positive terminal reward, and the mean return and length per
/// episode. The policy sees `inputs` beside each observation.
pub fn evaluate<E: Env>(
    env: &E,
    learner: &mut dyn Learner,
    inputs: GoalInputs<'_, E::State>,
    episodes: usize,
    max_steps: usize,
    seeds: &Seeds,
    round: u32,
) -> (f32, f32, f32) {
    let mut rng = seeds.substream(Stream::Eval, round);
    let mut greedy = Greedy::new(env, learner);
    greedy.frame = inputs.frame;
    let mut wins = 0usize;
    for _ in 0..episodes {
        let start = env.sample_start(&mut rng);
        aim(&mut greedy, inputs.goals, &start);
        wins += usize::from(greedy.episode(env, start, max_steps));
    }
    let e = episodes as f32;
    (wins as f32 / e, greedy.reward / e, greedy.steps as f32 / e)
}

/// The greedy policy of `learner` from each of `starts`, each episode at most `max_steps`
/// steps: whether it reached a positive terminal reward, and in how many steps. `inputs` as for
/// [`evaluate`].
pub fn greedy_episodes<E: Env>(
    env: &E,
    learner: &mut dyn Learner,
    inputs: GoalInputs<'_, E::State>,
    starts: Vec<E::State>,
    max_steps: usize,
) -> Vec<EvalEpisode> {
    let (goals, frame) = (inputs.goals, inputs.frame);
    let mut greedy = Greedy::new(env, learner);
    greedy.frame = frame;
    starts
        .into_iter()
        .map(|start| {
            aim(&mut greedy, goals, &start);
            let before = greedy.steps;
            let success = greedy.episode(env, start, max_steps);
            EvalEpisode {
                success,
                steps: greedy.steps - before,
            }
        })
        .collect()
}

/// With `goals`, the goal of the episode starting in `start` appended to what `greedy` sees.
fn aim<S>(greedy: &mut Greedy<'_>, goals: Option<&dyn Goals<S>>, start: &S) {
    if let Some(g) = goals {
        greedy.goal.resize(g.goal_dim(), 0.0);
        g.desired_goal(start, &mut greedy.goal);
    }
}

/// Trains a fresh learner on `env`'s own reward for `train.steps` environment steps, or until
/// an evaluation has `train.stop_at_successes` successful episodes.
/// `progress(steps, last_success)` is called after each evaluation.
pub fn train_vanilla<E: Env>(
    env: &E,
    learner_config: &LearnerConfig,
    train: &TrainConfig,
    seeds: &Seeds,
    kernel: Kernel,
    mut progress: impl FnMut(u64, f32),
) -> Result<TrainOutcome> {
    let mut run = VanillaRun::new(env, learner_config, train, seeds, kernel)?;
    run.train_until(u64::MAX, |_, steps, success| {
        progress(steps, success);
        Ok(())
    })?;
    run.finish()
}
