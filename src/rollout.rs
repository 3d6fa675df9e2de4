//! One rollout engine: episodes of an [`Agent`] on an [`Env`], many in lockstep (one batched
//! forward pass a step) or one at a time. Algorithm 3's training episodes and Backplay's
//! greedy tests (`phase2::task`), a chain's execution and verification
//! (`phase2::SkillChain::run`), the vanilla baselines' greedy evaluations and PBCS's
//! evaluation protocol all run through [`lockstep`]. Only the vanilla training loop keeps its
//! own: it runs a step budget across episodes (resets and evaluations between two steps of
//! one episode), not a set of episodes. (Phase 1 steps the environment too, with no policy:
//! random actions from archived states, and the straightening of τ.)
//!
//! An agent is the policy and whatever it does with what it meets: [`Agent::act`] gives the
//! actions of every running episode at once, [`Agent::after`] sees each step and says how its
//! episode stands (and may learn from it, count it or record it).
//!
//! ```
//! use pbcs::env::{Env, Step};
//! use pbcs::rollout::{lockstep, Agent, Tally, Verdict};
//! use pbcs::envs::toy::Toy1D;
//!
//! /// Always pushes left, towards the toy's target at 0 (five steps of 0.1 from its start);
//! /// an episode succeeds at the environment's positive reward.
//! struct Left;
//! impl Agent<Toy1D> for Left {
//!     fn act(&mut self, _lanes: &[usize], _obs: &[f32], actions: &mut [f32]) {
//!         actions.fill(-1.0);
//!     }
//!     fn after(&mut self, _j: usize, _lane: usize, _s: &f32, _o: &[f32], step: &Step<f32>,
//!              _next: &[f32]) -> Verdict {
//!         Verdict::of_terminal(step)
//!     }
//! }
//! let env = Toy1D;
//! let tally = lockstep(&env, &mut Left, vec![env.start(); 3], 100, |_| false);
//! assert_eq!(tally, Tally { successes: 3, failures: 0 });
//! // Too few steps to get there: neither a success nor a failure.
//! assert_eq!(lockstep(&env, &mut Left, vec![env.start()], 4, |_| false), Tally::default());
//! ```

use crate::env::{Env, Step};
use crate::learner::Learner;

/// How a step left its episode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// It goes on.
    Running,
    /// It ended reaching what it was after.
    Success,
    /// It ended without.
    Failure,
}

impl Verdict {
    /// The environment's own verdict: a terminal step ends the episode, a success when its
    /// reward is positive.
    pub fn of_terminal<S>(step: &Step<S>) -> Verdict {
        match (step.terminal, step.reward > 0.0) {
            (false, _) => Verdict::Running,
            (true, true) => Verdict::Success,
            (true, false) => Verdict::Failure,
        }
    }
}

/// A policy, and what it does with the steps it takes.
pub trait Agent<E: Env + ?Sized> {
    /// The environment actions of the running episodes: row j of `obs` (`E::obs_dim` wide) is
    /// the observation of episode `lanes[j]`, and its action goes in row j of `actions`
    /// (`E::action_dim` wide).
    fn act(&mut self, lanes: &[usize], obs: &[f32], actions: &mut [f32]);

    /// Episode `lane`, row `j` of the last [`Agent::act`], stepped from `state` (observed as
    /// `obs`) to `step` (observed as `next_obs`): how it stands now. Called for each running
    /// episode in row order after `act`.
    fn after(
        &mut self,
        j: usize,
        lane: usize,
        state: &E::State,
        obs: &[f32],
        step: &Step<E::State>,
        next_obs: &[f32],
    ) -> Verdict;
}

/// How the episodes of a [`lockstep`] ended (one still running at the step limit or at an
/// early stop is neither).
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub struct Tally {
    /// Episodes that ended in a success.
    pub successes: usize,
    /// Episodes that ended in a failure.
    pub failures: usize,
}

/// Runs one episode from each of `starts` in lockstep, at most `limit` steps each: every step,
/// the running episodes are observed, [`Agent::act`] gives all their actions at once, then
/// each episode steps and [`Agent::after`] judges it. Stops early once `stop` holds of the
/// tally after a step.
pub fn lockstep<E: Env + ?Sized, A: Agent<E> + ?Sized>(
    env: &E,
    agent: &mut A,
    mut states: Vec<E::State>,
    limit: usize,
    stop: impl Fn(Tally) -> bool,
) -> Tally {
    let (obs_dim, act_dim) = (env.obs_dim(), env.action_dim());
    let mut running: Vec<usize> = (0..states.len()).collect();
    let mut tally = Tally::default();
    let (mut obs, mut actions) = (Vec::new(), Vec::new());
    let mut next_obs = vec![0.0; obs_dim];
    for _ in 0..limit {
        if running.is_empty() {
            break;
        }
        obs.resize(obs_dim * running.len(), 0.0);
        actions.resize(act_dim * running.len(), 0.0);
        for (o, &lane) in obs.chunks_exact_mut(obs_dim).zip(&running) {
            env.observe(&states[lane], o);
        }
        agent.act(&running, &obs, &mut actions);
        let mut still = Vec::with_capacity(running.len());
        for (j, &lane) in running.iter().enumerate() {
            let step = env.step(&states[lane], &actions[j * act_dim..(j + 1) * act_dim]);
            env.observe(&step.state, &mut next_obs);
            let o = &obs[j * obs_dim..(j + 1) * obs_dim];
            let verdict = agent.after(j, lane, &states[lane], o, &step, &next_obs);
            states[lane] = step.state;
            match verdict {
                Verdict::Running => still.push(lane),
                Verdict::Success => tally.successes += 1,
                Verdict::Failure => tally.failures += 1,
            }
        }
        running = still;
        if stop(tally) {
            break;
        }
    }
    tally
}

/// A learner's greedy policy, its actions in [−1, 1]ᵈ scaled to the environment's bounds,
/// judged by the environment ([`Verdict::of_terminal`]); it adds up the reward and counts the
/// steps of what it runs. The vanilla baselines' evaluations.
pub struct Greedy<'a> {
    learner: &'a mut dyn Learner,
    bounds: Vec<f32>,
    /// A goal appended to every observation (a learner trained with HER), empty otherwise.
    pub goal: Vec<f32>,
    /// With a goal, the rewrite of each input into the body's frame
    /// ([`crate::env::Goals::body_frame`]), when the learner was trained so.
    pub frame: Option<fn(&mut [f32])>,
    input: Vec<f32>,
    /// Sum of the rewards met.
    pub reward: f32,
    /// Steps taken.
    pub steps: usize,
}

impl<'a> Greedy<'a> {
    /// `learner`'s greedy policy on `env`.
    pub fn new<E: Env + ?Sized>(env: &E, learner: &'a mut dyn Learner) -> Greedy<'a> {
        Greedy {
            learner,
            bounds: (0..env.action_dim()).map(|i| env.action_bound(i)).collect(),
            goal: Vec::new(),
            frame: None,
            input: Vec::new(),
            reward: 0.0,
            steps: 0,
        }
    }

    /// One episode from `start`, at most `max_steps` steps: whether it succeeded.
    pub fn episode<E: Env + ?Sized>(&mut self, env: &E, start: E::State, max_steps: usize) -> bool {
        lockstep(env, self, vec![start], max_steps, |_| false).successes == 1
    }
}

impl<E: Env + ?Sized> Agent<E> for Greedy<'_> {
    fn act(&mut self, lanes: &[usize], obs: &[f32], actions: &mut [f32]) {
        let obs = if self.goal.is_empty() {
            obs
        } else {
            self.input.clear();
            for row in obs.chunks(obs.len() / lanes.len()) {
                self.input.extend(row.iter().chain(&self.goal));
            }
            if let Some(frame) = self.frame {
                let width = self.input.len() / lanes.len();
                self.input.chunks_mut(width).for_each(frame);
            }
            &self.input
        };
        let a = self.learner.act(obs, lanes.len());
        for (row, out) in a
            .chunks(self.bounds.len())
            .zip(actions.chunks_mut(self.bounds.len()))
        {
            scale(row, &self.bounds, out);
        }
    }

    fn after(
        &mut self,
        _: usize,
        _: usize,
        _: &E::State,
        _: &[f32],
        step: &Step<E::State>,
        _: &[f32],
    ) -> Verdict {
        self.reward += step.reward;
        self.steps += 1;
        Verdict::of_terminal(step)
    }
}

/// `out_i = a_i · b_i`: an action in [−1, 1]ᵈ scaled to the bounds `b`.
#[inline]
pub fn scale(a: &[f32], b: &[f32], out: &mut [f32]) {
    for ((o, x), b) in out.iter_mut().zip(a).zip(b) {
        *o = x * b;
    }
}
