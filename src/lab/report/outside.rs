//! The report's LaTeX of the outside checks (`outside_maze.tex`, `outside_pendulum.tex` and
//! their numbers in `numbers.tex`), from `results/tables/outside.*.csv`.

use super::{def_res, tex, GENERATED};
use crate::fmt::human_steps;
use crate::tables::outside::Source;
use crate::tables::scope::Scope;
use std::fmt::Write as _;

/// `outside_maze.tex` (the table of ours against Stable-Baselines3 on the maze) and the numbers
/// `\res{outside:maze:<algo>:<field>}`: `steps`, `oursn`, `ourssolved`, `ourslo`, `ourshi`,
/// `oursseeds`, `sbn`, `sbsolved`, `sblo`, `sbhi`, `sbseeds`, `sbprotocol`, `fisherp`, `sbversion`
/// and `verdict` ([`maze_verdict`]).
pub fn outside_maze_tex(rows: &[crate::tables::outside::MazeComparison]) -> (String, String) {
    let mut table = String::from(GENERATED);
    table.push_str("\\begin{tabular}{lrcrcrl}\n\\toprule\n");
    table.push_str(
        "learner & \\multicolumn{2}{c}{ours: solved, Wilson 95\\,\\%} & \
         \\multicolumn{2}{c}{SB3: solved, Wilson 95\\,\\%} & SB3, PBCS's protocol & Fisher $p$ \\\\\n\\midrule\n",
    );
    let mut numbers = String::new();
    for r in rows {
        let name = match r.algo {
            Scope::Pooled => "both, pooled".to_string(),
            Scope::One(a) => a.name().to_uppercase(),
        };
        let _ = writeln!(
            table,
            "{} & {}/{} & [{:.2}, {:.2}] & {}/{} & [{:.2}, {:.2}] & {}/{} & {} \\\\",
            tex(&name),
            r.ours_solved,
            r.ours_n,
            r.ours_lo,
            r.ours_hi,
            r.sb3_solved,
            r.sb3_n,
            r.sb3_lo,
            r.sb3_hi,
            r.sb3_protocol_solved,
            r.sb3_n,
            p_value(r.fisher_p),
        );
        let key = format!("maze:{}", r.algo);
        let mut fields = vec![
            ("steps", human_steps(r.steps as f64)),
            ("oursn", r.ours_n.to_string()),
            ("ourssolved", r.ours_solved.to_string()),
            ("ourslo", format!("{:.2}", r.ours_lo)),
            ("ourshi", format!("{:.2}", r.ours_hi)),
            ("oursseeds", seeds_list(&r.ours_seeds)),
            ("sbn", r.sb3_n.to_string()),
            ("sbsolved", r.sb3_solved.to_string()),
            ("sblo", format!("{:.2}", r.sb3_lo)),
            ("sbhi", format!("{:.2}", r.sb3_hi)),
            ("sbseeds", seeds_list(&r.sb3_seeds)),
            ("sbprotocol", r.sb3_protocol_solved.to_string()),
            ("fisherp", p_value(r.fisher_p)),
            ("verdict", maze_verdict(r).to_string()),
            (
                "sbversion",
                r.sb3_library.trim_start_matches("sb3-").to_string(),
            ),
        ];
        // The pooled line has no seeds of its own.
        if r.algo == Scope::Pooled {
            fields.retain(|(f, _)| !f.ends_with("seeds"));
        }
        for (f, v) in fields {
            def_res(&mut numbers, "outside", &format!("{key}:{f}"), &v);
        }
    }
    table.push_str("\\bottomrule\n\\end{tabular}\n");
    (table, numbers)
}

/// `outside_pendulum.tex` (final mean returns on Pendulum-v1) and the numbers
/// `\res{outside:<key>:<source>:<field>}` (`key`: `pendulum` for TD3's check, `pendulumsac` for
/// SAC's): `n`, `steps`, `mean`, `sd`, `min`, `max`, `cilo`,
/// `cihi`, `episodes` (each run's evaluation episodes), `withinpublished` (runs within one
/// standard deviation of the published mean), and for a source tested against ours `diff`
/// (mean of ours − mean of this), `t`, `df`, `p`.
pub fn outside_pendulum_tex(
    rows: &[crate::tables::outside::PendulumRow],
    key: &str,
) -> (String, String) {
    let mut table = String::from(GENERATED);
    table.push_str("\\begin{tabular}{lrrrrrcl}\n\\toprule\n");
    table.push_str(
        "source & runs & mean & sd & min & max & mean, $t$ 95\\,\\% & Welch vs ours \\\\\n\\midrule\n",
    );
    // One decimal, with a true minus sign (`tex` sets it in math).
    let one = |x: f64| format!("{x:.1}").replace('-', "−");
    let mut numbers = String::new();
    for r in rows {
        let name = match r.source {
            Source::Ours => "ours (Rust port)".to_string(),
            Source::Sb3 => format!("SB3 {} (gymnasium)", r.library.trim_start_matches("sb3-")),
            Source::Published => "RL-Zoo (one agent)".to_string(),
        };
        let opt = |x: Option<f64>| x.map_or("--".to_string(), one);
        let ci = match (r.ci_lo, r.ci_hi) {
            (Some(a), Some(b)) => format!("[{}, {}]", one(a), one(b)),
            _ => "--".into(),
        };
        let test = match (r.welch_t, r.welch_p) {
            (Some(t), Some(p)) => format!(
                "t = {}, p = {}",
                format!("{t:.2}").replace('-', "−"),
                p_value(p)
            ),
            _ => "--".into(),
        };
        let _ = writeln!(
            table,
            "{} & {} & {} & {} & {} & {} & {} & {} \\\\",
            tex(&name),
            r.n,
            tex(&one(r.mean)),
            tex(&one(r.sd)),
            tex(&opt(r.min)),
            tex(&opt(r.max)),
            tex(&ci),
            tex(&test)
        );
        let key = format!("{key}:{}", r.source);
        for (f, v) in [
            ("n", r.n.to_string()),
            ("steps", human_steps(r.steps as f64)),
            ("mean", one(r.mean)),
            ("sd", one(r.sd)),
            ("min", opt(r.min)),
            ("max", opt(r.max)),
            ("cilo", opt(r.ci_lo)),
            ("cihi", opt(r.ci_hi)),
            ("diff", opt(r.diff_vs_ours)),
            (
                "t",
                r.welch_t
                    .map_or("--".into(), |t| format!("{t:.2}").replace('-', "−")),
            ),
            ("df", opt(r.welch_df)),
            ("p", r.welch_p.map_or("--".into(), p_value)),
            ("episodes", r.eval_episodes.to_string()),
            (
                "withinpublished",
                r.within_published.map_or("--".into(), |k| k.to_string()),
            ),
        ] {
            def_res(&mut numbers, "outside", &format!("{key}:{f}"), &v);
        }
    }
    table.push_str("\\bottomrule\n\\end{tabular}\n");
    (table, numbers)
}

/// The numbers `\res{outside:cost:<algo>:sb3}` and `\res{outside:cost:<algo>:ours}` (the time
/// per environment step of a library whose name starts with `sb3`, and of any other: ours) and
/// `\res{outside:cost:<algo>:ratio}` (SB3's over ours: whole from 10 up, else one decimal),
/// each where `outside.cost_ratio.csv` gives it: the times of every learner first, then the
/// ratios.
pub fn outside_cost_numbers(ratios: &[crate::tables::outside::CostRatio]) -> String {
    let mut s = String::new();
    let time = |us: f64| {
        if us >= 1000.0 {
            format!("{:.1} ms", us / 1000.0)
        } else {
            format!("{us:.0} µs")
        }
    };
    for r in ratios {
        use crate::tables::outside::Library;
        for (who, us) in [
            (Library::Sb3, r.sb3_us_per_step),
            (Library::Ours, r.ours_us_per_step),
        ] {
            if let Some(us) = us {
                def_res(
                    &mut s,
                    "outside",
                    &format!("cost:{}:{who}", r.algo),
                    &time(us),
                );
            }
        }
    }
    for r in ratios {
        if let Some(ratio) = r.ratio {
            let ratio = if ratio >= 10.0 {
                format!("{ratio:.0}")
            } else {
                format!("{ratio:.1}")
            };
            def_res(&mut s, "outside", &format!("cost:{}:ratio", r.algo), &ratio);
        }
    }
    s
}

/// The numbers `\res{outside:pointmaze:<method>-<env>:<field>}` of PointMaze's learner
/// baselines: `runs`, `ended`, `resumed` (SB3's; `--` for ours), `steps` (the most a run
/// trained), `solved`, `solvedat` (by SB3's protocol, the fewest steps to solve, `--` where
/// none did), `solvedmedian` (their median), `reached`, `best` (by SB3's protocol: successes of
/// 100; ours alone on PBCS's task: 0 or 1), `bestat` (`--` where no evaluation succeeded),
/// `bestunsolved` (by the protocol, the best successes of 100 of the runs that did not solve,
/// `--` where all did) and `seeds`.
pub fn outside_pointmaze_numbers(rows: &[crate::tables::outside::PointMazeBaseline]) -> String {
    let mut s = String::new();
    for r in rows {
        let protocol = r.library == crate::tables::outside::Library::Sb3
            || r.solved_at_min.is_some()
            || r.best_unsolved.is_some();
        let best = if protocol {
            format!("{:.0}", r.best * 100.0)
        } else {
            format!("{:.0}", r.best)
        };
        let best_at = r.best_at.map_or("--".into(), |n| human_steps(n as f64));
        for (f, v) in [
            ("runs", r.runs.to_string()),
            ("ended", r.ended.to_string()),
            ("resumed", r.resumed.map_or("--".into(), |n| n.to_string())),
            ("steps", human_steps(r.steps_max as f64)),
            ("solved", r.solved.to_string()),
            (
                "solvedat",
                r.solved_at_min
                    .map_or("--".into(), |n| human_steps(n as f64)),
            ),
            (
                "solvedmedian",
                r.solved_at_median
                    .map_or("--".into(), |n| human_steps(n as f64)),
            ),
            ("reached", r.reached.to_string()),
            ("best", best),
            ("bestat", best_at),
            (
                "bestunsolved",
                r.best_unsolved
                    .map_or("--".into(), |b| format!("{:.0}", b * 100.0)),
            ),
            ("seeds", r.seeds.clone()),
        ] {
            let key = format!("pointmaze:{}-{}:{f}", r.method, r.env.name());
            def_res(&mut s, "outside", &key, &v);
        }
    }
    s
}

/// The numbers `\res{outside:pointmazesb3:<method>-<env>:<field>}` of our runs by SB3's
/// protocol against SB3's on one map (`outside.pointmaze_sb3.csv`): `budget`, `oursn`,
/// `ourssolved`, `oursseeds`, `sbn`, `sbsolved`, `p` (Fisher's exact test) and `verdict`.
pub fn outside_pointmaze_sb3_numbers(
    rows: &[crate::tables::outside::PointMazeSb3Comparison],
) -> String {
    let mut s = String::new();
    for r in rows {
        let verdict = fisher_verdict(r.ours_solved, r.ours_n, r.sb3_solved, r.sb3_n, r.fisher_p);
        for (f, v) in [
            ("budget", human_steps(r.budget as f64)),
            ("oursn", r.ours_n.to_string()),
            ("ourssolved", r.ours_solved.to_string()),
            ("oursseeds", seeds_list(&r.ours_seeds)),
            ("sbn", r.sb3_n.to_string()),
            ("sbsolved", r.sb3_solved.to_string()),
            ("p", p_value(r.fisher_p)),
            ("verdict", verdict.to_string()),
        ] {
            let key = format!("pointmazesb3:{}-{}:{f}", r.method, r.env.name());
            def_res(&mut s, "outside", &key, &v);
        }
    }
    s
}

/// The verdict of one maze comparison at the 5 % level of Fisher's exact test: "no significant
/// difference", or which side solves more.
pub fn maze_verdict(r: &crate::tables::outside::MazeComparison) -> &'static str {
    fisher_verdict(r.ours_solved, r.ours_n, r.sb3_solved, r.sb3_n, r.fisher_p)
}

/// The verdict of ours (`k1` solved of `n1`) against SB3's (`k2` of `n2`) at the 5 % level of
/// Fisher's exact test `p`: "no significant difference", or which side solves more.
fn fisher_verdict(k1: u64, n1: u64, k2: u64, n2: u64, p: f64) -> &'static str {
    let rate = |k: u64, n: u64| k as f64 / n as f64;
    if p.is_nan() || p >= 0.05 {
        "no significant difference"
    } else if rate(k1, n1) > rate(k2, n2) {
        "ours solves significantly more"
    } else {
        "ours solves significantly fewer"
    }
}

/// A p-value as the report prints it: two decimals from 0.1, three below, `< 0.001` below
/// that, `1` from 0.995.
fn p_value(p: f64) -> String {
    if !p.is_finite() {
        "--".into()
    } else if p >= 0.995 {
        "1".into()
    } else if p < 0.001 {
        "< 0.001".into()
    } else if p >= 0.1 {
        format!("{p:.2}")
    } else {
        format!("{p:.3}")
    }
}

/// Space-separated seeds as a comma-separated list (`none` if empty).
fn seeds_list(seeds: &str) -> String {
    match seeds.split_whitespace().collect::<Vec<_>>() {
        v if v.is_empty() => "none".into(),
        v => v.join(", "),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The outside table's verdict follows Fisher's test at 5 %, in the direction of the rates.
    #[test]
    fn the_outside_verdict_follows_the_exact_test() {
        let line = |ok: u64, sk: u64| {
            let p = crate::stats::fisher_exact(ok, 10, sk, 10);
            crate::tables::outside::MazeComparison {
                algo: Scope::One(crate::learner::td3::Algo::Ddpg),
                maze: 2,
                steps: 300_000,
                ours_n: 10,
                ours_solved: ok,
                ours_lo: 0.0,
                ours_hi: 1.0,
                ours_seeds: String::new(),
                sb3_library: "sb3-x".into(),
                sb3_n: 10,
                sb3_solved: sk,
                sb3_lo: 0.0,
                sb3_hi: 1.0,
                sb3_seeds: String::new(),
                sb3_protocol_solved: 0,
                fisher_p: p,
            }
        };
        // 4/10 vs 1/10: p = 0.30; 9/10 vs 3/10: p = 0.0198.
        assert_eq!(maze_verdict(&line(4, 1)), "no significant difference");
        assert_eq!(maze_verdict(&line(9, 3)), "ours solves significantly more");
        assert_eq!(maze_verdict(&line(3, 9)), "ours solves significantly fewer");
        assert_eq!(p_value(0.30343), "0.30");
        assert_eq!(p_value(0.019_766), "0.020");
        assert_eq!(p_value(0.0004), "< 0.001");
        assert_eq!(p_value(1.0), "1");
        assert_eq!(p_value(f64::NAN), "--");
    }
}
