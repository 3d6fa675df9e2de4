//! Vanilla off-policy training on an environment's own reward (the paper's DDPG and TD3
//! baselines): episodes with a step limit, one update per environment step, periodic greedy
//! evaluation, the set of visited state bins for the "explored area" picture, and optionally
//! PBCS's evaluation protocol after training.

use crate::env::{evaluation_starts, random_action, Env, EvalEpisode};
use crate::error::{Error, Result};
use crate::learner::noise::Noise;
use crate::learner::replay::{Batch, Replay};
use crate::learner::{Learner, LearnerConfig};
use crate::nn::kernel::Kernel;
use crate::rng::{Seeds, Stream};
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
        if !(self.final_eval_epsilon.is_finite() && self.final_eval_epsilon > 0.0) {
            return Err(Error::invalid(
                "train.final_eval_epsilon",
                format!("must be positive, got {}", self.final_eval_epsilon),
            ));
        }
        Ok(())
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
    pub learner: Learner,
    /// PBCS's protocol after training (`train.final_eval_episodes` episodes; empty when off).
    pub final_eval: Vec<EvalEpisode>,
}

/// Scales a learner action in [−1, 1]ᵈ to the environment's bounds.
pub fn to_env_action<E: Env + ?Sized>(env: &E, a: &[f32], out: &mut [f32]) {
    for (i, (o, x)) in out.iter_mut().zip(a).enumerate() {
        *o = x * env.action_bound(i);
    }
}

/// Runs the greedy policy for `episodes` episodes from [`Env::sample_start`] (stream
/// [`Stream::Eval`], so evaluation never shifts training's randomness).
pub fn evaluate<E: Env>(
    env: &E,
    learner: &mut Learner,
    episodes: usize,
    max_steps: usize,
    seeds: &Seeds,
    round: u32,
) -> (f32, f32, f32) {
    let mut rng = seeds.substream(Stream::Eval, round);
    let mut obs = vec![0.0; env.obs_dim()];
    let mut action = vec![0.0; env.action_dim()];
    let (mut wins, mut ret, mut len) = (0usize, 0.0f32, 0usize);
    for _ in 0..episodes {
        let mut s = env.sample_start(&mut rng);
        for _ in 0..max_steps {
            env.observe(&s, &mut obs);
            to_env_action(env, learner.act(&obs, 1), &mut action);
            let step = env.step(&s, &action);
            ret += step.reward;
            len += 1;
            s = step.state;
            if step.terminal {
                wins += usize::from(step.reward > 0.0);
                break;
            }
        }
    }
    let e = episodes as f32;
    (wins as f32 / e, ret / e, len as f32 / e)
}

/// The greedy policy of `learner` from each of `starts`, each episode at most `max_steps`
/// steps: whether it reached a positive terminal reward, and in how many steps.
pub fn greedy_episodes<E: Env>(
    env: &E,
    learner: &mut Learner,
    starts: Vec<E::State>,
    max_steps: usize,
) -> Vec<EvalEpisode> {
    let mut obs = vec![0.0; env.obs_dim()];
    let mut action = vec![0.0; env.action_dim()];
    starts
        .into_iter()
        .map(|mut s| {
            let mut episode = EvalEpisode {
                success: false,
                steps: 0,
            };
            while episode.steps < max_steps {
                env.observe(&s, &mut obs);
                to_env_action(env, learner.act(&obs, 1), &mut action);
                let step = env.step(&s, &action);
                episode.steps += 1;
                s = step.state;
                if step.terminal {
                    episode.success = step.reward > 0.0;
                    break;
                }
            }
            episode
        })
        .collect()
}

/// Trains a fresh learner on `env`'s own reward for `train.steps` environment steps.
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
    // The learner acts in [−1, 1]ᵈ (Stable-Baselines3's convention); the environment gets
    // a_i · b_i. Exploration noise σ lives in the learner's space.
    let unit = vec![1.0; env.action_dim()];
    let mut learner = Learner::new(learner_config, env.obs_dim(), &unit, seeds, kernel)?;
    let lc = learner_config;
    let mut replay = Replay::new(lc.replay_size, env.obs_dim(), env.action_dim());
    let mut noise = Noise::new(lc.noise, lc.noise_sigma, lc.noise_theta, env.action_dim());
    let (mut rng_start, mut rng_noise, mut rng_replay) = (
        seeds.stream(Stream::Start),
        seeds.stream(Stream::Noise),
        seeds.stream(Stream::Replay),
    );
    let (mut obs, mut next_obs) = (vec![0.0; env.obs_dim()], vec![0.0; env.obs_dim()]);
    // The learner's action (in [−1, 1]ᵈ) and the environment's.
    let (mut action, mut env_action) = (vec![0.0; env.action_dim()], vec![0.0; env.action_dim()]);
    let mut batch = Batch::default();
    let mut visited: FxHashSet<Vec<i32>> = FxHashSet::default();
    let bin = |o: &[f32]| -> Vec<i32> {
        o.iter()
            .map(|x| (x / train.visit_bin).floor() as i32)
            .collect()
    };
    let mut evals = Vec::new();
    let (mut episodes, mut terminal_transitions, mut truncated_episodes) = (1u64, 0u64, 0u64);
    let mut state = env.sample_start(&mut rng_start);
    let mut t_episode = 0usize;
    noise.reset();
    env.observe(&state, &mut obs);
    visited.insert(bin(&obs));
    for step_i in 1..=train.steps {
        if step_i <= train.learning_starts {
            random_action(env, &mut rng_noise, &mut env_action);
            for (i, (a, e)) in action.iter_mut().zip(&env_action).enumerate() {
                *a = e / env.action_bound(i);
            }
        } else {
            action.copy_from_slice(learner.act(&obs, 1));
            noise.add(&mut rng_noise, &mut action);
            for a in action.iter_mut() {
                *a = a.clamp(-1.0, 1.0);
            }
        }
        to_env_action(env, &action, &mut env_action);
        let step = env.step(&state, &env_action);
        env.observe(&step.state, &mut next_obs);
        visited.insert(bin(&next_obs));
        // Only true terminal states stop bootstrapping; the time limit below does not.
        replay.push(&obs, &action, step.reward, &next_obs, step.terminal);
        terminal_transitions += u64::from(step.terminal);
        let learning = step_i > train.learning_starts;
        if learning && train.updates == Updates::Step && replay.len() >= lc.batch_size {
            replay.sample(lc.batch_size, &mut rng_replay, &mut batch);
            learner.update(&batch);
        }
        t_episode += 1;
        let truncated = t_episode >= train.max_episode_steps;
        if step.terminal || truncated {
            if learning && train.updates == Updates::Episode {
                for _ in 0..t_episode {
                    if replay.len() >= lc.batch_size {
                        replay.sample(lc.batch_size, &mut rng_replay, &mut batch);
                        learner.update(&batch);
                    }
                }
            }
            truncated_episodes += u64::from(truncated && !step.terminal);
            state = env.sample_start(&mut rng_start);
            t_episode = 0;
            episodes += 1;
            noise.reset();
            env.observe(&state, &mut obs);
            visited.insert(bin(&obs));
        } else {
            state = step.state;
            obs.copy_from_slice(&next_obs);
        }
        if step_i % train.eval_every == 0 {
            let round = evals.len() as u32;
            let (success, mean_return, mean_length) = evaluate(
                env,
                &mut learner,
                train.eval_episodes,
                train.max_episode_steps,
                seeds,
                round,
            );
            evals.push(EvalRow {
                steps: step_i,
                episodes,
                success,
                mean_return,
                mean_length,
            });
            progress(step_i, success);
        }
    }
    let mut visited: Vec<Vec<i32>> = visited.into_iter().collect();
    visited.sort();
    // PBCS's protocol, after training: it reads only the Eval stream, so it changes nothing
    // above (a run with it and one without train the same bytes).
    let final_eval = if train.final_eval_episodes > 0 {
        let starts = evaluation_starts(
            env,
            train.final_eval_epsilon,
            train.final_eval_episodes,
            seeds,
        )?;
        greedy_episodes(env, &mut learner, starts, train.final_eval_max_steps)
    } else {
        Vec::new()
    };
    Ok(TrainOutcome {
        final_eval,
        evals,
        visited,
        episodes,
        terminal_transitions,
        truncated_episodes,
        learner,
    })
}
