//! The goal-conditioned chain's training as one owned run ([`GoalConditionedRun`]): episodes
//! from τ's saved states drawn by the curriculum, overshooting through the sub-goals (unless
//! `overshoot = false`), `updates_per_step` updates a step, and a greedy test of the chain every
//! `test_every` training steps.
//!
//! Between two tests a run is its learner's state and the rest of what changes as it goes (the
//! HER replay, the random streams' positions, the curriculum's tries and frontier, the episode
//! in flight, the tests so far) and its ledger's (env steps, step counts, the trace):
//! [`GoalConditionedRun::state`] copies it out, [`GoalConditionedRun::resume`] goes on from
//! the copy to the bytes of a run never cut, and the caller decides when to save (a
//! checkpoint writes it: [`crate::runs::pbcs_resume`]). An AntMaze run of hours so outlives a
//! session's end or a cluster job's limit.

use super::curriculum::{start_state, Starts};
use super::settings::{Curriculum, GoalConditioned, GoalReward};
use super::SubGoals;
use crate::env::{Env, Goals};
use crate::error::{Error, Result};
use crate::learner::her::{GoalTransition, HerReplay};
use crate::learner::replay::Batch;
use crate::learner::Learner;
use crate::nn::kernel::Kernel;
use crate::phase2::goal::dist;
use crate::phase2::inputs::Ledger;
use crate::phase2::StepCounts;
use crate::phase2::{
    EventKind, Failure, FirstStarts, LastGoal, Phase2Inputs, Phase2Outcome, Progress, SkillChain,
    TraceRow,
};
use crate::rng::{Rng, Stream};
use rand::Rng as _;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::ops::ControlFlow;

/// One goal-conditioned phase 2 on τ, owning what it has learnt and spent: trained one test at
/// a time ([`GoalConditionedRun::next_test`]), copied out between two tests
/// ([`GoalConditionedRun::state`]) and resumed from the copy ([`GoalConditionedRun::resume`]),
/// then finished ([`GoalConditionedRun::finish`]).
///
/// ```
/// use pbcs::config::Preset;
/// use pbcs::envs::maze::Maze;
/// use pbcs::phase1::explore;
/// use pbcs::phase2::goal_conditioned::{GoalConditioned, GoalConditionedRun};
/// use pbcs::phase2::{chain_goal_conditioned, Phase2Inputs};
/// use pbcs::rng::{Seeds, Stream};
/// let mut job = Preset::Fast.job().unwrap();
/// (job.maze.size, job.seed) = (2, 0);
/// let maze = Maze::new(&job.maze).unwrap();
/// let seeds = Seeds::new(job.seed);
/// let found = explore(&maze, &job.explore, &mut seeds.stream(Stream::Explore), |_, _| {}).unwrap();
/// let tau = &found.trajectory.states;
/// let (ready, kernel) = (job.phase2.ready(&maze).unwrap(), pbcs::nn::kernel::Kernel::detect());
/// let inputs = || Phase2Inputs::new(&maze, tau, ready, &job.learner, &seeds, kernel)
///     .after(found.env_steps);
/// let settings = GoalConditioned::default();
/// // Cut after its first test, its state kept...
/// let mut run = GoalConditionedRun::start(inputs(), &settings).unwrap();
/// assert!(run.next_test(&mut |_, _| {}).is_continue());
/// let kept = run.state().unwrap();
/// assert_eq!(kept.steps.train, settings.test_every);
/// // ...it goes on to the outcome of the run never cut.
/// let resumed = GoalConditionedRun::resume(inputs(), &settings, kept).unwrap();
/// let resumed = resumed.finish(&mut |_, _| {});
/// let whole = chain_goal_conditioned(inputs(), &settings, &mut |_, _| {}).unwrap();
/// assert_eq!((resumed.chain, resumed.failure), (whole.chain, whole.failure));
/// assert_eq!(resumed.steps, whole.steps);
/// ```
pub struct GoalConditionedRun<'a, E: Env> {
    inputs: Phase2Inputs<'a, E>,
    settings: GoalConditioned,
    goals: &'a dyn Goals<E::State>,
    sub: SubGoals,
    /// The task's own goal (τ_0's desired goal): the last skill's where episodes do not draw one.
    task_goal: Vec<f32>,
    learner: Box<dyn Learner>,
    /// With `normalise`: the networks' view of the observation (its shift and scale).
    view: Option<crate::phase2::goal::Inputs>,
    ledger: Ledger,
    p: Moving<E::State>,
    /// Once training has ended: why it stopped early, if it did.
    ended: Option<Option<Failure>>,
}

/// What changes as a run goes, but its learner and ledger: with them, what
/// [`GoalConditionedState`] holds.
#[derive(Serialize, Deserialize)]
#[serde(bound = "S: Serialize + DeserializeOwned")]
struct Moving<S> {
    her: HerReplay,
    batch: Batch,
    noise: Rng,
    replay: Rng,
    starts: Rng,
    /// The curriculum's memory of each start's tries, and Backplay's frontier.
    curriculum: Starts,
    /// This round's tries and successes.
    round: (usize, usize),
    /// Tests run so far (test n draws its starts from substream n).
    tests: u32,
    /// The episode in flight.
    episode: Episode<S>,
}

/// A goal-conditioned phase 2 between two of its tests: what a run cut there goes on from
/// ([`GoalConditionedRun::resume`]).
#[derive(Debug, Clone, PartialEq)]
pub struct GoalConditionedState {
    /// The learner's [`Learner::save_state`] (weights, targets, optimiser moments, its streams).
    pub learner: Vec<u8>,
    /// The rest of what changes as the run goes (postcard): the replay, the random streams'
    /// positions, the curriculum, the tests so far, the episode in flight.
    pub progress: Vec<u8>,
    /// Environment steps of the whole run so far (phase 1 included).
    pub spent: u64,
    /// Phase 2's steps so far, by purpose.
    pub steps: StepCounts,
    /// The trace so far, wall clock included.
    pub trace: Vec<TraceRow>,
}

/// The episode being run.
#[derive(Clone, Serialize, Deserialize)]
#[serde(bound = "S: Serialize + DeserializeOwned")]
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

impl<'a, E: Env> GoalConditionedRun<'a, E> {
    /// Phase 2 by this strategy on τ = `inputs.tau` before its first episode: τ cut into
    /// sub-goals `settings.spacing` apart ([`SubGoals::cut`]), then [`GoalConditionedRun::new`].
    /// An environment without goals is refused.
    pub fn start(inputs: Phase2Inputs<'a, E>, settings: &GoalConditioned) -> Result<Self> {
        let env = inputs.env;
        let goals = env.goals().ok_or_else(|| {
            crate::env::Capability::Goals.missing("phase2.chain = \"goal_conditioned\"")
        })?;
        let sub = SubGoals::cut(env, goals, inputs.tau, settings.spacing)?;
        GoalConditionedRun::new(inputs, settings, goals, sub)
    }

    /// Before the first episode: a fresh learner whose networks see the observation and the
    /// sub-goal, an empty HER replay, the first episode begun. A replay smaller than the
    /// longest episode is refused.
    fn new(
        inputs: Phase2Inputs<'a, E>,
        settings: &GoalConditioned,
        goals: &'a dyn Goals<E::State>,
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
        let placeholder = Episode {
            state: inputs.tau[0].clone(),
            obs: Vec::new(),
            start: 0,
            tried: true,
            aim: 0,
            on_goal: 0,
            final_goal: Vec::new(),
        };
        let mut run = GoalConditionedRun {
            p: Moving {
                her: HerReplay::new(capacity, o, d, g, settings.her.clone()),
                batch: Batch::default(),
                noise: seeds.stream(Stream::Noise),
                replay: seeds.stream(Stream::Replay),
                starts: seeds.stream(Stream::Start),
                curriculum: Starts::new(sub.len()),
                round: (0, 0),
                tests: 0,
                episode: placeholder,
            },
            ledger: Ledger::new(inputs.spent),
            view: settings.normalise.then(|| sub.normalised_view()),
            task_goal,
            inputs,
            settings: settings.clone(),
            goals,
            sub,
            learner,
            ended: None,
        };
        run.p.episode = run.begin();
        Ok(run)
    }

    /// Trains to the next greedy test of the chain and runs it: `Continue` while training
    /// goes on (a state copied out now goes on from there), `Break` once a test has passed or
    /// the budget `phase2.max_env_steps` is spent (at once when it had).
    pub fn next_test(&mut self, progress: &mut dyn FnMut(usize, Progress)) -> ControlFlow<()> {
        if self.ended.is_some() {
            return ControlFlow::Break(());
        }
        let budget = self.inputs.config().max_env_steps;
        let mut episode = self.p.episode.clone();
        let mut flow = ControlFlow::Break(());
        self.ended = Some(Some(Failure::Budget));
        while self.ledger.spent < budget {
            if self.step(&mut episode) {
                episode = self.begin();
            }
            let every = self.settings.test_every;
            if self.ledger.steps.train.is_multiple_of(every) {
                self.record_round(progress);
                let tests = self.p.tests;
                self.p.tests = tests.saturating_add(1);
                if self.test(tests, progress) {
                    self.ended = Some(None);
                } else if self.ledger.spent < budget {
                    (self.ended, flow) = (None, ControlFlow::Continue(()));
                }
                break;
            }
        }
        self.p.episode = episode;
        flow
    }

    /// Trains until a greedy test of the chain passes (the chain, no failure) or the budget
    /// is spent (the chain as it stands, [`Failure::Budget`]).
    pub fn finish(mut self, progress: &mut dyn FnMut(usize, Progress)) -> Phase2Outcome {
        while self.next_test(progress).is_continue() {}
        Phase2Outcome {
            chain: self.chain(),
            failure: self.ended.flatten(),
            steps: self.ledger.steps,
            trace: self.ledger.trace,
        }
    }

    /// The run as it stands between two tests, for [`GoalConditionedRun::resume`].
    pub fn state(&self) -> Result<GoalConditionedState> {
        let progress = postcard::to_stdvec(&self.p)
            .map_err(|e| Error::invalid("goal-conditioned run state", e.to_string()))?;
        Ok(GoalConditionedState {
            learner: self.learner.save_state()?,
            progress,
            spent: self.ledger.spent,
            steps: self.ledger.steps,
            trace: self.ledger.trace.clone(),
        })
    }

    /// The kernel the learner computes on.
    pub fn kernel(&self) -> Kernel {
        self.learner.kernel()
    }

    /// The run of these inputs where a run of the same inputs stood when `state` was copied
    /// out of it: it goes on to the outcome of the run never cut (the same chain, failure,
    /// step counts and trace, its wall clock aside). A state that cannot be this run's (other
    /// sizes, sub-goals or steps) is refused. The learner goes on on this run's kernel (one of
    /// the same bytes, `Kernel::same_bytes`, which a checkpoint checks).
    pub fn resume(
        inputs: Phase2Inputs<'a, E>,
        settings: &GoalConditioned,
        state: GoalConditionedState,
    ) -> Result<Self> {
        let mut run = GoalConditionedRun::start(inputs, settings)?;
        let refused = |why: &str| {
            Error::invalid(
                "goal-conditioned run state",
                format!("it does not fit this run ({why}): it is another run's"),
            )
        };
        let p: Moving<E::State> = postcard::from_bytes(&state.progress)
            .map_err(|e| refused(&format!("it does not decode: {e}")))?;
        let (env, m) = (run.inputs.env, run.sub.len());
        let e = &p.episode;
        let fits = p.her.same_shape(&run.p.her)
            && p.curriculum.fits(m)
            && e.start < m
            && e.aim < m
            && e.obs.len() == env.obs_dim()
            && e.final_goal.len() == run.goals.goal_dim();
        if !fits {
            return Err(refused("other sizes or sub-goals"));
        }
        let adds_up = [state.steps.train, state.steps.test]
            .into_iter()
            .try_fold(run.ledger.spent, u64::checked_add);
        if adds_up != Some(state.spent) {
            return Err(refused("its env steps do not add up"));
        }
        let kernel = run.learner.kernel();
        run.learner.restore_state(&state.learner)?;
        run.learner.set_kernel(kernel);
        run.ledger.spent = state.spent;
        run.ledger.steps = state.steps;
        run.ledger.earlier_seconds = state.trace.last().map_or(0.0, |r| r.seconds);
        run.ledger.trace = state.trace;
        run.p = p;
        Ok(run)
    }

    /// The chain of the learner's current policy.
    fn chain(&self) -> SkillChain {
        let policy = self.learner.policy();
        let radius = self.settings.radius;
        let (goal, view) = (&self.task_goal, self.view.as_ref());
        self.sub
            .chain(&self.inputs, radius, goal, view, policy.as_ref())
    }

    /// A new episode: its start drawn, its state B_ε(τ_{k_j}) (at j = 0 with
    /// `phase2.first_starts = "drawn"`, the environment's own draw), its goal drawn where
    /// `phase2.last_goal = "drawn"`.
    fn begin(&mut self) -> Episode<E::State> {
        let (env, config) = (self.inputs.env, self.inputs.config());
        let j = self
            .p
            .curriculum
            .draw(self.settings.curriculum, &mut self.p.starts);
        let at = &self.inputs.tau[self.sub.start_index(j)];
        let state = start_state(&self.inputs, &self.settings, j, at, &mut self.p.starts);
        let state = match (config.last_goal, env.drawn_goals()) {
            (LastGoal::Drawn, Some(d)) => d.with_drawn_goal(&state, &mut self.p.starts),
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
    /// sub-goal), overshoot to the next sub-goal (or end there: `overshoot = false`), learn.
    /// `true` when the episode has ended.
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
        let fallen = self.settings.end_on_failure && !env.archivable(&step.state);
        let failed = (step.terminal && !success) || fallen;
        let chained = (reached && self.settings.value_chaining)
            .then(|| self.goal(episode, episode.aim + 1).to_vec());
        let (rew, done) = match (success || reached, chained.is_some()) {
            (true, true) => (1.0, false),
            (true, false) => (1.0, true),
            (false, _) if fallen => (self.settings.failure_reward, failed),
            (false, _) => (0.0, failed),
        };
        let desired = self.goal(episode, episode.aim).to_vec();
        self.p.her.push(GoalTransition {
            obs: &episode.obs,
            act: &action,
            rew,
            next_obs: &next_obs,
            done,
            desired: &desired,
            achieved_next: &achieved,
            rest: if fallen && !reached && !success {
                self.settings.failure_reward
            } else {
                0.0
            },
            chained: chained.as_deref(),
        });
        self.ledger.charge(StepCounts { train: 1, test: 0 });
        episode.on_goal += 1;
        let out_of_time = !reached && episode.on_goal >= self.settings.steps_per_goal;
        let ended = success || failed || out_of_time || (reached && !self.settings.overshoot);
        self.tally(episode, success, reached, ended);
        if reached {
            episode.aim += 1;
            episode.on_goal = 0;
        }
        if ended {
            self.p.her.end_episode();
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
                .map(|_| self.p.noise.random_range(-1.0..=1.0))
                .collect();
        }
        let mut input = episode.obs.clone();
        if let Some(view) = &self.view {
            view.observation(&episode.obs, &mut input);
        }
        let goal = self.goal(episode, episode.aim);
        input.extend(goal.iter().zip(&episode.obs).map(|(g, x)| g - x));
        self.learner
            .explore(&input, &[0], &mut self.p.noise)
            .to_vec()
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
        self.p.round.0 += 1;
        self.p.round.1 += usize::from(won);
        self.p.curriculum.record(&self.settings, episode.start, won);
    }

    /// `updates_per_step` updates, each on a batch of real and relabelled transitions, the
    /// networks seeing each goal minus the position, once an episode has ended and
    /// `learning_starts` have passed.
    fn learn(&mut self) {
        if self.ledger.steps.train < self.settings.learning_starts {
            return;
        }
        let radius = self.settings.radius;
        let reached = |a: &[f32], g: &[f32]| dist(a, g) <= radius;
        let n = self.learner.batch_size();
        for _ in 0..self.settings.updates_per_step {
            let p = &mut self.p;
            if !p
                .her
                .sample_reaching(n, &mut p.replay, &reached, &mut p.batch)
            {
                return;
            }
            let (o, g) = (self.inputs.env.obs_dim(), self.goals.goal_dim());
            match self.settings.reward {
                GoalReward::Sparse => {}
                GoalReward::Shaped => super::shape_rewards(&mut p.batch, o, g, radius),
                GoalReward::Progress => super::progress_rewards(&mut p.batch, o, g),
            }
            super::goal_minus_position(&mut p.batch, o, g);
            if let Some(view) = &self.view {
                view.observe_rows(&mut p.batch.obs, o + g);
                view.observe_rows(&mut p.batch.next_obs, o + g);
            }
            self.learner.update(&p.batch);
        }
    }

    /// Writes this round's training row (the fraction of its tries that succeeded).
    fn record_round(&mut self, progress: &mut dyn FnMut(usize, Progress)) {
        let (tries, wins) = std::mem::take(&mut self.p.round);
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
            Curriculum::Backplay => self.sub.start_index(self.p.curriculum.frontier()),
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
            self.ledger.charge(StepCounts {
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
