//! A second chaining strategy (`phase2.chain = "goal_conditioned"`): one goal-conditioned
//! learner for every sub-goal cut from τ, after DCIL-II (Chenu et al. 2022), instead of the
//! paper's separately trained skills. On a body (AntMaze) those do not hand over: each is
//! trained from τ_K's own joint state and the skill before it leaves the legs elsewhere. Here
//! hand-overs happen in training, because the same policy carries on through them.
//!
//! ```text
//! cut τ into sub-goals g_1 … g_M, ‖g_{i+1} − g_i‖ ≥ spacing in the goal space (g_M: the
//!     episode's own goal), each keeping τ's whole state s_i at its index
//! one learner π(s, g − position), Q(s, a, g − position), HER replay
//! repeat until a greedy test passes or the budget is spent:
//!     j ← the curriculum (failure-weighted, or Backplay's frontier);  s ← B_ε(s_j);  i ← j + 1
//!     until the final goal, a failure of the body, or steps_per_goal steps on g_i:
//!     (overshoot = false: also at g_i; end_on_failure = false: not at a failure)
//!         a ← π(s, g_i) + noise;  s′ ← step(s, a)
//!         if s′ reaches g_i, i < M:  store (s, g_i, a, r = 1, s′, g_{i+1}, not done)   value chaining
//!                                    i ← i + 1                                         overshoot
//!         else if s′ reaches g_M:    store (s, g_M, a, 1, s′, g_M, done)
//!         else:                      store (s, g_i, a, 0, s′, g_i, failed)
//!         update π, Q on a batch of real and relabelled transitions (updates_per_step times)
//! the chain: skill i = (π, A_i = B_radius(g_i), g_{i+1}), the last aiming at the episode's goal
//! ```
//!
//! The result is an ordinary [`SkillChain`]: its skills share one policy (one file in the saved
//! chain) and differ by the sub-goal they see ([`Inputs::goal`]); executing it gives the
//! policy each sub-goal in turn, as training did. Settings: [`GoalConditioned`].

mod curriculum;
mod run;
pub mod settings;

pub use run::{GoalConditionedRun, GoalConditionedState};
pub use settings::{ChainName, ChainStrategy, Curriculum, GoalConditioned, GoalReward};

use super::goal::{ball_center, dist, Inputs, REACHED_REWARD};
use super::{Ball, LastGoal, Phase2Inputs, Phase2Outcome, Progress, Skill, SkillChain};
use crate::env::{Env, Goals};
use crate::error::{Error, Result};
use crate::policy::Policy;

/// Phase 2 by the goal-conditioned strategy on τ = `inputs.tau`, with `settings`:
/// `progress(0, report)` after each training round and test.
pub fn chain_goal_conditioned<E: Env>(
    inputs: Phase2Inputs<'_, E>,
    settings: &GoalConditioned,
    progress: &mut dyn FnMut(usize, Progress),
) -> Result<Phase2Outcome> {
    Ok(GoalConditionedRun::start(inputs, settings)?.finish(progress))
}

/// Rewrites a HER batch (rows of an observation of `obs_dim` then a goal of `goal_dim`) into
/// what the goal-conditioned networks see: each goal minus the position, the observation's
/// first `goal_dim` numbers ([`Inputs::observation_toward`] at acting time).
pub fn goal_minus_position(
    batch: &mut crate::learner::replay::Batch,
    obs_dim: usize,
    goal_dim: usize,
) {
    for rows in [&mut batch.obs, &mut batch.next_obs] {
        for row in rows.chunks_mut(obs_dim + goal_dim) {
            let (seen, goal) = row.split_at_mut(obs_dim);
            for (g, x) in goal.iter_mut().zip(seen.iter()) {
                *g -= x;
            }
        }
    }
}

/// Rewrites a HER batch's sparse rewards (1 where the step reached the row's goal, else 0 or a
/// failure's penalty, which is never positive) into the paper's shaped ones
/// ([`GoalReward::Shaped`]): [`REACHED_REWARD`] where it reached, else the penalty plus
/// Φ(s′) − Φ(s), Φ = 1 / max(d(position, g), `radius`), g the goal of the row's observation
/// (the one the step aimed at: a value-chained row's next goal is the following sub-goal's).
/// Call it before [`goal_minus_position`], on rows of an observation of `obs_dim` whose first
/// `goal_dim` numbers are the position, then the goal.
///
/// ```
/// use pbcs::learner::replay::Batch;
/// use pbcs::phase2::goal_conditioned::shape_rewards;
/// // One-dimensional position and goal: from 3 to 2 toward the goal 0, then a step reaching it.
/// let mut batch = Batch {
///     len: 2,
///     obs: vec![3.0, 0.0, 0.5, 0.0],
///     act: vec![0.0, 0.0],
///     rew: vec![0.0, 1.0],
///     next_obs: vec![2.0, 0.0, 0.05, 0.0],
///     done: vec![0.0, 1.0],
/// };
/// shape_rewards(&mut batch, 1, 1, 0.1);
/// assert_eq!(batch.rew, [1.0 / 2.0 - 1.0 / 3.0, 10.0]);
/// ```
pub fn shape_rewards(
    batch: &mut crate::learner::replay::Batch,
    obs_dim: usize,
    goal_dim: usize,
    radius: f32,
) {
    let potential = |position: &[f32], goal: &[f32]| 1.0 / dist(position, goal).max(radius);
    add_potential(batch, obs_dim, goal_dim, REACHED_REWARD, potential);
}

/// Rewrites a HER batch's sparse rewards as [`shape_rewards`] does, with the linear potential
/// Φ = −d(position, g) ([`GoalReward::Progress`]): where the step did not reach its row's goal,
/// the metres it came closer to it (negative where it went away), plus the penalty; where it
/// reached, 1 as before.
///
/// ```
/// use pbcs::learner::replay::Batch;
/// use pbcs::phase2::goal_conditioned::progress_rewards;
/// // From 3 to 2 toward the goal 0, from 1 back to 1.5, then a step reaching it.
/// let mut batch = Batch {
///     len: 3,
///     obs: vec![3.0, 0.0, 1.0, 0.0, 0.5, 0.0],
///     act: vec![0.0; 3],
///     rew: vec![0.0, 0.0, 1.0],
///     next_obs: vec![2.0, 0.0, 1.5, 0.0, 0.05, 0.0],
///     done: vec![0.0, 0.0, 1.0],
/// };
/// progress_rewards(&mut batch, 1, 1);
/// assert_eq!(batch.rew, [1.0, -0.5, 1.0]);
/// ```
pub fn progress_rewards(
    batch: &mut crate::learner::replay::Batch,
    obs_dim: usize,
    goal_dim: usize,
) {
    add_potential(batch, obs_dim, goal_dim, 1.0, |position, goal| {
        -dist(position, goal)
    });
}

/// Each row's reward: `reached` where the sparse one is 1, else it plus Φ(s′) − Φ(s), Φ the
/// `potential` of the position (the first `goal_dim` numbers) toward the row's goal.
fn add_potential(
    batch: &mut crate::learner::replay::Batch,
    obs_dim: usize,
    goal_dim: usize,
    reached: f32,
    potential: impl Fn(&[f32], &[f32]) -> f32,
) {
    let width = obs_dim + goal_dim;
    for ((row, next), rew) in batch
        .obs
        .chunks(width)
        .zip(batch.next_obs.chunks(width))
        .zip(batch.rew.iter_mut())
    {
        if *rew == 1.0 {
            *rew = reached;
            continue;
        }
        let goal = &row[obs_dim..];
        *rew += potential(&next[..goal_dim], goal) - potential(&row[..goal_dim], goal);
    }
}

/// The least σ of `phase2.goal_conditioned.normalise`: an observation number nearly constant
/// along τ is divided by this, not by its spread there.
pub const MIN_SCALE: f32 = 0.1;

/// The mean μ and standard deviation σ (at least [`MIN_SCALE`]) of each number of the
/// observations `obs` (computed in f64), what `phase2.goal_conditioned.normalise` divides by.
/// σ is the population's (over n, as Stable-Baselines3's `VecNormalize` keeps it), not
/// [`crate::stats::mean_sd`]'s sample deviation (over n − 1) of an interval's estimate.
///
/// ```
/// use pbcs::phase2::goal_conditioned::spread;
/// let (mu, sigma) = spread(&[vec![0.0, 5.0], vec![2.0, 5.0]]);
/// assert_eq!((mu, sigma), (vec![1.0, 5.0], vec![1.0, 0.1]));
/// ```
pub fn spread(obs: &[Vec<f32>]) -> (Vec<f32>, Vec<f32>) {
    let dim = obs.first().map_or(0, Vec::len);
    let n = obs.len().max(1) as f64;
    let mean: Vec<f64> = (0..dim)
        .map(|i| obs.iter().map(|o| f64::from(o[i])).sum::<f64>() / n)
        .collect();
    let sigma = (0..dim).map(|i| {
        let var = obs
            .iter()
            .map(|o| (f64::from(o[i]) - mean[i]).powi(2))
            .sum::<f64>()
            / n;
        (var.sqrt() as f32).max(MIN_SCALE)
    });
    let sigma = sigma.collect();
    (mean.into_iter().map(|m| m as f32).collect(), sigma)
}

/// The sub-goals cut from τ: their indices on τ and their points in the goal space.
#[derive(Debug, Clone, PartialEq)]
pub struct SubGoals {
    /// The index on τ of each sub-goal g_1 … g_M (increasing; the last is τ's end, N).
    pub at: Vec<usize>,
    /// g_1 … g_M: the goal τ achieves at each index (the last is replaced by each episode's
    /// own goal in training and in the chain).
    pub points: Vec<Vec<f32>>,
    /// The observations of τ.
    obs: Vec<Vec<f32>>,
}

impl SubGoals {
    /// Walks τ and cuts a sub-goal wherever the goal achieved lies `spacing` or more from the
    /// last one cut (the first from τ_0's), then at τ's end (which replaces a last cut within
    /// spacing / 2 of it). The goal space must be the position ([`Env::position`]): the chain's
    /// activation balls measure the position.
    ///
    /// ```
    /// use pbcs::envs::maze::{Maze, MazeConfig};
    /// use pbcs::env::Env;
    /// use pbcs::phase2::goal_conditioned::SubGoals;
    /// let maze = Maze::new(&MazeConfig { size: 2, ..MazeConfig::default() }).unwrap();
    /// // A straight τ from (0.5, 0.5), 0.1 a step to (0.5, 1.7), cut every 0.45.
    /// let tau: Vec<_> = (0..=12).map(|i| nalgebra::Point2::new(0.5, 0.5 + 0.1 * i as f32)).collect();
    /// let cut = SubGoals::cut(&maze, maze.goals().unwrap(), &tau, 0.45).unwrap();
    /// assert_eq!(cut.at, [5, 12]); // 0.5 from τ_0, then τ's end (τ_10, 0.2 from it, is dropped)
    /// ```
    pub fn cut<E: Env>(
        env: &E,
        goals: &dyn Goals<E::State>,
        tau: &[E::State],
        spacing: f32,
    ) -> Result<Self> {
        let obs = crate::env::observations(env, tau);
        let achieved: Vec<Vec<f32>> = obs
            .iter()
            .map(|o| {
                let mut g = vec![0.0; goals.goal_dim()];
                goals.achieved_goal(o, &mut g);
                g
            })
            .collect();
        if let Some(i) = (0..obs.len()).find(|&i| achieved[i] != env.position(&obs[i])) {
            return Err(Error::invalid(
                "phase2.chain",
                format!(
                    "\"goal_conditioned\" needs goals that are the position (Env::position): \
                     τ_{i} achieves {:?} at the position {:?}",
                    achieved[i],
                    env.position(&obs[i])
                ),
            ));
        }
        let n = obs.len() - 1;
        let mut at: Vec<usize> = Vec::new();
        for i in 1..n {
            let last = at.last().map_or(0, |&k| k);
            if dist(&achieved[i], &achieved[last]) >= spacing {
                at.push(i);
            }
        }
        if let Some(&k) = at.last() {
            if dist(&achieved[k], &achieved[n]) < spacing / 2.0 {
                at.pop();
            }
        }
        at.push(n);
        let points = at.iter().map(|&k| achieved[k].clone()).collect();
        Ok(SubGoals { at, points, obs })
    }

    /// The networks' view of observations with `phase2.goal_conditioned.normalise`: shifted
    /// and scaled by their [`spread`] along τ (its [`Inputs::observation`] and
    /// [`Inputs::observe_rows`]; the chain's skills take its shift and scale).
    pub fn normalised_view(&self) -> Inputs {
        let (mu, sigma) = spread(&self.obs);
        Inputs::new(Vec::new(), Vec::new()).scaled(mu, sigma)
    }

    /// M: how many sub-goals (the last is the final goal).
    pub fn len(&self) -> usize {
        self.at.len()
    }

    /// Whether there are none (never: τ's end is always one).
    pub fn is_empty(&self) -> bool {
        self.at.is_empty()
    }

    /// The index on τ where an episode starting at sub-goal `j` starts: τ_0 for j = 0, else
    /// the index of g_j (of `at[j − 1]`).
    pub fn start_index(&self, j: usize) -> usize {
        if j == 0 {
            0
        } else {
            self.at[j - 1]
        }
    }

    /// The chain that gives `policy` each sub-goal in turn: skill i aims at g_{i+1} and takes
    /// over in A_i = B_radius(g_i) (skill 0 in B_ε(τ_0)); the last sees the episode's own goal
    /// where `phase2.last_goal = "drawn"` draws one per episode, the task's `final_goal`
    /// otherwise; with `view` (`normalise`), each skill sees the observation as it does.
    pub(super) fn chain<E: Env>(
        &self,
        inputs: &Phase2Inputs<'_, E>,
        radius: f32,
        final_goal: &[f32],
        view: Option<&Inputs>,
        policy: &dyn Policy,
    ) -> SkillChain {
        let env = inputs.env;
        let config = inputs.config();
        let scale: Vec<f32> = (0..env.action_dim()).map(|i| env.action_bound(i)).collect();
        let m = self.len();
        let skills = (0..m)
            .map(|i| {
                let last = i + 1 == m;
                let aim = if last { final_goal } else { &self.points[i] };
                let start = self.start_index(i);
                let activation = match i {
                    0 => Ball::new(ball_center(env, &self.obs[0]), config.epsilon),
                    _ => Ball::new(self.points[i - 1].clone(), radius),
                };
                let episode_goal = last && config.last_goal == LastGoal::Drawn;
                let toward =
                    Inputs::toward_goal(env.obs_dim(), aim.to_vec(), episode_goal, scale.clone());
                Skill {
                    policy: policy.boxed(),
                    activation,
                    start_index: start,
                    target_index: self.at[i],
                    inputs: match view {
                        Some(v) => toward.scaled(v.origin.clone(), v.scale.clone()),
                        None => toward,
                    },
                }
            })
            .collect();
        SkillChain {
            skills,
            kernel: inputs.kernel,
        }
    }
}
