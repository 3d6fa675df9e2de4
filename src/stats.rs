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
