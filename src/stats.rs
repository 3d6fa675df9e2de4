//! Small statistics: quantiles and Wilson score intervals.

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
