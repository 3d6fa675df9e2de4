//! The result of phase 2: a chain of skills — policies π_i with activation balls
//! A_i = B_ε(τ_{K_i}) — its execution (π_0 until the state enters A_1, then π_1, ...) and its
//! persistence (`manifest.toml` and one safetensors file per policy).

use super::goal::{weighted_dist, BallMetric};
use super::goal::{Goal, Inputs};
use crate::env::Env;
use crate::error::{Error, Result};
use crate::nn::kernel::Kernel;
use crate::policy::Policy;
use crate::rollout::{lockstep, Agent, Verdict};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A closed ball in observation space.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Ball {
    /// Centre.
    pub center: Vec<f32>,
    /// Radius.
    pub radius: f32,
    /// Weights of the distance ([`weighted_dist`]; empty: all 1, a ball in position;
    /// [`super::goal::BallMetric::weights`] with velocity).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub weights: Vec<f32>,
}

impl Ball {
    /// The ball of `radius` around `center`, in position (unit weights).
    pub fn new(center: Vec<f32>, radius: f32) -> Self {
        Ball {
            center,
            radius,
            weights: Vec::new(),
        }
    }

    /// The ball of `radius` around the observation `obs` of `env`, measured by `metric`.
    pub fn around<E: Env>(env: &E, obs: &[f32], radius: f32, metric: BallMetric) -> Self {
        Ball {
            center: metric.center(env, obs),
            radius,
            weights: metric.weights(env),
        }
    }

    /// Whether `obs` is in the ball (d ≤ radius, d in the ball's metric).
    pub fn contains(&self, obs: &[f32]) -> bool {
        weighted_dist(obs, &self.center, &self.weights) <= self.radius
    }
}

/// A skill: a policy and its activation set.
#[derive(Debug, Clone)]
pub struct Skill {
    /// π_i: any learner's actor ([`Policy`]).
    pub policy: Box<dyn Policy>,
    /// A_i = B_ε(τ_{K_i}).
    pub activation: Ball,
    /// K_i: the index on τ of the ball's centre.
    pub start_index: usize,
    /// The index on τ of the skill's target (the next skill's K, or N for the last one).
    pub target_index: usize,
    /// What π_i sees and emits (goal-relative observations, actions in [−1, 1]ᵈ).
    pub inputs: Inputs,
}

// By hand: a derived `PartialEq` cannot compare `Box<dyn Policy>` fields (rust-lang/rust#31740).
impl PartialEq for Skill {
    fn eq(&self, other: &Skill) -> bool {
        self.policy.same(other.policy.as_ref())
            && self.activation == other.activation
            && self.start_index == other.start_index
            && self.target_index == other.target_index
            && self.inputs == other.inputs
    }
}

/// A chain of skills in execution order.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SkillChain {
    /// π_0 … π_n with A_0 … A_n.
    pub skills: Vec<Skill>,
    /// The layer kernel the policies run on (not saved: [`SkillChain::load`] is told it).
    pub kernel: Kernel,
}

/// One execution of a chain.
#[derive(Debug, Clone, PartialEq)]
pub struct Rollout<S> {
    /// Visited states, start included.
    pub states: Vec<S>,
    /// Index of the skill that chose each action (one per step).
    pub skill_used: Vec<usize>,
    /// Whether the environment's reward was reached (with [`SkillChain::run_until`]'s target,
    /// whether that was).
    pub success: bool,
}

impl SkillChain {
    /// Executes the chain from `start`: π_0 until the state enters A_1, then π_1, and so on,
    /// until the environment's positive reward or `max_steps` steps. When a state lies in
    /// several later activation balls, the chain switches to the last of them (a skill that
    /// overshoots its goal into a later ball hands over there). Each skill sees its own
    /// [`Inputs`]. An empty chain takes no step.
    pub fn run<E: Env>(&self, env: &E, start: E::State, max_steps: usize) -> Rollout<E::State> {
        self.run_limited(env, start, max_steps, None)
    }

    /// [`SkillChain::run`], and with `per_skill = Some(m)` the episode also ends (a failure)
    /// when one skill has acted `m` times without handing over, or when a step does not move
    /// the state (a greedy chain on a pure step is then stuck for good): the limits of a
    /// skill's own tests, used by the chain's verification.
    pub fn run_limited<E: Env>(
        &self,
        env: &E,
        start: E::State,
        max_steps: usize,
        per_skill: Option<usize>,
    ) -> Rollout<E::State> {
        self.run_until(env, start, max_steps, per_skill, None)
    }

    /// [`SkillChain::run_limited`] with the episode's success decided by `target` (reached as
    /// [`Goal::reached`] decides) instead of the environment's reward, when one is given; a
    /// terminal step that does not reach it is then a failure. A hand-over lookahead
    /// ([`super::Ideas::lookahead`]) runs the skills found after a learning problem this way.
    pub fn run_until<E: Env>(
        &self,
        env: &E,
        start: E::State,
        max_steps: usize,
        per_skill: Option<usize>,
        target: Option<&Goal>,
    ) -> Rollout<E::State> {
        // The episode's goal, for a skill that sees where it stands from it.
        let goal = match (self.needs_goal(), env.goals()) {
            (true, Some(goals)) => {
                let mut g = vec![0.0; goals.goal_dim()];
                goals.desired_goal(&start, &mut g);
                Some(g)
            }
            _ => None,
        };
        let mut run = Execution {
            chain: self,
            goal,
            target,
            skill: 0,
            acted: 0,
            per_skill,
            obs: vec![0.0; env.obs_dim()],
            ws: crate::nn::Workspace::with_kernel(self.kernel),
            rollout: Rollout {
                states: vec![start.clone()],
                skill_used: Vec::new(),
                success: false,
            },
        };
        if self.skills.is_empty() || per_skill == Some(0) {
            return run.rollout;
        }
        let tally = lockstep(env, &mut run, vec![start], max_steps, |_| false);
        run.rollout.success = tally.successes == 1;
        run.rollout
    }

    /// The skill that acts at observation `raw` when skill `current` acted last: the last
    /// later skill whose activation ball contains `raw` (a skill that overshoots its goal into
    /// a later ball hands over there), else `current`. Start an execution with `current = 0`.
    ///
    /// ```
    /// use pbcs::phase2::{Ball, SkillChain};
    /// # use pbcs::phase2::{goal::Inputs, Skill};
    /// # use pbcs::nn::{Head, Mlp};
    /// # use pbcs::rng::{Seeds, Stream};
    /// # let skill = |c: [f32; 2]| Skill {
    /// #     policy: Box::new(Mlp::new(&[2, 2], Head::Linear, &mut Seeds::new(0).stream(Stream::Init))),
    /// #     activation: Ball::new(c.to_vec(), 0.1),
    /// #     start_index: 0, target_index: 1, inputs: Inputs::new(vec![0.0; 2], vec![1.0; 2]),
    /// # };
    /// // Three skills whose balls are centred at x = 0, 1 and 2.
    /// let chain = SkillChain { skills: vec![skill([0.0, 0.0]), skill([1.0, 0.0]), skill([2.0, 0.0])], ..Default::default() };
    /// assert_eq!(chain.active_skill(0, &[0.5, 0.0]), 0); // in no later ball: π_0 goes on
    /// assert_eq!(chain.active_skill(0, &[1.05, 0.0]), 1); // enters A_1
    /// assert_eq!(chain.active_skill(0, &[2.0, 0.0]), 2); // overshoots into A_2
    /// assert_eq!(chain.active_skill(2, &[1.0, 0.0]), 2); // never back to an earlier skill
    /// ```
    pub fn active_skill(&self, current: usize, raw: &[f32]) -> usize {
        (current + 1..self.skills.len())
            .rev()
            .find(|&j| self.skills[j].activation.contains(raw))
            .unwrap_or(current)
    }

    /// Skill `i`'s action at observation `raw`, in the environment's units, into `action`
    /// (`obs` is scratch space, resized to what π_i sees): π_i on what it sees
    /// ([`Inputs::observation`]), scaled back by [`Inputs::env_action`].
    pub fn act(
        &self,
        i: usize,
        raw: &[f32],
        obs: &mut Vec<f32>,
        action: &mut [f32],
        ws: &mut crate::nn::Workspace,
    ) {
        self.act_toward(i, raw, None, obs, action, ws);
    }

    /// [`SkillChain::act`] in an episode whose goal is `goal` (its
    /// [`crate::env::Goals::desired_goal`]), which a skill trained with
    /// `phase2.last_goal = "drawn"` sees its position relative to
    /// ([`Inputs::observation_toward`]; without a goal, relative to the task's own).
    pub fn act_toward(
        &self,
        i: usize,
        raw: &[f32],
        goal: Option<&[f32]>,
        obs: &mut Vec<f32>,
        action: &mut [f32],
        ws: &mut crate::nn::Workspace,
    ) {
        let skill = &self.skills[i];
        skill.inputs.observation_toward(raw, goal, obs);
        let a = skill.policy.act(obs, 1, ws);
        skill.inputs.env_action(a, action);
    }

    /// [`SkillChain::act_toward`] with the stochastic policy a SAC skill trained with: b ⊙
    /// tanh(μ + σ·ε) for the standard normal draws `eps` (one per action component,
    /// [`crate::learner::sac::SacPolicy::sample`]), in the environment's units. Refused for a
    /// skill that is not SAC's.
    pub fn sample_toward(
        &self,
        i: usize,
        raw: &[f32],
        goal: Option<&[f32]>,
        eps: &[f32],
        ws: &mut crate::nn::Workspace,
    ) -> Result<Vec<f32>> {
        let skill = &self.skills[i];
        let Some(pi) = skill
            .policy
            .as_any()
            .downcast_ref::<crate::learner::sac::SacPolicy>()
        else {
            return Err(Error::invalid(
                "noise",
                format!(
                    "skill {i} is a {} policy, which is deterministic: only SAC's skills sample",
                    skill.policy.kind()
                ),
            ));
        };
        if eps.len() != pi.action_dim() {
            return Err(Error::invalid(
                "noise",
                format!(
                    "{} draws for {} action components",
                    eps.len(),
                    pi.action_dim()
                ),
            ));
        }
        let (mut obs, mut action) = (Vec::new(), vec![0.0; pi.action_dim()]);
        skill.inputs.observation_toward(raw, goal, &mut obs);
        let a = pi.sample(&obs, eps, 1, ws);
        skill.inputs.env_action(a, &mut action);
        Ok(action)
    }

    /// `start` for one of this chain's episodes in `env`: given a goal drawn as the
    /// environment's reset draws it ([`crate::env::DrawGoals`]) when a skill aims at each
    /// episode's own ([`SkillChain::needs_goal`]); otherwise as it is, `rng` untouched.
    pub fn episode_start<E: Env>(
        &self,
        env: &E,
        start: E::State,
        rng: &mut crate::rng::Rng,
    ) -> E::State {
        match (self.needs_goal(), env.drawn_goals()) {
            (true, Some(d)) => d.with_drawn_goal(&start, rng),
            _ => start,
        }
    }

    /// Whether a skill sees its position relative to the episode's goal
    /// ([`Inputs::episode_goal`]): acting needs the goal ([`SkillChain::act_toward`]).
    pub fn needs_goal(&self) -> bool {
        self.skills.iter().any(|s| s.inputs.episode_goal)
    }

    /// Checks that the chain fits `env` (its manifest at `path`, named in errors): every
    /// policy takes the environment's observations and gives its actions, and a tanh policy's
    /// largest action (its bound times the skill's action scale) stays within the
    /// environment's bound (what training wrote: scale b with bound 1, or scale 1 with bound b).
    pub fn check_env<E: Env>(&self, env: &E, path: &Path) -> Result<()> {
        if let (true, None) = (self.needs_goal(), env.goals()) {
            return Err(Error::parse(
                path,
                "a skill sees its position relative to each episode's goal (episode_goal), \
                 and the environment has no goals (Env::goals)",
            ));
        }
        for (i, s) in self.skills.iter().enumerate() {
            let sizes = s.policy.sizes();
            let (input, output) = (s.policy.obs_dim(), s.policy.action_dim());
            let seen = env.obs_dim() + s.inputs.goal.len();
            if input != seen || output != env.action_dim() {
                let goal = match s.inputs.goal.len() {
                    0 => String::new(),
                    g => format!(" and a sub-goal of {g}"),
                };
                return Err(Error::parse(
                    path,
                    format!(
                        "skills[{i}].sizes: {sizes:?} takes {input} inputs and gives {output} \
                         actions, the environment has {} observations{goal} and {} actions",
                        env.obs_dim(),
                        env.action_dim()
                    ),
                ));
            }
            if !s.inputs.goal.is_empty() && s.inputs.goal.len() != env.position_dims() {
                return Err(Error::parse(
                    path,
                    format!(
                        "skills[{i}].goal: has {} values, the environment's position {}",
                        s.inputs.goal.len(),
                        env.position_dims()
                    ),
                ));
            }
            // A weighted ball measures the velocity too (BallMetric::PositionVelocity).
            let (velocity, what) = if s.activation.weights.is_empty() {
                (0, "position")
            } else {
                let dims = env.velocity_balls().map_or(0, |v| v.velocity_dims());
                (dims, "position and velocity")
            };
            let want = env.position_dims() + velocity;
            if s.activation.center.len() != want {
                return Err(Error::parse(
                    path,
                    format!(
                        "skills[{i}].center: has {} values, the environment's {what} {want}",
                        s.activation.center.len(),
                    ),
                ));
            }
            let bounds = s.policy.action_bounds();
            if !bounds.is_empty() {
                for (j, (scale, bound)) in s.inputs.action_scale.iter().zip(bounds).enumerate() {
                    let (reach, limit) = (scale * bound, env.action_bound(j));
                    if reach > limit * (1.0 + 1e-4) {
                        return Err(Error::parse(
                            path,
                            format!(
                                "skills[{i}].action_scale: {scale} times the policy's bound \
                                 {bound} gives actions up to {reach}, beyond the environment's \
                                 bound {limit}"
                            ),
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

/// One execution of a chain ([`SkillChain::run_limited`]) as an agent: the active skill acts,
/// a later skill whose ball the state enters takes over, and the states and the skill of each
/// step are recorded.
struct Execution<'c, S> {
    chain: &'c SkillChain,
    /// What the episode must reach ([`SkillChain::run_until`]); `None`: the environment's
    /// success.
    target: Option<&'c Goal>,
    /// The episode's goal, when a skill needs it ([`SkillChain::needs_goal`]).
    goal: Option<Vec<f32>>,
    /// The skill acting, and how many times it has acted since it took over.
    skill: usize,
    acted: usize,
    per_skill: Option<usize>,
    /// The acting skill's view of the observation.
    obs: Vec<f32>,
    ws: crate::nn::Workspace,
    rollout: Rollout<S>,
}

impl<E: Env> Agent<E> for Execution<'_, E::State> {
    fn act(&mut self, _lanes: &[usize], raw: &[f32], action: &mut [f32]) {
        let j = self.chain.active_skill(self.skill, raw);
        if j != self.skill {
            self.skill = j;
            self.acted = 0;
        }
        self.acted += 1;
        let goal = self.goal.as_deref();
        self.chain
            .act_toward(self.skill, raw, goal, &mut self.obs, action, &mut self.ws);
    }

    fn after(
        &mut self,
        _: usize,
        _: usize,
        state: &E::State,
        _: &[f32],
        step: &crate::env::Step<E::State>,
        next_raw: &[f32],
    ) -> Verdict {
        self.rollout.skill_used.push(self.skill);
        self.rollout.states.push(step.state.clone());
        match self.target {
            None if step.reward > 0.0 && step.terminal => return Verdict::Success,
            Some(t) if t.reached(next_raw, step.terminal, step.reward) => return Verdict::Success,
            Some(_) if step.terminal => return Verdict::Failure,
            _ => {}
        }
        let Some(m) = self.per_skill else {
            return Verdict::Running;
        };
        // With a per-skill limit, a step that does not move ends the episode (a greedy chain
        // on a pure step is stuck for good), and so does a skill about to act an m + 1-th
        // time without handing over.
        let stuck = step.state == *state;
        let spent = self.acted >= m && self.chain.active_skill(self.skill, next_raw) == self.skill;
        if stuck || spent {
            Verdict::Failure
        } else {
            Verdict::Running
        }
    }
}
