//! The environment interface: a pure step function with reset-anywhere.
//!
//! PBCS needs to reset the environment to any state (phase 1 resets to archived states,
//! Backplay to states near τ_K). Here that is free: [`Env::step`] is a pure function of
//! `(&State, action)`, as in gymnax, so "resetting" is just passing another state. Implement
//! this trait for your own environment to run phase 1 and phase 2 on it; PBCS's ball starts
//! (the presets' `phase2.start = "ball"`, and the evaluation's B_ε(s_0)), balls in position and
//! velocity (`phase2.velocity_scale`), clear balls and shortening need the hooks of
//! [`Capability`], which a setting refuses to run without.

use rand::Rng;
use serde::{Deserialize, Serialize};

/// The outcome of one environment step.
#[derive(Debug, Clone, PartialEq)]
pub struct Step<S> {
    /// The next state s'.
    pub state: S,
    /// The reward R(s, a, s').
    pub reward: f32,
    /// Whether s' ends the episode.
    pub terminal: bool,
}

/// An environment with continuous observations and actions and reset-anywhere.
///
/// Observations and actions are `f32` vectors of fixed length. The state is any cloneable
/// value; it must compare equal to itself so that phase 1 can recognise a step that did not
/// move.
pub trait Env {
    /// The full simulator state (a 2D point for the maze); serde's, so that a run's
    /// checkpoint holds it ([`crate::vanilla::resume`]).
    type State: Clone + PartialEq + std::fmt::Debug + Serialize + serde::de::DeserializeOwned;

    /// Length of the observation vector.
    fn obs_dim(&self) -> usize;

    /// Length of the action vector.
    fn action_dim(&self) -> usize;

    /// Bound `b_i` of the box action space: action component `i` lives in `[-b_i, b_i]`.
    fn action_bound(&self, i: usize) -> f32;

    /// The initial state s_0.
    fn start(&self) -> Self::State;

    /// A start state for a vanilla learner's training or evaluation episode: its start
    /// distribution, or [`Env::start`] for an environment whose episodes all start there
    /// (each environment says which: no default).
    fn sample_start(&self, rng: &mut crate::rng::Rng) -> Self::State;

    /// Backplay's starts in a ball ([`SampleBall`]), if this environment can make new states:
    /// return `Some(self)` from an environment that implements it. `None` (the default): the
    /// settings that need it (`phase2.start = "ball"` or `"archive"`, `phase2.chain_verify_episodes`, an
    /// evaluation ball of radius above 0) are refused with [`crate::error::Error::Capability`],
    /// never replaced by exact starts.
    fn ball_starts(&self) -> Option<&dyn SampleBall<Self::State>> {
        None
    }

    /// Balls in position and velocity ([`VelocityBalls`]), if this environment observes a
    /// velocity and can make states with a chosen one: `Some(self)` from one that implements
    /// it. Needed by `phase2.velocity_scale` above 0.
    fn velocity_balls(&self) -> Option<&dyn VelocityBalls<Self::State>> {
        None
    }

    /// Whether a ball touches anything that blocks ([`BallIsClear`]), if this environment
    /// knows: `Some(self)` from one that implements it. Needed by `phase2.stop_at_failure`.
    fn clear_balls(&self) -> Option<&dyn BallIsClear<Self::State>> {
        None
    }

    /// Short clear paths between two states ([`Connect`]), if this environment knows them:
    /// `Some(self)` from one that implements it. Needed by `phase2.shorten`.
    fn connector(&self) -> Option<&dyn Connect<Self::State>> {
        None
    }

    /// The environment's success region as a ball in observation space, `(centre, radius)`,
    /// if it has one (the maze: the target and its 0.2 radius). PBCS's last skill aims at it
    /// (`phase2.last_goal = "success_region"`, the presets'): its potential is measured to
    /// this centre, so that the last skill is paid for reaching the region the environment
    /// rewards and for nothing else. `None` (the default): that setting is refused
    /// ([`Capability::SuccessRegion`]); `phase2.last_goal = "ball"` aims at B_ε(τ_N) instead.
    fn success_region(&self) -> Option<(Vec<f32>, f32)> {
        None
    }

    /// The task as reaching a goal ([`Goals`]), for hindsight experience replay: `Some(self)`
    /// from an environment that implements it. Needed by `train.her`.
    fn goals(&self) -> Option<&dyn Goals<Self::State>> {
        None
    }

    /// Goals drawn as the environment's own reset draws them ([`DrawGoals`]): `Some(self)`
    /// from an environment that implements it. Needed by `phase2.last_goal = "drawn"`.
    fn drawn_goals(&self) -> Option<&dyn DrawGoals<Self::State>> {
        None
    }

    /// Starts drawn as the environment's own reset draws them ([`DrawStarts`]): `Some(self)`
    /// from an environment that implements it. Needed by `phase2.first_starts = "drawn"`.
    fn drawn_starts(&self) -> Option<&dyn DrawStarts<Self::State>> {
        None
    }

    /// Writes the observation of `state` into `out` (length [`Env::obs_dim`]).
    fn observe(&self, state: &Self::State, out: &mut [f32]);

    /// One step from `state` with `action`. Pure: the same inputs give the same output.
    fn step(&self, state: &Self::State, action: &[f32]) -> Step<Self::State>;

    /// How many leading components of the observation are the position: all of them by
    /// default (the maze's and the rooms' observations are positions), fewer for an
    /// environment that also observes velocities. Phase 1's archive bins on the position
    /// (over velocities too, nearly every state would have a bin of its own), and PBCS's balls
    /// measure it: the goals B_ε(τ_T), the activation sets A_i, the success region and τ's
    /// length for the path limits, reached or measured whatever the velocity (unless
    /// `phase2.velocity_scale` puts the velocity in the goals and activation sets,
    /// [`VelocityBalls`]).
    fn position_dims(&self) -> usize {
        self.obs_dim()
    }

    /// The position part of an observation `obs` ([`Env::position_dims`], at least one
    /// component).
    fn position<'o>(&self, obs: &'o [f32]) -> &'o [f32] {
        &obs[..self.position_dims().clamp(1, obs.len())]
    }

    /// How far one step can move the position ([`Env::position`]), which turns a path length
    /// into steps for PBCS's path limits (`phase2.path_limit`,
    /// `phase2.test_path_limit`): the action bound where an action is a displacement (the
    /// maze, the rooms), how far the fastest step goes where actions are forces. `None` (the
    /// default): those settings are refused ([`Capability::StepReach`]).
    fn step_reach(&self) -> Option<f32> {
        None
    }

    /// Whether phase 1 may keep this state in its archive (and so start from it again): every
    /// state by default. An environment says no to states no path should go through, which
    /// exploration would otherwise return to (AntMaze made with
    /// `AntMaze::refusing_flipped`: an ant on its back).
    fn archivable(&self, _state: &Self::State) -> bool {
        true
    }

    /// Column names of the observation, for CSV headers.
    fn obs_names(&self) -> Vec<String> {
        (0..self.obs_dim()).map(|i| format!("o{i}")).collect()
    }
}

/// A capability: states drawn uniformly from the ball of radius `radius` around `center` (in
/// observation space), Backplay's starts in B_ε(τ_K), usually states never visited. The state
/// may be one the agent cannot leave (inside a wall). An environment offers it through
/// [`Env::ball_starts`].
pub trait SampleBall<S> {
    /// One state uniform in the ball (as the environment defines "uniform", e.g. clamped to
    /// its bounds).
    fn sample_ball(&self, center: &S, radius: f32, rng: &mut crate::rng::Rng) -> S;
}

/// A capability: balls in position and velocity under the metric
/// d(s, c)² = ‖x − x_c‖² + λ²‖v − v_c‖² (λ, `phase2.velocity_scale`, in seconds: a velocity
/// difference of 1/λ weighs as much as a unit of distance), for an environment with momentum
/// whose observation holds a velocity right after its position. An environment offers it
/// through [`Env::velocity_balls`].
pub trait VelocityBalls<S> {
    /// How many observation components after the position ([`Env::position_dims`]) are its
    /// velocity (PointMaze: vx, vy).
    fn velocity_dims(&self) -> usize;

    /// One state uniform in the ball of radius `radius` around `center` under the metric with
    /// scale `scale` (λ > 0): position and velocity offsets drawn together, the state's other
    /// parts (a solver's warm start) the centre's.
    fn sample_velocity_ball(
        &self,
        center: &S,
        radius: f32,
        scale: f32,
        rng: &mut crate::rng::Rng,
    ) -> S;
}

/// A capability: whether the ball of radius `radius` around `center` is clear of everything
/// that blocks. PBCS's `phase2.stop_at_failure` ends a skill at a failure from a clear ball
/// (the policy's, not a wall's), and moved hand-overs try clear balls first. An environment
/// offers it through [`Env::clear_balls`].
pub trait BallIsClear<S> {
    /// `true` when nothing that blocks meets the ball (a conservative answer is allowed).
    fn ball_is_clear(&self, center: &S, radius: f32) -> bool;
}

/// A capability: the task as reaching a goal, for hindsight experience replay (HER, Andrychowicz et
/// al. 2017), in gymnasium-robotics' `GoalEnv` terms. A goal is a point of a goal space; an
/// observation achieves one ([`Goals::achieved_goal`], the maze's: its position), an episode
/// aims at one ([`Goals::desired_goal`], the maze's target), and [`Goals::goal_reward`] is the
/// part of [`Env::step`]'s reward that the goal decides, computed from the two goals alone (the
/// maze: 1 inside the target disc, by the same comparison its step makes). Whatever else the
/// step's reward holds (the maze's −1 on a wall) does not depend on the goal and is kept when HER
/// puts another goal in a stored transition (`learner::her`). An environment offers it through
/// [`Env::goals`]; tests/her.rs checks, for each one that does, that the step's reward is
/// `goal_reward(achieved, desired)` plus a part that does not depend on the goal.
pub trait Goals<S> {
    /// The goal space's dimension.
    fn goal_dim(&self) -> usize;
    /// The goal observation `obs` achieves, into `out` ([`Goals::goal_dim`] long).
    fn achieved_goal(&self, obs: &[f32], out: &mut [f32]);
    /// The goal of the episode in `state` (fixed tasks: the same for every state).
    fn desired_goal(&self, state: &S, out: &mut [f32]);
    /// The reward for having achieved `achieved` when the goal is `desired`.
    fn goal_reward(&self, achieved: &[f32], desired: &[f32]) -> f32;
    /// For an environment with a body, a function that rewrites a network's input (an
    /// observation followed by the goal, as HER's networks see them) in place so that the goal
    /// is seen from the body (`[train.her] goal_frame = "body"`); `None` (the default) for an
    /// environment without one.
    fn body_frame(&self) -> Option<fn(&mut [f32])> {
        None
    }
}

/// A capability: an episode's goal drawn the way the environment's own reset draws it
/// (gymnasium-robotics' mazes: the goal cell's centre plus a uniform draw in a square), put in a
/// state whose task is otherwise unchanged. PBCS's `phase2.last_goal = "drawn"` trains the last
/// skill toward goals drawn so, from states of τ, so that a chain reaches the goal its judge's
/// reset draws rather than the one τ reached. An environment offers it through
/// [`Env::drawn_goals`]; it needs [`Goals`], whose [`Goals::desired_goal`] reads the goal back.
pub trait DrawGoals<S>: Goals<S> {
    /// `state` with its episode's goal replaced by one drawn from the reset's law.
    fn with_drawn_goal(&self, state: &S, rng: &mut crate::rng::Rng) -> S;
}

/// A capability: a start drawn the way the environment's own reset draws it (gymnasium-robotics'
/// mazes: at rest at the start cell's centre plus a uniform draw in a square). PBCS's
/// `phase2.first_starts = "drawn"` makes these the first skill's starts at K = 0 and the chain's
/// verification and evaluation starts, so that the chain covers the starts its judge's reset
/// draws rather than B_ε(s_0) alone. An environment offers it through [`Env::drawn_starts`].
pub trait DrawStarts<S> {
    /// A start drawn from the reset's law, with the task (an episode's goal) of `like`.
    fn drawn_start(&self, like: &S, rng: &mut crate::rng::Rng) -> S;

    /// The body at rest as a reset leaves it, where `like` stands (its position and task):
    /// `phase2.goal_conditioned.rest_starts`. `None` (the default) where the environment has
    /// no such state.
    fn at_rest_like(&self, _like: &S) -> Option<S> {
        None
    }
}

/// A capability: a short sequence of actions that takes `from` to (within rounding of) `to`
/// while staying at least `clearance` away from anything that blocks, when the environment
/// knows one (a straight line in the maze); `None` for a pair it cannot join. Used only to
/// shorten phase-1 trajectories before phase 2 (`phase2.shorten`, off in the paper's preset).
/// An environment offers it through [`Env::connector`].
pub trait Connect<S> {
    /// The actions from `from` to `to`, or `None`.
    fn connect(&self, from: &S, to: &S, clearance: f32) -> Option<Vec<Vec<f32>>>;
}

/// The hooks of [`Env`] a setting needs, by name, for [`crate::error::Error::Capability`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Capability {
    /// [`Env::ball_starts`] ([`SampleBall`]).
    SampleBall,
    /// [`Env::clear_balls`] ([`BallIsClear`]).
    BallIsClear,
    /// [`Env::velocity_balls`] ([`VelocityBalls`]).
    VelocityBalls,
    /// [`Env::connector`] ([`Connect`]).
    Connect,
    /// [`Env::success_region`].
    SuccessRegion,
    /// [`Env::step_reach`].
    StepReach,
    /// [`Env::goals`] ([`Goals`]).
    Goals,
    /// [`Env::drawn_goals`] ([`DrawGoals`]).
    DrawGoals,
    /// [`Env::drawn_starts`] ([`DrawStarts`]).
    DrawStarts,
    /// [`DrawStarts::at_rest_like`] (of the environment's start).
    RestStarts,
}

impl Capability {
    /// The hook's name, as the error prints it (`Env::ball_starts`).
    pub fn hook(self) -> &'static str {
        match self {
            Capability::SampleBall => "Env::ball_starts (SampleBall)",
            Capability::BallIsClear => "Env::clear_balls (BallIsClear)",
            Capability::VelocityBalls => "Env::velocity_balls (VelocityBalls)",
            Capability::Connect => "Env::connector (Connect)",
            Capability::SuccessRegion => "Env::success_region",
            Capability::StepReach => "Env::step_reach",
            Capability::Goals => "Env::goals (Goals)",
            Capability::DrawGoals => "Env::drawn_goals (DrawGoals)",
            Capability::DrawStarts => "Env::drawn_starts (DrawStarts)",
            Capability::RestStarts => "DrawStarts::at_rest_like",
        }
    }

    /// Whether `env` offers it.
    pub fn offered_by<E: Env + ?Sized>(self, env: &E) -> bool {
        match self {
            Capability::SampleBall => env.ball_starts().is_some(),
            Capability::BallIsClear => env.clear_balls().is_some(),
            Capability::VelocityBalls => env.velocity_balls().is_some(),
            Capability::Connect => env.connector().is_some(),
            Capability::SuccessRegion => env.success_region().is_some(),
            Capability::StepReach => env.step_reach().is_some(),
            Capability::Goals => env.goals().is_some(),
            Capability::DrawGoals => env.drawn_goals().is_some(),
            Capability::DrawStarts => env.drawn_starts().is_some(),
            Capability::RestStarts => env
                .drawn_starts()
                .is_some_and(|d| d.at_rest_like(&env.start()).is_some()),
        }
    }

    /// `Ok` when `env` offers it, else the error naming `setting` (the field that asks for
    /// it, as written in a config: `phase2.start = "ball"`) and the hook.
    pub fn require<E: Env + ?Sized>(self, env: &E, setting: &str) -> crate::error::Result<()> {
        if self.offered_by(env) {
            Ok(())
        } else {
            Err(self.missing(setting))
        }
    }

    /// The error for `setting`, which needs this hook of an environment that lacks it.
    pub fn missing(self, setting: &str) -> crate::error::Error {
        crate::error::Error::Capability {
            setting: setting.to_string(),
            hook: self.hook(),
        }
    }
}

/// What a picture of a planar environment draws under the data ([`Planar::scene`]): its
/// extent, its walls, its target and its start, in the plane of [`Planar::point`].
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    /// The drawn extent: x in [0, `width`], y in [0, `height`].
    pub width: f32,
    /// See `width`.
    pub height: f32,
    /// Walls as axis-aligned rectangles: (min corner, max corner).
    pub walls: Vec<[(f32, f32); 2]>,
    /// The target disc: centre and radius.
    pub target: ((f32, f32), f32),
    /// The start s_0.
    pub start: (f32, f32),
}

/// An environment whose states are points of a plane, which `pbcs run` and `pbcs eval` can
/// draw: τ, the chain's rollouts and its activation balls over [`Planar::scene`]. The maze
/// and the two rooms are planar.
pub trait Planar: Env {
    /// Where `state` is drawn.
    fn point(&self, state: &Self::State) -> (f32, f32);

    /// The picture's frame: extent, walls, target, start.
    fn scene(&self) -> Scene;

    /// Where a ball centred at `center` (a position, [`Env::position`]: an activation set) is
    /// drawn, in the plane of [`Planar::point`] (the maze and the rooms: `center` itself;
    /// PointMaze: shifted as its points are).
    fn ball_point(&self, center: &[f32]) -> (f32, f32);
}

/// The observation of each of `states` ([`Env::observe`]), as the networks see them.
pub fn observations<E: Env + ?Sized>(env: &E, states: &[E::State]) -> Vec<Vec<f32>> {
    states
        .iter()
        .map(|s| {
            let mut o = vec![0.0; env.obs_dim()];
            env.observe(s, &mut o);
            o
        })
        .collect()
}

/// Fills `out` with an action drawn uniformly from the action box of `env`.
pub fn random_action<E: Env + ?Sized>(env: &E, rng: &mut impl Rng, out: &mut [f32]) {
    for (i, a) in out.iter_mut().enumerate() {
        let b = env.action_bound(i);
        *a = rng.random_range(-b..=b);
    }
}

/// One evaluation episode: whether it reached a positive terminal reward (the target), and in
/// how many steps. A PBCS run's chain (`evaluation.csv` of `pbcs run`, `s<seed>.evaluation.csv`
/// of a sweep, `eval-s<seed>.csv` of `pbcs eval`) and, when asked, a vanilla run's final greedy
/// policy are judged on these. The steps of the successful episodes are the path lengths.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct EvalEpisode {
    /// The episode reached the target.
    pub success: bool,
    /// Steps taken.
    pub steps: usize,
}

/// The start states of the evaluation protocol PBCS's chains are judged by: `episodes` states
/// uniform in B_ε(s_0) (radius `epsilon` around [`Env::start`]), drawn in order from the
/// [`crate::rng::Stream::Eval`] stream of `seeds`. The same seed gives every policy the same
/// starts, so a chain and a vanilla policy of one run seed are judged from the same states.
/// With `epsilon` = 0 every start is s_0; a ball needs [`Env::ball_starts`].
pub fn evaluation_starts<E: Env + ?Sized>(
    env: &E,
    epsilon: f32,
    episodes: usize,
    seeds: &crate::rng::Seeds,
) -> crate::error::Result<Vec<E::State>> {
    let start = env.start();
    let Some(ball) = env.ball_starts() else {
        if epsilon > 0.0 {
            let setting =
                "an evaluation ball B_ε(s_0), ε > 0 (phase2.epsilon, train.final_eval_epsilon)";
            Capability::SampleBall.require(env, setting)?;
        }
        return Ok(vec![start; episodes]);
    };
    let mut rng = seeds.stream(crate::rng::Stream::Eval);
    Ok((0..episodes)
        .map(|_| ball.sample_ball(&start, epsilon, &mut rng))
        .collect())
}
