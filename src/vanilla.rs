//! Vanilla off-policy training on an environment's own reward (the paper's DDPG and TD3
//! baselines): episodes with a step limit, one update per environment step, periodic greedy
//! evaluation, the set of visited state bins for the "explored area" picture, and optionally
//! PBCS's evaluation protocol after training. With `[train.her]`, hindsight experience replay
//! ([`crate::learner::her`]) on an environment that offers goals: the networks see the
//! observation followed by the episode's goal.

use crate::env::{evaluation_starts, random_action, Capability, Env, EvalEpisode, Goals};
use crate::error::{Error, Result};
use crate::learner::her::{HerConfig, HerReplay};
use crate::learner::replay::{Batch, Replay};
use crate::learner::{Learner, LearnerConfig};
use crate::nn::kernel::Kernel;
use crate::rng::{Seeds, Stream};
use crate::rollout::{scale, Greedy};
use crate::validate::Check;
use rustc_hash::FxHashSet;
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
    /// offers goals ([`crate::env::Env::goals`]: the maze, the rooms, PointMaze).
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
        for (field, v) in [
            ("train.steps", self.steps),
            ("train.max_episode_steps", self.max_episode_steps as u64),
            ("train.eval_every", self.eval_every),
            ("train.eval_episodes", self.eval_episodes as u64),
            (
                "train.final_eval_max_steps",
                self.final_eval_max_steps as u64,
            ),
        ] {
            if v == 0 {
                return Err(Error::invalid(field, "must be at least 1"));
            }
        }
        if !(self.visit_bin.is_finite() && self.visit_bin > 0.0) {
            return Err(Error::invalid("train.visit_bin", "must be positive"));
        }
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
}

/// Runs the greedy policy for `episodes` episodes from [`Env::sample_start`] (stream
/// [`Stream::Eval`], so evaluation never shifts training's randomness): the fraction that
/// reached a positive terminal reward, and the mean return and length per episode.
///
/// With `goals` (a learner trained with HER), the policy sees each observation followed by
/// the episode's goal.
pub fn evaluate<E: Env>(
    env: &E,
    learner: &mut dyn Learner,
    goals: Option<&dyn Goals<E::State>>,
    episodes: usize,
    max_steps: usize,
    seeds: &Seeds,
    round: u32,
) -> (f32, f32, f32) {
    let mut rng = seeds.substream(Stream::Eval, round);
    let mut greedy = Greedy::new(env, learner);
    let mut wins = 0usize;
    for _ in 0..episodes {
        let start = env.sample_start(&mut rng);
        aim(&mut greedy, goals, &start);
        wins += usize::from(greedy.episode(env, start, max_steps));
    }
    let e = episodes as f32;
    (wins as f32 / e, greedy.reward / e, greedy.steps as f32 / e)
}

/// The greedy policy of `learner` from each of `starts`, each episode at most `max_steps`
/// steps: whether it reached a positive terminal reward, and in how many steps.
pub fn greedy_episodes<E: Env>(
    env: &E,
    learner: &mut dyn Learner,
    goals: Option<&dyn Goals<E::State>>,
    starts: Vec<E::State>,
    max_steps: usize,
) -> Vec<EvalEpisode> {
    let mut greedy = Greedy::new(env, learner);
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
    train.check()?;
    let mut run = Vanilla::new(env, learner_config, train, seeds, kernel)?;
    for step_i in 1..=train.steps {
        run.step(step_i);
        run.steps = step_i;
        if step_i % train.eval_every == 0 {
            let success = run.evaluate(step_i);
            progress(step_i, success);
            let wins = (success * train.eval_episodes as f32).round() as usize;
            if train.stop_at_successes.is_some_and(|n| wins >= n) {
                break;
            }
        }
    }
    run.finish()
}

/// Where a vanilla run keeps its transitions.
enum Store<'a, S> {
    /// Uniform replay.
    Plain(Replay),
    /// Whole episodes with their goals ([`HerReplay`]), and the environment's goals.
    Her(&'a dyn Goals<S>, HerReplay),
}

/// A vanilla training run between two environment steps: one episode at a time, each step's
/// transition stored, the learner updated every step (or every episode's end, as many times
/// as it had steps), an episode ended by a terminal step or the step limit.
struct Vanilla<'a, E: Env> {
    env: &'a E,
    train: &'a TrainConfig,
    seeds: &'a Seeds,
    learner: Box<dyn Learner>,
    replay: Store<'a, E::State>,
    /// With HER: the episode's goal, the observations followed by it (what the learner sees),
    /// and the goal the next observation achieved.
    desired: Vec<f32>,
    input: Vec<f32>,
    achieved: Vec<f32>,
    batch: Batch,
    rng_start: crate::rng::Rng,
    rng_noise: crate::rng::Rng,
    rng_replay: crate::rng::Rng,
    /// The environment's action bounds b: the learner acts in [−1, 1]ᵈ (Stable-Baselines3's
    /// convention), the environment gets a_i · b_i; exploration noise σ lives in the
    /// learner's space.
    bounds: Vec<f32>,
    state: E::State,
    obs: Vec<f32>,
    next_obs: Vec<f32>,
    /// The learner's action (in [−1, 1]ᵈ) and the environment's.
    action: Vec<f32>,
    env_action: Vec<f32>,
    /// Bins of every observation met.
    visited: FxHashSet<Vec<i32>>,
    /// Steps of the current episode.
    t_episode: usize,
    episodes: u64,
    terminal_transitions: u64,
    truncated_episodes: u64,
    evals: Vec<EvalRow>,
    /// Environment steps taken.
    steps: u64,
}

impl<'a, E: Env> Vanilla<'a, E> {
    /// A fresh learner and the first episode's start.
    fn new(
        env: &'a E,
        lc: &LearnerConfig,
        train: &'a TrainConfig,
        seeds: &'a Seeds,
        kernel: Kernel,
    ) -> Result<Self> {
        let (obs_dim, act_dim) = (env.obs_dim(), env.action_dim());
        let replay = match &train.her {
            Some(config) => {
                Capability::Goals.require(env, "train.her")?;
                let goals = env.goals().expect("required");
                if lc.replay_size() < train.max_episode_steps {
                    return Err(Error::invalid(
                        "learner.replay_size",
                        "must hold a whole episode (train.max_episode_steps) with train.her",
                    ));
                }
                let g = goals.goal_dim();
                let buffer = HerReplay::new(lc.replay_size(), obs_dim, act_dim, g, config.clone());
                Store::Her(goals, buffer)
            }
            None => Store::Plain(Replay::new(lc.replay_size(), obs_dim, act_dim)),
        };
        let goal_dim = match &replay {
            Store::Her(g, _) => g.goal_dim(),
            Store::Plain(_) => 0,
        };
        let learner = lc.build(obs_dim + goal_dim, &vec![1.0; act_dim], seeds, kernel)?;
        let mut rng_start = seeds.stream(Stream::Start);
        let state = env.sample_start(&mut rng_start);
        let mut run = Vanilla {
            env,
            train,
            seeds,
            learner,
            replay,
            desired: vec![0.0; goal_dim],
            input: Vec::new(),
            achieved: vec![0.0; goal_dim],
            batch: Batch::default(),
            rng_start,
            rng_noise: seeds.stream(Stream::Noise),
            rng_replay: seeds.stream(Stream::Replay),
            bounds: (0..act_dim).map(|i| env.action_bound(i)).collect(),
            state,
            obs: vec![0.0; obs_dim],
            next_obs: vec![0.0; obs_dim],
            action: vec![0.0; act_dim],
            env_action: vec![0.0; act_dim],
            visited: FxHashSet::default(),
            t_episode: 0,
            episodes: 1,
            terminal_transitions: 0,
            truncated_episodes: 0,
            evals: Vec::new(),
            steps: 0,
        };
        run.begin_episode();
        Ok(run)
    }

    /// The bin of side `train.visit_bin` of an observation.
    fn visit(&mut self, next: bool) {
        let o = if next { &self.next_obs } else { &self.obs };
        let side = self.train.visit_bin;
        // Bins of the position (the whole observation of the maze and the rooms; PointMaze's
        // without its velocity), as phase 1's archive bins.
        let bin = self
            .env
            .position(o)
            .iter()
            .map(|x| (x / side).floor() as i32)
            .collect();
        self.visited.insert(bin);
    }

    /// The noise restarts and the episode's first state is observed (with HER, its goal too).
    fn begin_episode(&mut self) {
        self.learner.begin_episodes(1);
        self.env.observe(&self.state, &mut self.obs);
        if let Some(goals) = self.goals() {
            goals.desired_goal(&self.state, &mut self.desired);
        }
        self.visit(false);
    }

    /// The environment's goals when training with HER.
    fn goals(&self) -> Option<&'a dyn Goals<E::State>> {
        match &self.replay {
            Store::Her(goals, _) => Some(*goals),
            Store::Plain(_) => None,
        }
    }

    /// Step `step_i`'s action: uniformly random during `learning_starts`, else the policy's
    /// with noise, clipped to [−1, 1]ᵈ; then scaled to the environment's bounds.
    fn choose_action(&mut self, step_i: u64) {
        if step_i <= self.train.learning_starts {
            random_action(self.env, &mut self.rng_noise, &mut self.env_action);
            for ((a, e), b) in self
                .action
                .iter_mut()
                .zip(&self.env_action)
                .zip(&self.bounds)
            {
                *a = e / b;
            }
        } else {
            let input = match self.replay {
                Store::Plain(_) => &self.obs,
                Store::Her(..) => {
                    self.input.clear();
                    self.input.extend(self.obs.iter().chain(&self.desired));
                    &self.input
                }
            };
            let a = self.learner.explore(input, &[0], &mut self.rng_noise);
            self.action.copy_from_slice(a);
        }
        scale(&self.action, &self.bounds, &mut self.env_action);
    }

    /// One learner update from a sampled batch, once the replay holds a batch (with HER: once
    /// an episode has ended).
    fn update(&mut self) {
        let batch_size = self.learner.batch_size();
        match &mut self.replay {
            Store::Plain(replay) => {
                if replay.len() >= batch_size {
                    replay.sample(batch_size, &mut self.rng_replay, &mut self.batch);
                    self.learner.update(&self.batch);
                }
            }
            Store::Her(goals, her) => {
                let reward = |a: &[f32], d: &[f32]| goals.goal_reward(a, d);
                if her.sample(batch_size, &mut self.rng_replay, &reward, &mut self.batch) {
                    self.learner.update(&self.batch);
                }
            }
        }
    }

    /// Stores the transition from `self.obs` by `self.action` to `self.next_obs`; with HER,
    /// with the episode's goal, the goal achieved and the reward's part that is not the goal's.
    fn store(&mut self, reward: f32, terminal: bool) {
        match &mut self.replay {
            Store::Plain(replay) => {
                replay.push(&self.obs, &self.action, reward, &self.next_obs, terminal)
            }
            Store::Her(goals, her) => {
                goals.achieved_goal(&self.next_obs, &mut self.achieved);
                let rest = reward - goals.goal_reward(&self.achieved, &self.desired);
                her.push(
                    &self.obs,
                    &self.action,
                    reward,
                    &self.next_obs,
                    terminal,
                    &self.desired,
                    &self.achieved,
                    rest,
                );
            }
        }
    }

    /// Environment step `step_i` (counted from 1): act, store the transition (only a true
    /// terminal stops bootstrapping; the step limit does not), learn, and end the episode at
    /// a terminal step or the step limit.
    fn step(&mut self, step_i: u64) {
        self.choose_action(step_i);
        let step = self.env.step(&self.state, &self.env_action);
        self.env.observe(&step.state, &mut self.next_obs);
        self.visit(true);
        self.store(step.reward, step.terminal);
        self.terminal_transitions += u64::from(step.terminal);
        let learning = step_i > self.train.learning_starts;
        if let Store::Her(_, her) = &mut self.replay {
            // The episode ends with this transition: it is sampled from this step's update on
            // (as Stable-Baselines3 ends it when the transition is stored).
            if step.terminal || self.t_episode + 1 >= self.train.max_episode_steps {
                her.end_episode();
            }
        }
        if learning && self.train.updates == Updates::Step {
            self.update();
        }
        self.t_episode += 1;
        let truncated = self.t_episode >= self.train.max_episode_steps;
        if step.terminal || truncated {
            if learning && self.train.updates == Updates::Episode {
                for _ in 0..self.t_episode {
                    self.update();
                }
            }
            self.truncated_episodes += u64::from(truncated && !step.terminal);
            self.state = self.env.sample_start(&mut self.rng_start);
            self.t_episode = 0;
            self.episodes += 1;
            self.begin_episode();
        } else {
            self.state = step.state;
            self.obs.copy_from_slice(&self.next_obs);
        }
    }

    /// The greedy evaluation after step `step_i`, kept as a row; its success rate.
    fn evaluate(&mut self, step_i: u64) -> f32 {
        let round = self.evals.len() as u32;
        let goals = self.goals();
        let (success, mean_return, mean_length) = evaluate(
            self.env,
            self.learner.as_mut(),
            goals,
            self.train.eval_episodes,
            self.train.max_episode_steps,
            self.seeds,
            round,
        );
        self.evals.push(EvalRow {
            steps: step_i,
            episodes: self.episodes,
            success,
            mean_return,
            mean_length,
        });
        success
    }

    /// The outcome, after PBCS's protocol if it is on (it reads only the Eval stream, so it
    /// changes nothing of the training: a run with it and one without train the same bytes).
    fn finish(mut self) -> Result<TrainOutcome> {
        let goals = self.goals();
        let mut visited: Vec<Vec<i32>> = self.visited.into_iter().collect();
        visited.sort();
        let t = self.train;
        let final_eval = if t.final_eval_episodes > 0 {
            let starts = evaluation_starts(
                self.env,
                t.final_eval_epsilon,
                t.final_eval_episodes,
                self.seeds,
            )?;
            greedy_episodes(
                self.env,
                self.learner.as_mut(),
                goals,
                starts,
                t.final_eval_max_steps,
            )
        } else {
            Vec::new()
        };
        Ok(TrainOutcome {
            steps: self.steps,
            final_eval,
            evals: self.evals,
            visited,
            episodes: self.episodes,
            terminal_transitions: self.terminal_transitions,
            truncated_episodes: self.truncated_episodes,
            learner: self.learner,
        })
    }
}
