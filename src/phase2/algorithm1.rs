//! Algorithm 1 (skill chaining) on any learning problems, one learning problem at a time:
//! [`Between`] is where the algorithm stands between two of them, [`Between::step`] one pass
//! of its loop, [`Problems`] what poses them (a [`super::Phase2Run`] on an environment, or
//! [`Made`] from two closures, as the tests do).
//!
//! ```
//! use pbcs::phase2::backplay::Backplayer;
//! use pbcs::phase2::{Between, Made, Phase2Config};
//! // A problem whose policy solves every K within 10 indices of its goal τ_t.
//! struct Reach { t: usize }
//! impl Backplayer for Reach {
//!     type Policy = usize;
//!     fn test(&mut self, k: usize) -> f32 { if self.t - k <= 10 { 1.0 } else { 0.0 } }
//!     fn train(&mut self, k: usize) -> f32 { self.test(k) }
//!     fn policy(&self) -> usize { self.t }
//!     fn verify(&mut self, k: usize, _: &usize, _: usize) -> f32 { self.test(k) }
//!     fn exhausted(&self) -> bool { false }
//!     fn ball_is_clear(&self, _: usize) -> bool { true }
//! }
//! let config = Phase2Config::default();
//! let mut problems = Made::new(|_, t| Ok(Reach { t }), |_| {});
//! let mut at = Between::start(25);
//! while at.step(&config, &mut problems).unwrap().is_continue() {}
//! // Backwards from τ_25: 15 → 25, 5 → 15, 0 → 5; in execution order.
//! assert_eq!(at.into_skills(), vec![(0, 5, 5), (5, 15, 15), (15, 25, 25)]);
//! ```

use super::backplay::{self, handover, verified, Backplayer, Walk};
use super::{Failure, Phase2Config};
use crate::error::Result;
use std::ops::ControlFlow;

/// Where Algorithm 1 stands between two learning problems: what a run cut there goes on from.
#[derive(Debug, Clone, PartialEq)]
pub struct Between<P> {
    /// The skills found so far, in the order found (backwards from τ_N): (K, T, π).
    pub found: Vec<(usize, usize, P)>,
    /// T of the next learning problem.
    pub t: usize,
    /// Learning problems made so far (skills, restarts, hand-over tries).
    pub made: usize,
    /// Restarts of the current skill.
    pub restarts: usize,
    /// Moves of the hand-over of the skill found last.
    pub moves: usize,
}

/// What poses Algorithm 1's learning problems, one at a time.
pub trait Problems {
    /// A saved policy π.
    type Policy: Clone;
    /// Makes the next learning problem, whose goal is τ_`t`, with Algorithm 1 standing `at`;
    /// hands it to `solve`; takes it back: what `solve` returned, and whether the problem ran
    /// out of its step budget ([`Backplayer::exhausted`]).
    fn pose<R>(
        &mut self,
        at: &Between<Self::Policy>,
        t: usize,
        solve: impl FnOnce(&mut dyn Backplayer<Policy = Self::Policy>) -> R,
    ) -> Result<(R, bool)>;
}

/// [`Problems`] from two closures: `next(n, T)` makes the n-th learning problem (n =
/// [`Between::made`]) whose goal is τ_T, `finished(b)` receives it back after its Backplay.
pub struct Made<F, G> {
    next: F,
    finished: G,
}

impl<F, G> Made<F, G> {
    /// The problems `next` makes and `finished` takes back.
    pub fn new(next: F, finished: G) -> Self {
        Made { next, finished }
    }
}

impl<B, F, G> Problems for Made<F, G>
where
    B: Backplayer,
    F: FnMut(usize, usize) -> Result<B>,
    G: FnMut(B),
{
    type Policy = B::Policy;

    fn pose<R>(
        &mut self,
        at: &Between<B::Policy>,
        t: usize,
        solve: impl FnOnce(&mut dyn Backplayer<Policy = B::Policy>) -> R,
    ) -> Result<(R, bool)> {
        let mut b = (self.next)(at.made, t)?;
        let r = solve(&mut b);
        let exhausted = b.exhausted();
        (self.finished)(b);
        Ok((r, exhausted))
    }
}

impl<P: Clone> Between<P> {
    /// Before the first learning problem on τ_0 … τ_n.
    pub fn start(n: usize) -> Self {
        Between {
            found: Vec::new(),
            t: n,
            made: 0,
            restarts: 0,
            moves: 0,
        }
    }

    /// The skills found, in execution order: `(K_i, T_i, π_i)`.
    pub fn into_skills(self) -> Vec<(usize, usize, P)> {
        let mut skills = self.found;
        skills.reverse();
        skills
    }

    /// One pass of Algorithm 1's loop, on the learning problem `problems` poses next:
    ///
    /// ```text
    /// T = N
    /// while T > 0:
    ///     (π_n, T) = Backplay(τ_0 … τ_T);  A_n = B_ε(τ_T);  n += 1
    /// reverse π and A                                     (Between::into_skills)
    /// ```
    ///
    /// `Continue` while T > 0; `Break` with why it stopped early, if it did, once the loop has
    /// ended (at once where T = 0). α, the K walk, early stopping, verification, restarts and
    /// chaining come from `config`. A problem that runs out of its step budget ends the run with
    /// [`Failure::Budget`]; without chaining, a first skill that does not start at τ_0 ends it
    /// with [`Failure::NoChaining`]. A `Between` stepped on with the same problems goes on to the
    /// same result, wherever it was cut.
    pub fn step<Q>(
        &mut self,
        config: &Phase2Config,
        problems: &mut Q,
    ) -> Result<ControlFlow<Option<Failure>>>
    where
        Q: Problems<Policy = P>,
    {
        if self.t == 0 {
            return Ok(ControlFlow::Break(None));
        }
        let t = self.t;
        let walk = Walk::of(config, self.restarts < config.ideas.restarts);
        let (found, exhausted) = problems.pose(self, t, |b| {
            let candidates = backplay::backplay_candidates(b, t, &walk);
            verified(b, candidates, config.ideas.verify_skills)
        })?;
        self.made += 1;
        let failure = match found {
            _ if exhausted => Some(Failure::Budget),
            None if self.restarts < config.ideas.restarts => {
                self.restarts += 1;
                None
            }
            None if self.moves < config.ideas.dead_walk.map_or(0, |d| d.retargets)
                && !self.found.is_empty() =>
            {
                self.move_handover(config, problems)?
            }
            None => Some(Failure::BackplayFailed),
            Some((k, policy)) => {
                (self.restarts, self.moves) = (0, 0);
                self.found.push((k, t, policy));
                self.t = k;
                (k > 0 && !config.chaining).then_some(Failure::NoChaining)
            }
        };
        Ok(match failure {
            Some(f) => ControlFlow::Break(Some(f)),
            None if self.t == 0 => ControlFlow::Break(None),
            None => ControlFlow::Continue(()),
        })
    }

    /// No attempt found any K towards τ_T after a dead walk (`phase2.dead_walk`,
    /// `phase2.retargets`): a new learning problem moves the hand-over of the skill found last
    /// (start T, target T′) to a later index of τ, if that skill passes from there.
    fn move_handover<Q>(
        &mut self,
        config: &Phase2Config,
        problems: &mut Q,
    ) -> Result<Option<Failure>>
    where
        Q: Problems<Policy = P>,
    {
        let span = config.ideas.dead_walk.map_or(0, |d| d.after);
        let episodes = config.handover_episodes();
        let t = self.t;
        let (_, t_last, policy) = self.found.last().expect("a skill found");
        let (moved, exhausted) = problems.pose(self, *t_last, |b| {
            handover(b, t, *t_last, policy, episodes, span)
        })?;
        self.made += 1;
        Ok(match moved {
            _ if exhausted => Some(Failure::Budget),
            Some(k) => {
                self.found.last_mut().expect("a skill found").0 = k;
                self.t = k;
                (self.restarts, self.moves) = (0, self.moves + 1);
                None
            }
            None => Some(Failure::BackplayFailed),
        })
    }
}
