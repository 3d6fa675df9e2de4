//! Backplay's starts from phase 1's archive ([`crate::phase2::StartMode::Archive`]).
//!
//! The paper's appendix ("Need for resetting in unseen states") asks for starts in B_ε(τ_K)
//! and notes that they could be reached by running the environment instead of being made up.
//! Phase 1 already ran it: its archive holds every state it visited, each with the velocity
//! (and, in MuJoCo, the solver's warm start) it really had there. [`ArchiveStarts`] draws a
//! start uniformly among the archived states whose position lies in the ball, instead of
//! making a new state ([`crate::env::SampleBall`] of the environment, which, with momentum,
//! copies τ_K's velocity).

use super::goal::{ball_center, dist};
use super::{Phase2Config, StartMode};
use crate::env::{Env, SampleBall};
use crate::error::{Error, Result};
use crate::phase1::Archive;
use crate::rng::Rng;
use rustc_hash::FxHashMap;

/// Phase 1's archived states, looked up by position: a start in B_ε(c) is one of the archived
/// states within ε of c's position (position: [`Env::position`]), uniformly; where none is, the
/// environment's own ball sample. The archive holds τ_0 … τ_{N−1} (not τ_N, and not the new
/// states of a shortened τ), so a ball around one of those always finds one. A ball that holds
/// only a few archived states gives nearly exact starts (no mixing with the environment's
/// ball), and walls between an archived state and the centre are not looked at (with thick
/// walls, as in PointMaze, a ball of radius ε does not reach across one).
pub struct ArchiveStarts<'a, E: Env> {
    env: &'a E,
    states: &'a [E::State],
    /// Each state's position.
    positions: Vec<Vec<f32>>,
    /// Side of the lookup grid's square cells (on the first two position coordinates).
    side: f32,
    /// The states of each grid cell, in archive order.
    cells: FxHashMap<(i32, i32), Vec<u32>>,
}

impl<'a, E: Env> ArchiveStarts<'a, E> {
    /// The lookup of `archive`'s states, in a grid of cells of side `side` (ε: a ball then
    /// meets at most 3 × 3 cells).
    ///
    /// ```
    /// use nalgebra::Point2;
    /// use pbcs::env::SampleBall;
    /// use pbcs::phase1::Archive;
    /// use pbcs::envs::maze::{Maze, MazeConfig};
    /// use pbcs::phase2::ArchiveStarts;
    ///
    /// let maze = Maze::new(&MazeConfig::default()).unwrap();
    /// let (a, b, far) = (Point2::new(0.5, 0.5), Point2::new(0.6, 0.5), Point2::new(3.0, 3.0));
    /// let mut archive = Archive::new(a, &[0.5, 0.5], 2, 0.05);
    /// archive.insert(b, &[0.6, 0.5], 0, &[0.1, 0.0]);
    /// archive.insert(far, &[3.0, 3.0], 1, &[0.1, 0.0]);
    /// let starts = ArchiveStarts::new(&maze, &archive, 0.25);
    /// assert_eq!(starts.in_ball(&[0.5, 0.5], 0.25), vec![0, 1]);
    /// let mut rng = pbcs::rng::Seeds::new(0).stream(pbcs::rng::Stream::Start);
    /// for _ in 0..20 {
    ///     let s = starts.sample_ball(&a, 0.25, &mut rng);
    ///     assert!(s == a || s == b); // never the far state
    /// }
    /// ```
    pub fn new(env: &'a E, archive: &'a Archive<E::State>, side: f32) -> Self {
        let side = if side > 0.0 { side } else { 1.0 };
        let states = archive.states();
        let positions: Vec<Vec<f32>> = states.iter().map(|s| position(env, s)).collect();
        let mut cells: FxHashMap<(i32, i32), Vec<u32>> = FxHashMap::default();
        for (id, p) in positions.iter().enumerate() {
            cells.entry(cell(p, side)).or_default().push(id as u32);
        }
        ArchiveStarts {
            env,
            states,
            positions,
            side,
            cells,
        }
    }

    /// The ids of the archived states within `radius` of `centre` (a position), in a fixed
    /// order (cells row by row, then archive order).
    pub fn in_ball(&self, centre: &[f32], radius: f32) -> Vec<u32> {
        // At most the grid's extent: a huge (or infinite) radius scans every cell once.
        let reach = (radius / self.side)
            .ceil()
            .clamp(0.0, f32::from(1u16 << 15)) as i32;
        let (ci, cj) = cell(centre, self.side);
        let mut found = Vec::new();
        for i in ci - reach..=ci + reach {
            for j in cj - reach..=cj + reach {
                let Some(ids) = self.cells.get(&(i, j)) else {
                    continue;
                };
                found.extend(
                    ids.iter()
                        .copied()
                        .filter(|&id| dist(&self.positions[id as usize], centre) <= radius),
                );
            }
        }
        found
    }
}

impl<E: Env> SampleBall<E::State> for ArchiveStarts<'_, E> {
    /// An archived state in the ball, uniformly; else the environment's own ball sample
    /// (else the centre).
    fn sample_ball(&self, center: &E::State, radius: f32, rng: &mut Rng) -> E::State {
        use rand::Rng as _;
        let found = self.in_ball(&position(self.env, center), radius);
        if found.is_empty() {
            return match self.env.ball_starts() {
                Some(ball) => ball.sample_ball(center, radius, rng),
                None => center.clone(),
            };
        }
        self.states[found[rng.random_range(0..found.len())] as usize].clone()
    }
}

/// The position of `state`, as a ball measures it ([`ball_center`] of its observation).
fn position<E: Env>(env: &E, state: &E::State) -> Vec<f32> {
    let mut obs = vec![0.0; env.obs_dim()];
    env.observe(state, &mut obs);
    ball_center(env, &obs)
}

/// The grid cell of a position (its first two coordinates; a 1-D position uses row 0).
fn cell(p: &[f32], side: f32) -> (i32, i32) {
    let at = |i: usize| p.get(i).map_or(0, |x| (x / side).floor() as i32);
    (at(0), at(1))
}

/// The starts Backplay draws from where `config` asks for archive starts: `starts`, refused
/// when missing; `None` (the environment's ball, or exact starts) otherwise.
pub(crate) fn archive_starts<'a, S>(
    config: &Phase2Config,
    starts: Option<&'a dyn SampleBall<S>>,
) -> Result<Option<&'a dyn SampleBall<S>>> {
    match (config.start, starts) {
        (StartMode::Archive, None) => Err(Error::invalid(
            "phase2.start",
            "\"archive\" draws Backplay's starts from phase 1's archive, which this call was \
             not given (`Phase2Inputs::with_starts`; `pbcs run` and experiments pass it)",
        )),
        (StartMode::Archive, starts) => Ok(starts),
        _ => Ok(None),
    }
}
