//! The goal-conditioned chain's training ([`Training`]): episodes from τ's saved states drawn
//! by the curriculum, overshooting through the sub-goals, one update per step, and a greedy
//! test of the chain every `test_every` training steps.

use super::settings::{Curriculum, GoalConditioned};
use super::SubGoals;
use crate::env::{Env, Goals};
use crate::error::{Error, Result};
use crate::learner::her::{GoalTransition, HerReplay};
use crate::learner::replay::Batch;
use crate::learner::Learner;
use crate::phase2::goal::dist;
use crate::phase2::inputs::Ledger;
use crate::phase2::{
    EventKind, Failure, FirstStarts, LastGoal, Phase2Inputs, Phase2Outcome, Progress, SkillChain,
    TraceRow,
};
use crate::rng::{Rng, Stream};
use rand::Rng as _;
use std::collections::VecDeque;

/// One goal-conditioned phase 2: the learner, its replay, the curriculum's memory, the ledger.
pub(super) struct Training<'r, 'a, E: Env> {
    inputs: &'r Phase2Inputs<'a, E>,
    settings: &'r GoalConditioned,
    goals: &'r dyn Goals<E::State>,
    sub: SubGoals,
    learner: Box<dyn Learner>,
    her: HerReplay,
    batch: Batch,
    noise: Rng,
    replay: Rng,
    starts: Rng,
    ledger: Ledger,
    /// Per start j (0 … M − 1): its last `window` tries (reached g_{j+1}; with Backplay's
    /// order, reached the final goal).
    tries: Vec<VecDeque<bool>>,
    /// Backplay's frontier: the earliest start drawn.
    frontier: usize,
    /// The task's own goal (τ_0's desired goal): the last skill's where episodes do not draw one.
    task_goal: Vec<f32>,
    /// This round's tries and successes.
    round: (usize, usize),
}

/// The episode being run.
struct Episode<S> {
    state: S,
    obs: Vec<f32>,
    /// Its start j, and whether its try is recorded yet.
    start: usize,
    tried: bool,
    /// The sub-goal aimed at (an index of `SubGoals::points`), and the steps spent on it.
    aim: usize,
    on_goal: usize,
    /// The episode's own final goal.
    final_goal: Vec<f32>,
}

impl<'r, 'a, E: Env> Training<'r, 'a, E> {
    /// Before the first episode: a fresh learner whose networks see the observation and the
    /// sub-goal, an empty HER replay.
    pub fn new(
        inputs: &'r Phase2Inputs<'a, E>,
        settings: &'r GoalConditioned,
        goals: &'r dyn Goals<E::State>,
        sub: SubGoals,
    ) -> Result<Self> {
        let env = inputs.env;
        let (o, g, d) = (env.obs_dim(), goals.goal_dim(), env.action_dim());
        let capacity = inputs.learner.replay_size();
        let longest = sub.len().saturating_mul(settings.steps_per_goal);
        if capacity < longest {
            return Err(Error::invalid(
                "learner.replay_size",
                format!(
                    "{capacity} transitions, fewer than the longest goal-conditioned episode \
                     ({} sub-goals × phase2.goal_conditioned.steps_per_goal = {longest})",
                    sub.len()
                ),
            ));
        }
        let seeds = inputs.seeds;
        let learner = inputs
            .learner
            .build(o + g, &vec![1.0; d], seeds, inputs.kernel)?;
        let mut task_goal = vec![0.0; g];
        goals.desired_goal(&inputs.tau[0], &mut task_goal);
        Ok(Training {
            her: HerReplay::new(capacity, o, d, g, settings.her.clone()),
            batch: Batch::default(),
            noise: seeds.stream(Stream::Noise),
            replay: seeds.stream(Stream::Replay),
            starts: seeds.stream(Stream::Start),
            ledger: Ledger::new(inputs.spent),
            tries: vec![VecDeque::new(); sub.len()],
            frontier: sub.len() - 1,
            task_goal,
            round: (0, 0),
            inputs,
            settings,
            goals,
            sub,
            learner,
        })
    }

    /// Trains until a greedy test of the chain passes (the chain, no failure) or the budget
    /// `phase2.max_env_steps` is spent (the chain as it stands, [`Failure::Budget`]).
    pub fn run(mut self, progress: &mut dyn FnMut(usize, Progress)) -> Result<Phase2Outcome> {
        let budget = self.inputs.config().max_env_steps;
        let mut failure = Some(Failure::Budget);
        let mut episode = self.begin();
        let mut tests = 0u32;
        while self.ledger.spent < budget {
            if self.step(&mut episode) {
                episode = self.begin();
            }
            if self
                .ledger
                .steps
                .train
                .is_multiple_of(self.settings.test_every)
            {
                self.record_round(progress);
                if self.test(tests, progress) {
                    failure = None;
                    break;
                }
                tests += 1;
            }
        }
        Ok(Phase2Outcome {
            chain: self.chain(),
            failure,
            steps: self.ledger.steps,
            trace: self.ledger.trace,
        })
    }

    /// The chain of the learner's current policy.
    fn chain(&self) -> SkillChain {
        let policy = self.learner.policy();
        let radius = self.settings.radius;
        self.sub
            .chain(self.inputs, radius, &self.task_goal, policy.as_ref())
    }

    /// The curriculum's start j: failure-weighted, or uniform at or after Backplay's frontier.
    fn draw_start(&mut self) -> usize {
        let m = self.sub.len();
        match self.settings.curriculum {
            Curriculum::Backplay => self.starts.random_range(self.frontier..m),
            Curriculum::FailureWeighted => {
                let weight = |tries: &VecDeque<bool>| {
                    let rate = tries.iter().filter(|&&t| t).count() as f64 / tries.len() as f64;
                    if tries.is_empty() || rate <= 0.1 {
                        10.0
                    } else {
                        1.0 / rate
                    }
                };
                let weights: Vec<f64> = self.tries.iter().map(weight).collect();
                let mut u = self.starts.random::<f64>() * weights.iter().sum::<f64>();
                for (j, w) in weights.iter().enumerate() {
                    if u < *w {
                        return j;
                    }
                    u -= w;
                }
                m - 1
            }
        }
    }

    /// A new episode: its start drawn, its state B_ε(τ_{k_j}) (at j = 0 with
    /// `phase2.first_starts = "drawn"`, the environment's own draw), its goal drawn where
    /// `phase2.last_goal = "drawn"`.
    fn begin(&mut self) -> Episode<E::State> {
        let (env, config) = (self.inputs.env, self.inputs.config());
        let j = self.draw_start();
        let at = &self.inputs.tau[self.sub.start_index(j)];
        let state = match (
            j,
            config.first_starts,
            env.drawn_starts(),
            env.ball_starts(),
        ) {
            (0, FirstStarts::Drawn, Some(d), _) => d.drawn_start(at, &mut self.starts),
            (_, _, _, Some(ball)) => ball.sample_ball(at, config.epsilon, &mut self.starts),
            _ => at.clone(),
        };
        let state = match (config.last_goal, env.drawn_goals()) {
            (LastGoal::Drawn, Some(d)) => d.with_drawn_goal(&state, &mut self.starts),
            _ => state,
        };
        let mut final_goal = vec![0.0; self.goals.goal_dim()];
        self.goals.desired_goal(&state, &mut final_goal);
        let mut obs = vec![0.0; env.obs_dim()];
        env.observe(&state, &mut obs);
        self.learner.begin_episodes(1);
        Episode {
            state,
            obs,
            start: j,
            tried: false,
            aim: j,
            on_goal: 0,
            final_goal,
        }
    }

    /// Sub-goal `aim`'s point, the episode's own goal for the last.
    fn goal<'e>(&'e self, episode: &'e Episode<E::State>, aim: usize) -> &'e [f32] {
        if aim + 1 == self.sub.len() {
            &episode.final_goal
        } else {
            &self.sub.points[aim]
        }
    }

    /// One training step of `episode`: act, store the transition (value chaining at a reached
    /// sub-goal), overshoot to the next sub-goal, learn. `true` when the episode has ended.
    fn step(&mut self, episode: &mut Episode<E::State>) -> bool {
        let env = self.inputs.env;
        let action = self.act(episode);
        let env_action: Vec<f32> = (0..env.action_dim())
            .map(|i| action[i] * env.action_bound(i))
            .collect();
        let step = env.step(&episode.state, &env_action);
        let mut next_obs = vec![0.0; env.obs_dim()];
        env.observe(&step.state, &mut next_obs);
        let mut achieved = vec![0.0; self.goals.goal_dim()];
        self.goals.achieved_goal(&next_obs, &mut achieved);
        let success = step.terminal && step.reward > 0.0;
        let last = episode.aim + 1 == self.sub.len();
        let reached =
            !last && dist(&achieved, self.goal(episode, episode.aim)) <= self.settings.radius;
        let failed = (step.terminal && !success) || !env.archivable(&step.state);
        let chained = (reached && self.settings.value_chaining)
            .then(|| self.goal(episode, episode.aim + 1).to_vec());
        let (rew, done) = match (success || reached, chained.is_some()) {
            (true, true) => (1.0, false),
            (true, false) => (1.0, true),
            (false, _) => (0.0, failed),
        };
        let desired = self.goal(episode, episode.aim).to_vec();
        self.her.push(GoalTransition {
            obs: &episode.obs,
            act: &action,
            rew,
            next_obs: &next_obs,
            done,
            desired: &desired,
            achieved_next: &achieved,
            rest: 0.0,
            chained: chained.as_deref(),
        });
        self.ledger
            .charge(crate::phase2::StepCounts { train: 1, test: 0 });
        episode.on_goal += 1;
        let ended =
            success || failed || (!reached && episode.on_goal >= self.settings.steps_per_goal);
        self.tally(episode, success, reached, ended);
        if reached {
            episode.aim += 1;
            episode.on_goal = 0;
        }
        if ended {
            self.her.end_episode();
        }
        self.learn();
        episode.state = step.state;
        episode.obs = next_obs;
        ended
    }

    /// The action in [−1, 1]ᵈ: uniform during `learning_starts`, then the learner's, with its
    /// exploration, on the observation and the sub-goal minus the position.
    fn act(&mut self, episode: &Episode<E::State>) -> Vec<f32> {
        let d = self.inputs.env.action_dim();
        if self.ledger.steps.train < self.settings.learning_starts {
            return (0..d)
                .map(|_| self.noise.random_range(-1.0..=1.0))
                .collect();
        }
        let mut input = episode.obs.clone();
        let goal = self.goal(episode, episode.aim);
        input.extend(goal.iter().zip(&episode.obs).map(|(g, x)| g - x));
        self.learner.explore(&input, &[0], &mut self.noise).to_vec()
    }

    /// Records the episode's try once it is decided: with failure-weighted starts, whether it
    /// reached its first sub-goal; with Backplay's order, whether it reached the final goal
    /// (then moves the frontier back once `advance_at` of its last tries did).
    fn tally(
        &mut self,
        episode: &mut Episode<E::State>,
        success: bool,
        reached: bool,
        ended: bool,
    ) {
        let decided = match self.settings.curriculum {
            Curriculum::FailureWeighted => {
                (success || reached || ended).then_some(success || reached)
            }
            Curriculum::Backplay => ended.then_some(success),
        };
        let (Some(won), false) = (decided, episode.tried) else {
            return;
        };
        episode.tried = true;
        self.round.0 += 1;
        self.round.1 += usize::from(won);
        let tries = &mut self.tries[episode.start];
        tries.push_back(won);
        if tries.len() > self.settings.window {
            tries.pop_front();
        }
        let rate = tries.iter().filter(|&&t| t).count() as f32 / self.settings.window as f32;
        let at_frontier = episode.start == self.frontier && self.frontier > 0;
        if self.settings.curriculum == Curriculum::Backplay
            && at_frontier
            && rate >= self.settings.advance_at
        {
            self.frontier -= 1;
        }
    }

    /// One update on a batch of real and relabelled transitions, the networks seeing each
    /// goal minus the position, once an episode has ended and `learning_starts` have passed.
    fn learn(&mut self) {
        if self.ledger.steps.train < self.settings.learning_starts {
            return;
        }
        let radius = self.settings.radius;
        let reached = |a: &[f32], g: &[f32]| dist(a, g) <= radius;
        let n = self.learner.batch_size();
        if !self
            .her
            .sample_reaching(n, &mut self.replay, &reached, &mut self.batch)
        {
            return;
        }
        let (o, g) = (self.inputs.env.obs_dim(), self.goals.goal_dim());
        super::goal_minus_position(&mut self.batch, o, g);
        self.learner.update(&self.batch);
    }

    /// Writes this round's training row (the fraction of its tries that succeeded).
    fn record_round(&mut self, progress: &mut dyn FnMut(usize, Progress)) {
        let (tries, wins) = std::mem::take(&mut self.round);
        let success = if tries == 0 {
            0.0
        } else {
            wins as f32 / tries as f32
        };
        self.report(EventKind::Train, success, progress);
    }

    /// A trace row and a progress report of `kind` at Backplay's frontier (τ_0 with
    /// failure-weighted starts).
    fn report(&mut self, kind: EventKind, success: f32, progress: &mut dyn FnMut(usize, Progress)) {
        let k = match self.settings.curriculum {
            Curriculum::Backplay => self.sub.start_index(self.frontier),
            Curriculum::FailureWeighted => 0,
        };
        let t = self.inputs.tau.len() - 1;
        self.ledger.record(TraceRow {
            skill: 0,
            k,
            t,
            event: kind,
            success,
            env_steps: self.ledger.spent,
            seconds: 0.0,
        });
        let steps = self.ledger.steps;
        progress(
            0,
            Progress {
                k,
                t,
                kind,
                success,
                steps,
            },
        );
    }

    /// Greedy test `round` of the chain: `test_episodes` episodes from B_ε(s_0) (or drawn
    /// starts, and drawn goals), each failing where one skill acts `steps_per_goal` times
    /// without handing over, the test stopping at the first failure; `true` when every one
    /// reached the goal. Its steps are charged as test steps.
    fn test(&mut self, round: u32, progress: &mut dyn FnMut(usize, Progress)) -> bool {
        let (env, config) = (self.inputs.env, self.inputs.config());
        let chain = self.chain();
        let mut rng = self.inputs.seeds.substream(Stream::ChainVerify, round);
        let like = &self.inputs.tau[0];
        let mut passed = 0;
        for _ in 0..self.settings.test_episodes {
            let start = match (config.first_starts, env.drawn_starts(), env.ball_starts()) {
                (FirstStarts::Drawn, Some(d), _) => d.drawn_start(like, &mut rng),
                (_, _, Some(ball)) => ball.sample_ball(like, config.epsilon, &mut rng),
                _ => like.clone(),
            };
            let start = chain.episode_start(env, start, &mut rng);
            // A skill that spends steps_per_goal steps without handing over has failed.
            let per_goal = Some(self.settings.steps_per_goal);
            let run = chain.run_limited(env, start, config.eval_max_steps, per_goal);
            let steps = run.states.len() as u64 - 1;
            self.ledger.charge(crate::phase2::StepCounts {
                train: 0,
                test: steps,
            });
            if !run.success {
                break;
            }
            passed += 1;
        }
        let success = passed as f32 / self.settings.test_episodes as f32;
        self.report(EventKind::Test, success, progress);
        passed == self.settings.test_episodes
    }
}
