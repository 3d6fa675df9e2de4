//! Phase 1, the protocol's start states and whole PBCS runs.

use crate::{count, invalid, maze_of, py_err};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2};
use pbcs::config::{ExploreJob, PbcsJob, Preset};
use pbcs::nn::kernel::Kernel;
use pbcs::validate::Check;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// Phase 1 on the maze `size` of layout `layout` with run seed `seed`: τ (from s_0 to the
/// first rewarded state) as an array of shape (len, 2), the actions between its states
/// (len − 1, 2), the environment steps it took and the archive's size.
#[pyfunction]
#[pyo3(signature = (size, layout = 0, seed = 0, bin_side = None, budget = None))]
pub(crate) fn explore<'py>(
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
pub(crate) fn evaluation_starts<'py>(
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
    let starts = pbcs::env::evaluation_starts(&maze, epsilon, n, &seeds).map_err(py_err)?;
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
pub(crate) fn run<'py>(
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
