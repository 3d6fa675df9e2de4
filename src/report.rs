//! The paper's claims checked against our tables, and the generated LaTeX of the reproduction
//! report (`paper/generated/*.tex`): no number in the report is typed by hand.
//!
//! A claim is judged with 95 % Wilson score intervals: a method *fails reliably* on a maze when
//! the upper end of its success interval is below 1/2, *solves reliably* when the lower end is
//! above 1/2, and one method *beats* another when their intervals are disjoint. Anything else
//! is *inconclusive*.

use crate::figures::human_steps;
use crate::tables::CellStats;
use std::fmt::Write as _;

/// How our data stands to a claim of the paper.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Our data supports the claim at 95 %.
    Agrees,
    /// Our data supports the opposite at 95 %.
    Disagrees,
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
            Verdict::Inconclusive => "inconclusive",
            Verdict::NoClaim => "no claim in the paper",
        }
    }
}

/// One claim of the paper, our numbers, and the verdict.
#[derive(Debug, Clone)]
pub struct Claim {
    /// Short id (`vanilla_ddpg_fails`).
    pub id: &'static str,
    /// What the paper says.
    pub paper: String,
    /// What our data says, with numbers.
    pub ours: String,
    /// How they relate.
    pub verdict: Verdict,
}

/// Fails reliably: Wilson upper end below 1/2.
pub fn fails(s: &CellStats) -> bool {
    s.wilson_hi < 0.5
}

/// Solves reliably: Wilson lower end above 1/2.
pub fn solves(s: &CellStats) -> bool {
    s.wilson_lo > 0.5
}

/// `a` beats `b`: the intervals are disjoint with `a` above.
pub fn beats(a: &CellStats, b: &CellStats) -> bool {
    a.wilson_lo > b.wilson_hi
}

/// Compares method `a` with method `b` maze by maze: `a` beats `b` on a maze when their Wilson
/// intervals are disjoint with `a` above. The verdict agrees with "a does better than b" when
/// `a` beats `b` on some maze and `b` beats `a` on none; it disagrees when `b` beats `a`
/// somewhere; otherwise it is inconclusive. Returns one "maze N: A k/n […] vs B k/n […]" part
/// per maze both methods have, and the verdict.
fn per_maze(
    stats: &[CellStats],
    (a, a_name): (&str, &str),
    (b, b_name): (&str, &str),
) -> (Vec<String>, Verdict) {
    let mut parts = Vec::new();
    let (mut a_wins, mut b_wins) = (false, false);
    for s in cells(stats, a) {
        if let Some(t) = find(stats, b, s.maze) {
            parts.push(format!(
                "maze {}: {a_name} {} vs {b_name} {}",
                s.maze,
                k_of_n(s),
                k_of_n(t)
            ));
            a_wins |= beats(s, t);
            b_wins |= beats(t, s);
        }
    }
    let verdict = if b_wins {
        Verdict::Disagrees
    } else if a_wins {
        Verdict::Agrees
    } else {
        Verdict::Inconclusive
    };
    (parts, verdict)
}

fn k_of_n(s: &CellStats) -> String {
    format!(
        "{}/{} [{:.2}, {:.2}]",
        s.successes, s.n, s.wilson_lo, s.wilson_hi
    )
}

fn cells<'a>(stats: &'a [CellStats], method: &str) -> Vec<&'a CellStats> {
    stats.iter().filter(|s| s.method == method).collect()
}

fn find<'a>(stats: &'a [CellStats], method: &str, maze: usize) -> Option<&'a CellStats> {
    stats.iter().find(|s| s.method == method && s.maze == maze)
}

/// Pools a method's cells over mazes (counts added; interval recomputed).
fn pooled(stats: &[CellStats], method: &str) -> Option<CellStats> {
    let c = cells(stats, method);
    let first = (*c.first()?).clone();
    let (k, n) = c
        .iter()
        .fold((0, 0), |(k, n), s| (k + s.successes, n + s.n));
    Some(CellStats {
        cell: format!("{method}-pooled"),
        ..first.with_counts(k, n)
    })
}

/// "Method fails on every maze", judged maze by maze on the 10-seed cells of `stats` and, where
/// `longer` has the same method and maze, on those runs at a larger budget (the paper's; fewer
/// seeds). Per maze: a longer cell that solves disagrees; one with any success leaves the maze
/// inconclusive (the method reached the target within the paper's budget, but not reliably);
/// otherwise the 10-seed cell decides (fails: agrees, solves: disagrees, else inconclusive).
/// The claim agrees when every maze does and disagrees when any maze does.
fn fails_everywhere(
    id: &'static str,
    paper: &str,
    stats: &[CellStats],
    longer: &[CellStats],
    method: &str,
) -> Option<Claim> {
    let c = cells(stats, method);
    if c.is_empty() {
        return None;
    }
    let mut parts = Vec::new();
    let mut verdicts = Vec::new();
    for s in c {
        let mut part = format!(
            "maze {}: {} solved within {} steps",
            s.maze,
            k_of_n(s),
            human_steps(s.budget as f64)
        );
        let long = find(longer, method, s.maze).filter(|l| l.budget > s.budget);
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
        id,
        paper: paper.into(),
        ours: parts.join("; "),
        verdict,
    })
}

/// Evaluates the paper's claims on our tables (any of them may be empty: its claims are then
/// left out).
pub fn claims(
    table: &[CellStats],
    gamma: &[CellStats],
    unseen: &[CellStats],
    curves: &[CellStats],
) -> Vec<Claim> {
    let mut out = Vec::new();
    out.extend(fails_everywhere(
        "vanilla_ddpg_fails",
        "Vanilla DDPG does not reach the target on any maze (1M steps, one seed per maze).",
        table,
        curves,
        "ddpg",
    ));
    out.extend(fails_everywhere(
        "vanilla_td3_fails",
        "Vanilla TD3 does not reach the target on any maze (1M steps, one seed per maze).",
        table,
        curves,
        "td3",
    ));
    out.extend(fails_everywhere(
        "no_chaining_fails",
        "PBCS without skill chaining fails on every maze, 2×2 included.",
        table,
        &[],
        "pbcs_no_chaining",
    ));
    let pbcs = cells(table, "pbcs");
    if !pbcs.is_empty() {
        let verdict = if pbcs.iter().all(|s| solves(s)) {
            Verdict::Agrees
        } else if pbcs.iter().any(|s| fails(s)) {
            Verdict::Disagrees
        } else {
            Verdict::Inconclusive
        };
        out.push(Claim {
            id: "pbcs_solves_all",
            paper: "PBCS solves every maze (2×2 to 15×15; one seed each, up to 22M steps).".into(),
            ours: pbcs
                .iter()
                .map(|s| {
                    format!(
                        "maze {}: {} within {} steps",
                        s.maze,
                        k_of_n(s),
                        human_steps(s.budget as f64)
                    )
                })
                .collect::<Vec<_>>()
                .join("; "),
            verdict,
        });
        let (parts, verdict) = per_maze(
            table,
            ("pbcs", "PBCS"),
            ("pbcs_no_chaining", "without chaining"),
        );
        if !parts.is_empty() {
            out.push(Claim {
                id: "chaining_helps",
                paper: "Skill chaining is what lets PBCS solve mazes that PBCS without chaining \
                        fails on."
                    .into(),
                ours: parts.join("; "),
                verdict,
            });
        }
        let mut parts = Vec::new();
        let mut below = Vec::new();
        for s in &pbcs {
            if let (Some(m), Some(p)) = (s.solved_steps_median, s.paper_steps) {
                parts.push(format!(
                    "maze {}: median {} over {} solved runs vs the paper's {}",
                    s.maze,
                    human_steps(m),
                    s.successes,
                    human_steps(p as f64)
                ));
                below.push(m < p as f64);
            }
        }
        if !below.is_empty() {
            out.push(Claim {
                id: "pbcs_steps",
                paper: "PBCS's environment steps: 321k, 5M, 6M, 8M, 22M for the five sizes.".into(),
                ours: format!(
                    "{} (sizes with no solved run have no median)",
                    parts.join("; ")
                ),
                verdict: if below.iter().all(|&b| b) {
                    Verdict::Agrees
                } else {
                    Verdict::Inconclusive
                },
            });
        }
    }
    let (parts, verdict) = per_maze(gamma, ("g090", "γ = 0.9"), ("g099", "γ = 0.99"));
    if let (Some(g9), Some(g99)) = (pooled(gamma, "g090"), pooled(gamma, "g099")) {
        // Per maze, and pooled over mazes (more seeds per bar; it decides when no maze does).
        let verdict = match verdict {
            Verdict::Inconclusive if beats(&g9, &g99) => Verdict::Agrees,
            Verdict::Inconclusive if beats(&g99, &g9) => Verdict::Disagrees,
            v => v,
        };
        out.push(Claim {
            id: "gamma_lower_better",
            paper: "On small mazes, lowering γ from 0.99 to 0.9 raises the success rate of PBCS \
                    without skill chaining."
                .into(),
            ours: format!(
                "{}; pooled: {} vs {}",
                parts.join("; "),
                k_of_n(&g9),
                k_of_n(&g99)
            ),
            verdict,
        });
    }
    if let (Some(am), Some(g)) = (pooled(gamma, "g099_am"), pooled(gamma, "g099")) {
        let am9 = pooled(gamma, "g090_am");
        out.push(Claim {
            id: "argmax_actor",
            paper: "The argmax actor tests whether a weak reward signal (γ close to 1) hampers \
                    DDPG's actor update; the paper shows the bars without discussing them."
                .into(),
            ours: format!(
                "pooled over mazes: γ = 0.99 (am) {} vs γ = 0.99 {}{}",
                k_of_n(&am),
                k_of_n(&g),
                am9.map_or(String::new(), |a| format!("; γ = 0.9 (am) {}", k_of_n(&a)))
            ),
            verdict: Verdict::NoClaim,
        });
    }
    let (parts, verdict) = per_maze(unseen, ("ball", "ε-ball starts"), ("exact", "exact starts"));
    if !parts.is_empty() {
        out.push(Claim {
            id: "unseen_states",
            paper: "Starting Backplay's episodes exactly on τ fails: the policy meets states it \
                    never saw; starts sampled in B_ε(τ_K) avoid this."
                .into(),
            ours: parts.join("; "),
            verdict,
        });
    }
    out
}

/// Escapes text for LaTeX (pdflatex): special characters, and the Greek letters and symbols
/// our labels use.
pub fn tex(text: &str) -> String {
    let mut out = String::new();
    for c in text.chars() {
        match c {
            '\\' => out.push_str("\\textbackslash{}"),
            '&' | '%' | '$' | '#' | '_' | '{' | '}' => {
                out.push('\\');
                out.push(c);
            }
            '~' => out.push_str("\\textasciitilde{}"),
            '^' => out.push_str("\\textasciicircum{}"),
            'γ' => out.push_str("$\\gamma$"),
            'ε' => out.push_str("$\\varepsilon$"),
            'τ' => out.push_str("$\\tau$"),
            'α' => out.push_str("$\\alpha$"),
            'β' => out.push_str("$\\beta$"),
            'π' => out.push_str("$\\pi$"),
            '×' => out.push_str("$\\times$"),
            '·' => out.push_str("$\\cdot$"),
            '–' => out.push_str("--"),
            '—' => out.push_str("---"),
            '≤' => out.push_str("$\\le$"),
            '≥' => out.push_str("$\\ge$"),
            '∈' => out.push_str("$\\in$"),
            _ => out.push(c),
        }
    }
    out
}

const GENERATED: &str = "% Generated by `pbcs figures` from results/tables/*.csv. Do not edit.\n";

/// `numbers.tex`: every statistic of every cell as `\res{<experiment>:<cell>:<field>}`, with
/// fields `n`, `successes`, `rate`, `lo`/`hi` (Wilson 95 %), `median`/`q1`/`q3` (environment
/// steps), `solvedmedian`, `skills` (median), `evalmedian` (median final evaluation success
/// rate), `budget` and `paper`.
pub fn numbers_tex(tables: &[(String, Vec<CellStats>)]) -> String {
    let mut s = String::from(GENERATED);
    s.push_str("\\providecommand{\\res}[1]{\\csname res:#1\\endcsname}\n");
    for (exp, rows) in tables {
        for r in rows {
            let fields: Vec<(&str, String)> = vec![
                ("n", r.n.to_string()),
                ("successes", r.successes.to_string()),
                ("rate", format!("{:.2}", r.success_rate)),
                ("lo", format!("{:.2}", r.wilson_lo)),
                ("hi", format!("{:.2}", r.wilson_hi)),
                ("median", human_steps(r.steps_median)),
                ("q1", human_steps(r.steps_q1)),
                ("q3", human_steps(r.steps_q3)),
                (
                    "solvedmedian",
                    r.solved_steps_median.map_or("--".into(), human_steps),
                ),
                ("skills", format!("{}", r.skills_median)),
                ("evalmedian", format!("{:.2}", r.success_rate_median)),
                ("budget", human_steps(r.budget as f64)),
                (
                    "paper",
                    r.paper_steps.map_or("--".into(), |p| human_steps(p as f64)),
                ),
            ];
            for (f, v) in fields {
                let _ = writeln!(
                    s,
                    "\\expandafter\\def\\csname res:{exp}:{}:{f}\\endcsname{{{}}}",
                    r.cell,
                    tex(&v)
                );
            }
        }
    }
    s
}

/// The results table: rows = mazes, columns = methods; each entry "k/n solved, median steps"
/// with the paper's "steps S/F" below it.
pub fn results_table_tex(
    rows: &[CellStats],
    mazes: &[usize],
    methods: &[(String, String)],
) -> String {
    let mut s = String::from(GENERATED);
    let _ = writeln!(s, "\\begin{{tabular}}{{r{}}}", "c".repeat(methods.len()));
    s.push_str("\\toprule\nmaze");
    for (_, label) in methods {
        let _ = write!(s, " & {}", tex(label));
    }
    s.push_str(" \\\\\n\\midrule\n");
    for &n in mazes {
        let _ = write!(s, "${n}\\times{n}$");
        for (m, _) in methods {
            match find(rows, m, n) {
                Some(c) => {
                    let _ = write!(
                        s,
                        " & {}/{} \\textcolor{{gray}}{{[{:.2}, {:.2}]}}, {}",
                        c.successes,
                        c.n,
                        c.wilson_lo,
                        c.wilson_hi,
                        human_steps(c.steps_median)
                    );
                }
                None => s.push_str(" & --"),
            }
        }
        s.push_str(" \\\\\n");
        for (m, _) in methods {
            let paper = find(rows, m, n).and_then(|c| {
                c.paper_steps.map(|p| {
                    format!(
                        "{} {}",
                        human_steps(p as f64),
                        match c.paper_solved {
                            Some(true) => "S",
                            Some(false) => "F",
                            None => "",
                        }
                    )
                })
            });
            let _ = write!(
                s,
                " & \\textit{{\\small paper: {}}}",
                paper.unwrap_or_else(|| "--".into())
            );
        }
        s.push_str(" \\\\[2pt]\n");
    }
    s.push_str("\\bottomrule\n\\end{tabular}\n");
    s
}

/// One row per cell: n, solved with its interval, steps median [q1, q3], min–max, skills, the
/// step budget, and the paper's figure.
pub fn cells_table_tex(rows: &[CellStats]) -> String {
    let mut s = String::from(GENERATED);
    s.push_str("\\begin{tabular}{llrrcrrrrl}\n\\toprule\n");
    s.push_str(
        "method & maze & $n$ & solved & Wilson 95\\,\\% & median & $[q_1, q_3]$ & \
         min--max & skills & paper \\\\\n\\midrule\n",
    );
    for c in rows {
        let _ = writeln!(
            s,
            "{} & {} & {} & {} & [{:.2}, {:.2}] & {} & [{}, {}] & {}--{} & {} & {} \\\\",
            tex(&c.label),
            c.maze,
            c.n,
            c.successes,
            c.wilson_lo,
            c.wilson_hi,
            human_steps(c.steps_median),
            human_steps(c.steps_q1),
            human_steps(c.steps_q3),
            human_steps(c.steps_min),
            human_steps(c.steps_max),
            c.skills_median,
            c.paper_steps.map_or("--".into(), |p| format!(
                "{}{}",
                human_steps(p as f64),
                match c.paper_solved {
                    Some(true) => " S",
                    Some(false) => " F",
                    None => "",
                }
            )),
        );
    }
    s.push_str("\\bottomrule\n\\end{tabular}\n");
    s
}

/// The claims, one row each: the paper's statement, our numbers, the verdict.
pub fn claims_tex(claims: &[Claim]) -> String {
    let mut s = String::from(GENERATED);
    s.push_str("\\begin{description}\n");
    for c in claims {
        let _ = writeln!(
            s,
            "\\item[\\texttt{{{}}}: {}.] \\emph{{Paper:}} {} \\emph{{Ours:}} {}.",
            tex(c.id),
            tex(c.verdict.word()),
            tex(&c.paper),
            tex(&c.ours)
        );
    }
    s.push_str("\\end{description}\n");
    s
}

/// Writes an experiment's table (`<results>/tables/<name>.csv`) and its wall-clock companion
/// (`<name>.timing.csv`).
pub fn write_tables(
    exp: &crate::experiment::Experiment,
    results: &std::path::Path,
    stats: &[CellStats],
    rows: &[crate::experiment::RawRow],
) -> crate::Result<()> {
    crate::tables::write_table(&crate::tables::table_path(results, &exp.name), stats)?;
    let timing = crate::tables::cell_timings(exp, results, rows);
    crate::record::write_records(
        &results
            .join("tables")
            .join(format!("{}.timing.csv", exp.name)),
        &timing,
    )
}

/// Renders every figure of every experiment into `figures` and writes the report's generated
/// LaTeX into `tex`: `numbers.tex`, `<experiment>_cells.tex`, `table.tex` (the results table)
/// and `claims.tex`. Returns every file written.
pub fn render_all(
    experiments: &[(crate::experiment::Experiment, Vec<CellStats>)],
    results: &std::path::Path,
    figures: &std::path::Path,
    tex_dir: &std::path::Path,
) -> crate::Result<Vec<std::path::PathBuf>> {
    let mut files = Vec::new();
    for (exp, stats) in experiments {
        files.extend(crate::figures::render_experiment(
            exp, results, stats, figures,
        )?);
        let path = tex_dir.join(format!("{}_cells.tex", exp.name));
        let text = cells_table_tex(stats);
        crate::record::write_atomic(&path, |w| w.write_all(text.as_bytes()))?;
        files.push(path);
        if exp.name == "table" {
            for (name, text) in [
                (
                    "table.tex",
                    results_table_tex(stats, &exp.mazes, &exp.methods),
                ),
                ("settings.tex", settings_tex(exp)),
            ] {
                let path = tex_dir.join(name);
                crate::record::write_atomic(&path, |w| w.write_all(text.as_bytes()))?;
                files.push(path);
            }
        }
    }
    let named = |n: &str| {
        experiments
            .iter()
            .find(|(e, _)| e.name == n)
            .map_or(Vec::new(), |(_, s)| s.clone())
    };
    let all_claims = claims(
        &named("table"),
        &named("gamma"),
        &named("unseen"),
        &named("curves"),
    );
    let tables: Vec<(String, Vec<CellStats>)> = experiments
        .iter()
        .map(|(e, s)| (e.name.clone(), s.clone()))
        .collect();
    for (name, text) in [
        ("numbers.tex", numbers_tex(&tables)),
        ("claims.tex", claims_tex(&all_claims)),
    ] {
        let path = tex_dir.join(name);
        crate::record::write_atomic(&path, |w| w.write_all(text.as_bytes()))?;
        files.push(path);
    }
    Ok(files)
}

/// `settings.tex`: the settings of the table's PBCS and DDPG cells (maze 2) as
/// `\setting{<name>}`, so that the report quotes the configs instead of retyping them.
pub fn settings_tex(exp: &crate::experiment::Experiment) -> String {
    use crate::experiment::Job;
    let mut s = String::from(GENERATED);
    s.push_str("\\providecommand{\\setting}[1]{\\csname setting:#1\\endcsname}\n");
    let mut put = |name: &str, value: String| {
        let _ = writeln!(
            s,
            "\\expandafter\\def\\csname setting:{name}\\endcsname{{{}}}",
            tex(&value)
        );
    };
    for c in exp.cells.iter().filter(|c| c.maze == exp.mazes[0]) {
        match (&c.job, c.method.as_str()) {
            (Job::Pbcs(j), "pbcs") => {
                let (p, l) = (&j.phase2, &j.learner);
                put("alpha", p.alpha.to_string());
                put("beta", p.beta.to_string());
                put("epsilon", p.epsilon.to_string());
                put("maxsteps", p.max_steps.to_string());
                put("kstep", p.k_step.to_string());
                put("pbcsbudget", human_steps(p.max_env_steps as f64));
                put("evalepisodes", p.eval_episodes.to_string());
                put("evalmaxsteps", p.eval_max_steps.to_string());
                put("pbcsgamma", l.gamma.to_string());
                put(
                    "hidden",
                    l.hidden
                        .iter()
                        .map(|h| h.to_string())
                        .collect::<Vec<_>>()
                        .join("×"),
                );
                put("actorlr", l.actor_lr.to_string());
                put("criticlr", l.critic_lr.to_string());
                put("tau", l.tau.to_string());
                put("batch", l.batch_size.to_string());
                put("replay", human_steps(l.replay_size as f64));
                put("noisesigma", l.noise_sigma.to_string());
                put("argmaxsamples", l.argmax_samples.to_string());
                put("mazeseed", j.maze.seed.to_string());
            }
            (Job::Vanilla(j), "ddpg") => {
                put("vanillabudget", human_steps(j.train.steps as f64));
                put("vanillagamma", j.learner.gamma.to_string());
                put("episodesteps", j.train.max_episode_steps.to_string());
                put(
                    "learningstarts",
                    human_steps(j.train.learning_starts as f64),
                );
            }
            _ => {}
        }
    }
    put("seeds", exp.seed_count.to_string());
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A cell with `k` of `n` seeds solved and its 95 % Wilson interval.
    fn cell(method: &str, maze: usize, k: u64, n: u64) -> CellStats {
        CellStats {
            experiment: "t".into(),
            cell: format!("{method}-maze{maze}"),
            method: method.into(),
            label: method.into(),
            maze,
            n: 0,
            successes: 0,
            success_rate: 0.0,
            wilson_lo: 0.0,
            wilson_hi: 0.0,
            steps_median: 1.0,
            steps_q1: 1.0,
            steps_q3: 1.0,
            steps_min: 1.0,
            steps_max: 1.0,
            solved_steps_median: None,
            skills_median: 0.0,
            success_rate_median: 0.0,
            budget: 1,
            paper_steps: None,
            paper_solved: None,
        }
        .with_counts(k, n)
    }

    #[test]
    fn per_maze_agrees_when_one_maze_separates_and_none_reverses() {
        // 10/10 is [0.72, 1.00], 2/10 is [0.06, 0.51]: disjoint. 0/10 against 0/10: a tie.
        let stats = [
            cell("a", 2, 10, 10),
            cell("b", 2, 2, 10),
            cell("a", 3, 0, 10),
            cell("b", 3, 0, 10),
        ];
        let (parts, verdict) = per_maze(&stats, ("a", "A"), ("b", "B"));
        assert_eq!(verdict, Verdict::Agrees);
        assert_eq!(parts.len(), 2);
        assert!(parts[0].starts_with("maze 2: A 10/10 [0.72, 1.00] vs B 2/10 [0.06, 0.51]"));
        // Pooled, the same counts overlap (10/20 [0.30, 0.70] against 2/20 [0.03, 0.30] is a
        // near miss), which is why the verdict is per maze.
        let (a, b) = (pooled(&stats, "a").unwrap(), pooled(&stats, "b").unwrap());
        assert!(!beats(&a, &b), "{} vs {}", k_of_n(&a), k_of_n(&b));
    }

    #[test]
    fn fails_everywhere_weighs_runs_at_the_papers_budget() {
        let with_budget = |mut c: CellStats, b: u64| {
            c.budget = b;
            c
        };
        let table = [
            with_budget(cell("ddpg", 2, 0, 10), 100_000),
            with_budget(cell("ddpg", 5, 0, 10), 100_000),
        ];
        let verdict = |longer: &[CellStats]| {
            fails_everywhere("x", "", &table, longer, "ddpg")
                .unwrap()
                .verdict
        };
        // No longer runs, or longer runs that never succeed: the 10-seed failures decide.
        assert_eq!(verdict(&[]), Verdict::Agrees);
        assert_eq!(
            verdict(&[with_budget(cell("ddpg", 2, 0, 3), 1_000_000)]),
            Verdict::Agrees
        );
        // 2 of 3 at the paper's budget: reached, not reliably. 10 of 10: the claim is wrong.
        assert_eq!(
            verdict(&[with_budget(cell("ddpg", 2, 2, 3), 1_000_000)]),
            Verdict::Inconclusive
        );
        assert_eq!(
            verdict(&[with_budget(cell("ddpg", 5, 10, 10), 1_000_000)]),
            Verdict::Disagrees
        );
        // A "longer" cell with no larger budget is not evidence about a larger budget.
        assert_eq!(
            verdict(&[with_budget(cell("ddpg", 2, 2, 3), 100_000)]),
            Verdict::Agrees
        );
        let claim = fails_everywhere(
            "x",
            "",
            &table,
            &[with_budget(cell("ddpg", 2, 2, 3), 1_000_000)],
            "ddpg",
        )
        .unwrap();
        assert!(
            claim.ours.starts_with(
                "maze 2: 0/10 [0.00, 0.28] solved within 100k steps, 2/3 [0.21, 0.94] within 1.00M"
            ),
            "{}",
            claim.ours
        );
    }

    #[test]
    fn per_maze_disagrees_when_any_maze_reverses_and_is_inconclusive_on_overlaps() {
        let reversed = [
            cell("a", 2, 10, 10),
            cell("b", 2, 0, 10),
            cell("a", 5, 0, 10),
            cell("b", 5, 10, 10),
        ];
        assert_eq!(
            per_maze(&reversed, ("a", "A"), ("b", "B")).1,
            Verdict::Disagrees
        );
        // 6/10 [0.31, 0.83] against 3/10 [0.11, 0.60]: overlapping.
        let close = [cell("a", 2, 6, 10), cell("b", 2, 3, 10)];
        assert_eq!(
            per_maze(&close, ("a", "A"), ("b", "B")).1,
            Verdict::Inconclusive
        );
        // A maze only one method has is not compared.
        let alone = [cell("a", 2, 10, 10)];
        let (parts, verdict) = per_maze(&alone, ("a", "A"), ("b", "B"));
        assert!(parts.is_empty());
        assert_eq!(verdict, Verdict::Inconclusive);
    }
}
