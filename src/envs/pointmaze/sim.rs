//! The PointMaze environment on MuJoCo (feature `mujoco`): gymnasium-robotics'
//! `PointMazeEnv` step, reward and success, as a pure [`Env::step`] over the whole state.

use super::model::{sure_radius, MapName, PointMap, GOAL_NOISE, SUCCESS_DISTANCE};
use crate::env::{
    BallIsClear, DrawGoals, DrawStarts, Env, Goals, Planar, SampleBall, Scene, Step, VelocityBalls,
};
use crate::error::{Error, Result};
use mujoco_rs::prelude::*;
use std::sync::Mutex;

/// Speed limit applied to each velocity component before a step (`PointEnv.step`'s ±5).
pub const MAX_SPEED: f64 = 5.0;

/// Duration of one step, seconds (`point.xml`'s timestep; one `mj_step` per step).
pub const TIMESTEP: f64 = 0.01;

/// Radius of the point mass (`particle_geom`'s size in `point.xml`).
pub const RADIUS: f64 = 0.1;

/// Draws of a start in B_ε(τ_K) before one clear of the walls is taken; then τ_K itself.
const BALL_DRAWS: usize = 16;

/// The whole state of an episode: the point's position and velocity, the constraint solver's
/// warm start, which MuJoCo carries from one step to the next (the ball always touches the
/// floor, so the solver runs every step and starts from it: a state without it does not replay
/// exactly), and the episode's goal (gymnasium-robotics' `self.goal`: the task's goal, or the
/// one a goal-drawing reset drew, [`Resets::Gym`]).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PointState {
    /// Position (x, y), metres (`qpos`).
    pub qpos: [f64; 2],
    /// Velocity, metres per second (`qvel`).
    pub qvel: [f64; 2],
    /// The solver's warm start (`qacc_warmstart`).
    pub warmstart: [f64; 2],
    /// The episode's goal (x, y).
    pub goal: [f64; 2],
}

impl PointState {
    /// At rest at `xy`, as a reset leaves the point (`mj_resetData` zeroes the warm start),
    /// with the goal `goal`.
    pub fn at_rest(xy: [f64; 2], goal: [f64; 2]) -> PointState {
        PointState {
            qpos: xy,
            qvel: [0.0; 2],
            warmstart: [0.0; 2],
            goal,
        }
    }
}

/// Where an episode starts and what its goal is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Resets {
    /// This package's task: every episode from rest at the start cell's centre, to the goal
    /// cell's centre (success there for every goal gymnasium-robotics' reset may draw, with
    /// [`PointMaze::for_goal_noise`]).
    Fixed,
    /// gymnasium-robotics' own resets of the same cells (`MazeEnv.reset` with `goal_cell` and
    /// `reset_cell`): the goal, then the start, each its cell's centre plus noise uniform in
    /// ±[`GOAL_NOISE`] along x, then y; the point at rest there. A goal-conditioned task: the
    /// goal changes from episode to episode, and a policy must see it ([`Env::goals`]).
    Gym,
}

/// gymnasium-robotics' PointMaze with `continuing_task=False`: a point mass pushed by two
/// motors (actions in [−1, 1]², 0.01 s Euler steps), a sparse reward of 1 and the end of the
/// episode within [`SUCCESS_DISTANCE`] of the goal. The task is fixed: start at rest at the
/// centre of one cell, goal at the centre of another.
///
/// [`PointMaze::for_goal_noise`] makes success mean success for every goal the env's reset
/// may draw around that centre: the task a fixed policy has to solve for gymnasium-robotics
/// to count its episodes a success wherever the reset put the goal.
/// [`PointMaze::with_gym_resets`] instead draws start and goal per episode as
/// gymnasium-robotics' reset does: its own goal-conditioned task ([`Resets::Gym`]).
pub struct PointMaze {
    map: PointMap,
    start: [f64; 2],
    goal: [f64; 2],
    /// The start and goal cells.
    cells: ((usize, usize), (usize, usize)),
    /// Half-side of the square of goals success must hold for (0: the goal itself).
    goal_noise: f64,
    /// Where episodes start and end.
    resets: Resets,
    /// The simulator the pure step borrows: every step sets the whole state first, so what a
    /// previous step left in it does not matter.
    data: Mutex<MjData<Box<MjModel>>>,
}

impl std::fmt::Debug for PointMaze {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PointMaze")
            .field("map", &self.map)
            .field("start", &self.start)
            .field("goal", &self.goal)
            .field("goal_noise", &self.goal_noise)
            .field("resets", &self.resets)
            .finish()
    }
}

impl PointMaze {
    /// A map's task of this package: from its two free cells farthest apart
    /// ([`PointMap::farthest_cells`]).
    pub fn named(name: MapName) -> Result<PointMaze> {
        PointMaze::on(PointMap::named(name))
    }

    /// The task of this package on any map (a map of one's own, [`PointMap::from_config`]):
    /// from its two free cells farthest apart.
    pub fn on(map: PointMap) -> Result<PointMaze> {
        let (start, goal) = map.farthest_cells();
        PointMaze::new(map, start, goal)
    }

    /// The task from the centre of cell `start` (at rest) to the centre of cell `goal`, both
    /// free; the model compiled by MuJoCo.
    pub fn new(map: PointMap, start: (usize, usize), goal: (usize, usize)) -> Result<PointMaze> {
        for (what, cell) in [("start", start), ("goal", goal)] {
            if map.is_wall(cell) {
                return Err(Error::invalid(
                    "pointmaze task",
                    format!("the {what} cell {cell:?} is a wall or outside the map"),
                ));
            }
        }
        let model = MjModel::from_xml_string(&map.xml())
            .map_err(|e| Error::invalid("pointmaze model", format!("MuJoCo refused it: {e}")))?;
        let mut data = MjData::new(Box::new(model));
        let goal_xy = map.cell_xy(goal);
        if let Some(id) = data.model().name_to_id(MjtObjBase::mjOBJ_SITE, "target") {
            // Where gymnasium-robotics draws the goal (no effect on the simulation).
            // SAFETY: the model is owned by this data and not shared.
            unsafe { data.model_mut() }.site_pos_mut()[id] = [goal_xy[0], goal_xy[1], 0.2];
        }
        Ok(PointMaze {
            start: map.cell_xy(start),
            goal: goal_xy,
            cells: (start, goal),
            goal_noise: 0.0,
            resets: Resets::Fixed,
            map,
            data: Mutex::new(data),
        })
    }

    /// The same environment whose success (reward, end of episode) holds only where the point
    /// is within [`SUCCESS_DISTANCE`] of every goal in the square of half-side `noise` around
    /// the goal: the farthest such goal is a corner, so success is
    /// ‖(|Δx| + noise, |Δy| + noise)‖ ≤ 0.45. With [`super::GOAL_NOISE`], the region gymnasium-robotics'
    /// resets all agree on: within 0.45 − 0.25√2 ≈ 0.096 of the centre diagonally, 0.124 along
    /// the axes. `noise` = 0 is the environment itself, bit for bit.
    /// (`tests/pointmaze.rs` checks the region.)
    pub fn for_goal_noise(mut self, noise: f64) -> Result<PointMaze> {
        if self.resets == Resets::Gym && noise != 0.0 {
            return Err(Error::invalid(
                "goal_noise",
                "with gymnasium-robotics' resets the goal is the episode's own: no noise to \
                 agree over",
            ));
        }
        if !(noise >= 0.0 && noise * std::f64::consts::SQRT_2 < SUCCESS_DISTANCE) {
            return Err(Error::invalid(
                "goal_noise",
                format!(
                    "must be at least 0 and leave a region every goal agrees on (below \
                     0.45 / √2 ≈ 0.318), got {noise}"
                ),
            ));
        }
        self.goal_noise = noise;
        Ok(self)
    }

    /// The same cells with gymnasium-robotics' own resets ([`Resets::Gym`]): start and goal
    /// drawn per episode, success within [`SUCCESS_DISTANCE`] of the episode's goal. Refused
    /// after [`PointMaze::for_goal_noise`] with noise (a success region for goals this env
    /// would draw itself).
    pub fn with_gym_resets(mut self) -> Result<PointMaze> {
        if self.goal_noise != 0.0 {
            return Err(Error::invalid(
                "resets",
                "gymnasium-robotics' resets draw the episode's goal: success is for that goal, \
                 not for every goal of a noise square",
            ));
        }
        self.resets = Resets::Gym;
        Ok(self)
    }

    /// Where episodes start and what their goals are.
    pub fn resets(&self) -> Resets {
        self.resets
    }

    /// At rest at `xy`, with the task's goal (the goal cell's centre).
    pub fn at_rest(&self, xy: [f64; 2]) -> PointState {
        PointState::at_rest(xy, self.goal)
    }

    /// The radius of the disc around the goal where success holds for every goal of the
    /// noise square (the whole region is a little larger along the axes).
    pub fn sure_radius(&self) -> f64 {
        sure_radius(self.goal_noise)
    }

    /// The map.
    pub fn map(&self) -> &PointMap {
        &self.map
    }

    /// The start and goal cells.
    pub fn cells(&self) -> ((usize, usize), (usize, usize)) {
        self.cells
    }

    /// The task's goal: the goal cell's centre (an episode's goal is its state's,
    /// [`PointState::goal`]).
    pub fn goal(&self) -> [f64; 2] {
        self.goal
    }

    /// Distance from the point to the episode's goal.
    pub fn distance_to_goal(&self, s: &PointState) -> f64 {
        (s.qpos[0] - s.goal[0]).hypot(s.qpos[1] - s.goal[1])
    }

    /// Whether the point is within [`SUCCESS_DISTANCE`] of the episode's goal
    /// (`info["success"]`), or of every goal of the noise square around it
    /// ([`PointMaze::for_goal_noise`]).
    pub fn success(&self, s: &PointState) -> bool {
        let (dx, dy) = (s.qpos[0] - s.goal[0], s.qpos[1] - s.goal[1]);
        let n = self.goal_noise;
        (dx.abs() + n).hypot(dy.abs() + n) <= SUCCESS_DISTANCE
    }

    /// One step of `PointEnv.step` from `s`: the action clipped to [−1, 1] (in `f32`, as
    /// gymnasium keeps it), each velocity clipped to ±[`MAX_SPEED`], the whole state set, the
    /// action as motor controls, one `mj_step`. gymnasium's `set_state` also runs `mj_forward`
    /// before the step, and `mj_rnePostConstraint` after it: the first computes again, inside
    /// `mj_step`, from the same inputs (the solver starts from the warm start, not from what
    /// the forward pass left), the second computes forces nothing reads; leaving both out
    /// doubles the speed (`benches/pointmaze.rs`), and the equality test against
    /// gymnasium-robotics still finds every number the same, bit for bit.
    pub fn next(&self, s: &PointState, action: [f32; 2]) -> PointState {
        let mut d = self.data.lock().unwrap_or_else(|e| e.into_inner());
        d.qpos_mut().copy_from_slice(&s.qpos);
        d.qvel_mut()
            .copy_from_slice(&s.qvel.map(|v| v.clamp(-MAX_SPEED, MAX_SPEED)));
        d.qacc_warmstart_mut().copy_from_slice(&s.warmstart);
        d.ctrl_mut()
            .copy_from_slice(&action.map(|a| f64::from(a.clamp(-1.0, 1.0))));
        d.step();
        let (q, v, w) = (d.qpos(), d.qvel(), d.qacc_warmstart());
        PointState {
            qpos: [q[0], q[1]],
            qvel: [v[0], v[1]],
            warmstart: [w[0], w[1]],
            goal: s.goal,
        }
    }
}

impl Env for PointMaze {
    type State = PointState;

    fn obs_dim(&self) -> usize {
        4
    }

    fn action_dim(&self) -> usize {
        2
    }

    fn action_bound(&self, _i: usize) -> f32 {
        1.0
    }

    /// At rest at the start cell's centre, the goal at the goal cell's centre.
    fn start(&self) -> PointState {
        self.at_rest(self.start)
    }

    /// [`Resets::Fixed`]: every episode of our task starts at [`Env::start`]
    /// (gymnasium-robotics' resets add noise; the judge plays those, `pbcs.pointmaze`).
    /// [`Resets::Gym`]: the goal, then the start, as gymnasium-robotics' `add_xy_position_noise`
    /// moves them: each coordinate plus a uniform draw in [−[`GOAL_NOISE`], [`GOAL_NOISE`]),
    /// x then y (the same law; our stream, not numpy's).
    fn sample_start(&self, rng: &mut crate::rng::Rng) -> PointState {
        match self.resets {
            Resets::Fixed => self.start(),
            Resets::Gym => {
                let goal = noisy(self.goal, rng);
                PointState::at_rest(noisy(self.start, rng), goal)
            }
        }
    }

    /// `observation` of gymnasium-robotics: [x, y, vx, vy] (in `f32`).
    fn observe(&self, s: &PointState, out: &mut [f32]) {
        let o = [s.qpos[0], s.qpos[1], s.qvel[0], s.qvel[1]];
        for (out, o) in out.iter_mut().zip(o) {
            *out = o as f32;
        }
    }

    /// [`PointMaze::next`]; reward 1 and the end of the episode on success (sparse reward,
    /// `continuing_task=False`), else 0.
    fn step(&self, s: &PointState, action: &[f32]) -> Step<PointState> {
        let state = self.next(s, [action[0], action[1]]);
        let success = self.success(&state);
        Step {
            state,
            reward: if success { 1.0 } else { 0.0 },
            terminal: success,
        }
    }

    /// The position (x, y): phase 1 bins on it (binning the velocity too, nearly every state
    /// had a bin of its own, `results/dev/issue35/`), and, with balls in position (the
    /// preset), a goal B_ε(τ_T) or an activation set is reached at any velocity (balls in
    /// position and velocity: [`VelocityBalls`], `experiments/pointmaze_velocity.toml`).
    fn position_dims(&self) -> usize {
        2
    }

    /// The fastest step: [`MAX_SPEED`] for the model's 0.01 s.
    fn step_reach(&self) -> Option<f32> {
        Some((MAX_SPEED * TIMESTEP) as f32)
    }

    /// The goal and gymnasium-robotics' success distance, in position (with goal noise, the
    /// disc inscribed in the region every goal agrees on, [`PointMaze::sure_radius`]); none
    /// with gymnasium-robotics' resets, whose goal is each episode's own.
    fn success_region(&self) -> Option<(Vec<f32>, f32)> {
        if self.resets == Resets::Gym {
            return None;
        }
        Some((
            self.goal.map(|g| g as f32).to_vec(),
            self.sure_radius() as f32,
        ))
    }

    fn ball_starts(&self) -> Option<&dyn SampleBall<PointState>> {
        Some(self)
    }

    fn goals(&self) -> Option<&dyn Goals<PointState>> {
        Some(self)
    }

    fn drawn_goals(&self) -> Option<&dyn DrawGoals<PointState>> {
        Some(self)
    }

    fn drawn_starts(&self) -> Option<&dyn DrawStarts<PointState>> {
        Some(self)
    }

    fn velocity_balls(&self) -> Option<&dyn VelocityBalls<PointState>> {
        Some(self)
    }

    fn clear_balls(&self) -> Option<&dyn BallIsClear<PointState>> {
        Some(self)
    }

    fn obs_names(&self) -> Vec<String> {
        ["x", "y", "vx", "vy"].map(String::from).to_vec()
    }
}

impl SampleBall<PointState> for PointMaze {
    /// A position uniform in the disc of radius `radius` around the centre's (r = radius·√u,
    /// angle uniform), redrawn while the point would overlap a wall (at most 16 draws, then
    /// the centre's position); the centre's velocity and warm start. (Measured against
    /// velocities spread around the centre's, against phase 1's archived states in the
    /// ball, `phase2.start = "archive"`: neither did better, `results/dev/issue35/`. Balls in
    /// position and velocity draw their own starts, [`VelocityBalls`]; with λ = 0.1 s they
    /// did better in the registered comparison `experiments/pointmaze_velocity.toml`.)
    fn sample_ball(
        &self,
        center: &PointState,
        radius: f32,
        rng: &mut crate::rng::Rng,
    ) -> PointState {
        use crate::envs::pointmaze::model::disc_point;
        for _ in 0..BALL_DRAWS {
            let xy = disc_point([center.qpos[0], center.qpos[1]], f64::from(radius), rng);
            if self.map.clearance(xy) >= RADIUS {
                return PointState {
                    qpos: xy,
                    ..*center
                };
            }
        }
        *center
    }
}

impl VelocityBalls<PointState> for PointMaze {
    /// vx, vy.
    fn velocity_dims(&self) -> usize {
        2
    }

    /// A point u uniform in the unit ball of R⁴ (drawn uniform in [−1, 1]⁴ until it lies in
    /// the ball, which fills π²/32 ≈ 31 % of it), then position = centre's + radius·(u₀, u₁)
    /// and velocity = centre's + radius·(u₂, u₃)/λ, each component within ±[`MAX_SPEED`] (the
    /// step clips it there anyway); redrawn while the point would overlap a wall (at most 16
    /// draws, then the centre); the centre's warm start.
    fn sample_velocity_ball(
        &self,
        center: &PointState,
        radius: f32,
        scale: f32,
        rng: &mut crate::rng::Rng,
    ) -> PointState {
        use rand::Rng as _;
        let (r, l) = (f64::from(radius), f64::from(scale));
        for _ in 0..BALL_DRAWS {
            let u = loop {
                let u: [f64; 4] = std::array::from_fn(|_| rng.random_range(-1.0..=1.0));
                if u.iter().map(|x| x * x).sum::<f64>() <= 1.0 {
                    break u;
                }
            };
            let xy = [center.qpos[0] + r * u[0], center.qpos[1] + r * u[1]];
            if self.map.clearance(xy) >= RADIUS {
                let v = |i: usize| (center.qvel[i] + r * u[2 + i] / l).clamp(-MAX_SPEED, MAX_SPEED);
                return PointState {
                    qpos: xy,
                    qvel: [v(0), v(1)],
                    ..*center
                };
            }
        }
        *center
    }
}

impl BallIsClear<PointState> for PointMaze {
    /// No wall within `radius` + the point's radius of the centre's position.
    fn ball_is_clear(&self, center: &PointState, radius: f32) -> bool {
        self.map.clearance(center.qpos) >= f64::from(radius) + RADIUS
    }
}

impl Planar for PointMaze {
    /// The position, shifted so that the map spans [0, W] × [0, H].
    fn point(&self, s: &PointState) -> (f32, f32) {
        self.map.drawn(s.qpos)
    }

    /// A ball's centre (x, y), shifted as [`Planar::point`] shifts positions.
    fn ball_point(&self, center: &[f32]) -> (f32, f32) {
        let (w, h) = (self.map.cols() as f32, self.map.rows() as f32);
        (center[0] + w / 2.0, center[1] + h / 2.0)
    }

    fn scene(&self) -> Scene {
        let (start, goal) = self.cells;
        self.map.scene(start, goal, self.sure_radius() as f32)
    }
}

/// `c` moved as `add_xy_position_noise` moves a cell's centre: each coordinate plus a uniform
/// draw in [−0.25, 0.25), x then y (the same law; our stream, not numpy's).
fn noisy(c: [f64; 2], rng: &mut crate::rng::Rng) -> [f64; 2] {
    use rand::Rng as _;
    c.map(|c| c + rng.random_range(-GOAL_NOISE..GOAL_NOISE))
}

/// At rest at the start cell's centre moved as the env's reset moves it ([`noisy`]), whatever
/// this environment's own [`Resets`]: `phase2.first_starts = "drawn"` on the fixed task.
impl DrawStarts<PointState> for PointMaze {
    fn drawn_start(&self, like: &PointState, rng: &mut crate::rng::Rng) -> PointState {
        PointState::at_rest(noisy(self.start, rng), like.goal)
    }
}

/// The goal cell's centre moved as the env's reset moves it ([`noisy`]), whatever this
/// environment's own [`Resets`]: `phase2.last_goal = "drawn"` on the fixed task.
impl DrawGoals<PointState> for PointMaze {
    fn with_drawn_goal(&self, s: &PointState, rng: &mut crate::rng::Rng) -> PointState {
        PointState {
            goal: noisy(self.goal, rng),
            ..*s
        }
    }
}

/// Goals: positions (x, y); the episode's is its state's goal; the reward 1 where [`PointMaze::success`]
/// would say so of a point at `achieved` (its `f64` test on the observation's `f32` position: at
/// the very edge of the disc the two can differ by the rounding of a position to `f32`).
impl Goals<PointState> for PointMaze {
    fn goal_dim(&self) -> usize {
        2
    }
    fn achieved_goal(&self, obs: &[f32], out: &mut [f32]) {
        out.copy_from_slice(&obs[..2]);
    }
    fn desired_goal(&self, s: &PointState, out: &mut [f32]) {
        out.copy_from_slice(&s.goal.map(|g| g as f32));
    }
    fn goal_reward(&self, achieved: &[f32], desired: &[f32]) -> f32 {
        let (dx, dy) = (
            f64::from(achieved[0]) - f64::from(desired[0]),
            f64::from(achieved[1]) - f64::from(desired[1]),
        );
        let n = self.goal_noise;
        if (dx.abs() + n).hypot(dy.abs() + n) <= SUCCESS_DISTANCE {
            1.0
        } else {
            0.0
        }
    }
}
