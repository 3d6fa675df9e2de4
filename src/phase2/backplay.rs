//! Backplay (the paper's Algorithm 2), written against a small interface so that its control
//! flow can be read, and tested, apart from any learner.

pub use super::procedure::{KWalk, Stopping};

/// What Backplay needs from "a DDPG architecture with policy π" on a trajectory section
/// τ_0 … τ_T.
pub trait Backplayer {
    /// A saved copy of π.
    type Policy: Clone;
    /// Greedy success fraction of π over β episodes from B_ε(τ_k) to the goal.
    fn test(&mut self, k: usize) -> f32;
    /// One run of Algorithm 3 from B_ε(τ_k): β training episodes; the training success
    /// fraction.
    fn train(&mut self, k: usize) -> f32;
    /// A copy of the current π.
    fn policy(&self) -> Self::Policy;
    /// Greedy success fraction of a saved `policy` over `episodes` episodes from B_ε(τ_k)
    /// (the verification of a finished skill, with many more episodes than β).
    fn verify(&mut self, k: usize, policy: &Self::Policy, episodes: usize) -> f32;
    /// The same greedy episodes, run to move a hand-over: whether the skill found last
    /// (`policy`, this problem's goal) also reaches its goal from the later ball B_ε(τ_k)
    /// (`phase2.retargets`, [`super::Between::step`]). Default: [`Self::verify`].
    fn verify_handover(&mut self, k: usize, policy: &Self::Policy, episodes: usize) -> f32 {
        self.verify(k, policy, episodes)
    }
    /// Told that the walk gave up at K = `k` as a dead walk ([`Walk::dead_walk`]): no test or
    /// training round reached the goal once. Default: nothing (a [`super::task::SkillTask`]
    /// writes a `dead_walk` trace row).
    fn gave_up(&mut self, k: usize) {
        let _ = k;
    }
    /// Whether this problem ran out of its step budget (then its result is discarded).
    fn exhausted(&self) -> bool;
    /// Whether B_ε(τ_k) is known to be clear of obstacles (then a partial failure there is
    /// the policy's, not a wall's; `false` where it is not known, which `phase2.stop_at_failure`
    /// then never stops at).
    fn ball_is_clear(&self, k: usize) -> bool;
}

/// What Backplay needs of the procedure ([`Walk::of`] its settings): α, how K walks and
/// when training at one K stops, and when a walk gives up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Walk {
    /// α: consecutive non-improvements of the training success that end training at one K.
    pub alpha: usize,
    /// How K moves back after each K ([`KWalk::Fixed`] by 1: the paper).
    pub k_walk: KWalk,
    /// When training at one K ends ([`Stopping::UNTIL_STABLE`]: the paper).
    pub stopping: Stopping,
    /// End the walk at the first K that fails after training, once a skill is saved, when
    /// B_ε(τ_K) is clear of obstacles (ours): the paper goes on because a ball overlapping a
    /// wall can fail partly whatever the policy, which a clear ball cannot.
    pub stop_at_failure: bool,
    /// Return nothing at the first K whose test after training is 0 % while no K is saved
    /// yet (ours; the caller restarts the skill with a fresh learner). The paper walks on.
    pub give_up_when_dead: bool,
    /// Return nothing once K is this many indices below T without a single success in any
    /// test or training round (ours; `None`: the paper, whose walk goes on to K = 0 however
    /// dead it is). The caller may then move the hand-over (`phase2.retargets`).
    pub dead_walk: Option<usize>,
    /// Return the saved (K, π) once this many Ks in a row have been trained without a save
    /// after the last one (ours; `None`: the paper, which walks on until a test after training
    /// reads 0 %). Where a policy passes partly far beyond its last saved K, the paper's walk
    /// spends most of a skill's steps there for nothing it keeps.
    pub patience: Option<usize>,
}

impl Walk {
    /// Backplay's walk under the settings `config`, for a skill that has restarts left or not
    /// (a walk that may restart gives up when dead: [`Walk::give_up_when_dead`]).
    pub fn of(config: &super::Phase2Config, restarts_left: bool) -> Walk {
        let i = &config.ideas;
        Walk {
            alpha: config.alpha,
            k_walk: i.k_walk,
            stopping: i.stopping,
            stop_at_failure: i.stop_at_failure,
            give_up_when_dead: restarts_left,
            dead_walk: i.dead_walk.map(|d| d.after),
            patience: i.patience,
        }
    }

    /// The paper's walk: K back one index at a time, training until α misses in a row, never
    /// giving up before K = 0.
    pub fn paper(alpha: usize) -> Walk {
        Walk {
            alpha,
            k_walk: KWalk::Fixed { step: 1 },
            stopping: Stopping::UNTIL_STABLE,
            stop_at_failure: false,
            give_up_when_dead: false,
            dead_walk: None,
            patience: None,
        }
    }
}

/// The largest K step of the adaptive walk.
pub const MAX_ADAPTIVE_STEP: usize = 16;

/// Runs Algorithm 3 ([`Backplayer::train`]) from τ_k until its success fails to beat its best
/// `walk.alpha` times in a row ("until performance stabilizes"). Returns (rounds, best).
///
/// With [`Stopping::early_stop`] (an option of ours, off in the paper's procedure), a round at 100 %
/// is followed by a greedy test, and a 100 % test ends training at once: DDPG trained on past
/// success tends to drift away from it during the α further rounds. With `max_rounds`
/// (ours), training also ends after that many rounds: a K that needs more is rarely solved at
/// all, and the rounds spent there before α misses are most of a skill's training.
pub fn train_until_stable<B: Backplayer + ?Sized>(
    b: &mut B,
    k: usize,
    walk: &Walk,
) -> (usize, f32) {
    let (mut best, mut misses, mut rounds) = (f32::NEG_INFINITY, 0, 0);
    let Stopping {
        early_stop,
        max_rounds,
    } = walk.stopping;
    while misses < walk.alpha && max_rounds.is_none_or(|m| rounds < m) {
        let p = b.train(k);
        rounds += 1;
        if early_stop && p >= 1.0 && b.test(k) >= 1.0 {
            return (rounds, p);
        }
        if p > best {
            best = p;
            misses = 0;
        } else {
            misses += 1;
        }
    }
    (rounds, best)
}

/// Algorithm 2. Walks K back from T − 1; returns (K_s, π_s) such that π_s reliably reaches
/// the goal from B_ε(τ_{K_s}), or `None` if no K was ever solved. The last of
/// [`backplay_candidates`].
///
/// ```text
/// K = T − 1; fresh π
/// while K ≥ 0:
///     if test(K) = 100 %: (K_s, π_s) = (K, π)
///     else:
///         train until stable (α non-improvements in a row)
///         p = test(K)
///         if p = 100 %: (K_s, π_s) = (K, π)
///         if p = 0 % and K_s exists: return (K_s, π_s)
///     K = K − 1
/// return (K_s, π_s)
/// ```
///
/// The paper loops `while K > 0`; then K_s ≥ 1 always and Algorithm 1 (`while T > 0`) would
/// never end, so we let K reach 0 (the start τ_0). [`Walk`] holds our options (larger or
/// adaptive K steps, early stopping, a bound on a walk without any success); the pseudo-code
/// above is [`Walk::paper`].
pub fn backplay<B: Backplayer + ?Sized>(
    b: &mut B,
    t: usize,
    walk: &Walk,
) -> Option<(usize, B::Policy)> {
    backplay_candidates(b, t, walk).pop()
}

/// Algorithm 2, returning every (K, π) it saved, in the order saved (decreasing K): the last
/// one is the paper's (K_s, π_s); the earlier ones are shorter-reaching skills to fall back on
/// when the last fails its verification.
pub fn backplay_candidates<B: Backplayer + ?Sized>(
    b: &mut B,
    t: usize,
    walk: &Walk,
) -> Vec<(usize, B::Policy)> {
    let adaptive = matches!(walk.k_walk, KWalk::Adaptive { .. });
    let mut step = walk.k_walk.first_step();
    assert!(t >= 1 && step >= 1);
    let mut kept: Vec<(usize, B::Policy)> = Vec::new();
    let mut k = t - 1;
    // Whether any test or training round of this walk has reached the goal once.
    let mut any_success = false;
    // Ks trained since the last save without one (`walk.patience`).
    let mut unsaved = 0;
    loop {
        let first = b.test(k);
        any_success |= first > 0.0;
        let mut solved = first >= 1.0;
        if !solved && adaptive && step > 1 {
            // A jump too far: back halfway towards the last saved K (T if none), testing
            // before any training; once the step is 1, K is trained as the paper does.
            let last = kept.last().map_or(t, |(ks, _)| *ks);
            step /= 2;
            while step > 1 && last.saturating_sub(step) <= k {
                step /= 2;
            }
            if last.saturating_sub(step) > k {
                k = last - step;
                continue;
            }
        }
        let mut dead = false;
        if !solved {
            let (_, best) = train_until_stable(b, k, walk);
            let success = b.test(k);
            any_success |= best > 0.0 || success > 0.0;
            solved = success >= 1.0;
            dead = success <= 0.0 || (!solved && walk.stop_at_failure && b.ball_is_clear(k));
        }
        if solved {
            kept.push((k, b.policy()));
            unsaved = 0;
            if adaptive {
                step = (step * 2).min(MAX_ADAPTIVE_STEP);
            }
        } else {
            unsaved += 1;
        }
        if dead && (!kept.is_empty() || walk.give_up_when_dead) {
            return kept;
        }
        if !kept.is_empty() && walk.patience.is_some_and(|p| unsaved >= p) {
            return kept;
        }
        if k == 0 {
            return kept;
        }
        if !any_success && walk.dead_walk.is_some_and(|w| t - k >= w) {
            // A dead walk: `w` Ks below T without one success (nothing is kept either).
            b.gave_up(k);
            return kept;
        }
        k = k.saturating_sub(step);
    }
}

/// Most balls a moved hand-over tries ([`handover`]).
pub const MAX_HANDOVER_TRIES: usize = 4;

/// A new start for the skill found last, whose start is τ_t and whose goal is `b`'s (τ_{t_last}):
/// the indices t + 1 … t + `span` before t_last, those whose ball is clear of obstacles first,
/// nearest first; at most [`MAX_HANDOVER_TRIES`] of them are tried, the first from which
/// `policy` reaches its goal in every one of `episodes` greedy episodes is returned.
pub fn handover<B: Backplayer + ?Sized>(
    b: &mut B,
    t: usize,
    t_last: usize,
    policy: &B::Policy,
    episodes: usize,
    span: usize,
) -> Option<usize> {
    let mut ks: Vec<usize> = (t + 1..t_last.min(t + span + 1)).collect();
    // Clear balls first (a stable sort keeps them nearest first).
    ks.sort_by_key(|&k| !b.ball_is_clear(k));
    for k in ks.into_iter().take(MAX_HANDOVER_TRIES) {
        if b.verify_handover(k, policy, episodes) >= 1.0 {
            return Some(k);
        }
        if b.exhausted() {
            break;
        }
    }
    None
}

/// Most saved (K, π) of one Backplay that a failed verification falls back through.
pub const MAX_VERIFIED_CANDIDATES: usize = 4;

/// The skill kept from Backplay's saved `candidates` (in the order saved, decreasing K).
/// Without verification (`episodes` = `None`) the last one, as in the paper. With it, the last
/// one whose policy reaches the goal in all `episodes` greedy episodes from its ball, trying
/// at most [`MAX_VERIFIED_CANDIDATES`] from the last; if none passes, the one with the best
/// verified success (the farthest-reaching among ties).
pub fn verified<B: Backplayer + ?Sized>(
    b: &mut B,
    mut candidates: Vec<(usize, B::Policy)>,
    episodes: Option<usize>,
) -> Option<(usize, B::Policy)> {
    let Some(episodes) = episodes else {
        return candidates.pop();
    };
    let mut best: Option<(f32, usize)> = None;
    let first = candidates.len().saturating_sub(MAX_VERIFIED_CANDIDATES);
    for i in (first..candidates.len()).rev() {
        let (k, policy) = &candidates[i];
        let p = b.verify(*k, policy, episodes);
        if p >= 1.0 {
            return Some(candidates.swap_remove(i));
        }
        if best.is_none_or(|(bp, _)| p > bp) {
            best = Some((p, i));
        }
        if b.exhausted() {
            break;
        }
    }
    best.map(|(_, i)| candidates.swap_remove(i))
}
