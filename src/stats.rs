//! Small statistics: quantiles, Wilson score intervals, Fisher's exact test, and for samples of
//! real numbers (the outside checks' returns) the mean, Student's t interval and Welch's test.

/// A run counts as solved when its evaluation (greedy episodes of a vanilla policy, or of a
/// PBCS chain) reaches the target in at least this fraction of episodes.
pub const SOLVED_AT: f32 = 0.95;

/// The one rule every record, row and table judges a run by: solved when nothing stopped it
/// (`stopped`: PBCS's phase 2 failed or ran out of budget) and its evaluation's success rate
/// is at least [`SOLVED_AT`].
///
/// ```
/// use pbcs::stats::solved;
/// assert!(solved(false, 0.95) && solved(false, 1.0));
/// assert!(!solved(false, 0.94) && !solved(true, 1.0));
/// ```
pub fn solved(stopped: bool, rate: f32) -> bool {
    !stopped && rate >= SOLVED_AT
}

/// The fewest successes of `episodes` that solve a run by [`solved`]: ⌈[`SOLVED_AT`] ·
/// episodes⌉ (95 of 100, as SB3's protocol on PointMaze counts).
///
/// ```
/// use pbcs::stats::least_successes;
/// assert_eq!((least_successes(100), least_successes(20), least_successes(10)), (95, 19, 10));
/// for n in 1..=1000u64 {
///     let k = least_successes(n);
///     assert!(pbcs::stats::solved(false, k as f32 / n as f32));
///     assert!(k == 0 || !pbcs::stats::solved(false, (k - 1) as f32 / n as f32));
/// }
/// ```
pub fn least_successes(episodes: u64) -> u64 {
    (f64::from(SOLVED_AT) * episodes as f64).ceil() as u64
}

/// The median of `v` (sorted in place; mean of the two middle values for an even count;
/// NaN for an empty slice).
///
/// ```
/// let mut v = vec![3.0, 1.0, 2.0, 10.0];
/// assert_eq!(pbcs::stats::median(&mut v), 2.5);
/// assert_eq!(v, [1.0, 2.0, 3.0, 10.0]);
/// ```
pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => v[n / 2],
        _ => (v[n / 2 - 1] + v[n / 2]) / 2.0,
    }
}

/// z of every 95 % interval in the package (the normal quantile Φ⁻¹(0.975)).
pub const Z95: f64 = 1.959_963_984_540_054;

/// The Wilson score interval of `k` successes in `n` trials at normal quantile `z` (1.96 for
/// 95 %): centre (p̂ + z²/2n) / (1 + z²/n), half-width z·√(p̂(1 − p̂)/n + z²/4n²) / (1 + z²/n).
///
/// ```
/// let (lo, hi) = pbcs::stats::wilson(5, 10, 1.96);
/// assert!((lo - 0.2366).abs() < 1e-4 && (hi - 0.7634).abs() < 1e-4);
/// ```
pub fn wilson(k: u64, n: u64, z: f64) -> (f64, f64) {
    assert!(n > 0 && k <= n, "wilson: need 0 <= k <= n, n > 0");
    let (k, n) = (k as f64, n as f64);
    let p = k / n;
    let z2 = z * z;
    let denom = 1.0 + z2 / n;
    let centre = (p + z2 / (2.0 * n)) / denom;
    let half = z * (p * (1.0 - p) / n + z2 / (4.0 * n * n)).sqrt() / denom;
    // The ends are exactly 0 and 1 at k = 0 and k = n (the formula gives them up to rounding).
    let lo = if k == 0.0 {
        0.0
    } else {
        (centre - half).max(0.0)
    };
    let hi = if k == n {
        1.0
    } else {
        (centre + half).min(1.0)
    };
    (lo, hi)
}

/// The `q`-quantile of `v` with linear interpolation between order statistics (numpy's and
/// polars' `linear` method: position q·(n − 1)); NaN for an empty slice. Sorts `v`.
///
/// ```
/// let mut v = vec![4.0, 1.0, 3.0, 2.0];
/// assert_eq!(pbcs::stats::quantile(&mut v, 0.25), 1.75);
/// assert_eq!(pbcs::stats::quantile(&mut v, 0.5), 2.5);
/// assert_eq!(pbcs::stats::quantile(&mut v, 1.0), 4.0);
/// ```
pub fn quantile(v: &mut [f64], q: f64) -> f64 {
    assert!((0.0..=1.0).contains(&q), "quantile: q must be in [0, 1]");
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return f64::NAN;
    }
    let pos = q * (v.len() - 1) as f64;
    let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
    v[lo] + (v[hi] - v[lo]) * (pos - lo as f64)
}

/// The two-sided p-value of Fisher's exact test on the 2×2 table (k₁ of n₁ successes against
/// k₂ of n₂): conditioned on the margins, the number of successes of the first sample is
/// hypergeometric, and the p-value sums the probabilities of every table no more likely than
/// the one observed (a relative tolerance of 10⁻⁷ counts ties as ties, as R and SciPy do).
///
/// ```
/// // 9/10 against 3/10: p ≈ 0.0198 (SciPy's `fisher_exact` gives 0.019766…).
/// let p = pbcs::stats::fisher_exact(9, 10, 3, 10);
/// assert!((p - 0.019_766_6).abs() < 1e-6);
/// assert_eq!(pbcs::stats::fisher_exact(5, 10, 5, 10), 1.0);
/// ```
pub fn fisher_exact(k1: u64, n1: u64, k2: u64, n2: u64) -> f64 {
    assert!(
        k1 <= n1 && k2 <= n2 && n1 > 0 && n2 > 0,
        "fisher_exact: need 0 <= k <= n, n > 0"
    );
    let ln_fact = |n: u64| (1..=n).map(|i| (i as f64).ln()).sum::<f64>();
    let (k, n) = (k1 + k2, n1 + n2);
    // ln P(X = x) for X ~ Hypergeometric(n, k, n1): C(k, x) C(n − k, n1 − x) / C(n, n1).
    let ln_c = |a: u64, b: u64| ln_fact(a) - ln_fact(b) - ln_fact(a - b);
    let ln_p = |x: u64| ln_c(k, x) + ln_c(n - k, n1 - x) - ln_c(n, n1);
    let (lo, hi) = (k.saturating_sub(n2), k.min(n1));
    let observed = ln_p(k1);
    let p: f64 = (lo..=hi)
        .map(ln_p)
        .filter(|&l| l <= observed + 1e-7)
        .map(f64::exp)
        .sum();
    p.min(1.0)
}

/// The two-sided exact sign test of `fewer` pairs against `more` (ties dropped): under
/// H₀ each pair goes either way with probability 1/2, and p = min(1, 2·P(X ≤ min(k, n − k)))
/// with X ~ Binomial(n = fewer + more, 1/2) (SciPy's `binomtest(k, n, 0.5)`). 1 with no pair.
///
/// ```
/// // 9 of 10: p = 22/1024 (SciPy: 0.021484375).
/// assert!((pbcs::stats::sign_test(9, 1) - 0.021484375).abs() < 1e-12);
/// assert_eq!(pbcs::stats::sign_test(0, 0), 1.0);
/// ```
pub fn sign_test(fewer: u64, more: u64) -> f64 {
    use statrs::distribution::{Binomial, DiscreteCDF};
    let n = fewer + more;
    if n == 0 {
        return 1.0;
    }
    let tail = Binomial::new(0.5, n).map_or(1.0, |b| b.cdf(fewer.min(more)));
    (2.0 * tail).min(1.0)
}

/// Mean and sample standard deviation (n − 1 in the denominator) of `v`; `None` with fewer
/// than two values.
///
/// ```
/// let (m, sd) = pbcs::stats::mean_sd(&[1.0, 2.0, 3.0, 4.0, 5.0]).unwrap();
/// assert_eq!(m, 3.0);
/// assert!((sd - 2.5f64.sqrt()).abs() < 1e-15);
/// assert_eq!(pbcs::stats::mean_sd(&[1.0]), None);
/// ```
pub fn mean_sd(v: &[f64]) -> Option<(f64, f64)> {
    let n = v.len() as f64;
    (v.len() >= 2).then(|| {
        let m = v.iter().sum::<f64>() / n;
        let ss: f64 = v.iter().map(|x| (x - m).powi(2)).sum();
        (m, (ss / (n - 1.0)).sqrt())
    })
}

/// Student's t 95 % interval of the mean of `v`: m ± t₀.₉₇₅(n − 1)·sd/√n; `None` with fewer
/// than two values.
///
/// ```
/// // n = 10 values 0..9: mean 4.5, sd 3.0277, t₀.₉₇₅(9) = 2.262157 (SciPy).
/// let v: Vec<f64> = (0..10).map(f64::from).collect();
/// let (lo, hi) = pbcs::stats::t_interval(&v).unwrap();
/// let half = 2.262_157_162_798_205 * 3.027_650_354_097_491_7 / 10f64.sqrt();
/// assert!((lo - (4.5 - half)).abs() < 1e-9 && (hi - (4.5 + half)).abs() < 1e-9);
/// ```
pub fn t_interval(v: &[f64]) -> Option<(f64, f64)> {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    let (m, sd) = mean_sd(v)?;
    let n = v.len() as f64;
    let t = StudentsT::new(0.0, 1.0, n - 1.0).ok()?.inverse_cdf(0.975);
    let half = t * sd / n.sqrt();
    Some((m - half, m + half))
}

/// Welch's two-sample t-test of equal means (unequal variances): (t, Welch–Satterthwaite
/// degrees of freedom, two-sided p-value), t of mean(a) − mean(b); `None` with fewer than two
/// values in a sample or both samples constant.
///
/// ```
/// // SciPy: ttest_ind([1..5], [2, 4, .., 10], equal_var=False) → t = −1.897367,
/// // df = 5.882353, p = 0.107531.
/// let (t, df, p) = pbcs::stats::welch(&[1.0, 2.0, 3.0, 4.0, 5.0], &[2.0, 4.0, 6.0, 8.0, 10.0]).unwrap();
/// assert!((t + 1.897_366_596).abs() < 1e-8);
/// assert!((df - 5.882_352_941).abs() < 1e-8);
/// assert!((p - 0.107_531_194_9).abs() < 1e-8);
/// ```
pub fn welch(a: &[f64], b: &[f64]) -> Option<(f64, f64, f64)> {
    use statrs::distribution::{ContinuousCDF, StudentsT};
    let ((ma, sa), (mb, sb)) = (mean_sd(a)?, mean_sd(b)?);
    let (va, vb) = (sa * sa / a.len() as f64, sb * sb / b.len() as f64);
    if va + vb <= 0.0 {
        return None;
    }
    let t = (ma - mb) / (va + vb).sqrt();
    let df =
        (va + vb).powi(2) / (va * va / (a.len() as f64 - 1.0) + vb * vb / (b.len() as f64 - 1.0));
    let p = 2.0 * StudentsT::new(0.0, 1.0, df).ok()?.sf(t.abs());
    Some((t, df, p.min(1.0)))
}

/// Least-squares line through the points (x, y): (intercept, slope); None with fewer than two
/// distinct x.
pub fn fit_line(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let n = points.len() as f64;
    let mx = points.iter().map(|p| p.0).sum::<f64>() / n;
    let my = points.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (points.len() >= 2 && sxx > 1e-12).then(|| (my - sxy / sxx * mx, sxy / sxx))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fitted_line_recovers_a_power_law() {
        // steps = 500 · L^1.5 exactly: the log–log fit gives back ln 500 and 1.5.
        let pts: Vec<(f64, f64)> = [3.0f64, 8.0, 20.0, 57.0]
            .iter()
            .map(|&l| (l.ln(), (500.0 * l.powf(1.5)).ln()))
            .collect();
        let (a, b) = fit_line(&pts).unwrap();
        assert!(
            (a - 500f64.ln()).abs() < 1e-9 && (b - 1.5).abs() < 1e-12,
            "{a} {b}"
        );
        // Known small case: (0, 1), (1, 3), (2, 5) → y = 1 + 2x.
        assert_eq!(
            fit_line(&[(0.0, 1.0), (1.0, 3.0), (2.0, 5.0)]),
            Some((1.0, 2.0))
        );
        assert_eq!(fit_line(&[(1.0, 1.0)]), None);
        assert_eq!(fit_line(&[(2.0, 1.0), (2.0, 3.0)]), None);
    }
}
