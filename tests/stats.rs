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
