//! `pbcs._pbcs`: the compiled part of the Python package `pbcs` (python/pbcs/ wraps it).
//!
//! Everything here calls the Rust core: the maze steps with `pbcs::envs::maze::Maze`'s own step
//! function (no second implementation), phase 1 is `pbcs::phase1`, a PBCS run is
//! `pbcs::runs::PbcsRun::compute`, a saved chain is `pbcs::phase2::SkillChain::load` run by
//! `SkillChain::active_skill` and `SkillChain::act`. Every error of the core becomes a Python
//! exception carrying its message (`ValueError` for bad input and for a setting that needs a
//! hook the environment lacks, `OSError` for files,
//! `RuntimeError` for work that failed); arguments are checked before they reach the core, so
//! nothing panics across the boundary.

use numpy::{PyArray1, PyArrayMethods};
use parry2d::math::Point;
use pbcs::envs::maze::{Maze, MazeConfig};
use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;

/// A core error as the Python exception a Python user expects, with the core's message.
pub(crate) fn py_err(e: pbcs::Error) -> PyErr {
    match e {
        pbcs::Error::Invalid { .. }
        | pbcs::Error::Parse { .. }
        | pbcs::Error::Csv { .. }
        | pbcs::Error::Capability { .. } => PyValueError::new_err(e.to_string()),
        pbcs::Error::Io { .. } => PyOSError::new_err(e.to_string()),
        _ => PyRuntimeError::new_err(e.to_string()),
    }
}

pub(crate) fn invalid(field: &str, reason: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(format!("invalid `{field}`: {reason}"))
}

/// A non-negative integer argument, named in the error when it is not.
pub(crate) fn count(field: &str, v: i64) -> PyResult<u64> {
    u64::try_from(v).map_err(|_| invalid(field, format!("must be at least 0, got {v}")))
}

/// The maze a Python caller names; the core validates it (`maze.size` between 2 and 100, ...).
pub(crate) fn maze_of(
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
pub(crate) fn action_of(action: &Bound<'_, PyAny>) -> PyResult<[f32; 2]> {
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
pub(crate) fn state_of(maze: &Maze, field: &str, x: f32, y: f32) -> PyResult<Point<f32>> {
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
pub(crate) fn walls_of(maze: &Maze) -> Vec<(f32, f32, f32, f32)> {
    maze.walls()
        .walls()
        .iter()
        .map(|w| {
            let b = w.aabb();
            (b.mins.x, b.mins.y, b.maxs.x, b.maxs.y)
        })
        .collect()
}

mod adapter;
mod chain;
mod env;
mod named;
mod pipeline;

#[pymodule]
fn _pbcs(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<env::MazeEnv>()?;
    m.add_class::<env::MazeVecEnv>()?;
    m.add_class::<chain::ChainCore>()?;
    m.add_class::<named::NamedEnv>()?;
    m.add_class::<adapter::Draws>()?;
    m.add_function(wrap_pyfunction!(pipeline::explore, m)?)?;
    m.add_function(wrap_pyfunction!(pipeline::run, m)?)?;
    m.add_function(wrap_pyfunction!(pipeline::run_gym, m)?)?;
    m.add_function(wrap_pyfunction!(pipeline::explore_gym, m)?)?;
    m.add_function(wrap_pyfunction!(pipeline::evaluation_starts, m)?)?;
    m.add_function(wrap_pyfunction!(env::pendulum_step, m)?)?;
    m.add("MAX_MAZE_SIZE", pbcs::envs::maze::MAX_MAZE_SIZE)?;
    // The names this binding makes: not the goal-drawing ones, whose goal its observation
    // would not show (`NamedEnv::new` refuses them, saying what to use).
    let names: Vec<&str> = pbcs::envs::EnvName::all()
        .iter()
        .filter(|e| !e.goal_resets())
        .map(|e| e.name())
        .collect();
    m.add("ENV_NAMES", names)?;
    m.add("MUJOCO", cfg!(feature = "mujoco"))?;
    Ok(())
}
