//! A Gymnasium environment of the user's as the core's [`Env`]: each step is one call of the
//! Python `pbcs.adapter.Adapter` (python/pbcs/adapter.py, which checked the env before any
//! work), and `set_state` is called only when the state the core steps from is not the one
//! the Python environment is in (a rollout: one call per step).
//!
//! The core's step cannot fail, a Python step can: the exception raised in the user's code
//! unwinds the core's work ([`Gym::fail`]) to [`catching`], which gives it back as a Python
//! exception naming the call, before anything is written.

use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pbcs::env::{BallIsClear, Env, Planar, SampleBall, Scene, Step};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use rand::Rng as _;
use serde::{Deserialize, Serialize};
use std::cell::RefCell;
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};

/// A state of the user's environment: the vector its `get_state()` gave and the observation
/// (position first) that goes with it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(crate) struct GymState {
    sim: Vec<f64>,
    obs: Vec<f32>,
}

/// The user's environment behind the core's [`Env`].
pub(crate) struct Gym {
    adapter: Py<PyAny>,
    obs_dim: usize,
    position_dims: usize,
    action_high: Vec<f32>,
    start: GymState,
    /// Where the position lies in the state vector (ball starts write it there).
    state_position: Option<Vec<usize>>,
    /// The observation space's bounds of the position (a drawn start is clamped to them).
    low: Vec<f32>,
    high: Vec<f32>,
    success_region: Option<(Vec<f32>, f32)>,
    ball_is_clear: Option<Py<PyAny>>,
    /// Whether the user drew ball starts themselves (`Adapter.ball_start` calls the hook).
    own_ball_starts: bool,
    names: Vec<String>,
    /// The state the Python environment is in now: interior mutability because the core's
    /// `step` is a pure function of `&self` while the Python object it calls is not.
    at: RefCell<Option<GymState>>,
}

/// The unwinding payload of a failed Python call ([`Gym::fail`]): the call and its exception.
struct Failed(&'static str, PyErr);

/// Runs `work` (the core on a [`Gym`]), giving back an exception the user's code raised as a
/// `RuntimeError` naming the call, caused by it.
pub(crate) fn catching<T>(py: Python<'_>, work: impl FnOnce() -> T) -> PyResult<T> {
    match catch_unwind(AssertUnwindSafe(work)) {
        Ok(t) => Ok(t),
        Err(payload) => match payload.downcast::<Failed>() {
            Ok(failed) => {
                let Failed(call, e) = *failed;
                let what = e
                    .value(py)
                    .repr()
                    .map_or("an exception".into(), |r| r.to_string());
                let err = PyRuntimeError::new_err(format!(
                    "the environment's {call} raised {what}: PBCS stopped, nothing was written"
                ));
                err.set_cause(py, Some(e));
                Err(err)
            }
            Err(other) => resume_unwind(other),
        },
    }
}

/// The 1-D numpy array `adapter.<name>` as a vector.
fn vector<'py, T: numpy::Element + Copy>(
    adapter: &Bound<'py, PyAny>,
    name: &str,
) -> PyResult<Vec<T>> {
    let a: PyReadonlyArray1<'py, T> = adapter.getattr(name)?.extract()?;
    Ok(a.as_slice()?.to_vec())
}

impl Gym {
    /// The environment behind `adapter`, a checked `pbcs.adapter.Adapter`.
    pub(crate) fn new(adapter: &Bound<'_, PyAny>) -> PyResult<Gym> {
        let f32s = |name: &str| -> PyResult<Vec<f32>> {
            let v = adapter.getattr(name)?;
            let v = v.call_method1("astype", ("float32",))?;
            let a: PyReadonlyArray1<'_, f32> = v.extract()?;
            Ok(a.as_slice()?.to_vec())
        };
        let start = GymState {
            sim: vector::<f64>(adapter, "start_state")?,
            obs: f32s("start_observation")?,
        };
        let position: Vec<usize> = adapter.getattr("position")?.extract()?;
        let state_position: Option<Vec<usize>> = adapter.getattr("state_position")?.extract()?;
        let region: Option<(Bound<'_, PyAny>, f32)> =
            adapter.getattr("success_region")?.extract()?;
        let success_region = region
            .map(|(c, r)| -> PyResult<(Vec<f32>, f32)> {
                let c: PyReadonlyArray1<'_, f32> = c.extract()?;
                Ok((c.as_slice()?.to_vec(), r))
            })
            .transpose()?;
        let clear = adapter.getattr("ball_is_clear")?;
        Ok(Gym {
            adapter: adapter.clone().unbind(),
            obs_dim: start.obs.len(),
            position_dims: position.len(),
            action_high: f32s("action_high")?,
            // Unknown: an adapter used before may have left the env anywhere.
            at: RefCell::new(None),
            start,
            state_position,
            low: f32s("position_low")?,
            high: f32s("position_high")?,
            success_region,
            ball_is_clear: (!clear.is_none()).then(|| clear.unbind()),
            own_ball_starts: !adapter.getattr("sample_ball")?.is_none(),
            names: adapter.getattr("observation_names")?.extract()?,
        })
    }

    /// Unwinds the core's work to [`catching`] with the exception `e` of the call `call`.
    fn fail(&self, call: &'static str, e: PyErr) -> ! {
        resume_unwind(Box::new(Failed(call, e)))
    }

    fn try_step(&self, py: Python<'_>, state: &GymState, action: &[f32]) -> Step<GymState> {
        let adapter = self.adapter.bind(py);
        if self.at.borrow().as_ref() != Some(state) {
            let sim = state.sim.clone().into_pyarray(py);
            if let Err(e) = adapter.call_method1("set_state", (sim,)) {
                self.fail("set_state", e);
            }
        }
        let a = PyArray1::from_slice(py, action);
        let answer = adapter
            .call_method1("step", (a,))
            .and_then(|r| r.extract::<(Bound<'_, PyAny>, Bound<'_, PyAny>, f32, bool)>())
            .and_then(|(sim, obs, reward, terminal)| {
                let sim: PyReadonlyArray1<'_, f64> = sim.extract()?;
                let obs: PyReadonlyArray1<'_, f32> = obs.extract()?;
                let next = GymState {
                    sim: sim.as_slice()?.to_vec(),
                    obs: obs.as_slice()?.to_vec(),
                };
                Ok((next, reward, terminal))
            });
        match answer {
            Ok((next, reward, terminal)) => {
                if next.sim.len() != self.start.sim.len() || next.obs.len() != self.obs_dim {
                    let e = PyRuntimeError::new_err(format!(
                        "a state of {} and an observation of {} numbers, not {} and {}",
                        next.sim.len(),
                        next.obs.len(),
                        self.start.sim.len(),
                        self.obs_dim
                    ));
                    self.fail("step", e);
                }
                *self.at.borrow_mut() = Some(next.clone());
                Step {
                    state: next,
                    reward,
                    terminal,
                }
            }
            Err(e) => {
                // The env may be anywhere now: the next step sets its state.
                *self.at.borrow_mut() = None;
                self.fail("step", e)
            }
        }
    }
}

impl Env for Gym {
    type State = GymState;

    fn obs_dim(&self) -> usize {
        self.obs_dim
    }

    fn action_dim(&self) -> usize {
        self.action_high.len()
    }

    fn action_bound(&self, i: usize) -> f32 {
        self.action_high[i]
    }

    fn start(&self) -> GymState {
        self.start.clone()
    }

    /// Every episode of the user's environment starts at s_0 (its one seeded reset).
    fn sample_start(&self, _rng: &mut pbcs::rng::Rng) -> GymState {
        self.start.clone()
    }

    fn ball_starts(&self) -> Option<&dyn SampleBall<GymState>> {
        self.state_position.is_some().then_some(self as _)
    }

    fn clear_balls(&self) -> Option<&dyn BallIsClear<GymState>> {
        self.ball_is_clear.is_some().then_some(self as _)
    }

    fn success_region(&self) -> Option<(Vec<f32>, f32)> {
        self.success_region.clone()
    }

    fn observe(&self, state: &GymState, out: &mut [f32]) {
        out.copy_from_slice(&state.obs);
    }

    fn step(&self, state: &GymState, action: &[f32]) -> Step<GymState> {
        Python::attach(|py| {
            if let Err(e) = py.check_signals() {
                self.fail("step (interrupted)", e);
            }
            self.try_step(py, state, action)
        })
    }

    fn position_dims(&self) -> usize {
        self.position_dims
    }

    fn obs_names(&self) -> Vec<String> {
        self.names.clone()
    }
}

impl SampleBall<GymState> for Gym {
    /// A position uniform in the ball around the centre's, clamped to the observation space's
    /// bounds, written into the state where the position lies (`state_position`); the other
    /// components (velocities, the warm start) the centre's. In the plane it draws as the
    /// maze does (r = radius·√u, angle uniform), so that a maze written in Python draws the
    /// maze's starts; in other dimensions, uniform in the cube until inside the ball.
    /// With the user's `sample_ball` hook, its start, drawn from the run's stream
    /// ([`Draws`]).
    fn sample_ball(&self, center: &GymState, radius: f32, rng: &mut pbcs::rng::Rng) -> GymState {
        if self.own_ball_starts {
            return self.hooked_ball_start(center, radius, rng);
        }
        let d = self.position_dims;
        let c = &center.obs[..d];
        let offset: Vec<f32> = if d == 2 {
            let r = radius * rng.random::<f32>().sqrt();
            let angle = rng.random::<f32>() * std::f32::consts::TAU;
            vec![r * angle.cos(), r * angle.sin()]
        } else {
            loop {
                let u: Vec<f32> = (0..d).map(|_| rng.random_range(-1.0..=1.0f32)).collect();
                if u.iter().map(|x| x * x).sum::<f32>() <= 1.0 {
                    break u.iter().map(|x| x * radius).collect();
                }
            }
        };
        let mut next = center.clone();
        let at = self
            .state_position
            .as_ref()
            .expect("offered with a state position");
        for i in 0..d {
            let p = (c[i] + offset[i]).clamp(self.low[i], self.high[i]);
            next.obs[i] = p;
            next.sim[at[i]] = f64::from(p);
        }
        next
    }
}

impl Gym {
    /// `Adapter.ball_start`: the user's `sample_ball` given the centre, ε and the run's stream,
    /// which it leaves where the hook's draws left it.
    fn hooked_ball_start(
        &self,
        center: &GymState,
        radius: f32,
        rng: &mut pbcs::rng::Rng,
    ) -> GymState {
        Python::attach(|py| {
            let draws = match Py::new(py, Draws { rng: rng.clone() }) {
                Ok(d) => d,
                Err(e) => self.fail("sample_ball hook", e),
            };
            let sim = PyArray1::from_slice(py, &center.sim);
            let obs = PyArray1::from_slice(py, &center.obs);
            let answer = self
                .adapter
                .bind(py)
                .call_method1("ball_start", (sim, obs, radius, draws.clone_ref(py)))
                .and_then(|r| r.extract::<(Bound<'_, PyAny>, Bound<'_, PyAny>)>())
                .and_then(|(sim, obs)| {
                    let sim: PyReadonlyArray1<'_, f64> = sim.extract()?;
                    let obs: PyReadonlyArray1<'_, f32> = obs.extract()?;
                    Ok(GymState {
                        sim: sim.as_slice()?.to_vec(),
                        obs: obs.as_slice()?.to_vec(),
                    })
                });
            match answer {
                Ok(start) => {
                    *rng = draws.borrow(py).rng.clone();
                    start
                }
                Err(e) => self.fail("sample_ball hook", e),
            }
        })
    }
}

/// The run's random stream as a `sample_ball` hook draws from it: the numbers PBCS's core
/// would draw next, so that a hook written as an environment of ours draws its starts draws
/// theirs.
#[pyclass(module = "pbcs._pbcs")]
pub(crate) struct Draws {
    rng: pbcs::rng::Rng,
}

#[pymethods]
impl Draws {
    /// A number uniform in [0, 1): 53 bits of the stream's next 64 (`rand`'s `f64` draw).
    fn random(&mut self) -> f64 {
        self.rng.random::<f64>()
    }

    /// A number uniform in [0, 1) in single precision: 24 bits of the stream's next 32
    /// (`rand`'s `f32` draw), returned as a float.
    fn random_f32(&mut self) -> f32 {
        self.rng.random::<f32>()
    }
}

impl BallIsClear<GymState> for Gym {
    fn ball_is_clear(&self, center: &GymState, radius: f32) -> bool {
        let hook = self.ball_is_clear.as_ref().expect("offered with a hook");
        Python::attach(|py| {
            let c = PyArray1::from_slice(py, &center.obs[..self.position_dims]);
            match hook
                .bind(py)
                .call1((c, radius))
                .and_then(|r| r.extract::<bool>())
            {
                Ok(clear) => clear,
                Err(e) => self.fail("ball_is_clear hook", e),
            }
        })
    }
}

impl Planar for Gym {
    /// The position's first two components (the second 0 for a position of one).
    fn point(&self, state: &GymState) -> (f32, f32) {
        (
            state.obs[0],
            if self.position_dims > 1 {
                state.obs[1]
            } else {
                0.0
            },
        )
    }

    /// No walls known; the target where a success region is given. Pictures are not drawn
    /// for the user's environments (`pbcs.run` writes its data only).
    fn scene(&self) -> Scene {
        let (c, r) = self.success_region.clone().unwrap_or((vec![0.0, 0.0], 0.0));
        Scene {
            width: 1.0,
            height: 1.0,
            walls: Vec::new(),
            target: ((c[0], c.get(1).copied().unwrap_or(0.0)), r),
            start: self.point(&self.start),
        }
    }

    fn ball_point(&self, center: &[f32]) -> (f32, f32) {
        (center[0], center.get(1).copied().unwrap_or(0.0))
    }
}
