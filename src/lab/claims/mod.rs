//! The paper's claims checked against our tables. The claims are data: `experiments/claims.toml`
//! lists them in the report's order, each with the paper's statement, the experiment whose
//! table judges it and the test ([`ClaimTest`]); [`claims`] evaluates them. The LaTeX that
//! shows them is [`crate::report`]'s.
//!
//! A claim is judged with 95 % Wilson score intervals: a method *fails reliably* on a maze when
//! the upper end of its success interval is below 1/2, *solves reliably* when the lower end is
//! above 1/2, and one method *beats* another when their intervals are disjoint. Anything else
//! is *inconclusive*.

use crate::error::{Error, Result};
use crate::experiment::{ExperimentName, Method, Site};
use crate::fmt::human_steps;
use crate::tables::CellStats;
pub use rules::{beats, exact_better, exact_p, fails, solves, Counts, Pooled, EXACT_TEST_LEVEL};
use serde::Deserialize;
use std::path::Path;

/// How our data stands to a claim of the paper.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Our data supports the claim at 95 %.
    Agrees,
    /// Our data supports the opposite at 95 %.
    Disagrees,
    /// The intervals overlap, but Fisher's exact two-sided test finds the difference the
    /// claim states at p < 0.05 (on some maze, or pooled) and none the other way.
    ExactTestOnly,
    /// The median steps of our solved runs lie below the paper's single run on every size: a
    /// statement about our runs and the paper's one run, not a test of a claim.
    FewerSteps,
    /// Neither.
    Inconclusive,
    /// The paper makes no claim (it shows the experiment without stating a result).
    NoClaim,
}

impl Verdict {
    /// A word for tables.
    pub fn word(self) -> &'static str {
        match self {
            Verdict::Agrees => "agrees",
            Verdict::Disagrees => "disagrees",
            Verdict::ExactTestOnly => "exact test only (p < 0.05; intervals overlap)",
            Verdict::FewerSteps => "fewer steps than the paper's run",
            Verdict::Inconclusive => "inconclusive",
            Verdict::NoClaim => "no claim in the paper",
        }
    }
}

/// One claim of the paper, our numbers, and the verdict.
#[derive(Debug, Clone)]
pub struct Claim {
    /// Short id (`vanilla_ddpg_fails`).
    pub id: String,
    /// What the paper says.
    pub paper: String,
    /// What our data says, with numbers.
    pub ours: String,
    /// How they relate.
    pub verdict: Verdict,
}

/// "k/n [lo, hi] vs k/n [lo, hi], Fisher p = …".
fn versus(a: &impl Counts, b: &impl Counts, (a_name, b_name): (&str, &str)) -> String {
    let p = exact_p(a, b);
    let p = if p < 0.001 {
        "< 0.001".to_string()
    } else {
        format!("= {p:.3}")
    };
    format!(
        "{a_name} {} vs {b_name} {}, Fisher p {p}",
        k_of_n(a),
        k_of_n(b)
    )
}

/// Compares method `a` with method `b` maze by maze: `a` beats `b` on a maze when their Wilson
/// intervals are disjoint with `a` above. The verdict agrees with "a does better than b" when
/// `a` beats `b` on some maze and `b` beats `a` on none; it disagrees when `b` beats `a`
/// somewhere; where no interval separates, Fisher's exact test finding `a` better on some
/// maze (and `b` better on none) gives [`Verdict::ExactTestOnly`]; otherwise it is
/// inconclusive. Returns one "maze N: A k/n […] vs B k/n […], Fisher p …" part per maze both
/// methods have, and the verdict.
fn per_maze(
    stats: &[CellStats],
    (a, a_name): (Method, &str),
    (b, b_name): (Method, &str),
) -> (Vec<String>, Verdict) {
    let mut parts = Vec::new();
    let (mut a_wins, mut b_wins, mut a_exact, mut b_exact) = (false, false, false, false);
    for s in cells(stats, a) {
        if let Some(t) = find(stats, b, s.site) {
            parts.push(format!(
                "{}: {}",
                s.site.named(),
                versus(s, t, (a_name, b_name))
            ));
            a_wins |= beats(s, t);
            b_wins |= beats(t, s);
            a_exact |= exact_better(s, t);
            b_exact |= exact_better(t, s);
        }
    }
    let verdict = if b_wins {
        Verdict::Disagrees
    } else if a_wins {
        Verdict::Agrees
    } else if a_exact && !b_exact {
        Verdict::ExactTestOnly
    } else {
        Verdict::Inconclusive
    };
    (parts, verdict)
}

fn k_of_n(s: &impl Counts) -> String {
    let (lo, hi) = s.wilson();
    format!("{}/{} [{lo:.2}, {hi:.2}]", s.successes(), s.n())
}

fn cells(stats: &[CellStats], method: Method) -> Vec<&CellStats> {
    stats.iter().filter(|s| s.method == method).collect()
}

pub(crate) fn find(stats: &[CellStats], method: Method, site: Site) -> Option<&CellStats> {
    stats.iter().find(|s| s.method == method && s.site == site)
}

/// Pools a method's cells over mazes (counts added; interval recomputed); None without cells.
fn pooled(stats: &[CellStats], method: Method) -> Option<Pooled> {
    let c = cells(stats, method);
    (!c.is_empty()).then(|| Pooled {
        successes: c.iter().map(|s| s.successes).sum(),
        n: c.iter().map(|s| s.n).sum(),
    })
}

/// "Method fails on every maze", judged maze by maze on the 10-seed cells of `stats` and, where
/// `longer` has the same method and maze, on those runs at a larger budget (the paper's; fewer
/// seeds). Per maze: a longer cell that solves disagrees; one with any success leaves the maze
/// inconclusive (the method reached the target within the paper's budget, but not reliably);
/// otherwise the 10-seed cell decides (fails: agrees, solves: disagrees, else inconclusive).
/// The claim agrees when every maze does and disagrees when any maze does.
fn fails_everywhere(
    id: &str,
    paper: &str,
    stats: &[CellStats],
    longer: &[CellStats],
    method: Method,
) -> Option<Claim> {
    let c = cells(stats, method);
    if c.is_empty() {
        return None;
    }
    let mut parts = Vec::new();
    let mut verdicts = Vec::new();
    for s in c {
        let mut part = format!(
            "{}: {} solved within {} steps",
            s.site.named(),
            k_of_n(s),
            human_steps(s.budget as f64)
        );
        let long = find(longer, method, s.site).filter(|l| l.budget > s.budget);
        if let Some(l) = long {
            part.push_str(&format!(
                ", {} within {}",
                k_of_n(l),
                human_steps(l.budget as f64)
            ));
        }
        parts.push(part);
        verdicts.push(match long {
            Some(l) if solves(l) => Verdict::Disagrees,
            Some(l) if l.successes > 0 => Verdict::Inconclusive,
            _ if fails(s) => Verdict::Agrees,
            _ if solves(s) => Verdict::Disagrees,
            _ => Verdict::Inconclusive,
        });
    }
    let verdict = if verdicts.contains(&Verdict::Disagrees) {
        Verdict::Disagrees
    } else if verdicts.iter().all(|v| *v == Verdict::Agrees) {
        Verdict::Agrees
    } else {
        Verdict::Inconclusive
    };
    Some(Claim {
        id: id.into(),
        paper: paper.into(),
        ours: parts.join("; "),
        verdict,
    })
}

/// One claim of the paper as `experiments/claims.toml` states it.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClaimSpec {
    /// Short id (`vanilla_ddpg_fails`).
    pub id: String,
    /// What the paper says (math spans `$…$` as [`crate::report::tex`] reads them).
    pub paper: String,
    /// The experiment whose table judges it.
    pub experiment: ExperimentName,
    /// How it is judged.
    pub test: ClaimTest,
}

/// How a claim is judged on an experiment's table (`test = { kind = "...", ... }`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ClaimTest {
    /// `method` fails on every maze; where experiment `longer` ran the same method and maze at a
    /// larger budget, those runs weigh in (see `fails_everywhere`).
    FailsEverywhere {
        /// The method.
        method: Method,
        /// An experiment with the same method at a larger budget.
        #[serde(default)]
        longer: Option<ExperimentName>,
    },
    /// `method` solves every maze: agrees when every maze is solved reliably, disagrees when
    /// one fails reliably.
    SolvesEverywhere {
        /// The method.
        method: Method,
    },
    /// `method` does better than `than`, maze by maze (`per_maze`); with `pooled`, the
    /// counts pooled over mazes decide where no maze does.
    Beats {
        /// The method said to do better.
        method: Method,
        /// Its name in the text.
        label: String,
        /// The method it is compared with.
        than: Method,
        /// That method's name in the text.
        than_label: String,
        /// Whether pooled counts decide an inconclusive per-maze verdict.
        #[serde(default)]
        pooled: bool,
        /// The experiment whose table holds `than`'s cells, when not the claim's own (an
        /// ablation compared with the results table's cell of the unchanged preset).
        #[serde(default)]
        than_experiment: Option<ExperimentName>,
    },
    /// The median steps of `method`'s solved runs lie below the paper's, on every maze with a
    /// solved run and a paper figure (inconclusive otherwise).
    StepsBelowPaper {
        /// The method.
        method: Method,
    },
    /// No claim in the paper: the pooled counts of `methods` (method, label), the first two
    /// set against each other.
    Pooled {
        /// (method, label), at least two.
        methods: Vec<(Method, String)>,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ClaimsFile {
    #[serde(rename = "claim")]
    claims: Vec<ClaimSpec>,
}

/// Reads the claims file (`experiments/claims.toml`), in order; a malformed file, a `pooled`
/// test with fewer than two methods or a `paper` text with an unbalanced math span (`$…$`,
/// [`crate::mathtext::check_math`]) is an error naming the file and the claim.
pub fn load_claims(path: &Path) -> Result<Vec<ClaimSpec>> {
    let file: ClaimsFile = crate::validate::read_toml(path)?;
    for (i, c) in file.claims.iter().enumerate() {
        crate::mathtext::check_math(&c.paper)
            .map_err(|e| Error::parse(path, format!("claim[{i}] ({}), paper: {e}", c.id)))?;
        if let ClaimTest::Pooled { methods } = &c.test {
            if methods.len() < 2 {
                return Err(Error::parse(
                    path,
                    format!("claim[{i}] ({}): `pooled` needs at least two methods", c.id),
                ));
            }
        }
    }
    Ok(file.claims)
}

/// Evaluates `specs` on the experiments' tables (name, per-cell statistics), in order. Every
/// claim is judged: one whose experiment (or `longer`, or `than_experiment`) has no table
/// here, or whose table lacks the cells it compares, is an error naming the claim
/// ([`Error::Claim`]), never a silent skip.
pub fn claims(
    specs: &[ClaimSpec],
    tables: &[(ExperimentName, Vec<CellStats>)],
) -> Result<Vec<Claim>> {
    specs
        .iter()
        .map(|spec| {
            let table = |name: ExperimentName| -> Result<&[CellStats]> {
                tables
                    .iter()
                    .find(|(n, _)| *n == name)
                    .map(|(_, s)| s.as_slice())
                    .ok_or_else(|| {
                        missing(
                            spec,
                            format!(
                                "no table of experiment `{name}` (run it, then `pbcs aggregate`)"
                            ),
                        )
                    })
            };
            evaluate(spec, &table)
        })
        .collect()
}

/// A profile's (smaller) grid: every claim its tables can judge, in order, and the errors of
/// those they cannot ([`claims`] on each alone). The committed grids use [`claims`], where
/// any claim that cannot be judged is an error.
pub fn claims_partial(
    specs: &[ClaimSpec],
    tables: &[(ExperimentName, Vec<CellStats>)],
) -> (Vec<Claim>, Vec<Error>) {
    let mut judged = Vec::new();
    let mut errors = Vec::new();
    for spec in specs {
        match claims(std::slice::from_ref(spec), tables) {
            Ok(mut c) => judged.append(&mut c),
            Err(e) => errors.push(e),
        }
    }
    (judged, errors)
}

/// The error of a claim that cannot be judged.
fn missing(spec: &ClaimSpec, message: String) -> Error {
    Error::Claim {
        id: spec.id.clone(),
        message,
    }
}

/// The error of a claim whose table has no cell of `method`.
fn no_cells(spec: &ClaimSpec, experiment: ExperimentName, method: Method) -> Error {
    missing(
        spec,
        format!("the table of experiment `{experiment}` has no cell of method `{method}`"),
    )
}

fn evaluate<'a>(
    spec: &ClaimSpec,
    table: &dyn Fn(ExperimentName) -> Result<&'a [CellStats]>,
) -> Result<Claim> {
    let stats = table(spec.experiment)?;
    let claim = |ours: String, verdict: Verdict| Claim {
        id: spec.id.clone(),
        paper: spec.paper.clone(),
        ours,
        verdict,
    };
    match &spec.test {
        ClaimTest::FailsEverywhere { method, longer } => {
            let longer = match longer {
                Some(name) => table(*name)?,
                None => &[],
            };
            fails_everywhere(&spec.id, &spec.paper, stats, longer, *method)
                .ok_or_else(|| no_cells(spec, spec.experiment, *method))
        }
        ClaimTest::SolvesEverywhere { method } => {
            let (ours, verdict) = solves_everywhere(spec, stats, *method)?;
            Ok(claim(ours, verdict))
        }
        ClaimTest::Beats {
            method,
            label,
            than,
            than_label,
            pooled,
            than_experiment,
        } => {
            // With `than_experiment`, `than`'s cells come from that table, beside the claim's
            // own cells.
            let mut both = stats.to_vec();
            if let Some(other) = than_experiment {
                both.extend(table(*other)?.iter().filter(|s| s.method == *than).cloned());
            }
            let (ours, verdict) =
                beats_claim(&both, (*method, label), (*than, than_label), *pooled).ok_or_else(
                    || {
                        missing(
                            spec,
                            format!(
                            "no maze where both `{method}` and `{than}` have a cell (experiment \
                             `{}`{})",
                            spec.experiment,
                            than_experiment
                                .as_ref()
                                .map_or(String::new(), |o| format!(" and `{o}`"))
                        ),
                        )
                    },
                )?;
            Ok(claim(ours, verdict))
        }
        ClaimTest::StepsBelowPaper { method } => {
            let (ours, verdict) = steps_below_paper(spec, stats, *method)?;
            Ok(claim(ours, verdict))
        }
        ClaimTest::Pooled { methods } => {
            Ok(claim(pooled_claim(spec, stats, methods)?, Verdict::NoClaim))
        }
    }
}

/// The cells of `method` in `stats`, or the error that the claim's table has none.
fn method_cells<'a>(
    spec: &ClaimSpec,
    stats: &'a [CellStats],
    method: Method,
) -> Result<Vec<&'a CellStats>> {
    let c = cells(stats, method);
    if c.is_empty() {
        return Err(no_cells(spec, spec.experiment, method));
    }
    Ok(c)
}

/// `method` solves every maze of `stats` (within each cell's budget).
fn solves_everywhere(
    spec: &ClaimSpec,
    stats: &[CellStats],
    method: Method,
) -> Result<(String, Verdict)> {
    let c = method_cells(spec, stats, method)?;
    let verdict = if c.iter().all(solves) {
        Verdict::Agrees
    } else if c.iter().any(fails) {
        Verdict::Disagrees
    } else {
        Verdict::Inconclusive
    };
    let ours = c
        .iter()
        .map(|s| {
            format!(
                "{}: {} within {} steps",
                s.site.named(),
                k_of_n(s),
                human_steps(s.budget as f64)
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    Ok((ours, verdict))
}

/// `method`'s median steps of solved runs below the paper's on every size that has both.
fn steps_below_paper(
    spec: &ClaimSpec,
    stats: &[CellStats],
    method: Method,
) -> Result<(String, Verdict)> {
    let c = method_cells(spec, stats, method)?;
    let mut parts = Vec::new();
    let mut below = Vec::new();
    for s in c {
        if let (Some(m), Some(p)) = (s.solved_steps_median, s.paper_steps) {
            parts.push(format!(
                "{}: median {} over {} solved runs vs the paper's {}",
                s.site.named(),
                human_steps(m),
                s.successes,
                human_steps(p as f64)
            ));
            below.push(m < p as f64);
        }
    }
    if below.is_empty() {
        // Cells, but no solved run on a size the paper reports: nothing to compare.
        return Ok((
            "no solved run on a size with a paper figure".to_string(),
            Verdict::Inconclusive,
        ));
    }
    let ours = format!(
        "{} (sizes with no solved run have no median)",
        parts.join("; ")
    );
    let verdict = if below.iter().all(|&b| b) {
        Verdict::FewerSteps
    } else {
        Verdict::Inconclusive
    };
    Ok((ours, verdict))
}

/// The solved counts of `methods` (name, label) pooled over the mazes of `stats`.
fn pooled_claim(
    spec: &ClaimSpec,
    stats: &[CellStats],
    methods: &[(Method, String)],
) -> Result<String> {
    let pool = |m: Method| pooled(stats, m).ok_or_else(|| no_cells(spec, spec.experiment, m));
    let (m0, l0) = &methods[0];
    let (m1, l1) = &methods[1];
    let (a, b) = (pool(*m0)?, pool(*m1)?);
    let mut ours = format!(
        "pooled over mazes: {l0} {} vs {l1} {}",
        k_of_n(&a),
        k_of_n(&b)
    );
    for (m, l) in &methods[2..] {
        ours.push_str(&format!("; {l} {}", k_of_n(&pool(*m)?)));
    }
    Ok(ours)
}

/// "`a` does better than `b`" on `stats`: maze by maze ([`per_maze`]), and with `pool` the
/// counts pooled over the mazes both ran decide a verdict no maze decides. `None` when no maze
/// has both.
fn beats_claim(
    stats: &[CellStats],
    (method, label): (Method, &str),
    (than, than_label): (Method, &str),
    pool: bool,
) -> Option<(String, Verdict)> {
    let (parts, verdict) = per_maze(stats, (method, label), (than, than_label));
    if parts.is_empty() {
        return None;
    }
    if !pool {
        return Some((parts.join("; "), verdict));
    }
    // Pooled over the mazes both methods ran (more seeds per bar; it decides when no maze
    // does).
    let shared: Vec<CellStats> = stats
        .iter()
        .filter(|s| {
            (s.method == method || s.method == than)
                && find(stats, method, s.site).is_some()
                && find(stats, than, s.site).is_some()
        })
        .cloned()
        .collect();
    let (a, b) = (pooled(&shared, method)?, pooled(&shared, than)?);
    let verdict = match verdict {
        Verdict::Inconclusive | Verdict::ExactTestOnly if beats(&a, &b) => Verdict::Agrees,
        Verdict::Inconclusive if beats(&b, &a) => Verdict::Disagrees,
        Verdict::Inconclusive if exact_better(&a, &b) => Verdict::ExactTestOnly,
        v => v,
    };
    let ours = format!(
        "{}; pooled: {}",
        parts.join("; "),
        versus(&a, &b, (label, than_label))
    );
    Some((ours, verdict))
}

mod rules;
#[cfg(test)]
mod tests;
