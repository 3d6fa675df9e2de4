//! `pbcs._pbcs`: the compiled part of the Python package `pbcs` (python/pbcs/ wraps it).
//!
//! Everything here calls the Rust core: the maze steps with `pbcs::maze::Maze`'s own step
//! function (no second implementation), phase 1 is `pbcs::explore`, a PBCS run is
//! `pbcs::runs::PbcsRun::compute`, a saved chain is `pbcs::phase2::SkillChain::load` run by
//! `SkillChain::active_skill` and `SkillChain::act`. Every error of the core becomes a Python
//! exception carrying its message (`ValueError` for bad input, `OSError` for files,
//! `RuntimeError` for work that failed); arguments are checked before they reach the core, so
//! nothing panics across the boundary.

use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyArrayMethods, PyReadonlyArray2};
use parry2d::math::Point;
use pbcs::config::{ExploreJob, PbcsJob, Preset};
use pbcs::env::Env;
use pbcs::maze::{Maze, MazeConfig};
use pbcs::nn::kernel::Kernel;
use pbcs::nn::Workspace;
use pbcs::phase2::SkillChain;
use pbcs::plot::{render_rgb, MazePicture};
use pbcs::validate::Check;
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;

/// A core error as the Python exception a Python user expects, with the core's message.
fn py_err(e: pbcs::Error) -> PyErr {
    match e {
        pbcs::Error::Invalid { .. } | pbcs::Error::Parse { .. } | pbcs::Error::Csv { .. } => {
            PyValueError::new_err(e.to_string())
        }
        pbcs::Error::Io { .. } => PyOSError::new_err(e.to_string()),
        _ => PyRuntimeError::new_err(e.to_string()),
    }
}

fn invalid(field: &str, reason: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(format!("invalid `{field}`: {reason}"))
}

/// A non-negative integer argument, named in the error when it is not.
fn count(field: &str, v: i64) -> PyResult<u64> {
    u64::try_from(v).map_err(|_| invalid(field, format!("must be at least 0, got {v}")))
}

/// The maze a Python caller names; the core validates it (`maze.size` between 2 and 100, ...).
fn maze_of(
    size: i64,
    layout: i64,
    wall_thickness: f32,
    target_radius: f32,
    max_action: f32,
) -> PyResult<Maze> {
    let size = usize::try_from(size).map_err(|_| {
        invalid(
            "maze.size",
            format!("must be between 2 and 100 cells, got {size}"),
        )
    })?;
    let config = MazeConfig {
        size,
        seed: count("maze.seed", layout)?,
        wall_thickness,
        target_radius,
        max_action,
    };
    Maze::new(&config).map_err(py_err)
}

/// An action from Python: a length-2 sequence of numbers (numpy array, list, tuple).
fn action_of(action: &Bound<'_, PyAny>) -> PyResult<[f32; 2]> {
    if let Ok(a) = action.cast::<PyArray1<f32>>() {
        let a = a.readonly();
        if let Ok(s) = a.as_slice() {
            if s.len() == 2 {
                return Ok([s[0], s[1]]);
            }
        }
    }
    let v: Vec<f32> = action.extract().map_err(|_| {
        invalid(
            "action",
            "must be a sequence of two numbers (the x and y steps)",
        )
    })?;
    match v[..] {
        [x, y] => Ok([x, y]),
        _ => Err(invalid(
            "action",
            format!("must have 2 components, got {}", v.len()),
        )),
    }
}

/// A state in [0, N]² with finite coordinates.
fn state_of(maze: &Maze, field: &str, x: f32, y: f32) -> PyResult<Point<f32>> {
    let n = maze.size() as f32;
    if !(x.is_finite() && y.is_finite() && (0.0..=n).contains(&x) && (0.0..=n).contains(&y)) {
        return Err(invalid(
            field,
            format!("must lie in [0, {n}]², got ({x}, {y})"),
        ));
    }
    Ok(Point::new(x, y))
}

/// The walls as rectangles `(x0, y0, x1, y1)`.
fn walls_of(maze: &Maze) -> Vec<(f32, f32, f32, f32)> {
    maze.walls()
        .walls()
        .iter()
        .map(|w| {
            let b = w.aabb();
            (b.mins.x, b.mins.y, b.maxs.x, b.maxs.y)
        })
        .collect()
}

fn rgb<'py>(
    py: Python<'py>,
    maze: &Maze,
    picture: &MazePicture,
    side: i64,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    if !(16..=4096).contains(&side) {
        return Err(invalid(
            "size",
            format!("must be between 16 and 4096 pixels, got {side}"),
        ));
    }
    let side = side as u32;
    let buf = render_rgb(maze, picture, side).map_err(py_err)?;
    let a = Array3::from_shape_vec((side as usize, side as usize, 3), buf)
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    Ok(a.into_pyarray(py))
}

/// What `MazeEnv::step` returns: observation, reward, terminated, truncated, hit a wall.
type EnvStep<'py> = (Bound<'py, PyArray1<f32>>, f32, bool, bool, bool);

/// One maze episode: the core of `pbcs.ContinuousMaze`. The state is a 2-D point; `step`
/// applies the paper's step function (clip the action to ±max_action, stay put if the segment
/// crosses a wall; reward +1 inside the target disc, which ends the episode, −1 for a wall)
/// and truncates after `max_episode_steps` steps.
#[pyclass(module = "pbcs._pbcs")]
struct MazeEnv {
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
        let max_episode_steps = count("max_episode_steps", max_episode_steps)? as usize;
        if max_episode_steps == 0 {
            return Err(invalid("max_episode_steps", "must be at least 1"));
        }
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
        let step = self.maze.step(&self.state, &a);
        self.state = step.state;
        self.elapsed += 1;
        if self.path.len() <= self.max_episode_steps {
            self.path.push((self.state.x, self.state.y));
        }
        let truncated = !step.terminal && self.elapsed >= self.max_episode_steps;
        let obs = PyArray1::from_slice(py, &[self.state.x, self.state.y]);
        Ok((
            obs,
            step.reward,
            step.terminal,
            truncated,
            step.reward < 0.0,
        ))
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
        let picture = MazePicture {
            rollout_paths: vec![self.path.clone()],
            circles: vec![((self.state.x, self.state.y), 0.06)],
            ..MazePicture::default()
        };
        rgb(py, &self.maze, &picture, size)
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
struct MazeVecEnv {
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
        let max_episode_steps = u32::try_from(count("max_episode_steps", max_episode_steps)?)
            .ok()
            .filter(|&m| m > 0)
            .ok_or_else(|| invalid("max_episode_steps", "must be between 1 and 2^32 - 1"))?;
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

/// Phase 1 on the maze `size` of layout `layout` with run seed `seed`: τ (from s_0 to the
/// first rewarded state) as an array of shape (len, 2), the actions between its states
/// (len − 1, 2), the environment steps it took and the archive's size.
#[pyfunction]
#[pyo3(signature = (size, layout = 0, seed = 0, bin_side = None, budget = None))]
fn explore<'py>(
    py: Python<'py>,
    size: i64,
    layout: i64,
    seed: i64,
    bin_side: Option<f32>,
    budget: Option<i64>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut job = ExploreJob::default();
    job.maze.size = usize::try_from(size).unwrap_or(0);
    job.maze.seed = count("maze.seed", layout)?;
    job.seed = count("seed", seed)?;
    if let Some(b) = bin_side {
        job.explore.bin_side = b;
    }
    if let Some(b) = budget {
        job.explore.budget = count("explore.budget", b)?;
    }
    maze_of(size, layout, 0.1, 0.2, 0.1)?;
    job.check().map_err(py_err)?;
    let run = py
        .detach(|| pbcs::runs::ExploreRun::compute(&job, |_, _| {}))
        .map_err(py_err)?;
    let t = &run.found.trajectory;
    let tau: Vec<f32> = t.states.iter().flat_map(|p| [p.x, p.y]).collect();
    let actions: Vec<f32> = t.actions.iter().flatten().copied().collect();
    let d = PyDict::new(py);
    d.set_item(
        "tau",
        Array2::from_shape_vec((t.states.len(), 2), tau)
            .expect("two coordinates per state")
            .into_pyarray(py),
    )?;
    d.set_item(
        "actions",
        Array2::from_shape_vec((t.actions.len(), 2), actions)
            .expect("two components per action")
            .into_pyarray(py),
    )?;
    d.set_item("env_steps", run.found.env_steps)?;
    d.set_item("archive_states", run.found.archive.len())?;
    Ok(d)
}

/// The start states of PBCS's evaluation protocol on the maze `size` of layout `layout`:
/// `episodes` states uniform in B_ε(s_0) (radius `epsilon`), drawn from the Eval stream of run
/// seed `seed`; the same states a chain of that seed is evaluated from. Shape (episodes, 2).
#[pyfunction]
#[pyo3(signature = (size, layout = 0, seed = 0, episodes = 100, epsilon = 0.1))]
fn evaluation_starts<'py>(
    py: Python<'py>,
    size: i64,
    layout: i64,
    seed: i64,
    episodes: i64,
    epsilon: f32,
) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let maze = maze_of(size, layout, 0.1, 0.2, 0.1)?;
    let n = count("episodes", episodes)? as usize;
    if !(epsilon.is_finite() && epsilon > 0.0) {
        return Err(invalid(
            "epsilon",
            format!("must be positive, got {epsilon}"),
        ));
    }
    let seeds = pbcs::rng::Seeds::new(count("seed", seed)?);
    let starts = pbcs::env::evaluation_starts(&maze, epsilon, n, &seeds);
    let flat: Vec<f32> = starts.iter().flat_map(|p| [p.x, p.y]).collect();
    Ok(Array2::from_shape_vec((n, 2), flat)
        .expect("two coordinates per state")
        .into_pyarray(py))
}

/// A whole PBCS run (phase 1, phase 2, the chain's evaluation) of a preset (`fast` or `paper`)
/// or of a config file; with `out`, its files (record, trace, chain/, picture) are written
/// there, as `pbcs run --out` does. Returns the run's record as a dict, τ as an array, and
/// the chain folder when one was written.
#[pyfunction]
#[pyo3(signature = (size, layout = 0, seed = 0, preset = "fast", config = None, out = None, max_env_steps = None))]
#[allow(clippy::too_many_arguments)]
fn run<'py>(
    py: Python<'py>,
    size: i64,
    layout: i64,
    seed: i64,
    preset: &str,
    config: Option<PathBuf>,
    out: Option<PathBuf>,
    max_env_steps: Option<i64>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut job: PbcsJob = match &config {
        Some(p) => pbcs::config::load(p).map_err(py_err)?,
        None => match preset {
            "fast" => Preset::Fast.job(),
            "paper" => Preset::Paper.job(),
            other => Err(pbcs::Error::invalid(
                "preset",
                format!("must be `fast` or `paper`, got `{other}`"),
            )),
        }
        .map_err(py_err)?,
    };
    let maze = maze_of(
        size,
        layout,
        job.maze.wall_thickness,
        job.maze.target_radius,
        job.maze.max_action,
    )?;
    job.maze = maze.config().clone();
    job.seed = count("seed", seed)?;
    if let Some(m) = max_env_steps {
        job.phase2.max_env_steps = count("phase2.max_env_steps", m)?;
    }
    job.check().map_err(py_err)?;
    let kernel = Kernel::from_env().map_err(py_err)?;
    let done = py
        .detach(|| pbcs::runs::PbcsRun::compute(&job, kernel, |_, _| {}))
        .map_err(py_err)?;
    if let Some(dir) = &out {
        py.detach(|| done.write(&job, dir)).map_err(py_err)?;
    }
    let r = &done.record;
    let d = PyDict::new(py);
    d.set_item("maze", r.maze)?;
    d.set_item("maze_seed", r.maze_seed)?;
    d.set_item("seed", r.seed)?;
    d.set_item("solved", r.solved)?;
    d.set_item("success_rate", r.success_rate)?;
    d.set_item(
        "failure",
        r.failure.map(|f| <&'static str>::from(f).to_string()),
    )?;
    d.set_item("skills", r.skills)?;
    d.set_item("phase1_steps", r.phase1_steps)?;
    d.set_item("train_steps", r.train_steps)?;
    d.set_item("test_steps", r.test_steps)?;
    d.set_item("total_steps", r.total_steps)?;
    d.set_item("seconds", done.seconds)?;
    let tau: Vec<f32> = done.tau.iter().flat_map(|p| [p.x, p.y]).collect();
    d.set_item(
        "tau",
        Array2::from_shape_vec((done.tau.len(), 2), tau)
            .expect("two coordinates per state")
            .into_pyarray(py),
    )?;
    let steps: Vec<usize> = done.evaluation.iter().map(|e| e.steps).collect();
    let wins: Vec<bool> = done.evaluation.iter().map(|e| e.success).collect();
    d.set_item("evaluation_success", wins.into_pyarray(py))?;
    d.set_item("evaluation_steps", steps.into_pyarray(py))?;
    d.set_item("chain", out.map(|o| o.join("chain")))?;
    Ok(d)
}

/// A chain of skills saved by `pbcs run` (or `pbcs.run(out=...)`): the core of `pbcs.Chain`.
/// `act` executes it step by step (π_0 until the state enters A_1, then π_1, ...): it keeps
/// which skill acts, so `reset` starts a new episode.
#[pyclass(module = "pbcs._pbcs")]
struct ChainCore {
    chain: SkillChain,
    job: PbcsJob,
    maze: Maze,
    dir: PathBuf,
    active: usize,
    ws: Workspace,
}

#[pymethods]
impl ChainCore {
    #[new]
    fn new(dir: PathBuf) -> PyResult<Self> {
        let kernel = Kernel::from_env().map_err(py_err)?;
        let (job, maze, chain) = pbcs::runs::load_saved_chain(&dir, kernel).map_err(py_err)?;
        if chain.skills.is_empty() {
            return Err(PyValueError::new_err(format!(
                "{}: the chain has no skill",
                dir.join("manifest.toml").display()
            )));
        }
        for (i, s) in chain.skills.iter().enumerate() {
            if s.policy.sizes()[0] != 2 || s.policy.sizes().last() != Some(&2) {
                return Err(PyValueError::new_err(format!(
                    "{}: skill {i} is not a maze policy (2 inputs, 2 outputs)",
                    dir.join("manifest.toml").display()
                )));
            }
        }
        Ok(ChainCore {
            chain,
            job,
            maze,
            dir,
            active: 0,
            ws: Workspace::with_kernel(kernel),
        })
    }

    /// Starts a new execution: π_0 acts next.
    fn reset(&mut self) {
        self.active = 0;
    }

    /// The action at observation `obs` (switching to a later skill first if `obs` lies in
    /// its activation ball), in the environment's units.
    fn act<'py>(
        &mut self,
        py: Python<'py>,
        obs: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let raw = action_of(obs).map_err(|_| {
            invalid(
                "obs",
                "must be a sequence of two numbers (the x and y coordinates)",
            )
        })?;
        self.active = self.chain.active_skill(self.active, &raw);
        let (mut o, mut a) = ([0.0f32; 2], [0.0f32; 2]);
        self.chain
            .act(self.active, &raw, &mut o, &mut a, &mut self.ws);
        Ok(PyArray1::from_slice(py, &a))
    }

    /// The skill that chose the last action.
    #[getter]
    fn active_skill(&self) -> usize {
        self.active
    }

    /// The skills' activation balls: `(centre x, centre y, radius)`.
    #[getter]
    fn balls(&self) -> Vec<(f32, f32, f32)> {
        self.chain
            .skills
            .iter()
            .map(|s| {
                (
                    s.activation.center[0],
                    s.activation.center[1],
                    s.activation.radius,
                )
            })
            .collect()
    }

    /// The maze the chain was built for: `(size, layout)`.
    #[getter]
    fn maze(&self) -> (usize, u64) {
        (self.maze.size(), self.maze.config().seed)
    }

    /// The run seed of the job that built the chain.
    #[getter]
    fn seed(&self) -> u64 {
        self.job.seed
    }

    /// ε of the job that built the chain (the radius of B_ε(s_0) the evaluation starts in).
    #[getter]
    fn epsilon(&self) -> f32 {
        self.job.phase2.epsilon
    }

    /// The step limit of the job's evaluation episodes.
    #[getter]
    fn eval_max_steps(&self) -> usize {
        self.job.phase2.eval_max_steps
    }

    /// The start states of `pbcs eval`'s episodes for `seed` (default: the run's seed), in
    /// order: shape (episodes, 2).
    #[pyo3(signature = (episodes = 100, seed = None))]
    fn eval_starts<'py>(
        &self,
        py: Python<'py>,
        episodes: i64,
        seed: Option<i64>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let n = count("episodes", episodes)? as usize;
        let seed = seed
            .map(|s| count("seed", s))
            .transpose()?
            .unwrap_or(self.job.seed);
        let starts = pbcs::env::evaluation_starts(
            &self.maze,
            self.job.phase2.epsilon,
            n,
            &pbcs::rng::Seeds::new(seed),
        );
        let flat: Vec<f32> = starts.iter().flat_map(|p| [p.x, p.y]).collect();
        Ok(Array2::from_shape_vec((n, 2), flat)
            .expect("two coordinates per state")
            .into_pyarray(py))
    }

    /// One execution in the core from `start` (default s_0): the states visited, whether it
    /// reached the target, and the skill that chose each action.
    #[pyo3(signature = (start = None, max_steps = None))]
    fn rollout<'py>(
        &self,
        py: Python<'py>,
        start: Option<(f32, f32)>,
        max_steps: Option<i64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let s = match start {
            Some((x, y)) => state_of(&self.maze, "start", x, y)?,
            None => self.maze.start(),
        };
        let m = match max_steps {
            Some(m) => count("max_steps", m)? as usize,
            None => self.job.phase2.eval_max_steps,
        };
        let r = self.chain.run(&self.maze, s, m);
        let flat: Vec<f32> = r.states.iter().flat_map(|p| [p.x, p.y]).collect();
        let d = PyDict::new(py);
        d.set_item(
            "states",
            Array2::from_shape_vec((r.states.len(), 2), flat)
                .expect("two coordinates per state")
                .into_pyarray(py),
        )?;
        d.set_item("success", r.success)?;
        d.set_item("steps", r.states.len() - 1)?;
        d.set_item("skill_used", r.skill_used.into_pyarray(py))?;
        Ok(d)
    }

    /// `pbcs eval`'s evaluation, computed by the core: successes, episodes, the Wilson 95 %
    /// interval and each episode's steps.
    #[pyo3(signature = (episodes = 100, seed = None))]
    fn evaluate<'py>(
        &self,
        py: Python<'py>,
        episodes: i64,
        seed: Option<i64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let n = count("episodes", episodes)? as usize;
        let seed = seed.map(|s| count("seed", s)).transpose()?;
        let kernel = self.chain.kernel;
        let dir = self.dir.clone();
        let e = py
            .detach(|| pbcs::runs::eval_chain(&dir, n, seed, kernel))
            .map_err(py_err)?;
        let d = PyDict::new(py);
        d.set_item("successes", e.successes)?;
        d.set_item("episodes", e.episodes)?;
        d.set_item("interval", e.interval)?;
        d.set_item("seed", e.seed)?;
        let steps: Vec<usize> = e.rows.iter().map(|r| r.steps).collect();
        let wins: Vec<bool> = e.rows.iter().map(|r| r.success).collect();
        d.set_item("success", wins.into_pyarray(py))?;
        d.set_item("steps", steps.into_pyarray(py))?;
        Ok(d)
    }

    /// An RGB image of the chain's maze with its activation balls and `paths` (a list of
    /// (len, 2) arrays) in green.
    #[pyo3(signature = (paths = None, size = 256))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        paths: Option<&Bound<'py, PyList>>,
        size: i64,
    ) -> PyResult<Bound<'py, PyArray3<u8>>> {
        let mut rollout_paths = Vec::new();
        for p in paths.into_iter().flatten() {
            let a: PyReadonlyArray2<f32> = p.extract().map_err(|_| {
                invalid(
                    "paths",
                    "must be a list of float32 arrays of shape (len, 2)",
                )
            })?;
            let a = a.as_array();
            if a.ncols() != 2 {
                return Err(invalid("paths", "each path must have shape (len, 2)"));
            }
            rollout_paths.push(a.outer_iter().map(|r| (r[0], r[1])).collect());
        }
        let picture = MazePicture {
            rollout_paths,
            circles: self
                .chain
                .skills
                .iter()
                .map(|s| {
                    (
                        (s.activation.center[0], s.activation.center[1]),
                        s.activation.radius,
                    )
                })
                .collect(),
            ..MazePicture::default()
        };
        rgb(py, &self.maze, &picture, size)
    }

    fn __len__(&self) -> usize {
        self.chain.skills.len()
    }
}

#[pymodule]
fn _pbcs(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<MazeEnv>()?;
    m.add_class::<MazeVecEnv>()?;
    m.add_class::<ChainCore>()?;
    m.add_function(wrap_pyfunction!(explore, m)?)?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(evaluation_starts, m)?)?;
    m.add("MAX_MAZE_SIZE", pbcs::maze::MAX_MAZE_SIZE)?;
    Ok(())
}
