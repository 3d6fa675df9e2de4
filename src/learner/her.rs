//! Hindsight experience replay (Andrychowicz et al. 2017) as Stable-Baselines3's
//! `HerReplayBuffer` does it.
//!
//! Episodes are stored whole, each transition with the goal the episode aimed at and the goal its
//! next observation achieved ([`crate::env::Goals`]). Only finished episodes are sampled. Of a
//! mini-batch of n, the first n − ⌊n·(1 − 1/(k + 1))⌋ transitions keep their goal and reward;
//! each of the others gets a goal achieved later in its own episode (`future`: the next
//! observation's achieved goal at a step drawn uniformly from the transition's own to the
//! episode's last; `final`: the last one's; `episode`: any step of it) and the reward the
//! environment's own rule gives for it ([`crate::env::Goals::goal_reward`], plus the part of the
//! stored reward that is not the goal's: the maze's −1 on a wall). The stored end of episode is
//! kept (Stable-Baselines3 keeps `done` too). The networks see the observation followed by the
//! goal. When the ring overwrites the first transition of an old episode, the rest of that
//! episode stops being sampled.
//!
//! ```
//! use pbcs::learner::her::{GoalTransition, HerConfig, HerReplay};
//! use pbcs::learner::replay::Batch;
//! use pbcs::rng::{Seeds, Stream};
//! // A 1-D goal space: the goal is the observation; reward 1 exactly at the goal.
//! let reward = |achieved: &[f32], desired: &[f32]| f32::from(u8::from(achieved == desired));
//! let mut her = HerReplay::new(100, 1, 1, 1, HerConfig::default());
//! for t in 0..3 {
//!     let (obs, next) = ([t as f32], [t as f32 + 1.0]);
//!     // Aiming at 10, never reached: every stored reward is 0.
//!     her.push(GoalTransition { obs: &obs, act: &[1.0], rew: 0.0, next_obs: &next, done: false,
//!                               desired: &[10.0], achieved_next: &next, rest: 0.0, chained: None });
//! }
//! assert_eq!(her.sampleable(), 0); // the episode is not over
//! her.end_episode();
//! let mut batch = Batch::default();
//! assert!(her.sample(50, &mut Seeds::new(0).stream(Stream::Replay), &reward, &mut batch));
//! // 10 real rows (goal 10, reward 0), 40 relabelled with goals the episode reached.
//! assert!(batch.obs.chunks(2).take(10).all(|r| r[1] == 10.0));
//! assert!(batch.obs.chunks(2).skip(10).all(|r| r[1] > r[0] && r[1] <= 3.0));
//! assert!(batch.rew.iter().skip(10).any(|&r| r == 1.0));
//! ```

use super::replay::Batch;
use crate::error::{Error, Result};
use crate::rng::Rng;
use crate::validate::Check;
use rand::Rng as _;
use serde::{Deserialize, Serialize};

/// Which achieved goal a relabelled transition gets.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GoalSelection {
    /// One achieved at a step from the transition's own to the episode's last.
    Future,
    /// The one achieved at the episode's last step.
    Final,
    /// One achieved at any step of the episode.
    Episode,
}

/// HER's settings (`[train.her]`): Stable-Baselines3's defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HerConfig {
    /// k: virtual goals per real transition; a sampled transition is relabelled with
    /// probability 1 − 1/(k + 1).
    pub n_sampled_goal: usize,
    /// Where the new goals come from.
    pub goal_selection_strategy: GoalSelection,
    /// The frame in which the networks see the goal (ours; absent from a written job when
    /// `world`, Stable-Baselines3's).
    #[serde(skip_serializing_if = "GoalFrame::is_world")]
    pub goal_frame: GoalFrame,
}

/// How the networks of a goal-conditioned run see the goal (`[train.her] goal_frame`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GoalFrame {
    /// The observation followed by the goal, as the environment gives them (Stable-Baselines3).
    #[default]
    World,
    /// Seen from the body: the environment rewrites each input (observation then goal) by
    /// [`crate::env::Goals::body_frame`], for an environment with a body (AntMaze: the goal
    /// from the torso, turned by its heading, and from its position).
    Body,
}

impl GoalFrame {
    /// Whether this is Stable-Baselines3's frame (the default).
    pub fn is_world(&self) -> bool {
        *self == GoalFrame::World
    }
}

impl Default for HerConfig {
    fn default() -> Self {
        HerConfig {
            n_sampled_goal: 4,
            goal_selection_strategy: GoalSelection::Future,
            goal_frame: GoalFrame::World,
        }
    }
}

impl Check for HerConfig {
    fn check(&self) -> Result<()> {
        if self.n_sampled_goal == 0 {
            return Err(Error::invalid(
                "train.her.n_sampled_goal",
                "must be at least 1 (0 relabels nothing: leave [train.her] out)",
            ));
        }
        crate::validate::at_most(
            "train.her.n_sampled_goal",
            self.n_sampled_goal as u64,
            crate::validate::bounds::SAMPLES,
        )
    }
}

impl HerConfig {
    /// How many of a batch of `n` are relabelled: ⌊n·(1 − 1/(k + 1))⌋, as SB3's
    /// `int(her_ratio * batch_size)`.
    pub fn virtual_count(&self, n: usize) -> usize {
        self.relabelling().virtual_count(n)
    }

    fn relabelling(&self) -> Relabelling {
        Relabelling {
            n_sampled_goal: self.n_sampled_goal,
            goal_selection_strategy: self.goal_selection_strategy,
        }
    }
}

impl Relabelling {
    /// [`HerConfig::virtual_count`].
    fn virtual_count(&self, n: usize) -> usize {
        let ratio = 1.0 - 1.0 / (self.n_sampled_goal as f64 + 1.0);
        (ratio * n as f64) as usize
    }
}

/// What a [`HerReplay`] keeps of its [`HerConfig`]: the settings that relabel. A vanilla run's
/// checkpoint (postcard, fields in order, no names) saves it, in the layout `HerConfig` had
/// before `goal_frame` (the networks' business, not the buffer's), so that checkpoints saved
/// before it still resume.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct Relabelling {
    n_sampled_goal: usize,
    goal_selection_strategy: GoalSelection,
}

/// How a relabelled transition is rewarded and ended: `(achieved, goal, rest, stored end)` to
/// `(reward, end)`.
type Relabel<'f> = dyn Fn(&[f32], &[f32], f32, f32) -> (f32, f32) + 'f;

/// Whole episodes of transitions with their goals, sampled with relabelled goals.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct HerReplay {
    /// The settings that relabel (checkpoints keep this layout: [`Relabelling`]).
    config: Relabelling,
    capacity: usize,
    obs_dim: usize,
    act_dim: usize,
    goal_dim: usize,
    /// Per transition: s, a, r, s', done, desired goal, the goal its own target bootstraps
    /// through (the desired one but with value chaining), goal achieved in s', the reward's
    /// part that is not the goal's.
    rows: Vec<f32>,
    /// Per transition: where its episode began (ring index).
    ep_start: Vec<usize>,
    /// Per transition: its episode's length once the episode ended, 0 before (or once the ring
    /// overwrote the episode's beginning).
    ep_len: Vec<usize>,
    /// Transitions written (≤ capacity).
    len: usize,
    /// The next index to write.
    next: usize,
    /// The episode being written: its first index and length.
    current: (usize, usize),
    /// Transitions with `ep_len > 0`.
    sampleable: usize,
    /// Scratch: the goal a relabelled transition gets.
    goal: Vec<f32>,
}

/// One transition as [`HerReplay::push`] stores it.
#[derive(Debug, Clone, Copy)]
pub struct GoalTransition<'t> {
    /// s.
    pub obs: &'t [f32],
    /// a.
    pub act: &'t [f32],
    /// r.
    pub rew: f32,
    /// s′.
    pub next_obs: &'t [f32],
    /// Whether s′ is terminal.
    pub done: bool,
    /// The episode's goal.
    pub desired: &'t [f32],
    /// The goal s′ achieved.
    pub achieved_next: &'t [f32],
    /// The part of r that is not the goal's (a relabelled transition keeps it).
    pub rest: f32,
    /// The goal this transition's own target bootstraps through, when it is not `desired`:
    /// value chaining's next sub-goal at a step that reached its own
    /// ([`crate::phase2::goal_conditioned`]). A relabelled copy bootstraps through its new
    /// goal, as every relabelled transition does. `None`: `desired`.
    pub chained: Option<&'t [f32]>,
}

impl HerReplay {
    /// An empty buffer of `capacity` transitions.
    pub fn new(
        capacity: usize,
        obs_dim: usize,
        act_dim: usize,
        goal_dim: usize,
        config: HerConfig,
    ) -> Self {
        HerReplay {
            config: config.relabelling(),
            capacity,
            obs_dim,
            act_dim,
            goal_dim,
            rows: Vec::new(),
            ep_start: Vec::new(),
            ep_len: Vec::new(),
            len: 0,
            next: 0,
            current: (0, 0),
            sampleable: 0,
            goal: vec![0.0; goal_dim],
        }
    }

    fn width(&self) -> usize {
        2 * self.obs_dim + self.act_dim + 3 + 3 * self.goal_dim
    }

    /// Whether `other` holds transitions of this buffer's sizes and capacity (a checkpoint's
    /// buffer is checked against the run's before it replaces it).
    pub fn same_shape(&self, other: &HerReplay) -> bool {
        let sizes = |h: &HerReplay| (h.capacity, h.obs_dim, h.act_dim, h.goal_dim);
        let whole = |h: &HerReplay| {
            let (start, written) = h.current;
            h.rows.len() == h.len * h.width()
                && h.ep_start.len() == h.len
                && h.ep_len.len() == h.len
                && h.len <= h.capacity
                && h.next < h.capacity.max(1)
                && (h.len == h.capacity || h.next == h.len)
                && h.goal.len() == h.goal_dim
                && start < h.capacity.max(1)
                && written <= h.capacity
                && h.sampleable <= h.len
                && h.ep_start.iter().all(|&s| s < h.capacity)
                && h.ep_len.iter().all(|&l| l <= h.capacity)
                && h.sampleable == h.ep_len.iter().filter(|&&l| l > 0).count()
        };
        sizes(self) == sizes(other) && whole(other)
    }

    /// Transitions that can be sampled (those of finished episodes still whole in the ring).
    pub fn sampleable(&self) -> usize {
        self.sampleable
    }

    /// Stores one transition of the current episode.
    pub fn push(&mut self, t: GoalTransition<'_>) {
        let GoalTransition {
            obs,
            act,
            rew,
            next_obs,
            done,
            desired,
            achieved_next,
            rest,
            chained,
        } = t;
        let w = self.width();
        let i = self.next;
        // Overwriting a finished episode (the ring writes in order: at its first transition):
        // the rest of it is not whole any more and stops being sampled.
        if i < self.len && self.ep_len[i] > 0 {
            let (start, len) = (self.ep_start[i], self.ep_len[i]);
            let left = len - (i + self.capacity - start) % self.capacity;
            for t in 0..left {
                self.ep_len[(i + t) % self.capacity] = 0;
            }
            self.sampleable -= left;
        }
        let row = [
            obs,
            act,
            &[rew],
            next_obs,
            &[f32::from(u8::from(done))],
            desired,
            chained.unwrap_or(desired),
            achieved_next,
            &[rest],
        ]
        .concat();
        debug_assert_eq!(row.len(), w);
        if i == self.len {
            self.rows.extend_from_slice(&row);
            self.ep_start.push(self.current.0);
            self.ep_len.push(0);
            self.len += 1;
        } else {
            self.rows[i * w..(i + 1) * w].copy_from_slice(&row);
            self.ep_start[i] = self.current.0;
            self.ep_len[i] = 0;
        }
        self.next = (i + 1) % self.capacity;
        self.current.1 += 1;
    }

    /// Ends the current episode (a terminal step or the time limit): its transitions can be
    /// sampled from now on.
    ///
    /// # Panics
    /// If the episode is longer than the buffer (a job's check refuses a replay smaller than
    /// the episode limit).
    pub fn end_episode(&mut self) {
        let (start, len) = self.current;
        assert!(
            len <= self.capacity,
            "an episode longer than the HER buffer"
        );
        for t in 0..len {
            let j = (start + t) % self.capacity;
            self.ep_len[j] = len;
        }
        self.sampleable += len;
        self.current = (self.next, 0);
    }

    /// A mini-batch of `n` into `out` (observations and next observations followed by the
    /// goal), `reward(achieved, desired)` the environment's goal reward; `false` (and nothing
    /// written) while no episode has ended.
    pub fn sample(
        &mut self,
        n: usize,
        rng: &mut Rng,
        reward: &dyn Fn(&[f32], &[f32]) -> f32,
        out: &mut Batch,
    ) -> bool {
        let relabel = |achieved: &[f32], goal: &[f32], rest: f32, done: f32| {
            (reward(achieved, goal) + rest, done)
        };
        self.sample_with(n, rng, &relabel, out)
    }

    /// [`HerReplay::sample`] for a task that ends where its goal is reached (a goal-conditioned
    /// chain's sub-goals): a relabelled transition whose next observation `reached(achieved,
    /// goal)` gets reward 1 and ends there (its target does not bootstrap), any other its
    /// reward's part that is not the goal's (`rest`: 0, or a failure's penalty) and its stored
    /// end.
    ///
    /// ```
    /// use pbcs::learner::her::{GoalTransition, HerConfig, HerReplay};
    /// use pbcs::learner::replay::Batch;
    /// use pbcs::rng::{Seeds, Stream};
    /// let mut her = HerReplay::new(10, 1, 1, 1, HerConfig { n_sampled_goal: 1_000_000, ..HerConfig::default() });
    /// her.push(GoalTransition { obs: &[0.0], act: &[1.0], rew: 0.0, next_obs: &[1.0], done: false,
    ///                           desired: &[5.0], achieved_next: &[1.0], rest: 0.0, chained: None });
    /// her.end_episode();
    /// let mut batch = Batch::default();
    /// let reached = |a: &[f32], g: &[f32]| (a[0] - g[0]).abs() <= 0.1;
    /// assert!(her.sample_reaching(4, &mut Seeds::new(0).stream(Stream::Replay), &reached, &mut batch));
    /// // Every row relabelled with the goal its step achieved: reached, rewarded and ended.
    /// assert_eq!((batch.rew[3], batch.done[3], batch.next_obs[7]), (1.0, 1.0, 1.0));
    /// ```
    pub fn sample_reaching(
        &mut self,
        n: usize,
        rng: &mut Rng,
        reached: &dyn Fn(&[f32], &[f32]) -> bool,
        out: &mut Batch,
    ) -> bool {
        let relabel = |achieved: &[f32], goal: &[f32], rest: f32, done: f32| {
            if reached(achieved, goal) {
                (1.0, 1.0)
            } else {
                (rest, done)
            }
        };
        self.sample_with(n, rng, &relabel, out)
    }

    /// A mini-batch of `n`, a relabelled transition's reward and end given by
    /// `relabel(achieved, goal, rest, stored end)`.
    fn sample_with(
        &mut self,
        n: usize,
        rng: &mut Rng,
        relabel: &Relabel<'_>,
        out: &mut Batch,
    ) -> bool {
        if self.sampleable == 0 {
            return false;
        }
        let (o, a, g, w) = (self.obs_dim, self.act_dim, self.goal_dim, self.width());
        out.len = n;
        for v in [
            &mut out.obs,
            &mut out.act,
            &mut out.rew,
            &mut out.next_obs,
            &mut out.done,
        ] {
            v.clear();
        }
        let real = n - self.config.virtual_count(n);
        for k in 0..n {
            // Uniform over the sampleable transitions (rejection keeps it uniform).
            let i = loop {
                let i = rng.random_range(0..self.len);
                if self.ep_len[i] > 0 {
                    break i;
                }
            };
            let row = &self.rows[i * w..(i + 1) * w];
            let (s, rest) = row.split_at(o);
            let (act, rest) = rest.split_at(a);
            let (r, rest) = rest.split_at(1);
            let (s2, rest) = rest.split_at(o);
            let (done, rest) = rest.split_at(1);
            let (desired, rest) = rest.split_at(g);
            let (chained, rest) = rest.split_at(g);
            let (achieved, other) = rest.split_at(g);
            let goal_and_reward = if k < real {
                None
            } else {
                let (start, len) = (self.ep_start[i], self.ep_len[i]);
                let t = (i + self.capacity - start) % self.capacity;
                let t2 = match self.config.goal_selection_strategy {
                    GoalSelection::Future => rng.random_range(t..len),
                    GoalSelection::Final => len - 1,
                    GoalSelection::Episode => rng.random_range(0..len),
                };
                let j = (start + t2) % self.capacity;
                let at = j * w + 2 * o + a + 2 + 2 * g;
                self.goal.copy_from_slice(&self.rows[at..at + g]);
                Some(relabel(achieved, &self.goal, other[0], done[0]))
            };
            let (goal, next_goal) = match goal_and_reward {
                Some(_) => (&self.goal[..], &self.goal[..]),
                None => (desired, chained),
            };
            let (rew, end) = goal_and_reward.unwrap_or((r[0], done[0]));
            out.obs.extend(s.iter().chain(goal));
            out.act.extend_from_slice(act);
            out.rew.push(rew);
            out.next_obs.extend(s2.iter().chain(next_goal));
            out.done.push(end);
        }
        true
    }
}
