//! Statistics helpers against known values and invariants.

use pbcs::stats::{median, wilson};

#[test]
fn wilson_known_values() {
    // From the reference sheet: 0/10 → [0, 0.2775]; 5/10 → [0.2366, 0.7634]; 10/10 → [0.7225, 1].
    for (k, lo, hi) in [(0, 0.0, 0.2775), (5, 0.2366, 0.7634), (10, 0.7225, 1.0)] {
        let (l, h) = wilson(k, 10, 1.96);
        assert!(
            (l - lo).abs() < 1e-4 && (h - hi).abs() < 1e-4,
            "{k}/10: [{l}, {h}]"
        );
    }
}

/// The Wilson interval is the set of p that the score test does not reject:
/// |p̂ − p| ≤ z √(p (1 − p) / n). Its ends found by bisection on that inequality (no closed
/// form shared with `wilson`) equal the closed form's, both ends, for every k of n ≤ 40.
#[test]
fn wilson_equals_the_inverted_score_test() {
    let z = pbcs::stats::Z95;
    for n in 1..=40u64 {
        for k in 0..=n {
            let p_hat = k as f64 / n as f64;
            let accepted = |p: f64| (p_hat - p).abs() <= z * (p * (1.0 - p) / n as f64).sqrt();
            // Bisection between a rejected and an accepted point (p̂ is always accepted).
            let edge = |mut out: f64, mut inside: f64| {
                for _ in 0..200 {
                    let mid = 0.5 * (out + inside);
                    if accepted(mid) {
                        inside = mid;
                    } else {
                        out = mid;
                    }
                }
                inside
            };
            let lo = if accepted(0.0) { 0.0 } else { edge(0.0, p_hat) };
            let hi = if accepted(1.0) { 1.0 } else { edge(1.0, p_hat) };
            let (l, h) = wilson(k, n, z);
            assert!(
                (l - lo).abs() < 1e-9 && (h - hi).abs() < 1e-9,
                "{k}/{n}: closed form [{l}, {h}], bisection [{lo}, {hi}]"
            );
        }
    }
}

#[test]
fn wilson_invariants() {
    for n in 1..=60u64 {
        for k in 0..=n {
            let p = k as f64 / n as f64;
            let (lo, hi) = wilson(k, n, 1.96);
            assert!(
                0.0 <= lo && lo <= p + 1e-12 && p <= hi + 1e-12 && hi <= 1.0,
                "{k}/{n}"
            );
            // Symmetry: k successes and n − k failures mirror each other.
            let (lo2, hi2) = wilson(n - k, n, 1.96);
            assert!((lo - (1.0 - hi2)).abs() < 1e-12 && (hi - (1.0 - lo2)).abs() < 1e-12);
        }
    }
}

#[test]
fn median_of_odd_even_and_empty() {
    assert_eq!(median(&mut [5.0, 1.0, 3.0]), 3.0);
    assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
    assert!(median(&mut []).is_nan());
}

#[test]
fn quantile_matches_linear_interpolation() {
    use pbcs::stats::quantile;
    // numpy.quantile([10, 20, 30, 40, 50], [0, .25, .5, .9, 1]) = [10, 20, 30, 46, 50]
    let mut v = vec![50.0, 10.0, 40.0, 20.0, 30.0];
    for (q, want) in [
        (0.0, 10.0),
        (0.25, 20.0),
        (0.5, 30.0),
        (0.9, 46.0),
        (1.0, 50.0),
    ] {
        assert!((quantile(&mut v, q) - want).abs() < 1e-12, "q = {q}");
    }
    assert_eq!(quantile(&mut [7.0], 0.75), 7.0);
    assert!(quantile(&mut [], 0.5).is_nan());
}

#[test]
fn wilson_narrows_with_n_and_is_monotone_in_k() {
    // Same rate, more trials: a narrower interval. More successes: both ends move up.
    let width = |k, n| {
        let (lo, hi) = wilson(k, n, 1.96);
        hi - lo
    };
    assert!(width(5, 10) > width(50, 100) && width(50, 100) > width(500, 1000));
    for k in 0..20 {
        let (a, b) = (wilson(k, 20, 1.96), wilson(k + 1, 20, 1.96));
        assert!(b.0 > a.0 && b.1 > a.1, "{k}/20");
    }
}

#[test]
fn fisher_exact_matches_scipy() {
    use pbcs::stats::fisher_exact;
    // scipy.stats.fisher_exact([[k1, n1 - k1], [k2, n2 - k2]]).pvalue (SciPy 1.x, two-sided).
    for (k1, n1, k2, n2, want) in [
        (9, 10, 3, 10, 0.019_766_611_097_880_443),
        (10, 10, 2, 10, 0.000_714_455_822_814_955_8),
        (5, 10, 4, 10, 1.0),
        (7, 10, 2, 10, 0.069_778_518_694_927_36),
        (0, 10, 0, 10, 1.0),
        (10, 10, 0, 10, 1.082_508_822_446_903e-5),
        (6, 10, 10, 10, 0.086_687_306_501_547_99),
        (3, 20, 12, 20, 0.007_911_693_673_651_405),
    ] {
        let p = fisher_exact(k1, n1, k2, n2);
        assert!(
            (p - want).abs() < 1e-9 * want.max(1e-3),
            "{k1}/{n1} vs {k2}/{n2}: {p}"
        );
    }
}

#[test]
fn fisher_exact_is_symmetric_and_a_probability() {
    use pbcs::stats::fisher_exact;
    for n1 in 1..=12u64 {
        for n2 in [1, 5, 12u64] {
            for k1 in 0..=n1 {
                for k2 in 0..=n2 {
                    let p = fisher_exact(k1, n1, k2, n2);
                    assert!(p > 0.0 && p <= 1.0, "{k1}/{n1} vs {k2}/{n2}: {p}");
                    // Swapping the samples, or successes with failures, asks the same question.
                    assert!((p - fisher_exact(k2, n2, k1, n1)).abs() < 1e-12);
                    assert!((p - fisher_exact(n1 - k1, n1, n2 - k2, n2)).abs() < 1e-12);
                }
            }
        }
    }
    // Equal proportions are never evidence of a difference.
    assert_eq!(fisher_exact(3, 10, 3, 10), 1.0);
}

#[test]
fn sign_test_matches_scipy() {
    use pbcs::stats::sign_test;
    // scipy.stats.binomtest(k, n, 0.5).pvalue (SciPy 1.17.1, two-sided): (k, n − k, p).
    for (k, m, p) in [
        (9, 1, 0.021484375),
        (7, 3, 0.34375),
        (3, 7, 0.34375),
        (24, 6, 0.0014309063553810122),
        (0, 5, 0.0625),
        (15, 15, 1.0),
        (1, 0, 1.0),
        (20, 7, 0.0191572904586792),
    ] {
        let ours = sign_test(k, m);
        assert!(
            (ours - p).abs() < 1e-12 * p.max(1e-3),
            "{k} {m}: {ours} vs {p}"
        );
    }
}
