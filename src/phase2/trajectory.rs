//! The trajectory phase 2 chains along: τ as phase 1 found it, or shortened ([`shorten`], ours).

use super::Phase2Config;
use crate::env::Env;
use crate::error::Result;
use crate::phase1::Trajectory;

/// The trajectory phase 2 works on: τ itself, or τ shortened with clearance ε when
/// [`super::Ideas::shorten`] is on.
pub fn phase2_trajectory<E: Env>(
    env: &E,
    tau: &Trajectory<E::State>,
    config: &Phase2Config,
) -> Result<Trajectory<E::State>> {
    if config.ideas.shorten {
        shorten(env, tau, config.epsilon)
    } else {
        Ok(tau.clone())
    }
}

/// Shortens a trajectory by cutting its detours: from each kept state, go to the farthest
/// later state of τ that the environment's [`crate::env::Connect`] links it to while keeping
/// `clearance` from walls (phase 2 passes ε, so that the start balls B_ε(τ_K) along new
/// segments miss the walls), by the actions it gives, keeping the states those steps actually
/// land on. The result starts at τ_0, ends within rounding of τ_N, and every transition is a
/// real step of the environment. An environment without [`Env::connector`] is refused
/// ([`Error::Capability`]). An improvement of ours, off in the paper's preset.
///
/// ```
/// use pbcs::config::{ExploreConfig, MazeConfig};
/// use pbcs::phase1::explore;
/// use pbcs::phase2::shorten;
/// use pbcs::envs::maze::Maze;
/// use pbcs::rng::{Seeds, Stream};
///
/// let maze = Maze::new(&MazeConfig { size: 5, ..Default::default() }).unwrap();
/// let tau = explore(&maze, &ExploreConfig::default(), &mut Seeds::new(0).stream(Stream::Explore), |_, _| {})
///     .unwrap()
///     .trajectory;
/// let short = shorten(&maze, &tau, 0.1).unwrap();
/// assert!(short.len() < tau.len() / 2);
/// assert!(maze.reached(short.states.last().unwrap()));
/// ```
pub fn shorten<E: Env>(
    env: &E,
    tau: &Trajectory<E::State>,
    clearance: f32,
) -> Result<Trajectory<E::State>> {
    let connector = env
        .connector()
        .ok_or_else(|| crate::env::Capability::Connect.missing("phase2.shorten"))?;
    let n = tau.states.len();
    let mut states = vec![tau.states[0].clone()];
    let mut actions = Vec::new();
    let mut i = 0;
    while i + 1 < n {
        let cur = states.last().unwrap().clone();
        // The farthest j that `connect` reaches; τ's own action always reaches i + 1.
        let (j, path) = (i + 1..n)
            .rev()
            .find_map(|j| {
                connector
                    .connect(&cur, &tau.states[j], clearance)
                    .map(|p| (j, p))
            })
            .unwrap_or_else(|| (i + 1, vec![tau.actions[i].clone()]));
        let mut s = cur;
        for a in path {
            s = env.step(&s, &a).state;
            states.push(s.clone());
            actions.push(a);
        }
        i = j;
    }
    Ok(Trajectory { states, actions })
}
