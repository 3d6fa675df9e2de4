//! A vanilla training run between two environment steps ([`VanillaRun`]): what
//! [`super::train_vanilla`] drives to the end, and what a checkpoint saves and resumes
//! ([`super::resume`]).

use super::{evaluate, greedy_episodes, EvalRow, TrainConfig, TrainOutcome, Updates};
use crate::env::{evaluation_starts, random_action, Capability, Env, Goals};
use crate::error::{Error, Result};
use crate::learner::her::{GoalFrame, GoalTransition, HerReplay};
use crate::learner::replay::{Batch, Replay};
use crate::learner::{Learner, LearnerConfig};
use crate::nn::kernel::Kernel;
use crate::rng::{Rng, Seeds, Stream};
use crate::rollout::scale;
use crate::validate::Check;
use rustc_hash::FxHashSet;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

/// Where a vanilla run keeps its transitions.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(super) enum Store {
    /// Uniform replay.
    Plain(Replay),
    /// Whole episodes with their goals ([`HerReplay`]).
    Her(HerReplay),
}

/// Everything of a run that changes as it goes, but the learner: with the learner's own
/// state ([`Learner::save_state`]), what a checkpoint holds.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(bound = "S: Serialize + DeserializeOwned")]
pub(super) struct Progress<S> {
    replay: Store,
    /// With HER: the episode's goal, the observations followed by it (what the learner sees),
    /// and the goal the next observation achieved.
    desired: Vec<f32>,
    input: Vec<f32>,
    achieved: Vec<f32>,
    batch: Batch,
    rng_start: Rng,
    rng_noise: Rng,
    rng_replay: Rng,
    /// The environment's action bounds b: the learner acts in [−1, 1]ᵈ (Stable-Baselines3's
    /// convention), the environment gets a_i · b_i; exploration noise σ lives in the
    /// learner's space.
    bounds: Vec<f32>,
    state: S,
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
    /// Whether an evaluation had `train.stop_at_successes` successes (the run is over).
    stopped: bool,
}

/// A vanilla training run between two environment steps: one episode at a time, each step's
/// transition stored, the learner updated every step (or every episode's end, as many times
/// as it had steps), an episode ended by a terminal step or the step limit.
///
/// ```
/// use pbcs::envs::toy::Toy1D;
/// use pbcs::learner::LearnerConfig;
/// use pbcs::nn::kernel::Kernel;
/// use pbcs::rng::Seeds;
/// use pbcs::vanilla::{TrainConfig, VanillaRun};
/// let learner: LearnerConfig = toml::from_str("algo = \"td3\"\nhidden = [8]").unwrap();
/// let train = TrainConfig { steps: 300, learning_starts: 100, eval_every: 100,
///                           max_episode_steps: 20, ..TrainConfig::default() };
/// let seeds = Seeds::new(0);
/// let mut run = VanillaRun::new(&Toy1D, &learner, &train, &seeds, Kernel::detect()).unwrap();
/// run.train_until(200, |_, _, _| Ok(())).unwrap();
/// assert_eq!(run.steps(), 200);
/// assert!(!run.done());
/// run.train_until(u64::MAX, |_, _, _| Ok(())).unwrap();
/// assert!(run.done());
/// assert_eq!(run.finish().unwrap().evals.len(), 3);
/// ```
pub struct VanillaRun<'a, E: Env> {
    env: &'a E,
    train: &'a TrainConfig,
    seeds: &'a Seeds,
    /// The environment's goals, when training with HER.
    goals: Option<&'a dyn Goals<E::State>>,
    /// The rewrite of the networks' inputs into the body's frame (`[train.her] goal_frame =
    /// "body"`).
    frame: Option<Frame>,
    learner: Box<dyn Learner>,
    p: Progress<E::State>,
    /// Wall-clock seconds of the run before it was resumed (0 for a fresh run).
    pub(super) earlier_seconds: f64,
}

/// A rewrite of the networks' inputs in place (into the body's frame, [`body_frame`]).
type Frame = fn(&mut [f32]);

/// With `train.her`, the environment's goals (refused where it has none, or where the replay
/// buffer cannot hold a whole episode); `None` without HER.
fn her_goals<'a, E: Env>(
    env: &'a E,
    lc: &LearnerConfig,
    train: &TrainConfig,
) -> Result<Option<&'a dyn Goals<E::State>>> {
    if train.her.is_none() {
        return Ok(None);
    }
    Capability::Goals.require(env, "train.her")?;
    if lc.replay_size() < train.max_episode_steps {
        return Err(Error::invalid(
            "learner.replay_size",
            "must hold a whole episode (train.max_episode_steps) with train.her",
        ));
    }
    Ok(Some(env.goals().expect("required")))
}

/// With `[train.her] goal_frame = "body"`, the rewrite of the networks' inputs into the body's
/// frame (refused where the environment has no body); `None` otherwise.
fn body_frame<S>(goals: Option<&dyn Goals<S>>, train: &TrainConfig) -> Result<Option<Frame>> {
    match (goals, &train.her) {
        (Some(goals), Some(her)) if her.goal_frame == GoalFrame::Body => {
            Ok(Some(goals.body_frame().ok_or_else(|| {
                Error::invalid(
                    "train.her.goal_frame",
                    "is \"body\", but this environment has no body to see the goal from \
                     (leave it out: \"world\")",
                )
            })?))
        }
        _ => Ok(None),
    }
}

impl<'a, E: Env> VanillaRun<'a, E> {
    /// A fresh learner and the first episode's start.
    pub fn new(
        env: &'a E,
        lc: &LearnerConfig,
        train: &'a TrainConfig,
        seeds: &'a Seeds,
        kernel: Kernel,
    ) -> Result<Self> {
        train.check()?;
        let (obs_dim, act_dim) = (env.obs_dim(), env.action_dim());
        let goals = her_goals(env, lc, train)?;
        let (replay, goal_dim) = match (goals, &train.her) {
            (Some(goals), Some(config)) => {
                let g = goals.goal_dim();
                let size = lc.replay_size();
                let buffer = HerReplay::new(size, obs_dim, act_dim, g, config.clone());
                (Store::Her(buffer), g)
            }
            _ => (
                Store::Plain(Replay::new(lc.replay_size(), obs_dim, act_dim)),
                0,
            ),
        };
        let frame = body_frame(goals, train)?;
        let learner = lc.build(obs_dim + goal_dim, &vec![1.0; act_dim], seeds, kernel)?;
        let mut rng_start = seeds.stream(Stream::Start);
        let state = env.sample_start(&mut rng_start);
        let mut run = VanillaRun {
            env,
            train,
            seeds,
            goals,
            frame,
            learner,
            p: Progress {
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
                stopped: false,
            },
            earlier_seconds: 0.0,
        };
        run.begin_episode();
        Ok(run)
    }

    /// Environment steps taken so far.
    pub fn steps(&self) -> u64 {
        self.p.steps
    }

    /// Whether the run is over: all `train.steps` taken, or stopped at an evaluation with
    /// `train.stop_at_successes` successes.
    pub fn done(&self) -> bool {
        self.p.stopped || self.p.steps >= self.train.steps
    }

    /// Trains until `until` environment steps have been taken or the run is
    /// [done](Self::done); `at_eval(run, steps, success)` is called after each evaluation, and
    /// its error stops the run there.
    pub fn train_until(
        &mut self,
        until: u64,
        mut at_eval: impl FnMut(&Self, u64, f32) -> Result<()>,
    ) -> Result<()> {
        while !self.done() && self.p.steps < until {
            let step_i = self.p.steps + 1;
            self.step(step_i);
            self.p.steps = step_i;
            if step_i.is_multiple_of(self.train.eval_every) {
                let success = self.evaluate(step_i);
                let wins = (success * self.train.eval_episodes as f32).round() as usize;
                self.p.stopped = self.train.stop_at_successes.is_some_and(|n| wins >= n);
                at_eval(self, step_i, success)?;
            }
        }
        Ok(())
    }

    /// The learner's state and the rest of the run's, as a checkpoint holds them.
    pub(super) fn saved(&self) -> Result<(Vec<u8>, Vec<u8>)> {
        let progress =
            postcard::to_stdvec(&self.p).map_err(|e| Error::invalid("run state", e.to_string()))?;
        Ok((self.learner.save_state()?, progress))
    }

    /// This fresh run (of the same job) become the one whose [`VanillaRun::saved`] gave
    /// `learner` and `progress` after `steps` steps; refused, unchanged, with the reason, when
    /// they do not fit it. The learner goes on on this run's kernel, which must compute the
    /// saved one's bytes ([`Kernel::same_bytes`]).
    pub(super) fn restore(
        &mut self,
        learner: &[u8],
        progress: &[u8],
        steps: u64,
    ) -> std::result::Result<(), String> {
        let p: Progress<E::State> = postcard::from_bytes(progress)
            .map_err(|e| format!("its run state does not decode ({e})"))?;
        let same_shape = matches!(
            (&p.replay, &self.p.replay),
            (Store::Plain(_), Store::Plain(_)) | (Store::Her(_), Store::Her(_))
        ) && (p.obs.len(), p.action.len(), p.desired.len())
            == (self.p.obs.len(), self.p.action.len(), self.p.desired.len());
        if !same_shape || p.steps != steps || p.steps > self.train.steps {
            return Err("its run state has other sizes or steps than this run".into());
        }
        let kernel = self.learner.kernel();
        let mut restored = self.learner.clone();
        restored.restore_state(learner).map_err(|e| e.to_string())?;
        let saved_on = restored.kernel().name();
        if !Kernel::same_bytes(saved_on, kernel.name()) {
            return Err(format!(
                "it was saved on kernel {saved_on}, whose bytes differ from this run's {} (run \
                 with PBCS_KERNEL={saved_on} to go on from it)",
                kernel.name()
            ));
        }
        restored.set_kernel(kernel);
        self.learner = restored;
        self.p = p;
        Ok(())
    }

    /// The bin of side `train.visit_bin` of an observation.
    fn visit(&mut self, next: bool) {
        let o = if next { &self.p.next_obs } else { &self.p.obs };
        let side = self.train.visit_bin;
        // Bins of the position (the whole observation of the maze and the rooms; PointMaze's
        // without its velocity), as phase 1's archive bins.
        let bin = self
            .env
            .position(o)
            .iter()
            .map(|x| (x / side).floor() as i32)
            .collect();
        self.p.visited.insert(bin);
    }

    /// The noise restarts and the episode's first state is observed (with HER, its goal too).
    fn begin_episode(&mut self) {
        self.learner.begin_episodes(1);
        self.env.observe(&self.p.state, &mut self.p.obs);
        if let Some(goals) = self.goals {
            goals.desired_goal(&self.p.state, &mut self.p.desired);
        }
        self.visit(false);
    }

    /// Step `step_i`'s action: uniformly random during `learning_starts`, else the policy's
    /// with noise, clipped to [−1, 1]ᵈ; then scaled to the environment's bounds.
    fn choose_action(&mut self, step_i: u64) {
        let p = &mut self.p;
        if step_i <= self.train.learning_starts {
            random_action(self.env, &mut p.rng_noise, &mut p.env_action);
            for ((a, e), b) in p.action.iter_mut().zip(&p.env_action).zip(&p.bounds) {
                *a = e / b;
            }
        } else {
            let input = match p.replay {
                Store::Plain(_) => &p.obs,
                Store::Her(..) => {
                    p.input.clear();
                    p.input.extend(p.obs.iter().chain(&p.desired));
                    if let Some(frame) = self.frame {
                        frame(&mut p.input);
                    }
                    &p.input
                }
            };
            let a = self.learner.explore(input, &[0], &mut p.rng_noise);
            p.action.copy_from_slice(a);
        }
        scale(&p.action, &p.bounds, &mut p.env_action);
    }

    /// One learner update from a sampled batch, once the replay holds a batch (with HER: once
    /// an episode has ended).
    fn update(&mut self) {
        let batch_size = self.learner.batch_size();
        let p = &mut self.p;
        match (&mut p.replay, self.goals) {
            (Store::Plain(replay), _) => {
                if replay.len() >= batch_size {
                    replay.sample(batch_size, &mut p.rng_replay, &mut p.batch);
                    self.learner.update(&p.batch);
                }
            }
            (Store::Her(her), Some(goals)) => {
                let reward = |a: &[f32], d: &[f32]| goals.goal_reward(a, d);
                if her.sample(batch_size, &mut p.rng_replay, &reward, &mut p.batch) {
                    if let Some(frame) = self.frame {
                        let width = p.batch.obs.len() / p.batch.len;
                        p.batch.obs.chunks_mut(width).for_each(frame);
                        p.batch.next_obs.chunks_mut(width).for_each(frame);
                    }
                    self.learner.update(&p.batch);
                }
            }
            (Store::Her(_), None) => unreachable!("a HER replay is made with the env's goals"),
        }
    }

    /// Stores the transition from `obs` by `action` to `next_obs`; with HER, with the
    /// episode's goal, the goal achieved and the reward's part that is not the goal's.
    fn store(&mut self, reward: f32, terminal: bool) {
        let p = &mut self.p;
        match (&mut p.replay, self.goals) {
            (Store::Plain(replay), _) => {
                replay.push(&p.obs, &p.action, reward, &p.next_obs, terminal)
            }
            (Store::Her(her), Some(goals)) => {
                goals.achieved_goal(&p.next_obs, &mut p.achieved);
                let rest = reward - goals.goal_reward(&p.achieved, &p.desired);
                her.push(GoalTransition {
                    obs: &p.obs,
                    act: &p.action,
                    rew: reward,
                    next_obs: &p.next_obs,
                    done: terminal,
                    desired: &p.desired,
                    achieved_next: &p.achieved,
                    rest,
                    chained: None,
                });
            }
            (Store::Her(_), None) => unreachable!("a HER replay is made with the env's goals"),
        }
    }

    /// Environment step `step_i` (counted from 1): act, store the transition (only a true
    /// terminal stops bootstrapping; the step limit does not), learn, and end the episode at
    /// a terminal step or the step limit.
    fn step(&mut self, step_i: u64) {
        self.choose_action(step_i);
        let step = self.env.step(&self.p.state, &self.p.env_action);
        self.env.observe(&step.state, &mut self.p.next_obs);
        self.visit(true);
        self.store(step.reward, step.terminal);
        self.p.terminal_transitions += u64::from(step.terminal);
        let learning = step_i > self.train.learning_starts;
        if let Store::Her(her) = &mut self.p.replay {
            // The episode ends with this transition: it is sampled from this step's update on
            // (as Stable-Baselines3 ends it when the transition is stored).
            if step.terminal || self.p.t_episode + 1 >= self.train.max_episode_steps {
                her.end_episode();
            }
        }
        if learning && self.train.updates == Updates::Step {
            self.update();
        }
        self.p.t_episode += 1;
        let truncated = self.p.t_episode >= self.train.max_episode_steps;
        if step.terminal || truncated {
            if learning && self.train.updates == Updates::Episode {
                for _ in 0..self.p.t_episode {
                    self.update();
                }
            }
            self.p.truncated_episodes += u64::from(truncated && !step.terminal);
            self.p.state = self.env.sample_start(&mut self.p.rng_start);
            self.p.t_episode = 0;
            self.p.episodes += 1;
            self.begin_episode();
        } else {
            self.p.state = step.state;
            self.p.obs.copy_from_slice(&self.p.next_obs);
        }
    }

    /// What the policy sees beside each observation.
    fn inputs(&self) -> super::GoalInputs<'a, E::State> {
        super::GoalInputs {
            goals: self.goals,
            frame: self.frame,
        }
    }

    /// The greedy evaluation after step `step_i`, kept as a row; its success rate.
    fn evaluate(&mut self, step_i: u64) -> f32 {
        let round = self.p.evals.len() as u32;
        let inputs = self.inputs();
        let (success, mean_return, mean_length) = evaluate(
            self.env,
            self.learner.as_mut(),
            inputs,
            self.train.eval_episodes,
            self.train.max_episode_steps,
            self.seeds,
            round,
        );
        self.p.evals.push(EvalRow {
            steps: step_i,
            episodes: self.p.episodes,
            success,
            mean_return,
            mean_length,
        });
        success
    }

    /// The outcome, after PBCS's protocol if it is on (it reads only the Eval stream, so it
    /// changes nothing of the training: a run with it and one without train the same bytes).
    pub fn finish(mut self) -> Result<TrainOutcome> {
        let inputs = self.inputs();
        let mut visited: Vec<Vec<i32>> = self.p.visited.into_iter().collect();
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
                inputs,
                starts,
                t.final_eval_max_steps,
            )
        } else {
            Vec::new()
        };
        Ok(TrainOutcome {
            steps: self.p.steps,
            final_eval,
            evals: self.p.evals,
            visited,
            episodes: self.p.episodes,
            terminal_transitions: self.p.terminal_transitions,
            truncated_episodes: self.p.truncated_episodes,
            learner: self.learner,
            earlier_seconds: self.earlier_seconds,
        })
    }
}
