//! The rules a claim is judged by: solved counts with their 95 % Wilson interval, a cell's or
//! pooled over cells; *fails* and *solves reliably*, *beats*, and Fisher's exact test beside
//! them.

use crate::tables::CellStats;

/// Solved counts with their 95 % Wilson interval: a cell's ([`CellStats`]) or a method's
/// pooled over cells ([`Pooled`]). The rules below judge either.
pub trait Counts {
    /// Runs solved.
    fn successes(&self) -> u64;
    /// Runs.
    fn n(&self) -> u64;
    /// The interval's ends.
    fn wilson(&self) -> (f64, f64);
    /// successes / n.
    fn rate(&self) -> f64 {
        self.successes() as f64 / self.n() as f64
    }
}

impl<T: Counts> Counts for &T {
    fn successes(&self) -> u64 {
        (*self).successes()
    }
    fn n(&self) -> u64 {
        (*self).n()
    }
    fn wilson(&self) -> (f64, f64) {
        (*self).wilson()
    }
}

impl Counts for CellStats {
    fn successes(&self) -> u64 {
        self.successes
    }
    fn n(&self) -> u64 {
        self.n
    }
    fn wilson(&self) -> (f64, f64) {
        (self.wilson_lo, self.wilson_hi)
    }
}

/// A method's counts pooled over cells (counts added; interval recomputed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pooled {
    pub(super) successes: u64,
    pub(super) n: u64,
}

impl Counts for Pooled {
    fn successes(&self) -> u64 {
        self.successes
    }
    fn n(&self) -> u64 {
        self.n
    }
    fn wilson(&self) -> (f64, f64) {
        crate::stats::wilson(self.successes, self.n, crate::stats::Z95)
    }
}

/// Fails reliably: Wilson upper end below 1/2.
pub fn fails(s: &impl Counts) -> bool {
    s.wilson().1 < 0.5
}

/// Solves reliably: Wilson lower end above 1/2.
pub fn solves(s: &impl Counts) -> bool {
    s.wilson().0 > 0.5
}

/// `a` beats `b`: the intervals are disjoint with `a` above.
pub fn beats(a: &impl Counts, b: &impl Counts) -> bool {
    a.wilson().0 > b.wilson().1
}

/// The significance level of Fisher's exact test beside the interval rule.
pub const EXACT_TEST_LEVEL: f64 = 0.05;

/// `a` does better than `b` by Fisher's exact two-sided test at [`EXACT_TEST_LEVEL`].
pub fn exact_better(a: &impl Counts, b: &impl Counts) -> bool {
    a.rate() > b.rate() && exact_p(a, b) < EXACT_TEST_LEVEL
}

/// Fisher's exact two-sided p-value of two cells' solved counts.
pub fn exact_p(a: &impl Counts, b: &impl Counts) -> f64 {
    crate::stats::fisher_exact(a.successes(), a.n(), b.successes(), b.n())
}
