//! The report's table of the goal-conditioned chain's development arms on AntMaze UMaze
//! (`antmaze_gc.tex`) and its numbers `\res{antmaze:gc:…}`, read from the committed folder
//! `<results>/dev/issue79/antmaze/` (its README in `results/dev/issue79/README.md`). None of
//! these runs is a registered grid; every number the section quotes comes from these files.
//!
//! Each arm's files, checked as they are read (a missing or malformed one is an error naming
//! it): `record.csv` (the run's row: its env steps), `trace.csv` (every training round's share
//! of tries that reached their next sub-goal, every greedy test's), and where the arm's chain
//! was evaluated, `eval-s100.csv` (`pbcs eval`'s episodes).

use super::{def_res, percent, tex, GENERATED};
use crate::fmt::human_steps;
use crate::phase2::{EventKind, TraceRow};
use crate::{Error, Result};
use std::fmt::Write as _;
use std::path::Path;

/// The arms' folder, under a results folder.
pub const GC_DEV: &str = "dev/issue79/antmaze";

/// The arms in the table's order: (folder under [`GC_DEV`], `.` for the base job whose files
/// lie in it, the key of its numbers, what it changes).
const ARMS: [(&str, &str, &str); 16] = [
    (
        ".",
        "ant_gc",
        "DDPG, sub-goals 1 m apart reached within 0.45 m, 100 steps each",
    ),
    ("td3_64", "td3_64", "TD3"),
    (
        "td3_64_penalty",
        "td3_64_penalty",
        "TD3, a flip rewarded −1",
    ),
    ("sac_64", "sac_64", "SAC, α learned from 0.01"),
    (
        "td3_64_far",
        "td3_64_far",
        "TD3, 2 m apart within 1 m, 150 steps",
    ),
    (
        "td3_64_2m",
        "td3_64_2m",
        "TD3, 2 m apart within 0.45 m, 150 steps",
    ),
    (
        "td3_64_2m_u2",
        "td3_64_2m_u2",
        "the same, two updates per step",
    ),
    ("td3_64_3m", "td3_64_3m", "the same, 3 m apart, 200 steps"),
    ("td3_256_2m", "td3_256_2m", "the same at 256 × 256"),
    ("td3_64_2m_6m", "td3_64_2m_6m", "the same for 6M steps"),
    (
        "td3_64_2m_shaped",
        "td3_64_2m_shaped",
        "the same on the paper's shaped reward",
    ),
    (
        "td3_64_2m_l2",
        "td3_64_2m_l2",
        "the same, the actions penalised (λ = 0.02)",
    ),
    (
        "td3_64_2m_norm",
        "td3_64_2m_norm",
        "the same, the observations normalised",
    ),
    (
        "td3_64_2m_progress",
        "td3_64_2m_progress",
        "the same on the progress reward",
    ),
    (
        "td3_64_2m_rest",
        "td3_64_2m_rest",
        "the same, starts at rest where τ stands",
    ),
    ("sac_64_2m", "sac_64_2m", "the same with SAC"),
];

/// The one column of a run's `record.csv` the table reads.
#[derive(Debug, serde::Deserialize)]
struct RecordSteps {
    total_steps: u64,
}

/// One episode of `eval-s100.csv`.
#[derive(Debug, serde::Deserialize)]
struct EvalEpisode {
    success: bool,
}

/// What the table shows of one arm.
#[derive(Debug, Clone, PartialEq)]
struct Arm {
    steps: u64,
    /// Mean share of the first 10 and the last 50 training rounds' tries.
    first: f64,
    last: f64,
    /// Greedy tests passed (every episode) and run.
    passed: usize,
    tests: usize,
    /// The chain's successes and episodes (`pbcs eval`), where it was evaluated.
    chain: Option<(usize, usize)>,
}

fn mean(xs: &[f32]) -> f64 {
    xs.iter().map(|&x| f64::from(x)).sum::<f64>() / xs.len().max(1) as f64
}

/// One arm's numbers from its folder.
fn read_arm(dir: &Path) -> Result<Arm> {
    let record = dir.join("record.csv");
    let rows: Vec<RecordSteps> = crate::record::read_records(&record)?;
    let [row] = rows.as_slice() else {
        return Err(Error::parse(&record, "not one row".to_string()));
    };
    let trace = dir.join("trace.csv");
    let events: Vec<TraceRow> = crate::record::read_records(&trace)?;
    let of = |kind| -> Vec<f32> {
        events
            .iter()
            .filter(|r| r.event == kind)
            .map(|r| r.success)
            .collect()
    };
    let (train, tests) = (of(EventKind::Train), of(EventKind::Test));
    if train.len() < 50 || train.iter().chain(&tests).any(|x| !(0.0..=1.0).contains(x)) {
        return Err(Error::parse(
            &trace,
            "fewer than 50 training rounds, or a success outside [0, 1]".to_string(),
        ));
    }
    let eval = dir.join("eval-s100.csv");
    let chain = if eval.exists() {
        let episodes: Vec<EvalEpisode> = crate::record::read_records(&eval)?;
        Some((
            episodes.iter().filter(|e| e.success).count(),
            episodes.len(),
        ))
    } else {
        None
    };
    Ok(Arm {
        steps: row.total_steps,
        first: mean(&train[..10]),
        last: mean(&train[train.len() - 50..]),
        passed: tests.iter().filter(|&&x| x == 1.0).count(),
        tests: tests.len(),
        chain,
    })
}

/// `antmaze_gc.tex` and per arm `\res{antmaze:gc:<arm>:…}`: `steps`, `first` and `last` (%),
/// `passed`, `tests`, and where evaluated `chain` and `chainn`; `\res{antmaze:gc:arms}`,
/// `\res{antmaze:gc:passed}` (greedy tests passed over every arm) and `\res{antmaze:gc:chainbest}`
/// (the most successes of any chain). `None` where the folder does not exist (a results
/// folder of the smoke profile); an arm whose folder is not there yet is left out (one still
/// running).
pub fn gc_table(s: &mut String, results: &Path) -> Result<Option<String>> {
    let dev = results.join(GC_DEV);
    if !dev.is_dir() {
        return Ok(None);
    }
    chance_numbers(s, &dev.join("chance.txt"))?;
    saturation_numbers(s, &dev.join("saturation.txt"))?;
    let mut t = String::from(GENERATED);
    t.push_str("\\begin{tabular}{llrrrr}\n\\toprule\n");
    let _ = writeln!(
        t,
        "arm & change & env steps & {} & tests passed & chain \\\\\n\\midrule",
        tex("tries reaching (first 10 → last 50)")
    );
    let (mut arms, mut passed, mut best) = (0, 0, 0);
    for (folder, key, change) in ARMS {
        let dir = dev.join(folder);
        if !dir.join("record.csv").exists() {
            continue;
        }
        let arm = read_arm(&dir)?;
        arms += 1;
        passed += arm.passed;
        let chain = match arm.chain {
            Some((wins, n)) => {
                best = best.max(wins);
                def_res(s, "antmaze", &format!("gc:{key}:chain"), &wins.to_string());
                def_res(s, "antmaze", &format!("gc:{key}:chainn"), &n.to_string());
                format!("{wins} of {n}")
            }
            None => "—".to_string(),
        };
        let fields = [
            ("steps", human_steps(arm.steps as f64)),
            ("first", percent(arm.first)),
            ("last", percent(arm.last)),
            ("passed", arm.passed.to_string()),
            ("tests", arm.tests.to_string()),
        ];
        let _ = writeln!(
            t,
            "{} & {} & {} & {} & {} & {} \\\\",
            tex(&key.replace('_', " ")),
            tex(change),
            fields[0].1,
            tex(&format!("{} % → {} %", fields[1].1, fields[2].1)),
            tex(&format!("{} of {}", arm.passed, arm.tests)),
            tex(&chain)
        );
        for (f, v) in fields {
            def_res(s, "antmaze", &format!("gc:{key}:{f}"), &v);
        }
    }
    def_res(s, "antmaze", "gc:arms", &arms.to_string());
    def_res(s, "antmaze", "gc:passed", &passed.to_string());
    def_res(s, "antmaze", "gc:chainbest", &best.to_string());
    t.push_str("\\bottomrule\n\\end{tabular}\n");
    Ok(Some(t))
}

/// The runs of `chance.txt` the report quotes: (`chance.py`'s arguments after the manifest,
/// the key of their numbers).
const CHANCE: [(&str, &str); 6] = [
    ("20 100 0.45", "1m"),
    ("20 150 1.0", "far"),
    ("20 100 0.45 --spacing 1.0 --rest", "1mrest"),
    ("20 150 0.45 --spacing 2.0", "2m"),
    ("20 150 0.45 --spacing 2.0 --rest", "2mrest"),
    ("20 200 0.45 --spacing 3.0 --rest", "3mrest"),
];

/// `\res{antmaze:gc:chance:<key>:random}` and `…:still` (%) from `chance.txt`
/// (`chance.py`'s output: a `## python … manifest.toml ARGS` line, then per run a `mean over N
/// skills: random X, still Y` line): the share of training tries from τ's saved states that
/// uniform random actions, and holding still, win. Every run of [`CHANCE`] must be there.
pub fn chance_numbers(s: &mut String, path: &Path) -> Result<()> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let bad = |what: &str| Error::parse(path, what.to_string());
    let mut args: Option<&str> = None;
    let mut found = Vec::new();
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("## python ") {
            let after = rest.split_once("manifest.toml ").map(|(_, a)| a.trim());
            args = Some(after.ok_or_else(|| bad("a `## python` line without its manifest"))?);
        } else if let Some(rest) = line.strip_prefix("mean over ") {
            let parse = |key: &str| -> Option<f64> {
                let v = rest.split(key).nth(1)?.split(',').next()?.trim();
                v.parse::<f64>().ok().filter(|x| (0.0..=1.0).contains(x))
            };
            let (Some(random), Some(still)) = (parse("random "), parse("still ")) else {
                return Err(bad("a `mean over` line without its shares in [0, 1]"));
            };
            let run = args
                .take()
                .ok_or_else(|| bad("a `mean over` line before its run"))?;
            if let Some((_, key)) = CHANCE.iter().find(|(a, _)| *a == run) {
                def_res(
                    s,
                    "antmaze",
                    &format!("gc:chance:{key}:random"),
                    &percent(random),
                );
                def_res(
                    s,
                    "antmaze",
                    &format!("gc:chance:{key}:still"),
                    &percent(still),
                );
                found.push(*key);
            }
        }
    }
    match CHANCE.iter().find(|(_, key)| !found.contains(key)) {
        Some((a, _)) => Err(bad(&format!("no run `{a}`"))),
        None => Ok(()),
    }
}

/// The arms whose actor is penalised for its actions (`learner.action_l2`): left out of the
/// saturation's range, which describes the actors without the penalty.
const PENALISED: [&str; 1] = ["td3_64_2m_l2"];

/// `\res{antmaze:gc:saturated:lo}` and `…:hi` (%), the least and the most of the unpenalised
/// arms' greedy action components within 5 % of a bound, `\res{antmaze:gc:saturated:arms}`
/// (how many), and per arm `\res{antmaze:gc:<arm>:saturated}`, from `saturation.txt`
/// (`saturation.py`'s output: per chain a `## python … <arm>/chain N` line, its episodes, then
/// `mean: saturated X%, upside down Y%, …`).
pub fn saturation_numbers(s: &mut String, path: &Path) -> Result<()> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let bad = |what: &str| Error::parse(path, what.to_string());
    let (mut arm, mut shares): (Option<String>, Vec<u32>) = (None, Vec::new());
    for line in text.lines() {
        if line.starts_with("## python ") {
            let name = line
                .split_whitespace()
                .find_map(|t| t.strip_suffix("/chain"))
                .map(|a| a.rsplit('/').next());
            arm = Some(
                name.flatten()
                    .ok_or_else(|| bad("a `## python` line without its chain"))?
                    .to_string(),
            );
            continue;
        }
        let Some(rest) = line.strip_prefix("mean: saturated ") else {
            continue;
        };
        let share = rest
            .split('%')
            .next()
            .and_then(|v| v.trim().parse::<u32>().ok())
            .filter(|v| *v <= 100)
            .ok_or_else(|| bad("a `mean:` line without a share in [0, 100] %"))?;
        let name = arm
            .take()
            .ok_or_else(|| bad("a `mean:` line before its chain"))?;
        def_res(
            s,
            "antmaze",
            &format!("gc:{name}:saturated"),
            &share.to_string(),
        );
        if !PENALISED.contains(&name.as_str()) {
            shares.push(share);
        }
    }
    let (Some(lo), Some(hi)) = (shares.iter().min(), shares.iter().max()) else {
        return Err(bad("no `mean:` line of an unpenalised arm"));
    };
    def_res(s, "antmaze", "gc:saturated:lo", &lo.to_string());
    def_res(s, "antmaze", "gc:saturated:hi", &hi.to_string());
    def_res(s, "antmaze", "gc:saturated:arms", &shares.len().to_string());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arm_folder(trace: &str, eval: Option<&str>) -> tempfile::TempDir {
        let dir = tempfile::tempdir().unwrap();
        let record = "seed,total_steps\n100,1500000\n";
        std::fs::write(dir.path().join("record.csv"), record).unwrap();
        std::fs::write(dir.path().join("trace.csv"), trace).unwrap();
        if let Some(e) = eval {
            std::fs::write(dir.path().join("eval-s100.csv"), e).unwrap();
        }
        dir
    }

    fn trace(rounds: usize, test: f32) -> String {
        let mut t = String::from("skill,k,t,event,success,env_steps\n");
        for i in 0..rounds {
            let x = if i < 10 { 0.1 } else { 0.5 };
            let _ = writeln!(t, "0,0,9,train,{x},{i}");
            let _ = writeln!(t, "0,0,9,test,{test},{i}");
        }
        t
    }

    #[test]
    fn an_arm_gives_its_rounds_its_tests_and_its_chain() {
        let dir = arm_folder(&trace(60, 1.0), Some("success,steps\ntrue,10\nfalse,700\n"));
        let arm = read_arm(dir.path()).unwrap();
        assert_eq!(arm.steps, 1_500_000);
        assert!((arm.first - 0.1).abs() < 1e-6 && (arm.last - 0.5).abs() < 1e-6);
        assert_eq!((arm.passed, arm.tests, arm.chain), (60, 60, Some((1, 2))));
        let unevaluated = arm_folder(&trace(60, 0.5), None);
        let arm = read_arm(unevaluated.path()).unwrap();
        assert_eq!((arm.passed, arm.chain), (0, None));
    }

    #[test]
    fn a_damaged_arm_is_refused_naming_its_file() {
        for (text, file) in [
            (trace(20, 0.0), "trace.csv"),
            (trace(60, 0.0).replace("0.5,", "1.5,"), "trace.csv"),
            (trace(60, 0.0).replace("train", "walk"), "trace.csv"),
        ] {
            let dir = arm_folder(&text, None);
            let err = read_arm(dir.path()).unwrap_err().to_string();
            assert!(err.contains(file), "{err}");
        }
        let dir = arm_folder(&trace(60, 0.0), Some("success,steps\nmaybe,3\n"));
        let err = read_arm(dir.path()).unwrap_err().to_string();
        assert!(err.contains("eval-s100.csv"), "{err}");
    }

    #[test]
    fn chance_runs_are_read_and_a_missing_or_damaged_one_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("chance.txt");
        let mut text = String::from("# a comment\n");
        for (i, (args, _)) in CHANCE.iter().enumerate() {
            let _ = writeln!(text, "## python chance.py t.csv m/manifest.toml {args}");
            let _ = writeln!(text, "skill 0: τ_0 → τ_9, 1.0 m; random 1/2, still False");
            let _ = writeln!(text, "mean over 3 skills: random 0.{i}5, still 0.0{i}");
        }
        std::fs::write(&path, &text).unwrap();
        let mut s = String::new();
        chance_numbers(&mut s, &path).unwrap();
        assert!(
            s.contains("res:antmaze:gc:chance:far:random\\endcsname{15}"),
            "{s}"
        );
        assert!(
            s.contains("res:antmaze:gc:chance:3mrest:still\\endcsname{5}"),
            "{s}"
        );
        for damaged in [
            text.replace("--spacing 3.0 --rest", "--spacing 4.0"),
            text.replace("random 0.15", "random 1.15"),
            text.replace("## python chance.py t.csv m/manifest.toml 20 150 1.0\n", ""),
        ] {
            std::fs::write(&path, damaged).unwrap();
            let err = chance_numbers(&mut String::new(), &path)
                .unwrap_err()
                .to_string();
            assert!(err.contains("chance.txt"), "{err}");
        }
    }

    #[test]
    fn saturation_shares_are_read_and_a_damaged_line_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("saturation.txt");
        let text = "## python saturation.py x/a/chain 10\nepisode 0: ...\n\
                    mean: saturated 97%, upside down 3%\n## python saturation.py x/b/chain 10\n\
                    mean: saturated 100%, upside down 50%\n\
                    ## python saturation.py x/td3_64_2m_l2/chain 10\nmean: saturated 0%, up 0%\n";
        std::fs::write(&path, text).unwrap();
        let mut s = String::new();
        saturation_numbers(&mut s, &path).unwrap();
        assert!(s.contains("gc:saturated:lo\\endcsname{97}"), "{s}");
        assert!(s.contains("gc:saturated:hi\\endcsname{100}"), "{s}");
        assert!(s.contains("gc:td3_64_2m_l2:saturated\\endcsname{0}"), "{s}");
        assert!(s.contains("gc:a:saturated\\endcsname{97}"), "{s}");
        for damaged in [
            text.replace("97%", "970%"),
            text.replace("mean:", "mean;"),
            text.replace("x/a/chain", "x/a/chains"),
        ] {
            std::fs::write(&path, damaged).unwrap();
            let err = saturation_numbers(&mut String::new(), &path)
                .unwrap_err()
                .to_string();
            assert!(err.contains("saturation.txt"), "{err}");
        }
    }

    #[test]
    fn the_committed_arms_give_the_tables_numbers() {
        let results = Path::new(env!("CARGO_MANIFEST_DIR")).join("results");
        let mut numbers = String::new();
        let table = gc_table(&mut numbers, &results).unwrap().unwrap();
        assert!(table.contains("td3 64 2m 6m"), "{table}");
        // Known values of the committed files (results/dev/issue79/README.md's table).
        for (key, value) in [
            ("gc:td3_64_2m_6m:first", "16"),
            ("gc:td3_64_2m_6m:last", "52"),
            ("gc:td3_64_2m_6m:tests", "296"),
            ("gc:td3_64:chain", "0"),
            ("gc:ant_gc:last", "58"),
            ("gc:passed", "0"),
            ("gc:chance:1m:random", "67"),
            ("gc:chance:1m:still", "38"),
            ("gc:chance:far:random", "49"),
            ("gc:chance:2m:random", "30"),
            ("gc:chance:2mrest:random", "13"),
            ("gc:chance:3mrest:random", "9"),
            ("gc:saturated:lo", "98"),
            ("gc:saturated:hi", "100"),
            ("gc:saturated:arms", "12"),
            ("gc:td3_64_2m_norm:first", "21"),
            ("gc:td3_64_2m_norm:last", "36"),
            ("gc:td3_64_2m_progress:first", "18"),
            ("gc:td3_64_2m_progress:last", "39"),
            ("gc:td3_64_2m_progress:chain", "0"),
            ("gc:td3_64_2m_rest:first", "3"),
            ("gc:td3_64_2m_rest:last", "20"),
            ("gc:sac_64_2m:last", "34"),
            ("gc:arms", "16"),
            ("gc:td3_64_2m_l2:saturated", "0"),
        ] {
            let def = format!("\\csname res:antmaze:{key}\\endcsname{{{value}}}");
            assert!(numbers.contains(&def), "{key}: {numbers}");
        }
    }
}
