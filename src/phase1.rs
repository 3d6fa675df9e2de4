//! Phase 1: explore until solved (the paper's appendix algorithm "Exploration algorithm").
//!
//! An [`Archive`] keeps every visited non-terminal state, grouped in square bins of side 0.05
//! (over the position part of the observation, [`Env::position`]).
//! Each bin has a usage counter c_b and each state a usage counter c_s, all starting at 0.
//! One iteration:
//!
//! 1. pick the non-empty bin with the lowest c_b, then the state of that bin with the lowest
//!    c_s, ties broken uniformly at random; increment both counters;
//! 2. reset the environment to that state (free here: [`Env::step`] is pure);
//! 3. take one uniformly random action;
//! 4. add s' to the archive, with the selected state as its parent, unless it is terminal (or
//!    equal to the selected state, i.e. the step was blocked: it is already present, or one
//!    the environment does not let the archive keep, [`Env::archivable`]);
//! 5. as soon as a positive reward is received, rebuild τ_0 … τ_N by following parents from
//!    the rewarded state back to s_0.
//!
//! Both selections are O(1) whatever the archive's size: [`LeastUsed`] keeps items grouped by
//! usage count, so "uniform among the least used" is one index into the lowest group.

use crate::env::{random_action, Env};
use crate::error::{Error, Result};
use crate::rng::Rng;
use crate::validate::{positive_finite, Check};
use rand::Rng as _;
use rustc_hash::FxHashMap;
use serde::{Deserialize, Serialize};

/// Phase 1 (appendix algorithm "Exploration algorithm").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExploreConfig {
    /// Side of the square state-space bins of the archive (0.05 in the paper).
    pub bin_side: f32,
    /// Budget of environment steps in all; phase 1 fails with an error if the reward is not
    /// found within it. (The paper runs until the reward is found.) Called `max_steps` before
    /// (still read, so stored configs compare equal); `phase2.max_steps` is a different thing,
    /// the length limit of one Backplay episode.
    #[serde(alias = "max_steps")]
    pub budget: u64,
    /// Env steps one random action is held for (1, the paper's: one step per iteration). Each
    /// state the held action reaches is archived, its parent the one before, until the hold
    /// ends or a step is blocked, terminal or not archivable. Left out of written jobs at 1.
    #[serde(skip_serializing_if = "is_one")]
    pub hold: u32,
}

fn is_one(hold: &u32) -> bool {
    *hold == 1
}

impl Default for ExploreConfig {
    fn default() -> Self {
        ExploreConfig {
            bin_side: 0.05,
            budget: 100_000_000,
            hold: 1,
        }
    }
}

impl Check for ExploreConfig {
    fn check(&self) -> Result<()> {
        positive_finite("explore.bin_side", self.bin_side, 1.0)?;
        let budget = crate::validate::bounds::ENV_STEPS;
        crate::validate::count("explore.budget", self.budget, budget)?;
        if self.hold == 0 {
            return Err(Error::invalid(
                "explore.hold",
                "must be at least 1 (env steps)",
            ));
        }
        Ok(())
    }
}

/// Items `0..len` with usage counters, answering "a uniformly random item among the least
/// used" in O(1), and incrementing a counter in O(1).
///
/// Items are kept in `levels[count]`; `pos[item]` is the item's index in its level, so an item
/// moves to the next level by a swap-remove. Counters only grow by one and new items enter at
/// 0, so the lowest non-empty level is tracked without search.
#[derive(Debug, Clone, Default)]
pub struct LeastUsed {
    count: Vec<u32>,
    pos: Vec<u32>,
    levels: Vec<Vec<u32>>,
    min: usize,
}

impl LeastUsed {
    /// Adds an item with counter 0 and returns its index.
    pub fn push(&mut self) -> u32 {
        let item = self.count.len() as u32;
        if self.levels.is_empty() {
            self.levels.push(Vec::new());
        }
        self.count.push(0);
        self.pos.push(self.levels[0].len() as u32);
        self.levels[0].push(item);
        self.min = 0;
        item
    }

    /// Number of items.
    pub fn len(&self) -> usize {
        self.count.len()
    }

    /// Whether there is no item.
    pub fn is_empty(&self) -> bool {
        self.count.is_empty()
    }

    /// Usage counter of `item`.
    pub fn count(&self, item: u32) -> u32 {
        self.count[item as usize]
    }

    /// The lowest counter (`None` when empty).
    pub fn min_count(&self) -> Option<u32> {
        (!self.is_empty()).then_some(self.min as u32)
    }

    /// A uniformly random item among those with the lowest counter. Panics when empty.
    #[inline]
    pub fn pick(&self, rng: &mut Rng) -> u32 {
        let level = &self.levels[self.min];
        level[rng.random_range(0..level.len())]
    }

    /// Increments the counter of `item`.
    #[inline]
    pub fn increment(&mut self, item: u32) {
        let c = self.count[item as usize] as usize;
        let p = self.pos[item as usize] as usize;
        let level = &mut self.levels[c];
        level.swap_remove(p);
        if let Some(&moved) = level.get(p) {
            self.pos[moved as usize] = p as u32;
        }
        let level_was_empty = level.is_empty();
        if c + 1 == self.levels.len() {
            self.levels.push(Vec::new());
        }
        self.pos[item as usize] = self.levels[c + 1].len() as u32;
        self.levels[c + 1].push(item);
        self.count[item as usize] += 1;
        if c == self.min && level_was_empty {
            self.min += 1;
        }
    }
}

/// One archive bin: its states (global ids) and their usage counters c_s.
#[derive(Debug, Clone, Default)]
struct Bin {
    states: Vec<u32>,
    usage: LeastUsed,
}

/// The archive of phase 1: visited states, their parents, and the bins with their counters.
#[derive(Debug, Clone)]
pub struct Archive<S> {
    bin_side: f32,
    action_dim: usize,
    states: Vec<S>,
    /// Parent of each state (`u32::MAX` for s_0).
    parent: Vec<u32>,
    /// Action that led from the parent to each state (`action_dim` floats per state).
    actions: Vec<f32>,
    /// Bin of each state and the state's index inside that bin.
    state_bin: Vec<(u32, u32)>,
    bins: Vec<Bin>,
    bin_usage: LeastUsed,
    bin_of_key: FxHashMap<Box<[i32]>, u32>,
    key: Vec<i32>,
}

/// Parent id of the root state.
pub const NO_PARENT: u32 = u32::MAX;

impl<S: Clone> Archive<S> {
    /// An archive holding only `s0` (with observation `obs0`).
    pub fn new(s0: S, obs0: &[f32], action_dim: usize, bin_side: f32) -> Self {
        let mut archive = Archive {
            bin_side,
            action_dim,
            states: Vec::new(),
            parent: Vec::new(),
            actions: Vec::new(),
            state_bin: Vec::new(),
            bins: Vec::new(),
            bin_usage: LeastUsed::default(),
            bin_of_key: FxHashMap::default(),
            key: vec![0; obs0.len()],
        };
        archive.insert(s0, obs0, NO_PARENT, &vec![0.0; action_dim]);
        archive
    }

    /// Adds a state reached from `parent` by `action`; returns its id.
    pub fn insert(&mut self, state: S, obs: &[f32], parent: u32, action: &[f32]) -> u32 {
        for (k, o) in self.key.iter_mut().zip(obs) {
            *k = (o / self.bin_side).floor() as i32;
        }
        let bin = match self.bin_of_key.get(self.key.as_slice()) {
            Some(&b) => b,
            None => {
                let b = self.bin_usage.push();
                self.bins.push(Bin::default());
                self.bin_of_key
                    .insert(self.key.clone().into_boxed_slice(), b);
                b
            }
        };
        let id = self.states.len() as u32;
        let slot = self.bins[bin as usize].usage.push();
        self.bins[bin as usize].states.push(id);
        self.states.push(state);
        self.parent.push(parent);
        self.actions.extend_from_slice(action);
        self.state_bin.push((bin, slot));
        id
    }

    /// Selection step: the least-chosen bin, then its least-chosen state (uniform tie-breaks);
    /// increments both counters and returns the state's id.
    #[inline]
    pub fn select(&mut self, rng: &mut Rng) -> u32 {
        let bin = self.bin_usage.pick(rng);
        self.bin_usage.increment(bin);
        let b = &mut self.bins[bin as usize];
        let slot = b.usage.pick(rng);
        b.usage.increment(slot);
        b.states[slot as usize]
    }

    /// Number of states.
    pub fn len(&self) -> usize {
        self.states.len()
    }

    /// Whether the archive is empty (never, after [`Archive::new`]).
    pub fn is_empty(&self) -> bool {
        self.states.is_empty()
    }

    /// Number of non-empty bins.
    pub fn bins(&self) -> usize {
        self.bins.len()
    }

    /// Every state, by id (in the order visited).
    pub fn states(&self) -> &[S] {
        &self.states
    }

    /// State `id`.
    pub fn state(&self, id: u32) -> &S {
        &self.states[id as usize]
    }

    /// Parent of state `id` ([`NO_PARENT`] for s_0).
    pub fn parent(&self, id: u32) -> u32 {
        self.parent[id as usize]
    }

    /// Action that led to state `id` from its parent (zeros for s_0).
    pub fn action(&self, id: u32) -> &[f32] {
        let d = self.action_dim;
        &self.actions[id as usize * d..(id as usize + 1) * d]
    }

    /// Usage counter c_s of state `id` and counter c_b of its bin.
    pub fn usage(&self, id: u32) -> (u32, u32) {
        let (bin, slot) = self.state_bin[id as usize];
        (
            self.bins[bin as usize].usage.count(slot),
            self.bin_usage.count(bin),
        )
    }

    /// Ids from s_0 to `id`, following parents.
    pub fn path_to(&self, id: u32) -> Vec<u32> {
        let mut path = vec![id];
        let mut cur = id;
        while self.parent(cur) != NO_PARENT {
            cur = self.parent(cur);
            path.push(cur);
        }
        path.reverse();
        path
    }
}

/// A state-space trajectory τ_0 … τ_N with the actions between consecutive states.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory<S> {
    /// τ_0 … τ_N.
    pub states: Vec<S>,
    /// `actions[i]` led from τ_i to τ_{i+1} (N actions in all).
    pub actions: Vec<Vec<f32>>,
}

impl<S> Trajectory<S> {
    /// Number of states (N + 1).
    pub fn len(&self) -> usize {
        self.states.len()
    }

    /// Whether there is no state.
    pub fn is_empty(&self) -> bool {
        self.states.is_empty()
    }
}

/// The output of phase 1.
#[derive(Debug, Clone)]
pub struct Exploration<S> {
    /// τ_0 … τ_N, from s_0 to the first rewarded state.
    pub trajectory: Trajectory<S>,
    /// Environment steps used (one per iteration, or up to `hold`).
    pub env_steps: u64,
    /// The archive when the reward was found.
    pub archive: Archive<S>,
}

/// Runs phase 1 on `env` until the first positive reward, or fails after
/// `config.budget` steps. `progress(steps, archive_len)` is called every 65 536 steps.
///
/// ```
/// use pbcs::{config::{ExploreConfig, MazeConfig}, env::Env, phase1::explore, envs::maze::Maze};
/// use pbcs::rng::{Seeds, Stream};
///
/// let maze = Maze::new(&MazeConfig { size: 2, ..Default::default() }).unwrap();
/// let mut rng = Seeds::new(0).stream(Stream::Explore);
/// let found = explore(&maze, &ExploreConfig::default(), &mut rng, |_, _| {}).unwrap();
/// let tau = &found.trajectory.states;
/// assert_eq!(tau[0], maze.start());
/// assert!(maze.reached(tau.last().unwrap()));
/// ```
pub fn explore<E: Env>(
    env: &E,
    config: &ExploreConfig,
    rng: &mut Rng,
    mut progress: impl FnMut(u64, usize),
) -> Result<Exploration<E::State>> {
    let mut obs = vec![0.0; env.obs_dim()];
    let mut action = vec![0.0; env.action_dim()];
    let s0 = env.start();
    env.observe(&s0, &mut obs);
    let mut archive = Archive::new(s0, env.position(&obs), env.action_dim(), config.bin_side);
    let mut steps = 0;
    while steps < config.budget {
        let chosen = archive.select(rng);
        random_action(env, rng, &mut action);
        // The action held from the chosen state: each state it reaches archived after the last.
        let mut from = chosen;
        for _ in 0..config.hold {
            steps += 1;
            let step = env.step(archive.state(from), &action);
            if step.reward > 0.0 {
                let mut ids = archive.path_to(from);
                let mut states: Vec<E::State> =
                    ids.iter().map(|&i| archive.state(i).clone()).collect();
                let mut actions: Vec<Vec<f32>> =
                    ids.drain(1..).map(|i| archive.action(i).to_vec()).collect();
                states.push(step.state);
                actions.push(action);
                return Ok(Exploration {
                    trajectory: Trajectory { states, actions },
                    env_steps: steps,
                    archive,
                });
            }
            let ended =
                step.terminal || step.state == *archive.state(from) || !env.archivable(&step.state);
            if !ended {
                env.observe(&step.state, &mut obs);
                from = archive.insert(step.state, env.position(&obs), from, &action);
            }
            if steps % 65_536 == 0 {
                progress(steps, archive.len());
            }
            if ended || steps == config.budget {
                break;
            }
        }
    }
    Err(Error::ExplorationBudget {
        steps: config.budget,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::{Seeds, Stream};

    #[test]
    fn least_used_picks_only_among_minimum_and_tracks_it() {
        let mut lu = LeastUsed::default();
        let mut rng = Seeds::new(1).stream(Stream::Explore);
        for _ in 0..5 {
            lu.push();
        }
        // Each round of 5 picks must visit every item once: counters never differ by > 1.
        for round in 0..20 {
            let mut seen = [false; 5];
            for _ in 0..5 {
                let i = lu.pick(&mut rng);
                assert_eq!(lu.count(i), round, "picked an item that is not least used");
                assert!(!seen[i as usize]);
                seen[i as usize] = true;
                lu.increment(i);
            }
            assert_eq!(lu.min_count(), Some(round + 1));
        }
        // A new item enters at 0 and is the only candidate.
        let new = lu.push();
        assert_eq!(lu.min_count(), Some(0));
        assert_eq!(lu.pick(&mut rng), new);
    }

    #[test]
    fn least_used_ties_are_broken_uniformly() {
        // 4 tied items, 40 000 picks without incrementing: each should get about 10 000.
        // Under uniformity the count is Binomial(40000, 1/4): sd ≈ 86.6, and the bound
        // 10 000 ± 500 is > 5.7 sd, a false-failure probability below 1e-7.
        let mut lu = LeastUsed::default();
        for _ in 0..4 {
            lu.push();
        }
        let mut rng = Seeds::new(2).stream(Stream::Explore);
        let mut hits = [0u32; 4];
        for _ in 0..40_000 {
            hits[lu.pick(&mut rng) as usize] += 1;
        }
        for h in hits {
            assert!((9_500..=10_500).contains(&h), "{hits:?}");
        }
    }
}
