//! Backplay (the paper's Algorithm 2), written against a small interface so that its control
//! flow can be read, and tested, apart from any learner.

/// What Backplay needs from "a DDPG architecture with policy π" on a trajectory section
/// τ_0 … τ_T.
pub trait Backplayer {
    /// A saved copy of π.
    type Policy: Clone;
    /// Greedy success fraction of π over β episodes from B_ε(τ_k) to B_ε(τ_T).
    fn test(&mut self, k: usize) -> f32;
    /// One run of Algorithm 3 from B_ε(τ_k): β training episodes; the training success
    /// fraction.
    fn train(&mut self, k: usize) -> f32;
    /// A copy of the current π.
    fn policy(&self) -> Self::Policy;
    /// Called at each K with the test result (for progress displays). Optional.
    fn observe(&mut self, _event: Event) {}
    /// Whether this problem ran out of its step budget (then its result is discarded).
    fn exhausted(&self) -> bool {
        false
    }
}

/// What happened at one K (for progress displays and tests).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Event {
    /// First test at K: success fraction.
    Tested {
        /// K.
        k: usize,
        /// Success fraction.
        success: f32,
    },
    /// Training at K stopped after `rounds` rounds; the test after it gave `success`.
    Trained {
        /// K.
        k: usize,
        /// Training rounds run.
        rounds: usize,
        /// Best training success.
        best: f32,
        /// Test success after training.
        success: f32,
    },
}

/// Runs Algorithm 3 ([`Backplayer::train`]) from τ_k until its success fails to beat its best
/// `alpha` times in a row ("until performance stabilizes"). Returns (rounds, best).
///
/// With `early_stop` (an option of ours, off in the paper's procedure), a round at 100 % is
/// followed by a greedy test, and a 100 % test ends training at once: DDPG trained on past
/// success tends to drift away from it during the α further rounds.
pub fn train_until_stable<B: Backplayer>(
    b: &mut B,
    k: usize,
    alpha: usize,
    early_stop: bool,
) -> (usize, f32) {
    let (mut best, mut misses, mut rounds) = (f32::NEG_INFINITY, 0, 0);
    while misses < alpha {
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
/// B_ε(τ_T) from B_ε(τ_{K_s}), or `None` if no K was ever solved.
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
/// never end, so we let K reach 0 (the start τ_0). `k_step` walks K back by more than one
/// index at a time (1 is the paper's walk; larger steps are our option, never the default);
/// `early_stop` is explained at [`train_until_stable`].
pub fn backplay<B: Backplayer>(
    b: &mut B,
    t: usize,
    alpha: usize,
    k_step: usize,
    early_stop: bool,
) -> Option<(usize, B::Policy)> {
    assert!(t >= 1 && k_step >= 1);
    let mut kept: Option<(usize, B::Policy)> = None;
    let mut k = t - 1;
    loop {
        let ku = k;
        let success = b.test(ku);
        b.observe(Event::Tested { k: ku, success });
        if success >= 1.0 {
            kept = Some((ku, b.policy()));
        } else {
            let (rounds, best) = train_until_stable(b, ku, alpha, early_stop);
            let success = b.test(ku);
            b.observe(Event::Trained {
                k: ku,
                rounds,
                best,
                success,
            });
            if success >= 1.0 {
                kept = Some((ku, b.policy()));
            }
            if success <= 0.0 && kept.is_some() {
                return kept;
            }
        }
        if k == 0 {
            return kept;
        }
        k = k.saturating_sub(k_step);
    }
}
