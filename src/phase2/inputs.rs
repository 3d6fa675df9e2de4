//! What one phase 2 reads ([`Phase2Inputs`]: τ, the settings, the learner's, the seeds) and what
//! it writes as it goes ([`Ledger`]: steps spent, learning problems made, the trace).

use super::{Ball, Phase2Config, Ready, Skill, StepCounts, TraceRow};
use crate::env::{Env, SampleBall};
use crate::learner::{Learner, LearnerConfig};
use crate::nn::kernel::Kernel;
use crate::policy::Policy;
use crate::rng::Seeds;
use std::time::Instant;

/// What phase 2 runs on: τ, the environment it was found in, phase 2's settings checked against
/// it, the learner's settings, the run's seeds and the layer kernel of every network.
///
/// Learning problem n's learner is initialised from `seeds` for sub-run n (or, with
/// `phase2.warm_start`, taken over from the skill before it), and its starts, noise and replay
/// sampling read substream n (n counts restarts and repairs too, so it equals the skill's
/// index when nothing restarts).
pub struct Phase2Inputs<'a, E: Env> {
    /// The environment τ was found in.
    pub env: &'a E,
    /// τ_0 … τ_N (states).
    pub tau: &'a [E::State],
    /// Phase 2's settings, checked against `env` ([`super::Phase2Config::ready`]).
    pub ready: Ready<'a, E>,
    /// Every learning problem's learner.
    pub learner: &'a LearnerConfig,
    /// The run's seeds.
    pub seeds: &'a Seeds,
    /// The layer kernel of every learner and of the chain.
    pub kernel: Kernel,
    /// Environment steps the run spent before phase 2 (phase 1), charged against
    /// `phase2.max_env_steps` ([`Phase2Inputs::after`]; 0 by default).
    pub spent: u64,
    /// Backplay's starts in B_ε(τ_K) where `phase2.start = "archive"` asks for them (phase
    /// 1's archive, [`super::ArchiveStarts`]; [`Phase2Inputs::with_starts`]). That setting
    /// without them is refused.
    pub starts: Option<&'a dyn SampleBall<E::State>>,
}

impl<'a, E: Env> Phase2Inputs<'a, E> {
    /// Phase 2 on τ = `tau`, found in `env`, with nothing spent before it and no archive.
    pub fn new(
        env: &'a E,
        tau: &'a [E::State],
        ready: Ready<'a, E>,
        learner: &'a LearnerConfig,
        seeds: &'a Seeds,
        kernel: Kernel,
    ) -> Self {
        Phase2Inputs {
            env,
            tau,
            ready,
            learner,
            seeds,
            kernel,
            spent: 0,
            starts: None,
        }
    }

    /// After `spent` environment steps (phase 1's).
    pub fn after(self, spent: u64) -> Self {
        Phase2Inputs { spent, ..self }
    }

    /// With Backplay's starts drawn by `starts` where `phase2.start = "archive"` asks.
    pub fn with_starts(self, starts: Option<&'a dyn SampleBall<E::State>>) -> Self {
        Phase2Inputs { starts, ..self }
    }

    /// The settings.
    pub fn config(&self) -> &'a Phase2Config {
        self.ready.settings()
    }
}

/// [`Phase2Inputs`] with τ's observations: what skills and goals are made from.
pub(super) struct Along<'r, 'a, E: Env> {
    pub inputs: &'r Phase2Inputs<'a, E>,
    /// The observations of τ.
    pub obs: &'r [Vec<f32>],
}

impl<E: Env> Clone for Along<'_, '_, E> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<E: Env> Copy for Along<'_, '_, E> {}

impl<'a, E: Env> Along<'_, 'a, E> {
    /// The settings.
    pub fn config(&self) -> &'a Phase2Config {
        self.inputs.config()
    }

    /// The goal of τ_`i` ([`Phase2Config::goal`]).
    pub fn goal(&self, i: usize) -> super::goal::Goal {
        self.config().goal(self.inputs.env, self.obs, i)
    }

    /// The skills of `found` (execution order, indices on the section from τ_lo).
    pub fn skills(&self, lo: usize, found: Vec<(usize, usize, Box<dyn Policy>)>) -> Vec<Skill> {
        let (env, config) = (self.inputs.env, self.config());
        found
            .into_iter()
            .map(|(k, t, policy)| Skill {
                policy,
                activation: Ball::around(env, &self.obs[lo + k], config.epsilon, config.ball),
                start_index: lo + k,
                target_index: lo + t,
                inputs: config.inputs(env, &self.goal(lo + t)),
            })
            .collect()
    }
}

/// What one phase 2 has spent and written so far.
pub(super) struct Ledger {
    /// Environment steps of the whole run so far (phase 1 included).
    pub spent: u64,
    /// Learning problems made so far (skills, restarts, repairs).
    pub made: usize,
    /// The last learning problem's learner and its target's index on τ (`phase2.warm_start`).
    pub last: Option<(usize, Box<dyn Learner>)>,
    /// Phase 2's steps so far, by purpose.
    pub steps: StepCounts,
    pub trace: Vec<TraceRow>,
    /// When this process began phase 2.
    pub clock: Instant,
    /// Wall-clock seconds of the run before this process resumed it (trace rows count on).
    pub earlier_seconds: f64,
}

impl Ledger {
    /// Nothing spent by phase 2 yet, `spent` before it.
    pub fn new(spent: u64) -> Self {
        Ledger {
            spent,
            made: 0,
            last: None,
            steps: StepCounts::default(),
            trace: Vec::new(),
            clock: Instant::now(),
            earlier_seconds: 0.0,
        }
    }

    /// Writes `row` to the trace, stamped with the run's wall clock.
    pub fn record(&mut self, row: TraceRow) {
        stamp(&mut self.trace, row, self.clock, self.earlier_seconds);
    }

    /// Charges `steps` to the run.
    pub fn charge(&mut self, steps: StepCounts) {
        self.steps.train += steps.train;
        self.steps.test += steps.test;
        self.spent += steps.train + steps.test;
    }
}

/// Pushes `row` onto `trace` with its wall clock: `earlier` seconds and those since `clock`.
pub(super) fn stamp(trace: &mut Vec<TraceRow>, mut row: TraceRow, clock: Instant, earlier: f64) {
    row.seconds = earlier + clock.elapsed().as_secs_f64();
    trace.push(row);
}
