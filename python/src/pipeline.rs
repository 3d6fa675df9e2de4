//! Phase 1, the protocol's start states and whole PBCS runs.

use crate::{count, invalid, maze_of, py_err};
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2};
use pbcs::config::{ExploreJob, Located, PbcsJob, Preset};
use pbcs::env::{Env as _, EvalEpisode, Planar};
use pbcs::nn::kernel::Kernel;
use pbcs::runs::{PbcsRun, RunRecord};
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
    let m = &job.maze;
    maze_of(
        size,
        layout,
        m.wall_thickness,
        m.target_radius,
        m.max_action,
    )?;
    let job = job.valid().map_err(py_err)?;
    let maze = pbcs::envs::maze::Maze::new(&job.maze).map_err(py_err)?;
    let run = py
        .detach(|| pbcs::runs::ExploreRun::compute(maze, &job, |_, _| {}))
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
    let m = pbcs::config::MazeConfig::default();
    let maze = maze_of(
        size,
        layout,
        m.wall_thickness,
        m.target_radius,
        m.max_action,
    )?;
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
/// or of a config file, on the environment it names (`env`, else the config's, else the
/// maze: of size `size` and layout `layout`, else the config's; `pointmaze` and `antmaze`: on
/// the map `map` or `map_file`, else the config's); with `out`, its files
/// (record, trace, chain/, picture) are written there, as `pbcs run --out` does. Returns the
/// run's record as a dict, τ as an array of points, and the chain folder when one was
/// written.
#[pyfunction]
#[pyo3(signature = (size = None, layout = None, seed = 0, preset = "fast", config = None, out = None, max_env_steps = None, env = None, map = None, map_file = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn run<'py>(
    py: Python<'py>,
    size: Option<i64>,
    layout: Option<i64>,
    seed: i64,
    preset: &str,
    config: Option<PathBuf>,
    out: Option<PathBuf>,
    max_env_steps: Option<i64>,
    env: Option<&str>,
    map: Option<&Bound<'py, PyAny>>,
    map_file: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let mut job = job_of(preset, config.as_deref())?;
    let env = env.map(crate::named::env_name).transpose()?;
    let map = crate::named::Map {
        rows: map,
        file: map_file,
    };
    let place = crate::named::place_of(env, size, layout, Some(seed), map)?;
    place.apply(&mut job).map_err(py_err)?;
    if let Some(m) = max_env_steps {
        job.phase2.max_env_steps = count("phase2.max_env_steps", m)?;
    }
    let job = job.valid().map_err(py_err)?;
    let kernel = Kernel::from_env().map_err(py_err)?;
    let built = job.env_spec().build().map_err(py_err)?;
    let done = py
        .detach(|| {
            pbcs::with_env!(built, |env| {
                let run = PbcsRun::compute(env, &job, kernel, |_, _| {})?;
                if let Some(dir) = out.as_deref() {
                    run.write(&job, dir, &pbcs::plot::draw_run)?;
                }
                pbcs::Result::Ok(RunDone {
                    tau: run.tau.iter().map(|s| run.env.point(s)).collect(),
                    record: run.record,
                    seconds: run.seconds,
                    evaluation: run.evaluation,
                })
            })
        })
        .map_err(py_err)?;
    record_dict(py, &done, out)
}

/// [`run`]'s answer: the record, τ, the evaluation episodes and the chain's folder.
fn record_dict<'py>(
    py: Python<'py>,
    done: &RunDone,
    out: Option<PathBuf>,
) -> PyResult<Bound<'py, PyDict>> {
    let r = &done.record;
    let d = PyDict::new(py);
    d.set_item("env", r.env.name())?;
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
    let tau: Vec<f32> = done.tau.iter().flat_map(|&(x, y)| [x, y]).collect();
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

/// What [`run`] returns of a run on any environment: τ as points of its plane.
struct RunDone {
    record: RunRecord,
    seconds: f64,
    tau: Vec<(f32, f32)>,
    evaluation: Vec<EvalEpisode>,
}

/// The job in the config file `config`, else the preset named `preset`.
fn job_of(preset: &str, config: Option<&std::path::Path>) -> PyResult<PbcsJob> {
    match config {
        Some(p) => pbcs::config::load(p),
        None => Preset::named(preset).and_then(Preset::job),
    }
    .map_err(py_err)
}

/// The job of a run on the user's environment behind `adapter`: the preset or config file,
/// with `seed` and `max_env_steps` (checked by the core), its environment the adapter's:
/// recorded as `gym`, the job's `[maze]` and `[pointmaze]` (which describe ours) left at
/// their defaults, or as the registry's environment the adapter says it copies
/// (`recorded_as`, whose sections the job keeps).
fn gym_job(
    adapter: &Bound<'_, PyAny>,
    seed: i64,
    preset: &str,
    config: Option<&std::path::Path>,
    max_env_steps: Option<i64>,
) -> PyResult<pbcs::validate::Valid<PbcsJob>> {
    let mut job = job_of(preset, config)?;
    let recorded: Option<String> = adapter.getattr("recorded_as")?.extract()?;
    match recorded {
        Some(name) => job.env = crate::named::env_name(&name)?,
        None => {
            job.env = pbcs::envs::EnvName::Gym;
            job.maze = Default::default();
            job.pointmaze = Default::default();
        }
    }
    job.seed = count("seed", seed)?;
    if let Some(m) = max_env_steps {
        job.phase2.max_env_steps = count("phase2.max_env_steps", m)?;
    }
    job.valid().map_err(py_err)
}

/// PBCS (phase 1, phase 2, the chain's evaluation from B_ε(s_0)) on the user's Gymnasium
/// environment behind `adapter` (a checked `pbcs.adapter.Adapter`), with a preset or a
/// config file; with `out`, the run's files (no picture) written there as `pbcs run --out`
/// writes them. A setting that needs a hook the adapter was not given is refused before any
/// work. With `progress`, phase 2 shows what it does on standard error.
#[pyfunction]
#[pyo3(signature = (adapter, seed = 0, preset = "fast", config = None, out = None, max_env_steps = None, progress = true))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_gym<'py>(
    py: Python<'py>,
    adapter: &Bound<'py, PyAny>,
    seed: i64,
    preset: &str,
    config: Option<PathBuf>,
    out: Option<PathBuf>,
    max_env_steps: Option<i64>,
    progress: bool,
) -> PyResult<Bound<'py, PyDict>> {
    use std::io::IsTerminal as _;
    let job = gym_job(adapter, seed, preset, config.as_deref(), max_env_steps)?;
    let kernel = Kernel::from_env().map_err(py_err)?;
    let env = crate::adapter::Gym::new(adapter)?;
    let bar = if progress {
        indicatif::ProgressBar::new_spinner()
    } else {
        indicatif::ProgressBar::hidden()
    };
    let lines = progress && !std::io::stderr().is_terminal();
    // Phase 1 reports nothing to a whole run's caller: its spinner says what runs, and ticks.
    let exploring = "phase 1: exploring from s_0 (returns to archived states, random actions)";
    bar.set_message(exploring);
    bar.enable_steady_tick(std::time::Duration::from_millis(250));
    if lines {
        eprintln!("{exploring}");
    }
    let mut shown = pbcs::runs::Phase2Progress::new(bar, lines);
    let run = crate::adapter::catching(py, || {
        PbcsRun::compute(env, &job, kernel, |skill, p| shown.report(skill, p))
    })?
    .map_err(py_err)?;
    shown.finish();
    if let Some(dir) = out.as_deref() {
        run.write(&job, dir, &pbcs::picture::no_pictures)
            .map_err(py_err)?;
    }
    let done = RunDone {
        tau: run.tau.iter().map(|s| run.env.point(s)).collect(),
        record: run.record,
        seconds: run.seconds,
        evaluation: run.evaluation,
    };
    record_dict(py, &done, out)
}

/// Phase 1 alone on the user's environment behind `adapter`: τ as observations (position
/// first), the actions between them, the env steps and the archive's size. With `progress`,
/// a spinner on standard error with the steps, the archive and the steps per second.
#[pyfunction]
#[pyo3(signature = (adapter, seed = 0, preset = "fast", config = None, progress = true))]
pub(crate) fn explore_gym<'py>(
    py: Python<'py>,
    adapter: &Bound<'py, PyAny>,
    seed: i64,
    preset: &str,
    config: Option<PathBuf>,
    progress: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let job = gym_job(adapter, seed, preset, config.as_deref(), None)?;
    let env = crate::adapter::Gym::new(adapter)?;
    let mut rng = pbcs::rng::Seeds::new(job.seed).stream(pbcs::rng::Stream::Explore);
    let bar = if progress {
        indicatif::ProgressBar::new_spinner()
    } else {
        indicatif::ProgressBar::hidden()
    };
    let clock = std::time::Instant::now();
    let shown = |steps: u64, archive: usize| {
        let rate = steps as f64 / clock.elapsed().as_secs_f64().max(1e-9);
        bar.set_message(format!(
            "phase 1: {steps} env steps, {archive} states archived ({rate:.0} steps/s)"
        ));
        bar.tick();
    };
    let found = crate::adapter::catching(py, || {
        pbcs::phase1::explore(&env, &job.explore, &mut rng, shown)
    })?
    .map_err(py_err)?;
    bar.finish_and_clear();
    let t = &found.trajectory;
    let observations = pbcs::env::observations(&env, &t.states);
    let rows = |v: &[Vec<f32>], width: usize| {
        let flat: Vec<f32> = v.iter().flatten().copied().collect();
        Array2::from_shape_vec((v.len(), width), flat).expect("rows of one width")
    };
    let d = PyDict::new(py);
    d.set_item("tau", rows(&observations, env.obs_dim()).into_pyarray(py))?;
    d.set_item(
        "actions",
        rows(&t.actions, env.action_dim()).into_pyarray(py),
    )?;
    d.set_item("env_steps", found.env_steps)?;
    d.set_item("archive_states", found.archive.len())?;
    Ok(d)
}
