//! The AntMaze environment on MuJoCo (feature `mujoco`): gymnasium-robotics' `AntMazeEnv`
//! (v5) step, observation, reward and success, as a pure [`Env::step`] over the whole state.

use super::model::{self, POSITION_NOISE, SCALE};
use crate::env::{BallIsClear, DrawGoals, DrawStarts, Env, Goals, Planar, SampleBall, Scene, Step};
use crate::envs::pointmaze::{MapName, PointMap, Resets, SUCCESS_DISTANCE};
use crate::error::{Error, Result};
use mujoco_rs::prelude::*;
use std::sync::Mutex;

/// Position coordinates: the torso's free joint (x, y, z and a unit quaternion w, x, y, z),
/// then the 8 hinges (hip_1, ankle_1, …, hip_4, ankle_4).
pub const NQ: usize = 15;

/// Velocity coordinates: the torso's 6 (linear, then angular), then the 8 hinges'.
pub const NV: usize = 14;

/// Draws of a start in B_ε(τ_K) before one clear of the walls is taken; then τ_K itself.
const BALL_DRAWS: usize = 16;

/// Motors, one per hinge, in `ant.xml`'s order (hip_4, ankle_4, hip_1, …).
pub const NU: usize = 8;

/// MuJoCo steps per env step (`AntEnv`'s `frame_skip`): 5 × 0.01 s.
pub const FRAME_SKIP: usize = 5;

/// The whole state of an episode: what `mj_getState(mjSTATE_INTEGRATION)` holds that this
/// model uses — positions, velocities and the constraint solver's warm start (restoring
/// positions and velocities alone does not replay contacts exactly) — and the episode's goal
/// (gymnasium-robotics' `self.goal`). The model has no activations, mocap bodies or
/// equality constraints; controls are the step's action and applied forces stay zero.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AntState {
    /// `qpos` ([`NQ`]).
    pub qpos: [f64; NQ],
    /// `qvel` ([`NV`]).
    pub qvel: [f64; NV],
    /// `qacc_warmstart` ([`NV`]).
    pub warmstart: [f64; NV],
    /// The episode's goal (x, y).
    pub goal: [f64; 2],
}

impl AntState {
    /// The torso's position (x, y): gymnasium-robotics' `achieved_goal`.
    pub fn xy(&self) -> [f64; 2] {
        [self.qpos[0], self.qpos[1]]
    }

    /// The world z component of the torso's up axis, 1 − 2(qx² + qy²): 1 upright, below 0
    /// upside down.
    pub fn up(&self) -> f64 {
        let (x, y) = (self.qpos[4], self.qpos[5]);
        1.0 - 2.0 * (x * x + y * y)
    }
}

/// gymnasium-robotics' `AntMaze_<map>-v5` with `continuing_task=False` and
/// `include_cfrc_ext_in_observation=False`: gymnasium's ant (8 motors, gear 150, controls in
/// [−1, 1], RK4 at 0.01 s, 5 steps per env step) in a maze of 4 m cells, a sparse reward of 1
/// and the end of the episode within [`SUCCESS_DISTANCE`] of the goal. The ant's own reward
/// and termination are gymnasium-robotics' to discard, and are not computed; it never ends
/// for falling over.
///
/// [`Resets::Gym`] (the registry's `antmaze_<map>`): each episode's goal and start as the env's
/// reset draws them around the task's cells, ±1 m. [`Resets::Fixed`]: from rest at the start
/// cell's centre to the goal cell's centre.
pub struct AntMaze {
    map: PointMap,
    /// The start and goal cells.
    cells: ((usize, usize), (usize, usize)),
    start: [f64; 2],
    goal: [f64; 2],
    resets: Resets,
    /// Whether phase 1 may archive an ant on its back ([`Env::archivable`]).
    archive_flipped: bool,
    /// The model's `qpos0`: the ant as `ant.xml` places it (torso 0.75 m up, level, joints at 0).
    qpos0: [f64; NQ],
    /// The simulator the pure step borrows: every step sets the whole state first.
    data: Mutex<MjData<Box<MjModel>>>,
}

impl std::fmt::Debug for AntMaze {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("AntMaze")
            .field("map", &self.map)
            .field("cells", &self.cells)
            .field("resets", &self.resets)
            .field("archive_flipped", &self.archive_flipped)
            .finish()
    }
}

impl AntMaze {
    /// A map's task of this package (its two free cells farthest apart), with
    /// gymnasium-robotics' resets of those cells.
    pub fn named(name: MapName) -> Result<AntMaze> {
        AntMaze::on(PointMap::named(name))
    }

    /// The task of this package on any map, with gymnasium-robotics' resets of its cells.
    pub fn on(map: PointMap) -> Result<AntMaze> {
        let (start, goal) = map.farthest_cells();
        AntMaze::new(map, start, goal, Resets::Gym)
    }

    /// The task between the cells `start` and `goal`, both free, reset as `resets` says; the
    /// model compiled by MuJoCo.
    pub fn new(
        map: PointMap,
        start: (usize, usize),
        goal: (usize, usize),
        resets: Resets,
    ) -> Result<AntMaze> {
        for (what, cell) in [("start", start), ("goal", goal)] {
            if map.is_wall(cell) {
                return Err(Error::invalid(
                    "antmaze task",
                    format!("the {what} cell {cell:?} is a wall or outside the map"),
                ));
            }
        }
        let mj = MjModel::from_xml_string(&model::xml(&map))
            .map_err(|e| Error::invalid("antmaze model", format!("MuJoCo refused it: {e}")))?;
        let (nq, nv, nu) = (mj.ffi().nq, mj.ffi().nv, mj.ffi().nu);
        if (nq, nv, nu) != (NQ as i64, NV as i64, NU as i64) {
            return Err(Error::invalid(
                "antmaze model",
                format!("has nq {nq}, nv {nv}, nu {nu}: not the ant's 15, 14 and 8"),
            ));
        }
        let mut qpos0 = [0.0; NQ];
        qpos0.copy_from_slice(mj.qpos0());
        Ok(AntMaze {
            start: model::cell_xy(&map, start),
            goal: model::cell_xy(&map, goal),
            cells: (start, goal),
            resets,
            archive_flipped: true,
            qpos0,
            map,
            data: Mutex::new(MjData::new(Box::new(mj))),
        })
    }

    /// The same environment whose phase 1 never archives an ant on its back
    /// ([`AntState::up`] below 0): exploration does not start again from states it would
    /// have to get up from. The steps are unchanged.
    pub fn refusing_flipped(mut self) -> AntMaze {
        self.archive_flipped = false;
        self
    }

    /// The map.
    pub fn map(&self) -> &PointMap {
        &self.map
    }

    /// The start and goal cells.
    pub fn cells(&self) -> ((usize, usize), (usize, usize)) {
        self.cells
    }

    /// Where episodes start and what their goals are.
    pub fn resets(&self) -> Resets {
        self.resets
    }

    /// The task's goal, the goal cell's centre (an episode's goal is its state's).
    pub fn goal(&self) -> [f64; 2] {
        self.goal
    }

    /// The state a reset leaves: `ant.xml`'s pose with the torso moved to `xy`, at rest, the
    /// warm start zero (`mj_resetData`; gymnasium's `set_state` then runs `mj_forward`, which
    /// leaves it so), toward `goal`.
    pub fn at_rest(&self, xy: [f64; 2], goal: [f64; 2]) -> AntState {
        let mut qpos = self.qpos0;
        qpos[..2].copy_from_slice(&xy);
        AntState {
            qpos,
            qvel: [0.0; NV],
            warmstart: [0.0; NV],
            goal,
        }
    }

    /// Whether the torso is within [`SUCCESS_DISTANCE`] of the episode's goal
    /// (`info["success"]`).
    pub fn success(&self, s: &AntState) -> bool {
        (s.qpos[0] - s.goal[0]).hypot(s.qpos[1] - s.goal[1]) <= SUCCESS_DISTANCE
    }

    /// One env step from `s`: the whole state set, the action as the motors' controls (as
    /// given: MuJoCo clamps them to the control range, as in gymnasium), [`FRAME_SKIP`] ×
    /// `mj_step`, the state read back. gymnasium's `do_simulation` then runs
    /// `mj_rnePostConstraint`, which computes forces that only the 105-number observation
    /// reads; `mj_step` runs the whole forward pass first, from these inputs alone.
    pub fn next(&self, s: &AntState, action: &[f32]) -> AntState {
        let mut d = self.data.lock().unwrap_or_else(|e| e.into_inner());
        d.qpos_mut().copy_from_slice(&s.qpos);
        d.qvel_mut().copy_from_slice(&s.qvel);
        d.qacc_warmstart_mut().copy_from_slice(&s.warmstart);
        // Every control set, so that the step depends on this action alone (a missing one is 0).
        for (k, c) in d.ctrl_mut().iter_mut().enumerate() {
            *c = action.get(k).map_or(0.0, |&a| f64::from(a));
        }
        for _ in 0..FRAME_SKIP {
            d.step();
        }
        let mut next = AntState { goal: s.goal, ..*s };
        next.qpos.copy_from_slice(d.qpos());
        next.qvel.copy_from_slice(d.qvel());
        next.warmstart.copy_from_slice(d.qacc_warmstart());
        next
    }
}

impl Env for AntMaze {
    type State = AntState;

    /// `achieved_goal` ++ `observation`: the torso's (x, y), then gymnasium-robotics' 27 —
    /// qpos[2..] and qvel.
    fn obs_dim(&self) -> usize {
        NQ + NV
    }

    fn action_dim(&self) -> usize {
        NU
    }

    fn action_bound(&self, _i: usize) -> f32 {
        1.0
    }

    /// At rest at the start cell's centre, toward the goal cell's centre.
    fn start(&self) -> AntState {
        self.at_rest(self.start, self.goal)
    }

    /// [`Resets::Fixed`]: [`Env::start`]. [`Resets::Gym`]: the goal, then the start, as
    /// `add_xy_position_noise` moves them from their cells' centres: each coordinate plus a
    /// uniform draw in [−0.25, 0.25) times [`SCALE`], x then y (the same law; our stream, not
    /// numpy's); the ant at rest there.
    fn sample_start(&self, rng: &mut crate::rng::Rng) -> AntState {
        match self.resets {
            Resets::Fixed => self.start(),
            Resets::Gym => {
                let goal = noisy(self.goal, rng);
                self.at_rest(noisy(self.start, rng), goal)
            }
        }
    }

    /// `achieved_goal` then `observation` (in `f32`): qpos, then qvel.
    fn observe(&self, s: &AntState, out: &mut [f32]) {
        for (o, v) in out.iter_mut().zip(s.qpos.iter().chain(&s.qvel)) {
            *o = *v as f32;
        }
    }

    /// [`AntMaze::next`]; reward 1 and the end of the episode on success (sparse reward,
    /// `continuing_task=False`), else 0.
    fn step(&self, s: &AntState, action: &[f32]) -> Step<AntState> {
        let state = self.next(s, action);
        let success = self.success(&state);
        Step {
            state,
            reward: if success { 1.0 } else { 0.0 },
            terminal: success,
        }
    }

    /// The torso's (x, y).
    fn position_dims(&self) -> usize {
        2
    }

    /// The goal and the success distance, for the fixed task; none with gymnasium-robotics'
    /// resets, whose goal is each episode's own.
    fn success_region(&self) -> Option<(Vec<f32>, f32)> {
        (self.resets == Resets::Fixed).then(|| {
            (
                self.goal.map(|g| g as f32).to_vec(),
                SUCCESS_DISTANCE as f32,
            )
        })
    }

    fn goals(&self) -> Option<&dyn Goals<AntState>> {
        Some(self)
    }

    fn drawn_goals(&self) -> Option<&dyn DrawGoals<AntState>> {
        Some(self)
    }

    fn drawn_starts(&self) -> Option<&dyn DrawStarts<AntState>> {
        Some(self)
    }

    fn ball_starts(&self) -> Option<&dyn SampleBall<AntState>> {
        Some(self)
    }

    fn clear_balls(&self) -> Option<&dyn BallIsClear<AntState>> {
        Some(self)
    }

    /// Every state, or (made [`AntMaze::refusing_flipped`]) every state with the torso's up
    /// axis not pointing down.
    fn archivable(&self, s: &AntState) -> bool {
        self.archive_flipped || s.up() >= 0.0
    }

    fn obs_names(&self) -> Vec<String> {
        let joints = (1..=4).flat_map(|k| [format!("hip_{k}"), format!("ankle_{k}")]);
        let pos = ["x", "y", "z", "qw", "qx", "qy", "qz"].map(String::from);
        let vel = ["vx", "vy", "vz", "wx", "wy", "wz"].map(String::from);
        pos.into_iter()
            .chain(joints.clone())
            .chain(vel)
            .chain(joints.map(|j| format!("d{j}")))
            .collect()
    }
}

impl SampleBall<AntState> for AntMaze {
    /// The centre's body moved in the plane: the torso's (x, y) uniform in the disc of radius
    /// `radius` around the centre's (r = radius·√u, angle uniform), redrawn while a wall lies
    /// within the ant's reach ([`model::REACH`]; at most 16 draws, then the centre itself);
    /// height, orientation, joints, velocities and warm start the centre's. (Phase 2's
    /// `start = "archive"` draws phase 1's own states in the ball instead.)
    fn sample_ball(&self, center: &AntState, radius: f32, rng: &mut crate::rng::Rng) -> AntState {
        use crate::envs::pointmaze::model::disc_point;
        for _ in 0..BALL_DRAWS {
            let xy = disc_point([center.qpos[0], center.qpos[1]], f64::from(radius), rng);
            if model::clearance(&self.map, xy) >= model::REACH {
                let mut s = *center;
                s.qpos[..2].copy_from_slice(&xy);
                return s;
            }
        }
        *center
    }
}

impl BallIsClear<AntState> for AntMaze {
    /// No wall within `radius` + the ant's reach of the torso's position.
    fn ball_is_clear(&self, center: &AntState, radius: f32) -> bool {
        model::clearance(&self.map, center.xy()) >= f64::from(radius) + model::REACH
    }
}

/// Goals: the torso's (x, y); the episode's is its state's; the reward 1 within
/// [`SUCCESS_DISTANCE`] (in `f64` on the observation's `f32` position).
impl Goals<AntState> for AntMaze {
    fn goal_dim(&self) -> usize {
        2
    }
    fn achieved_goal(&self, obs: &[f32], out: &mut [f32]) {
        out.copy_from_slice(&obs[..2]);
    }
    fn desired_goal(&self, s: &AntState, out: &mut [f32]) {
        out.copy_from_slice(&s.goal.map(|g| g as f32));
    }
    fn goal_reward(&self, achieved: &[f32], desired: &[f32]) -> f32 {
        let (dx, dy) = (
            f64::from(achieved[0]) - f64::from(desired[0]),
            f64::from(achieved[1]) - f64::from(desired[1]),
        );
        if dx.hypot(dy) <= SUCCESS_DISTANCE {
            1.0
        } else {
            0.0
        }
    }
    fn body_frame(&self) -> Option<fn(&mut [f32])> {
        Some(model::body_frame)
    }
}

/// `c` moved as `add_xy_position_noise` moves a cell's centre: each coordinate plus a uniform
/// draw in [−0.25, 0.25) times [`SCALE`], x then y (the same law; our stream, not numpy's).
fn noisy(c: [f64; 2], rng: &mut crate::rng::Rng) -> [f64; 2] {
    use rand::Rng as _;
    c.map(|c| c + rng.random_range(-POSITION_NOISE..POSITION_NOISE) * SCALE)
}

/// At rest at the start cell's centre moved as the env's reset moves it ([`noisy`]), whatever
/// this environment's own [`Resets`]: `phase2.first_starts = "drawn"` on the fixed task.
impl DrawStarts<AntState> for AntMaze {
    fn drawn_start(&self, like: &AntState, rng: &mut crate::rng::Rng) -> AntState {
        self.at_rest(noisy(self.start, rng), like.goal)
    }

    /// `ant.xml`'s pose at rest with the torso moved to `like`'s (x, y) ([`AntMaze::at_rest`]).
    fn at_rest_like(&self, like: &AntState) -> Option<AntState> {
        Some(self.at_rest(like.xy(), like.goal))
    }
}

/// The goal cell's centre moved as the env's reset moves it ([`noisy`]), whatever this
/// environment's own [`Resets`]: `phase2.last_goal = "drawn"` on the fixed task.
impl DrawGoals<AntState> for AntMaze {
    fn with_drawn_goal(&self, s: &AntState, rng: &mut crate::rng::Rng) -> AntState {
        AntState {
            goal: noisy(self.goal, rng),
            ..*s
        }
    }
}

impl Planar for AntMaze {
    /// The torso's position, shifted so that the map spans [0, 4W] × [0, 4H].
    fn point(&self, s: &AntState) -> (f32, f32) {
        model::drawn(&self.map, s.xy())
    }

    /// A ball's centre (x, y), shifted as [`Planar::point`] shifts positions.
    fn ball_point(&self, center: &[f32]) -> (f32, f32) {
        let (w, h) = (
            (self.map.cols() as f64 * SCALE) as f32,
            (self.map.rows() as f64 * SCALE) as f32,
        );
        (center[0] + w / 2.0, center[1] + h / 2.0)
    }

    fn scene(&self) -> Scene {
        let (start, goal) = self.cells;
        model::scene(&self.map, start, goal, SUCCESS_DISTANCE as f32)
    }
}
