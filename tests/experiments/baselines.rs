//! PointMaze's learner baselines (the raw rows of `experiments/pointmaze_vanilla.toml`,
//! `results/pointmaze/sb3/`) are read back checked into `outside.pointmaze.csv`: the committed
//! rows give the counts their CSVs say, SB3's evaluations give known values, and a row that
//! disagrees with its folder or its evaluations is refused naming the file.

use pbcs::envs::EnvName;
use pbcs::experiment::Experiment;
use pbcs::tables::outside::{pointmaze_baselines, Library, PointMazeBaseline};
use std::path::Path;

/// The experiment of our learners on PointMaze.
fn vanilla() -> Experiment {
    Experiment::load(Path::new("experiments/pointmaze_vanilla.toml"), None).unwrap()
}

/// The values of `column` in every `s<seed>.csv` of `dir`, as text.
fn column(dir: &Path, column: &str) -> Vec<String> {
    let mut out = Vec::new();
    for seed in 0..100 {
        let Ok(text) = std::fs::read_to_string(dir.join(format!("s{seed}.csv"))) else {
            continue;
        };
        let mut lines = text.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let row: Vec<&str> = lines.next().unwrap().split(',').collect();
        let i = header.iter().position(|h| *h == column).unwrap();
        out.push(row[i].to_string());
    }
    out
}

#[test]
fn the_committed_vanilla_rows_give_the_counts_their_files_say() {
    let lines = pointmaze_baselines(&[&vanilla()], Path::new("results")).unwrap();
    let ours: Vec<&PointMazeBaseline> = lines
        .iter()
        .filter(|l| l.library == Library::Ours)
        .collect();
    assert_eq!(ours.len(), 6, "DDPG and TD3 on three maps");
    for l in ours {
        let dir = Path::new("results/raw/pointmaze_vanilla").join(format!(
            "{}-{}",
            l.method,
            l.env.name()
        ));
        let finals = column(&dir, "success_rate");
        assert_eq!(l.runs as usize, finals.len(), "{dir:?}");
        let solved = finals
            .iter()
            .filter(|v| v.parse::<f32>().unwrap() >= 1.0)
            .count();
        // Reached: a run with any evaluation that reached the goal.
        let reached = (0..l.runs)
            .filter(|seed| {
                let evals = std::fs::read_to_string(dir.join(format!("s{seed}.evals.csv")));
                evals
                    .unwrap()
                    .lines()
                    .skip(1)
                    .any(|e| e.split(',').nth(2) != Some("0.0"))
            })
            .count();
        assert_eq!(
            (l.solved as usize, l.reached as usize),
            (solved, reached),
            "{dir:?}"
        );
        assert_eq!(l.steps_max, 1_000_000, "{dir:?}");
        // Whether one of our runs was cut and resumed is not in its row (it gives the uncut
        // run's bytes): the column is SB3's and stays empty for ours.
        assert_eq!(l.resumed, None, "{dir:?}");
    }
}

/// A scratch results folder with `files` (path under `pointmaze/`, contents).
fn scratch(files: &[(&str, String)]) -> tempfile::TempDir {
    let tmp = tempfile::tempdir().unwrap();
    for (path, text) in files {
        let path = tmp.path().join("pointmaze").join(path);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    tmp
}

fn evals(successes: &[u64]) -> String {
    let mut s = "env_steps,successes,episodes,wall_seconds\n".to_string();
    for (i, k) in successes.iter().enumerate() {
        s += &format!("{},{k},100,{}.0\n", 10_000 * (i + 1), i + 1);
    }
    s
}

const SB3_HEADER: &str = "library,algo,map,start_cell,goal_cell,cells_apart,seed,budget,solved,\
                          steps_to_solve,best_successes,best_at_steps,env_steps,episodes\n";

#[test]
fn sb3_evaluations_give_known_values() {
    let dir = "sb3/sac_her-pointmaze_umaze";
    let tmp = scratch(&[
        (&format!("{dir}/s0.evals.csv"), evals(&[3, 94, 96])),
        (&format!("{dir}/s1.evals.csv"), evals(&[0, 0])),
        // An ended run that never succeeded: the script writes its best as 0 at 0 steps.
        (
            &format!("{dir}/s1.csv"),
            format!(
                "{SB3_HEADER}sb3-2.9.2,sac_her,pointmaze_umaze,3 1,1 1,6,1,20000,false,,0,0,\
                 20000,100\n"
            ),
        ),
        (&format!("{dir}/s2.evals.csv"), evals(&[40, 97])),
        (
            &format!("{dir}/s2.resumes.csv"),
            "env_steps\n10000\n".to_string(),
        ),
        (&format!("{dir}/s3.evals.csv"), evals(&[])),
        (
            &format!("{dir}/s2.csv"),
            format!(
                "{SB3_HEADER}sb3-2.9.2,sac_her,pointmaze_umaze,3 1,1 1,6,2,500000,true,20000,\
                 97,20000,20000,100\n"
            ),
        ),
    ]);
    let lines = pointmaze_baselines(&[], tmp.path()).unwrap();
    // Seed 3 stopped before its first evaluation: left out; seed 2 was resumed once.
    let want = PointMazeBaseline {
        method: "sac_her".parse().unwrap(),
        library: Library::Sb3,
        env: EnvName::PointmazeUmaze,
        runs: 3,
        ended: 2,
        resumed: Some(1),
        steps_max: 30_000,
        solved: 2,
        solved_at_min: Some(20_000),
        // Seeds 2 and 0 solved at 20 000 and 30 000; seed 1's best was 0 of 100.
        solved_at_median: Some(25_000),
        best_unsolved: Some(0.0),
        reached: 2,
        best: 0.97,
        best_at: Some(20_000),
        seeds: "0 1 2".into(),
    };
    assert_eq!(lines, vec![want]);
}

#[test]
fn rows_that_disagree_with_their_folder_or_evaluations_are_refused_naming_the_file() {
    let dir = "sb3/sac_her-pointmaze_umaze";
    let ended = |best: u64| {
        format!(
            "{SB3_HEADER}sb3-2.9.2,sac_her,pointmaze_umaze,3 1,1 1,6,0,500000,false,,{best},\
             20000,20000,100\n"
        )
    };
    type Case = (Vec<(String, String)>, &'static str, &'static str);
    let cases: Vec<Case> = vec![
        (
            vec![(format!("{dir}/s0.evals.csv"), evals(&[3, 101]))],
            "s0.evals.csv",
            "evaluation 2",
        ),
        (
            vec![(
                format!("{dir}/s0.evals.csv"),
                evals(&[3, 4]).replace("20000,", "30000,"),
            )],
            "s0.evals.csv",
            "every",
        ),
        (
            vec![
                (format!("{dir}/s0.evals.csv"), evals(&[3, 40])),
                (format!("{dir}/s0.csv"), ended(41)),
            ],
            "s0.csv",
            "does not agree",
        ),
        (
            vec![(format!("{dir}/s0.csv"), ended(40))],
            "s0.csv",
            "without its evaluations",
        ),
        (
            vec![(format!("{dir}/s0.evals.csv"), evals(&[96, 97]))],
            "s0.evals.csv",
            "none after one with 95",
        ),
        (
            vec![(format!("{dir}/s0.evals.csv"), evals(&[]))],
            "sac_her-pointmaze_umaze",
            "holds no run",
        ),
        (
            vec![(
                format!("{dir}/s0.csv"),
                ended(40).replace("sac_her,", "td3,"),
            )],
            "s0.csv",
            "not a run of sac_her",
        ),
        (
            vec![(
                "sb3/sac_her-pointmaze_nowhere/s0.evals.csv".into(),
                evals(&[1]),
            )],
            "pointmaze_nowhere",
            "a map of the registry",
        ),
    ];
    for (files, file, why) in cases {
        let files: Vec<(&str, String)> =
            files.iter().map(|(p, t)| (p.as_str(), t.clone())).collect();
        let tmp = scratch(&files);
        let err = pointmaze_baselines(&[], tmp.path())
            .unwrap_err()
            .to_string();
        assert!(err.contains(file) && err.contains(why), "{why}: {err}");
    }
    // Our learners' rows: one committed run copied into a scratch results folder, then
    // contradicted (its row, then its evaluations).
    let exp = vanilla();
    let cell = exp.cell("ddpg-pointmaze_umaze").unwrap();
    let from = exp.cell_dir(Path::new("results"), cell);
    let copy = |row: &str, evals: &str| {
        let tmp = tempfile::tempdir().unwrap();
        let dir = exp.cell_dir(tmp.path(), cell);
        std::fs::create_dir_all(&dir).unwrap();
        for ext in [".toml", ".timing.toml"] {
            let name = format!("s8{ext}");
            std::fs::copy(from.join(&name), dir.join(&name)).unwrap();
        }
        std::fs::write(dir.join("s8.csv"), row).unwrap();
        std::fs::write(dir.join("s8.evals.csv"), evals).unwrap();
        tmp
    };
    let row = std::fs::read_to_string(from.join("s8.csv")).unwrap();
    let evals8 = std::fs::read_to_string(from.join("s8.evals.csv")).unwrap();
    let tmp = copy(&row, &evals8);
    assert_eq!(pointmaze_baselines(&[&exp], tmp.path()).unwrap().len(), 1);
    for (bad, why) in [
        (row.replace(",8,ddpg,", ",9,ddpg,"), "seed"),
        (row.replace(",ddpg,vanilla,", ",td3,vanilla,"), "method"),
        (
            row.replace(",1000000,1000000,", ",990000,1000000,"),
            "env_steps",
        ),
    ] {
        let tmp = copy(&bad, &evals8);
        let err = pointmaze_baselines(&[&exp], tmp.path())
            .unwrap_err()
            .to_string();
        assert!(err.contains("s8") && err.contains(why), "{why}: {err}");
    }
    // Its last evaluation says the goal was reached, its row that it was not: refused (by
    // the row's own check against its evaluations, naming both files and the column).
    let mut lines: Vec<String> = evals8.lines().map(String::from).collect();
    let last = lines.len() - 1;
    let mut cols: Vec<&str> = lines[last].split(',').collect();
    assert_eq!(cols[2], "0.0", "the committed run ends unsolved");
    cols[2] = "1.0";
    lines[last] = cols.join(",");
    let tmp = copy(&row, &(lines.join("\n") + "\n"));
    let err = pointmaze_baselines(&[&exp], tmp.path())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("s8.csv")
            && err.contains("s8.evals.csv")
            && err.contains("column `success_rate`"),
        "{err}"
    );
    // Its evaluations out of order (the first two swapped): refused too.
    let mut lines: Vec<&str> = evals8.lines().collect();
    lines.swap(1, 2);
    let tmp = copy(&row, &(lines.join("\n") + "\n"));
    let err = pointmaze_baselines(&[&exp], tmp.path())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("s8.evals.csv") && err.contains("in order"),
        "{err}"
    );
}
