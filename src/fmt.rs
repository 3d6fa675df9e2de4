//! Number formatting shared by tables, claims, the report and the figures.

/// An environment-step count as people write it: `1234567` → `1.23M`, `171000` → `171k`.
///
/// ```
/// use pbcs::fmt::human_steps;
/// assert_eq!(human_steps(1_234_567.0), "1.23M");
/// assert_eq!(human_steps(171_000.0), "171k");
/// assert_eq!(human_steps(950.0), "950");
/// assert_eq!(human_steps(f64::NAN), "–");
/// ```
pub fn human_steps(steps: f64) -> String {
    if !steps.is_finite() {
        "–".into()
    } else if steps >= 1e6 {
        format!("{:.2}M", steps / 1e6)
    } else if steps >= 1e3 {
        format!("{:.0}k", steps / 1e3)
    } else {
        format!("{steps:.0}")
    }
}
