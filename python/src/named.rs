//! Any environment of the registry, by name, for Python: one episode (`NamedEnv`, the core of
//! `pbcs.make`) and a saved chain's environment (`ChainEnv`, behind `pbcs.Chain`'s rollouts,
//! evaluation and pictures). Each environment is made once by the registry
//! (`pbcs::envs::EnvSpec::build`) and kept behind a trait object, its type erased at that one
//! door ([`pbcs::with_env!`]); every step below is the environment's own.

use crate::{count, invalid, py_err};
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArray3};
use pbcs::config::{Located, PbcsJob, Place};
use pbcs::env::{Env, Planar};
use pbcs::envs::{EnvName, EnvSpec};
use pbcs::phase2::SkillChain;
use pbcs::plot::{render_rgb, Picture};
use pbcs::rng::{Seeds, Stream};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

/// `name` as a registry name, or a `ValueError` listing them.
pub(crate) fn env_name(name: &str) -> PyResult<EnvName> {
    name.parse::<EnvName>().map_err(|_| {
        invalid(
            "env",
            format!(
                "`{name}` is not an environment (maze, {})",
                EnvName::others()
            ),
        )
    })
}

/// The environment `env` with the maze of `size` and `layout` or the `map` of one's own (the
/// defaults where not given), checked: a maze for another environment, or a map for any but
/// `pointmaze` and `antmaze`, is refused, as `pbcs run --maze` and `--map` are ([`Place`]).
fn spec_for(env: EnvName, size: Option<i64>, layout: Option<i64>, map: Map) -> PyResult<EnvSpec> {
    let mut job = pbcs::config::ExploreJob::default();
    place_of(Some(env), size, layout, None, map)?
        .apply(&mut job)
        .map_err(py_err)?;
    let spec = job.env_spec();
    spec.check().map_err(py_err)?;
    Ok(spec)
}

/// A PointMaze map of one's own as Python gives it: `map` (rows as strings of `0`/`1`, or as
/// sequences of 0 and 1, gymnasium-robotics' `maze_map`) or `map_file` (a file of rows), not
/// both.
pub(crate) struct Map<'a, 'py> {
    pub(crate) rows: Option<&'a Bound<'py, PyAny>>,
    pub(crate) file: Option<std::path::PathBuf>,
}

impl Map<'_, '_> {
    /// The rows, read from whichever was given.
    fn rows(&self) -> PyResult<Option<Vec<String>>> {
        match (self.rows, &self.file) {
            (Some(_), Some(_)) => Err(invalid(
                "map",
                "give the map's rows (map=) or a file of them (map_file=), not both",
            )),
            (None, Some(file)) => Ok(Some(
                pbcs::envs::pointmaze::PointMazeConfig::from_file(file)
                    .map_err(py_err)?
                    .map,
            )),
            (Some(rows), None) => {
                if let Ok(text) = rows.extract::<Vec<String>>() {
                    return Ok(Some(text));
                }
                let cells: Vec<Vec<i64>> = rows.extract().map_err(|_| {
                    invalid(
                        "map",
                        "rows as strings of 0 and 1 ([\"111\", \"101\", ...]) or as lists of \
                         0 and 1 ([[1, 1, 1], [1, 0, 1], ...])",
                    )
                })?;
                let row = |r: &Vec<i64>| -> PyResult<String> {
                    r.iter()
                        .map(|&c| match c {
                            0 => Ok('0'),
                            1 => Ok('1'),
                            _ => Err(invalid(
                                "map",
                                format!("cells are 0 (free) or 1 (wall), got {c}"),
                            )),
                        })
                        .collect()
                };
                Ok(Some(cells.iter().map(row).collect::<PyResult<_>>()?))
            }
            (None, None) => Ok(None),
        }
    }
}

/// Where a Python call runs a job ([`Place`], as `pbcs run`'s flags): the environment, the
/// maze's `size` and `layout`, the run `seed`, each checked as a count, and a PointMaze map.
pub(crate) fn place_of(
    env: Option<EnvName>,
    size: Option<i64>,
    layout: Option<i64>,
    seed: Option<i64>,
    map: Map,
) -> PyResult<Place> {
    Ok(Place {
        env,
        maze_size: size
            .map(|n| count("maze.size", n).map(|n| usize::try_from(n).unwrap_or(usize::MAX)))
            .transpose()?,
        maze_seed: layout.map(|m| count("maze.seed", m)).transpose()?,
        seed: seed.map(|s| count("seed", s)).transpose()?,
        map: map.rows()?,
    })
}

/// A picture of `scene` with `picture` over it, as an RGB array of `side` × `side` pixels.
pub(crate) fn rgb_of<'py>(
    py: Python<'py>,
    scene: &pbcs::env::Scene,
    picture: &Picture,
    side: i64,
) -> PyResult<Bound<'py, PyArray3<u8>>> {
    if !(16..=4096).contains(&side) {
        return Err(invalid(
            "size",
            format!("must be between 16 and 4096 pixels, got {side}"),
        ));
    }
    let side = side as u32;
    let buf = render_rgb(scene, picture, side).map_err(py_err)?;
    let a = Array3::from_shape_vec((side as usize, side as usize, 3), buf)
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    Ok(a.into_pyarray(py))
}

/// One episode of an environment whose type is erased: what `NamedEnv` needs of it.
trait Episode {
    fn obs_dim(&self) -> usize;
    fn action_bounds(&self) -> Vec<f32>;
    /// Starts an episode from the environment's start distribution (its stream `Start` of
    /// `seed`'s seeds, or the last reset's stream): the observation.
    fn reset(&mut self, seed: Option<u64>) -> Vec<f32>;
    /// One step: observation, reward, terminal.
    fn step(&mut self, action: &[f32]) -> (Vec<f32>, f32, bool);
    /// The scene with the episode's path.
    fn picture(&self) -> (pbcs::env::Scene, Vec<(f32, f32)>);
}

/// An environment, its current state, the episode's drawn path (at most `cap` points: stepping
/// on past the time limit draws no more) and its start stream.
struct Running<E: Planar> {
    env: E,
    state: E::State,
    path: Vec<(f32, f32)>,
    cap: usize,
    rng: pbcs::rng::Rng,
}

impl<E: Planar> Running<E> {
    fn new(env: E, cap: usize) -> Self {
        let state = env.start();
        Running {
            path: vec![env.point(&state)],
            state,
            cap,
            rng: Seeds::new(0).stream(Stream::Start),
            env,
        }
    }

    fn obs(&self) -> Vec<f32> {
        let mut o = vec![0.0; self.env.obs_dim()];
        self.env.observe(&self.state, &mut o);
        o
    }
}

impl<E: Planar> Episode for Running<E> {
    fn obs_dim(&self) -> usize {
        self.env.obs_dim()
    }

    fn action_bounds(&self) -> Vec<f32> {
        (0..self.env.action_dim())
            .map(|i| self.env.action_bound(i))
            .collect()
    }

    fn reset(&mut self, seed: Option<u64>) -> Vec<f32> {
        if let Some(seed) = seed {
            self.rng = Seeds::new(seed).stream(Stream::Start);
        }
        self.state = self.env.sample_start(&mut self.rng);
        self.path = vec![self.env.point(&self.state)];
        self.obs()
    }

    fn step(&mut self, action: &[f32]) -> (Vec<f32>, f32, bool) {
        let s = self.env.step(&self.state, action);
        self.state = s.state;
        if self.path.len() < self.cap {
            self.path.push(self.env.point(&self.state));
        }
        (self.obs(), s.reward, s.terminal)
    }

    fn picture(&self) -> (pbcs::env::Scene, Vec<(f32, f32)>) {
        (self.env.scene(), self.path.clone())
    }
}

/// One episode of any environment of the registry: the core of `pbcs.make(name)`. `reset`
/// starts from the environment's start distribution (s_0 for the maze, the rooms and
/// PointMaze's task); `step` is the environment's own, truncated after `max_episode_steps`.
#[pyclass(module = "pbcs._pbcs", unsendable)]
pub(crate) struct NamedEnv {
    name: EnvName,
    episode: Box<dyn Episode>,
    bounds: Vec<f32>,
    elapsed: usize,
    max_episode_steps: usize,
}

#[pymethods]
impl NamedEnv {
    #[new]
    #[pyo3(signature = (name, size = None, layout = None, max_episode_steps = 1000, map = None, map_file = None))]
    fn new(
        name: &str,
        size: Option<i64>,
        layout: Option<i64>,
        max_episode_steps: i64,
        map: Option<&Bound<'_, PyAny>>,
        map_file: Option<std::path::PathBuf>,
    ) -> PyResult<Self> {
        let env = env_name(name)?;
        if env.goal_resets() {
            // Its observation would not hold the episode's goal.
            let gym_id = match (env.point_map(), env.ant_map()) {
                (Some(m), _) => m.gym_id(),
                (None, Some(m)) => pbcs::envs::antmaze::model::gym_id(m),
                (None, None) => String::new(),
            };
            let fixed = format!(", or `{}` for PBCS's fixed task", env.fixed_name());
            return Err(invalid(
                "env",
                format!(
                    "`{name}` draws a goal per episode, which this binding's observation does \
                     not show: in Python, use gymnasium-robotics' own {gym_id} (its observation \
                     dict holds the goal){fixed}"
                ),
            ));
        }
        let map = Map {
            rows: map,
            file: map_file,
        };
        let spec = spec_for(env, size, layout, map)?;
        let max_episode_steps = count("max_episode_steps", max_episode_steps)? as usize;
        if max_episode_steps == 0 {
            return Err(invalid("max_episode_steps", "must be at least 1"));
        }
        let built = spec.build().map_err(py_err)?;
        let episode: Box<dyn Episode> =
            pbcs::with_env!(built, |e| Box::new(Running::new(e, max_episode_steps + 1))
                as Box<dyn Episode>);
        Ok(NamedEnv {
            name: env,
            bounds: episode.action_bounds(),
            episode,
            elapsed: 0,
            max_episode_steps,
        })
    }

    /// The observation's length.
    #[getter]
    fn obs_dim(&self) -> usize {
        self.episode.obs_dim()
    }

    /// Each action component's bound b_i: the action lives in [−b_i, b_i].
    #[getter]
    fn action_bounds(&self) -> Vec<f32> {
        self.bounds.clone()
    }

    /// The registry's name.
    #[getter]
    fn name(&self) -> &'static str {
        self.name.name()
    }

    /// Starts an episode (the start stream seeded by `seed` when given): the observation.
    #[pyo3(signature = (seed = None))]
    fn reset<'py>(
        &mut self,
        py: Python<'py>,
        seed: Option<i64>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let seed = seed.map(|s| count("seed", s)).transpose()?;
        self.elapsed = 0;
        Ok(PyArray1::from_slice(py, &self.episode.reset(seed)))
    }

    /// One step: `(observation, reward, terminated, truncated)`. The action is clipped to its
    /// box (NaN counts as 0).
    fn step<'py>(
        &mut self,
        py: Python<'py>,
        action: Vec<f32>,
    ) -> PyResult<(Bound<'py, PyArray1<f32>>, f32, bool, bool)> {
        if action.len() != self.bounds.len() {
            return Err(invalid(
                "action",
                format!(
                    "must have {} components, got {}",
                    self.bounds.len(),
                    action.len()
                ),
            ));
        }
        let a: Vec<f32> = action
            .iter()
            .zip(&self.bounds)
            .map(|(&x, &b)| if x.is_nan() { 0.0 } else { x.clamp(-b, b) })
            .collect();
        let (obs, reward, terminal) = self.episode.step(&a);
        self.elapsed += 1;
        let truncated = !terminal && self.elapsed >= self.max_episode_steps;
        Ok((PyArray1::from_slice(py, &obs), reward, terminal, truncated))
    }

    /// The environment's picture with the episode's path, `size` × `size` pixels.
    #[pyo3(signature = (size = 256))]
    fn render<'py>(&self, py: Python<'py>, size: i64) -> PyResult<Bound<'py, PyArray3<u8>>> {
        let (scene, path) = self.episode.picture();
        let picture = Picture {
            rollout_paths: vec![path],
            ..Picture::default()
        };
        rgb_of(py, &scene, &picture, size)
    }
}

/// What a chain's picture draws: the environment's scene and its activation balls (centre as
/// drawn, radius).
pub(crate) type ChainPicture = (pbcs::env::Scene, Vec<((f32, f32), f32)>);

/// A saved chain's environment, its type erased: what `pbcs.Chain` runs on it.
pub(crate) trait ChainEnv: Send + Sync {
    /// The observations of `episodes` evaluation starts of `seed` (`pbcs::runs::chain_eval_starts`).
    fn eval_starts(&self, job: &PbcsJob, episodes: usize, seed: u64)
        -> pbcs::Result<Vec<Vec<f32>>>;
    /// One execution of `chain` from s_0: drawn points, success, skill of each step.
    fn rollout(&self, chain: &SkillChain, max_steps: usize) -> (Vec<(f32, f32)>, bool, Vec<usize>);
    /// The scene and the chain's activation balls where they are drawn.
    fn picture(&self, chain: &SkillChain) -> ChainPicture;
    /// The number of observation components.
    fn obs_dim(&self) -> usize;
    /// The length of a goal ([`pbcs::env::Goals::goal_dim`]), for an environment with goals.
    fn goal_dim(&self) -> Option<usize>;
}

impl<E: Planar + Send + Sync + 'static> ChainEnv for E {
    fn eval_starts(
        &self,
        job: &PbcsJob,
        episodes: usize,
        seed: u64,
    ) -> pbcs::Result<Vec<Vec<f32>>> {
        let starts = pbcs::runs::chain_eval_starts(self, job, episodes, seed)?;
        Ok(pbcs::env::observations(self, &starts))
    }

    fn rollout(&self, chain: &SkillChain, max_steps: usize) -> (Vec<(f32, f32)>, bool, Vec<usize>) {
        let r = chain.run(self, self.start(), max_steps);
        let points = r.states.iter().map(|s| self.point(s)).collect();
        (points, r.success, r.skill_used)
    }

    fn picture(&self, chain: &SkillChain) -> ChainPicture {
        let circles = chain
            .skills
            .iter()
            .map(|s| (self.ball_point(&s.activation.center), s.activation.radius))
            .collect();
        (self.scene(), circles)
    }

    fn obs_dim(&self) -> usize {
        Env::obs_dim(self)
    }

    fn goal_dim(&self) -> Option<usize> {
        self.goals().map(|g| g.goal_dim())
    }
}

/// The environment of a chain's job, erased; the registry's error where this build cannot
/// make it (PointMaze without MuJoCo), which acting alone does not need.
pub(crate) fn chain_env(job: &PbcsJob) -> pbcs::Result<Box<dyn ChainEnv>> {
    let built = job.env_spec().build()?;
    Ok(pbcs::with_env!(built, |e| Box::new(e) as Box<dyn ChainEnv>))
}

/// `starts` (observations) as an array of shape (len, obs_dim).
pub(crate) fn obs_array<'py>(
    py: Python<'py>,
    rows: &[Vec<f32>],
    dim: usize,
) -> Bound<'py, PyArray2<f32>> {
    let flat: Vec<f32> = rows.iter().flatten().copied().collect();
    Array2::from_shape_vec((rows.len(), dim), flat)
        .expect("one observation per row")
        .into_pyarray(py)
}
