//! The maze environments: one episode (`MazeEnv`) and N mazes per call (`MazeVecEnv`).

use crate::named::rgb_of;
use crate::{action_of, count, invalid, maze_of, state_of, walls_of};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray2};
use parry2d::math::Point;
use pbcs::env::Env;
use pbcs::envs::maze::Maze;
use pbcs::plot::Picture;
use pyo3::prelude::*;

/// `max_episode_steps` of both environments: 1 to 2³² − 1.
fn episode_limit(v: i64) -> PyResult<u32> {
    u32::try_from(count("max_episode_steps", v)?)
        .ok()
        .filter(|&m| m > 0)
        .ok_or_else(|| invalid("max_episode_steps", "must be between 1 and 2^32 - 1"))
}

/// What `MazeEnv::step` returns: observation, reward, terminated, truncated, hit a wall.
type EnvStep<'py> = (Bound<'py, PyArray1<f32>>, f32, bool, bool, bool);

/// One maze episode: the core of `pbcs.ContinuousMaze`. The state is a 2-D point; `step`
/// applies the paper's step function (clip the action to ±max_action, stay put if the segment
/// crosses a wall; reward +1 inside the target disc, which ends the episode, −1 for a wall)
/// and truncates after `max_episode_steps` steps.
#[pyclass(module = "pbcs._pbcs")]
pub(crate) struct MazeEnv {
    maze: Maze,
    state: Point<f32>,
    elapsed: usize,
    max_episode_steps: usize,
    /// The episode's states, for `render`.
    path: Vec<(f32, f32)>,
}

#[pymethods]
impl MazeEnv {
    #[new]
    #[pyo3(signature = (size, layout = 0, max_episode_steps = 1000, wall_thickness = 0.1, target_radius = 0.2, max_action = 0.1))]
    fn new(
        size: i64,
        layout: i64,
        max_episode_steps: i64,
        wall_thickness: f32,
        target_radius: f32,
        max_action: f32,
    ) -> PyResult<Self> {
        let maze = maze_of(size, layout, wall_thickness, target_radius, max_action)?;
        let max_episode_steps = episode_limit(max_episode_steps)? as usize;
        let state = maze.start();
        Ok(MazeEnv {
            maze,
            state,
            elapsed: 0,
            max_episode_steps,
            path: vec![(state.x, state.y)],
        })
    }

    /// Starts an episode at `state` (reset-anywhere), else at s_0; returns the observation.
    #[pyo3(signature = (state = None))]
    fn reset<'py>(
        &mut self,
        py: Python<'py>,
        state: Option<(f32, f32)>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        self.state = match state {
            Some((x, y)) => state_of(&self.maze, "options['state']", x, y)?,
            None => self.maze.start(),
        };
        self.elapsed = 0;
        self.path.clear();
        self.path.push((self.state.x, self.state.y));
        Ok(PyArray1::from_slice(py, &[self.state.x, self.state.y]))
    }

    /// One step: `(observation, reward, terminated, truncated, hit_wall)`.
    fn step<'py>(&mut self, py: Python<'py>, action: &Bound<'py, PyAny>) -> PyResult<EnvStep<'py>> {
        let a = action_of(action)?;
        // The step's own wall test (its reward cannot tell: a step from inside the target
        // disc into a wall is paid 1 − 1 = 0).
        let hit = {
            let next = self.state + self.maze.clip_action(&a);
            self.maze.walls().segment_hits(&self.state, &next)
        };
        let step = self.maze.step(&self.state, &a);
        self.state = step.state;
        self.elapsed += 1;
        if self.path.len() <= self.max_episode_steps {
            self.path.push((self.state.x, self.state.y));
        }
        let truncated = !step.terminal && self.elapsed >= self.max_episode_steps;
        let obs = PyArray1::from_slice(py, &[self.state.x, self.state.y]);
        Ok((obs, step.reward, step.terminal, truncated, hit))
    }

    /// The pure step function: `(x', y', reward, terminal)` from `(x, y)` and `(ax, ay)`,
    /// without touching the episode.
    fn step_from(&self, x: f32, y: f32, ax: f32, ay: f32) -> PyResult<(f32, f32, f32, bool)> {
        let s = state_of(&self.maze, "state", x, y)?;
        let step = self.maze.step(&s, &[ax, ay]);
        Ok((step.state.x, step.state.y, step.reward, step.terminal))
    }

    /// An RGB image of the maze (walls black, start blue, target green) with the episode's
    /// path in green and the agent as a small purple circle.
    #[pyo3(signature = (size = 256))]
    fn render<'py>(&self, py: Python<'py>, size: i64) -> PyResult<Bound<'py, PyArray3<u8>>> {
        let picture = Picture {
            rollout_paths: vec![self.path.clone()],
            circles: vec![((self.state.x, self.state.y), 0.06)],
            ..Picture::default()
        };
        rgb_of(py, &pbcs::env::Planar::scene(&self.maze), &picture, size)
    }

    #[getter]
    fn size(&self) -> usize {
        self.maze.size()
    }
    #[getter]
    fn layout(&self) -> u64 {
        self.maze.config().seed
    }
    #[getter]
    fn max_episode_steps(&self) -> usize {
        self.max_episode_steps
    }
    #[getter]
    fn max_action(&self) -> f32 {
        self.maze.config().max_action
    }
    #[getter]
    fn target(&self) -> (f32, f32) {
        (self.maze.target().x, self.maze.target().y)
    }
    #[getter]
    fn target_radius(&self) -> f32 {
        self.maze.config().target_radius
    }
    #[getter]
    fn start(&self) -> (f32, f32) {
        (self.maze.start().x, self.maze.start().y)
    }
    #[getter]
    fn state(&self) -> (f32, f32) {
        (self.state.x, self.state.y)
    }
    #[getter]
    fn elapsed_steps(&self) -> usize {
        self.elapsed
    }
    /// The walls as rectangles `(x0, y0, x1, y1)`.
    #[getter]
    fn walls(&self) -> Vec<(f32, f32, f32, f32)> {
        walls_of(&self.maze)
    }
    /// The fewest steps from s_0 to the target disc (shortest collision-free path, in the
    /// Chebyshev norm, over the largest step), if the target is reachable.
    #[getter]
    fn fewest_steps(&self) -> Option<usize> {
        self.maze.fewest_steps()
    }
}

/// N mazes of one layout stepped in one call: the core of `pbcs.ContinuousMazeVec`.
/// Gymnasium's next-step autoreset: after an episode ends, the next `step` call resets that
/// maze to s_0 (its action is ignored; reward 0, neither terminated nor truncated).
#[pyclass(module = "pbcs._pbcs")]
pub(crate) struct MazeVecEnv {
    maze: Maze,
    states: Vec<Point<f32>>,
    elapsed: Vec<u32>,
    ended: Vec<bool>,
    max_episode_steps: u32,
}

type VecStep<'py> = (
    Bound<'py, PyArray2<f32>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<bool>>,
    Bound<'py, PyArray1<bool>>,
);

impl MazeVecEnv {
    fn observations<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f32>> {
        let flat: Vec<f32> = self.states.iter().flat_map(|p| [p.x, p.y]).collect();
        Array2::from_shape_vec((self.states.len(), 2), flat)
            .expect("two coordinates per state")
            .into_pyarray(py)
    }
}

#[pymethods]
impl MazeVecEnv {
    #[new]
    #[pyo3(signature = (num_envs, size, layout = 0, max_episode_steps = 1000, wall_thickness = 0.1, target_radius = 0.2, max_action = 0.1))]
    fn new(
        num_envs: i64,
        size: i64,
        layout: i64,
        max_episode_steps: i64,
        wall_thickness: f32,
        target_radius: f32,
        max_action: f32,
    ) -> PyResult<Self> {
        let maze = maze_of(size, layout, wall_thickness, target_radius, max_action)?;
        let n = count("num_envs", num_envs)? as usize;
        if n == 0 {
            return Err(invalid("num_envs", "must be at least 1"));
        }
        let max_episode_steps = episode_limit(max_episode_steps)?;
        Ok(MazeVecEnv {
            states: vec![maze.start(); n],
            maze,
            elapsed: vec![0; n],
            ended: vec![false; n],
            max_episode_steps,
        })
    }

    /// Starts every maze at s_0, or at `states` (shape (N, 2)); returns the observations.
    #[pyo3(signature = (states = None))]
    fn reset<'py>(
        &mut self,
        py: Python<'py>,
        states: Option<PyReadonlyArray2<'py, f32>>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let n = self.states.len();
        match states {
            None => self.states.fill(self.maze.start()),
            Some(s) => {
                let a = s.as_array();
                if a.shape() != [n, 2] {
                    return Err(invalid(
                        "options['states']",
                        format!("must have shape ({n}, 2), got {:?}", a.shape()),
                    ));
                }
                for (i, row) in a.outer_iter().enumerate() {
                    self.states[i] = state_of(&self.maze, "options['states']", row[0], row[1])?;
                }
            }
        }
        self.elapsed.fill(0);
        self.ended.fill(false);
        Ok(self.observations(py))
    }

    /// One step of every maze with `actions` (shape (N, 2), float32): observations,
    /// rewards, terminated, truncated.
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        actions: PyReadonlyArray2<'py, f32>,
    ) -> PyResult<VecStep<'py>> {
        let n = self.states.len();
        let a = actions.as_array();
        if a.shape() != [n, 2] {
            return Err(invalid(
                "actions",
                format!("must have shape ({n}, 2), got {:?}", a.shape()),
            ));
        }
        let mut rewards = vec![0.0f64; n];
        let mut terminated = vec![false; n];
        let mut truncated = vec![false; n];
        let start = self.maze.start();
        for i in 0..n {
            if self.ended[i] {
                self.states[i] = start;
                self.elapsed[i] = 0;
                self.ended[i] = false;
                continue;
            }
            let step = self.maze.step(&self.states[i], &[a[[i, 0]], a[[i, 1]]]);
            self.states[i] = step.state;
            self.elapsed[i] += 1;
            rewards[i] = f64::from(step.reward);
            terminated[i] = step.terminal;
            truncated[i] = !step.terminal && self.elapsed[i] >= self.max_episode_steps;
            self.ended[i] = terminated[i] || truncated[i];
        }
        Ok((
            self.observations(py),
            rewards.into_pyarray(py),
            terminated.into_pyarray(py),
            truncated.into_pyarray(py),
        ))
    }

    #[getter]
    fn num_envs(&self) -> usize {
        self.states.len()
    }
    #[getter]
    fn size(&self) -> usize {
        self.maze.size()
    }
    #[getter]
    fn max_action(&self) -> f32 {
        self.maze.config().max_action
    }
}

/// One step of the Rust port of gymnasium's Pendulum-v1 (`pbcs::envs::pendulum`) from (θ, θ̇) with
/// torque `torque`: the next (θ, θ̇), the reward and the observation (cos θ, sin θ, θ̇). For the
/// test that the port's steps are gymnasium's.
#[pyfunction]
pub(crate) fn pendulum_step(
    theta: f64,
    theta_dot: f64,
    torque: f32,
) -> ((f64, f64), f32, [f32; 3]) {
    let p = pbcs::envs::pendulum::Pendulum;
    let step = p.step(&[theta, theta_dot], &[torque]);
    let mut obs = [0.0f32; 3];
    p.observe(&step.state, &mut obs);
    ((step.state[0], step.state[1]), step.reward, obs)
}
