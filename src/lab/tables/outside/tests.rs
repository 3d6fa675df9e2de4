//! Tests of the outside tables: fixtures written into a temporary results folder.

use super::*;

fn table() -> Experiment {
    Experiment::load(Path::new("experiments/table.toml"), None).unwrap()
}

fn write(path: &Path, text: &str) {
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    std::fs::write(path, text).unwrap();
}

/// Our side: `raw/table/<algo>-maze2/s<seed>.evals.csv` with the greedy success at 300k.
fn ours(results: &Path, algo: &str, solved: &[bool]) {
    for (seed, &s) in solved.iter().enumerate() {
        let success = if s { "1.0" } else { "0.0" };
        write(
            &results.join(format!("raw/table/{algo}-maze2/s{seed}.evals.csv")),
            &format!(
                "steps,episodes,success,mean_return,mean_length\n\
                 290000,10,1.0,1.0,14.0\n300000,11,{success},0.0,1000.0\n"
            ),
        );
    }
}

fn sb3(results: &Path, algo: &str, solved: &[bool]) {
    for (seed, &s) in solved.iter().enumerate() {
        write(
            &results.join(format!("outside/sb3/{algo}-maze2/s{seed}.csv")),
            &format!(
                "library,algo,seed,steps,solved_s0,protocol_successes,protocol_episodes\n\
                 sb3-9.9,{algo},{seed},300000,{s},{},100\n",
                if s { 96 } else { 3 }
            ),
        );
    }
}

#[test]
fn the_maze_comparison_counts_both_sides_at_the_same_step() {
    let dir = tempfile::tempdir().unwrap();
    let r = dir.path();
    // Ours 4 of 5 (the 290k evaluation, solved everywhere, must not count); SB3 1 of 4.
    ours(r, "ddpg", &[true, true, false, true, true]);
    sb3(r, "ddpg", &[false, false, true, false]);
    ours(r, "td3", &[false, true, false]);
    sb3(r, "td3", &[true, true, false]);
    let lines = maze_comparisons(&table(), r).unwrap();
    assert_eq!(lines.len(), 3, "{lines:?}");
    let d = &lines[0];
    assert_eq!(
        (d.algo, d.maze, d.steps),
        (Scope::One(Algo::Ddpg), 2, 300_000)
    );
    assert_eq!(
        (d.ours_n, d.ours_solved, d.sb3_n, d.sb3_solved),
        (5, 4, 4, 1)
    );
    assert_eq!(
        (d.ours_seeds.as_str(), d.sb3_seeds.as_str()),
        ("0 1 3 4", "2")
    );
    assert_eq!(d.sb3_protocol_solved, 1);
    assert_eq!(d.fisher_p, fisher_exact(4, 5, 1, 4));
    assert_eq!((d.ours_lo, d.ours_hi), wilson(4, 5, Z95));
    let p = &lines[2];
    assert_eq!(p.algo, Scope::Pooled);
    assert_eq!(
        (p.ours_n, p.ours_solved, p.sb3_n, p.sb3_solved),
        (8, 5, 7, 3)
    );
    assert_eq!(p.fisher_p, fisher_exact(5, 8, 3, 7));
    assert_eq!((p.ours_seeds.as_str(), p.sb3_seeds.as_str()), ("", ""));
}

#[test]
fn inconsistent_outside_rows_are_errors_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let r = dir.path();
    ours(r, "ddpg", &[true, false]);
    sb3(r, "ddpg", &[true, false]);
    // A row whose seed is not its file's.
    let s1 = r.join("outside/sb3/ddpg-maze2/s1.csv");
    let text = std::fs::read_to_string(&s1).unwrap();
    write(&s1, &text.replace(",ddpg,1,", ",ddpg,7,"));
    let e = maze_comparisons(&table(), r).unwrap_err().to_string();
    assert!(e.contains("s1.csv") && e.contains("seed"), "{e}");
    // Another step count than the folder's first run.
    write(&s1, &text.replace("300000", "200000"));
    let e = maze_comparisons(&table(), r).unwrap_err().to_string();
    assert!(e.contains("s1.csv") && e.contains("300000 steps"), "{e}");
    // Our evaluations stop before the SB3 runs' steps.
    write(&s1, &text);
    let ours0 = r.join("raw/table/ddpg-maze2/s0.evals.csv");
    write(
        &ours0,
        "steps,episodes,success,mean_return,mean_length\n10000,1,0.0,0.0,1000.0\n",
    );
    let e = maze_comparisons(&table(), r).unwrap_err().to_string();
    assert!(e.contains("s0.evals.csv") && e.contains("300000"), "{e}");
    // A protocol of no episodes.
    write(&s1, &text.replace(",3,100", ",0,0"));
    let e = maze_comparisons(&table(), r).unwrap_err().to_string();
    assert!(
        e.contains("s1.csv") && e.contains("protocol_episodes"),
        "{e}"
    );
    write(&s1, &text);
    // Two rows in one run's file.
    write(
        &ours0,
        "steps,episodes,success,mean_return,mean_length\n300000,1,0.0,0.0,1000.0\n",
    );
    write(&s1, &format!("{text}{}", text.lines().nth(1).unwrap()));
    let e = maze_comparisons(&table(), r).unwrap_err().to_string();
    assert!(e.contains("s1.csv") && e.contains("one row"), "{e}");
}

#[test]
fn pendulum_lines_give_the_mean_the_interval_and_welchs_test() {
    let dir = tempfile::tempdir().unwrap();
    let r = dir.path();
    let runs = |who: &str, lib: &str, returns: &[f64]| {
        for (seed, x) in returns.iter().enumerate() {
            write(
                &r.join(format!("outside/pendulum/{who}/s{seed}.csv")),
                &format!(
                    "library,algo,seed,steps,eval_episodes,mean_return\n\
                     {lib},td3,{seed},20000,10,{x}\n"
                ),
            );
        }
    };
    let (a, b) = ([1.0, 2.0, 3.0, 4.0, 5.0], [2.0, 4.0, 6.0, 8.0, 10.0]);
    runs("ours", "pbcs", &a);
    runs("sb3", "sb3-9.9", &b);
    write(
        &r.join("outside/pendulum/published.toml"),
        "source = \"x\"\nalgo = \"td3\"\nsteps = 20000\neval_episodes = 750\nmean = 3.0\nstd = 1.5\n",
    );
    let rows = pendulum_rows(r).unwrap();
    assert_eq!(rows.len(), 3);
    let (o, s, p) = (&rows[0], &rows[1], &rows[2]);
    assert_eq!((o.n, o.mean, o.min, o.max), (5, 3.0, Some(1.0), Some(5.0)));
    assert_eq!(o.welch_p, None);
    // SciPy: ttest_ind(a, b, equal_var=False) → t = −1.897367, p = 0.107531.
    assert!((s.welch_t.unwrap() + 1.897_366_596).abs() < 1e-8);
    assert!((s.welch_p.unwrap() - 0.107_531_194_9).abs() < 1e-8);
    assert_eq!(s.diff_vs_ours, Some(-3.0));
    assert_eq!(
        (p.source, p.mean, p.sd, p.ci_lo),
        (Source::Published, 3.0, 1.5, None)
    );
    // Within [1.5, 4.5]: ours 2, 3, 4; SB3's 2, 4.
    assert_eq!((o.within_published, s.within_published), (Some(3), Some(2)));
    // A published figure of another training length is an error naming the file.
    write(
        &r.join("outside/pendulum/published.toml"),
        "source = \"x\"\nalgo = \"td3\"\nsteps = 1000\neval_episodes = 750\nmean = 3.0\nstd = 1.5\n",
    );
    let e = pendulum_rows(r).unwrap_err().to_string();
    assert!(
        e.contains("published.toml") && e.contains("20000 steps"),
        "{e}"
    );
    // A run that is not a number, or of another length than the folder's first, is an error
    // naming its file.
    let s2 = r.join("outside/pendulum/sb3/s2.csv");
    let text = std::fs::read_to_string(&s2).unwrap();
    write(&s2, &text.replace(",6\n", ",NaN\n"));
    let e = pendulum_rows(r).unwrap_err().to_string();
    assert!(e.contains("s2.csv") && e.contains("finite"), "{e}");
    write(&s2, &text.replace(",20000,", ",30000,"));
    let e = pendulum_rows(r).unwrap_err().to_string();
    assert!(e.contains("s2.csv") && e.contains("steps"), "{e}");
    write(&s2, &text);
    // A misspelt field of the published figure is an error naming the file.
    write(&r.join("outside/pendulum/published.toml"), "mean = 1.0\n");
    let e = pendulum_rows(r).unwrap_err().to_string();
    assert!(e.contains("published.toml"), "{e}");
}

/// SAC's lines come from their own folders and figure, and are absent without our folder; a
/// side of another learner than ours is refused naming SB3's folder.
#[test]
fn pendulum_sac_lines_read_their_own_folders() {
    let dir = tempfile::tempdir().unwrap();
    let r = dir.path();
    assert!(pendulum_sac_rows(r).unwrap().is_empty());
    let runs = |who: &str, lib: &str, algo: &str| {
        for (seed, x) in [-150.0, -140.0, -160.0].iter().enumerate() {
            write(
                &r.join(format!("outside/pendulum/{who}/s{seed}.csv")),
                &format!(
                    "library,algo,seed,steps,eval_episodes,mean_return\n\
                     {lib},{algo},{seed},20000,10,{x}\n"
                ),
            );
        }
    };
    runs("ours_sac", "pbcs", "sac");
    runs("sb3_sac", "sb3-9.9", "sac");
    write(
        &r.join("outside/pendulum/published_sac.toml"),
        "source = \"x\"\nalgo = \"sac\"\nsteps = 20000\neval_episodes = 750\nmean = -157.0\nstd = 88.7\n",
    );
    let rows = pendulum_sac_rows(r).unwrap();
    assert_eq!(rows.len(), 3);
    assert_eq!((rows[0].n, rows[0].mean), (3, -150.0));
    assert_eq!(rows[1].diff_vs_ours, Some(0.0));
    assert_eq!(rows[2].mean, -157.0);
    // The TD3 lines are not there: SAC's folders do not make them.
    assert!(pendulum_rows(r).unwrap().is_empty());
    runs("sb3_sac", "sb3-9.9", "td3");
    let e = pendulum_sac_rows(r).unwrap_err().to_string();
    assert!(e.contains("sb3_sac"), "{e}");
}
