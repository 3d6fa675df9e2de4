//! A saved chain of skills as a policy.

use crate::named::{chain_env, obs_array, rgb_of, ChainEnv};
use crate::{count, invalid, py_err, state_of};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3, PyReadonlyArray2};
use pbcs::config::{Located, PbcsJob};
use pbcs::envs::maze::Maze;
use pbcs::nn::kernel::Kernel;
use pbcs::nn::Workspace;
use pbcs::phase2::SkillChain;
use pbcs::plot::Picture;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;

/// A chain of skills saved by `pbcs run` (or `pbcs.run(out=...)`): the core of `pbcs.Chain`.
/// `act` executes it step by step (π_0 until the state enters A_1, then π_1, ...): it keeps
/// which skill acts, so `reset` starts a new episode.
#[pyclass(module = "pbcs._pbcs")]
pub(crate) struct ChainCore {
    chain: SkillChain,
    job: PbcsJob,
    /// The maze of a maze chain (rollouts from a given point); None for another environment.
    maze: Option<Maze>,
    /// The chain's environment, made by the registry for rollouts, starts and pictures; the
    /// registry's error where this build cannot make it (acting needs no environment).
    env: Result<Box<dyn ChainEnv>, String>,
    dir: PathBuf,
    active: usize,
    /// The policies' input and output sizes (the environment's observation and action).
    dims: (usize, usize),
    ws: Workspace,
}

impl ChainCore {
    /// The chain's maze, or a `ValueError` naming the environment it was built for.
    fn the_maze(&self) -> PyResult<&Maze> {
        self.maze.as_ref().ok_or_else(|| {
            PyValueError::new_err(format!(
                "{}: a chain of env = \"{}\", not of the maze (a start point needs the maze: \
                 leave it out to start at s_0)",
                self.dir.join("manifest.toml").display(),
                self.job.env.name()
            ))
        })
    }

    /// The chain's environment, or the error that says why this build cannot make it.
    fn the_env(&self) -> PyResult<&dyn ChainEnv> {
        match &self.env {
            Ok(env) => Ok(env.as_ref()),
            Err(why) => Err(PyValueError::new_err(format!(
                "{}: {why} (acting on observations needs no environment)",
                self.dir.join("manifest.toml").display()
            ))),
        }
    }
}

/// A PointMaze task as Python sees it: gymnasium-robotics' id, the start and goal cells (row,
/// column), the time limit.
type PointTask = (String, (usize, usize), (usize, usize), usize);

/// `value` as `n` finite numbers, or a `ValueError` naming `field` and saying what it is.
fn finite_floats(
    value: &Bound<'_, PyAny>,
    field: &str,
    n: usize,
    what: &str,
) -> PyResult<Vec<f32>> {
    let v: Vec<f32> = value
        .extract()
        .map_err(|_| invalid(field, format!("must be a sequence of {n} numbers ({what})")))?;
    if v.len() != n || v.iter().any(|x| !x.is_finite()) {
        return Err(invalid(
            field,
            format!("must be {n} finite numbers ({what}), got {v:?}"),
        ));
    }
    Ok(v)
}

/// The observation and action sizes (and ball dimension) every skill of `chain` shares, or an
/// error naming the skill that differs.
fn shared_dims(chain: &SkillChain, manifest: &std::path::Path) -> PyResult<(usize, usize)> {
    let dims = |i: usize| {
        let s = &chain.skills[i];
        let p = &s.policy;
        // The observation a skill is given: its policy's inputs less the sub-goal it sees
        // (`Inputs::goal`: a goal-conditioned chain's), which `act` appends itself.
        let seen = p.obs_dim().saturating_sub(s.inputs.goal.len());
        (seen, p.action_dim(), s.activation.center.len())
    };
    let first = dims(0);
    match (1..chain.skills.len()).find(|&i| dims(i) != first) {
        Some(i) => Err(PyValueError::new_err(format!(
            "{}: skill {i} takes {} observations, gives {} actions and has a ball of {} \
             coordinates, skill 0 {}, {} and {}",
            manifest.display(),
            dims(i).0,
            dims(i).1,
            dims(i).2,
            first.0,
            first.1,
            first.2
        ))),
        None => Ok((first.0, first.1)),
    }
}

#[pymethods]
impl ChainCore {
    /// The chain saved in `dir`; with `dims` (a user's Gymnasium environment's observation and
    /// action lengths, `pbcs.load_chain(path, adapter=...)`), checked against those instead of
    /// the job's environment, which a run through the adapter did not run on.
    #[new]
    #[pyo3(signature = (dir, dims = None))]
    fn new(dir: PathBuf, dims: Option<(usize, usize)>) -> PyResult<Self> {
        let kernel = Kernel::from_env().map_err(py_err)?;
        let (job, chain) = pbcs::runs::load_saved_job(&dir, kernel).map_err(py_err)?;
        let manifest = dir.join("manifest.toml");
        if chain.skills.is_empty() {
            return Err(PyValueError::new_err(format!(
                "{}: the chain has no skill",
                manifest.display()
            )));
        }
        if let Some(want) = dims {
            let got = shared_dims(&chain, &manifest)?;
            if got != want {
                return Err(PyValueError::new_err(format!(
                    "{}: the skills take {} observations and give {} actions, the adapter's \
                     environment {} and {}",
                    manifest.display(),
                    got.0,
                    got.1,
                    want.0,
                    want.1
                )));
            }
            return Ok(ChainCore {
                chain,
                job,
                maze: None,
                env: Err(
                    "a chain of a Gymnasium environment run through pbcs.Adapter: play it \
                          with Chain.evaluate_in(adapter)"
                        .into(),
                ),
                dir,
                active: 0,
                dims: got,
                ws: Workspace::with_kernel(kernel),
            });
        }
        // The maze needs no MuJoCo: a maze chain is checked against it; another environment's
        // chain is checked for consistent skills (`shared_dims`).
        let maze = if job.env.is_maze() {
            let maze = pbcs::envs::maze::Maze::new(&job.maze).map_err(py_err)?;
            chain.check_env(&maze, &manifest).map_err(py_err)?;
            Some(maze)
        } else {
            None
        };
        let dims = shared_dims(&chain, &manifest)?;
        let env = chain_env(&job).map_err(|e| e.to_string());
        if let Ok(env) = &env {
            if env.obs_dim() != dims.0 {
                return Err(PyValueError::new_err(format!(
                    "{}: the skills take {} observations, but env = \"{}\" observes {}",
                    manifest.display(),
                    dims.0,
                    job.env.name(),
                    env.obs_dim()
                )));
            }
        }
        Ok(ChainCore {
            chain,
            job,
            maze,
            env,
            dir,
            active: 0,
            dims,
            ws: Workspace::with_kernel(kernel),
        })
    }

    /// Starts a new execution: π_0 acts next.
    fn reset(&mut self) {
        self.active = 0;
    }

    /// The action at observation `obs` (switching to a later skill first if `obs` lies in
    /// its activation ball), in the environment's units; `goal`, the episode's goal (a
    /// goal-conditioned env's `desired_goal`), for a chain whose last skill aims at each
    /// episode's own (`phase2.last_goal = "drawn"`), which then needs it.
    /// With `noise` (standard normal draws, one per action component), a SAC chain's
    /// stochastic action b ⊙ tanh(μ + σ·noise), as its skills explored in training.
    #[pyo3(signature = (obs, goal = None, noise = None))]
    fn act<'py>(
        &mut self,
        py: Python<'py>,
        obs: &Bound<'py, PyAny>,
        goal: Option<&Bound<'py, PyAny>>,
        noise: Option<&Bound<'py, PyAny>>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let (n, m) = self.dims;
        let raw = finite_floats(obs, "obs", n, "the environment's observation")?;
        let goal = match (goal, self.chain.needs_goal()) {
            (Some(g), true) => {
                // The environment's goal length; (x, y) where it cannot be built here.
                let goal_len = self
                    .env
                    .as_ref()
                    .ok()
                    .and_then(|e| e.goal_dim())
                    .unwrap_or(2);
                Some(finite_floats(g, "goal", goal_len, "the episode's goal")?)
            }
            (None, true) => {
                return Err(PyValueError::new_err(
                    "this chain's last skill aims at each episode's own goal \
                     (phase2.last_goal = \"drawn\"): pass goal=, the env's desired_goal",
                ))
            }
            (_, false) => None,
        };
        self.active = self.chain.active_skill(self.active, &raw);
        if let Some(noise) = noise {
            let eps = finite_floats(noise, "noise", m, "the action's components")?;
            let a = self
                .chain
                .sample_toward(self.active, &raw, goal.as_deref(), &eps, &mut self.ws)
                .map_err(py_err)?;
            return Ok(PyArray1::from_slice(py, &a));
        }
        let (mut o, mut a) = (vec![0.0f32; n], vec![0.0f32; m]);
        self.chain.act_toward(
            self.active,
            &raw,
            goal.as_deref(),
            &mut o,
            &mut a,
            &mut self.ws,
        );
        Ok(PyArray1::from_slice(py, &a))
    }

    /// Whether acting needs the episode's goal (`act(obs, goal=...)`): a chain whose last
    /// skill aims at each episode's own (`phase2.last_goal = "drawn"`).
    #[getter]
    fn needs_goal(&self) -> bool {
        self.chain.needs_goal()
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
    fn maze(&self) -> PyResult<(usize, u64)> {
        let maze = self.the_maze()?;
        Ok((maze.size(), maze.config().seed))
    }

    /// The environment's name in the registry (`maze`, `rooms`, `pointmaze_medium`, ...).
    #[getter]
    fn env(&self) -> &'static str {
        self.job.env.name()
    }

    /// For a chain of PointMaze: gymnasium-robotics' id, the start and goal cells (row,
    /// column) of the task and the env's time limit; None for another environment. On a map
    /// of one's own: `PointMaze_UMaze-v3`, made with `maze_map=` [`Self::pointmaze_map`] and
    /// `max_episode_steps=` the job's `pointmaze.time_limit`.
    #[getter]
    fn pointmaze(&self) -> PyResult<Option<PointTask>> {
        use pbcs::envs::pointmaze::MapName;
        let Some(map) = self.job.env_spec().point_map().map_err(py_err)? else {
            return Ok(None);
        };
        let (start, goal) = map.farthest_cells();
        Ok(Some(match self.job.env.point_map() {
            Some(named) => (named.gym_id(), start, goal, named.time_limit()),
            None => (
                MapName::UMaze.gym_id(),
                start,
                goal,
                self.job.pointmaze.time_limit,
            ),
        }))
    }

    /// For a chain of AntMaze's fixed task: gymnasium-robotics' id, the start and goal cells
    /// (row, column) and the env's time limit; None for another environment. On a map of one's
    /// own (`antmaze`): `AntMaze_UMaze-v5`, made with `maze_map=` [`Self::pointmaze_map`] and
    /// `max_episode_steps=` the job's `pointmaze.time_limit`.
    #[getter]
    fn antmaze(&self) -> PyResult<Option<PointTask>> {
        use pbcs::envs::{antmaze::model, pointmaze::MapName};
        let env = self.job.env;
        if !env.is_antmaze() || env.goal_resets() {
            return Ok(None);
        }
        let map = self.job.env_spec().ant_map().map_err(py_err)?;
        let (start, goal) = map.farthest_cells();
        let (gym_id, time_limit) = match env.ant_map() {
            Some(named) => (model::gym_id(named), model::time_limit(named)),
            None => (model::gym_id(MapName::UMaze), self.job.pointmaze.time_limit),
        };
        Ok(Some((gym_id, start, goal, time_limit)))
    }

    /// For a chain on a map of one's own (`pointmaze`, `antmaze`): the map as
    /// gymnasium-robotics' `maze_map` takes it (rows of 0 and 1); None otherwise.
    #[getter]
    fn pointmaze_map(&self) -> PyResult<Option<Vec<Vec<u32>>>> {
        if !self.job.env.takes_map() {
            return Ok(None);
        }
        let map = pbcs::envs::pointmaze::PointMap::from_config(&self.job.pointmaze);
        let rows = map.map_err(py_err)?.to_rows();
        Ok(Some(
            rows.iter()
                .map(|r| r.bytes().map(|b| u32::from(b - b'0')).collect())
                .collect(),
        ))
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
    /// order, as observations: shape (episodes, observation length): (x, y) in the maze; uniform
    /// in B_ε(s_0), or drawn as the env's reset draws them with `phase2.first_starts = "drawn"`.
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
        let starts = (self.the_env()?)
            .eval_starts(&self.job, n, seed)
            .map_err(py_err)?;
        Ok(obs_array(py, &starts, self.dims.0))
    }

    /// One execution in the core from `start` (default s_0; a start point needs the maze): the
    /// states visited as the points they are drawn at, whether it reached the target, and the
    /// skill that chose each action.
    #[pyo3(signature = (start = None, max_steps = None))]
    fn rollout<'py>(
        &self,
        py: Python<'py>,
        start: Option<(f32, f32)>,
        max_steps: Option<i64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let m = match max_steps {
            Some(m) => count("max_steps", m)? as usize,
            None => self.job.phase2.eval_max_steps,
        };
        let (points, success, skill_used) = match start {
            Some((x, y)) => {
                let maze = self.the_maze()?;
                let r = self.chain.run(maze, state_of(maze, "start", x, y)?, m);
                let points: Vec<(f32, f32)> = r.states.iter().map(|p| (p.x, p.y)).collect();
                (points, r.success, r.skill_used)
            }
            None => self.the_env()?.rollout(&self.chain, m),
        };
        let flat: Vec<f32> = points.iter().flat_map(|&(x, y)| [x, y]).collect();
        let d = PyDict::new(py);
        d.set_item(
            "states",
            Array2::from_shape_vec((points.len(), 2), flat)
                .expect("two coordinates per state")
                .into_pyarray(py),
        )?;
        d.set_item("success", success)?;
        d.set_item("steps", points.len() - 1)?;
        d.set_item("skill_used", skill_used.into_pyarray(py))?;
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

    /// An RGB image of the chain's environment with its activation balls and `paths` (a list
    /// of (len, 2) arrays of drawn points, as `rollout` gives them) in green.
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
        let (scene, circles) = self.the_env()?.picture(&self.chain);
        let picture = Picture {
            rollout_paths,
            circles,
            ..Picture::default()
        };
        rgb_of(py, &scene, &picture, size)
    }

    fn __len__(&self) -> usize {
        self.chain.skills.len()
    }
}
