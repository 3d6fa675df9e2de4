//! Experiment files: every file parses under every profile with unique cells, bad files are
//! rejected with the field named, and the smoke profile runs end to end to tables and figures,
//! deterministically and resumably.

use pbcs::experiment::{experiment_files, plan, read_raw, sweep, Event, Experiment};
use std::collections::BTreeSet;
use std::path::Path;
use std::sync::Mutex;

fn files() -> Vec<std::path::PathBuf> {
    experiment_files(Path::new("experiments")).unwrap()
}

#[test]
fn every_experiment_file_parses_with_unique_cells() {
    let names: BTreeSet<String> = files()
        .iter()
        .map(|f| f.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    for want in ["table", "gamma", "unseen"] {
        assert!(names.contains(want), "experiments/{want}.toml is missing");
    }
    for f in files() {
        for profile in [None, Some("smoke")] {
            let exp = Experiment::load(&f, profile)
                .unwrap_or_else(|e| panic!("{} ({profile:?}): {e}", f.display()));
            let ids: BTreeSet<&str> = exp.cells.iter().map(|c| c.id.as_str()).collect();
            assert_eq!(
                ids.len(),
                exp.cells.len(),
                "{}: duplicate cells",
                f.display()
            );
            // Every cell is one (method, size) of the grid; the paper's experiments run every
            // method on every size (the ablations choose sizes per method).
            for c in &exp.cells {
                assert!(exp.mazes.contains(&c.maze), "{}: {}", f.display(), c.id);
                assert!(exp.methods.iter().any(|(m, _)| *m == c.method), "{}", c.id);
            }
            if COMPLETE.contains(&exp.name.as_str()) {
                assert_eq!(exp.cells.len(), exp.mazes.len() * exp.methods.len());
            }
        }
        // The committed grid holds at least 10 seeds per cell.
        let exp = Experiment::load(&f, None).unwrap();
        assert!(exp.seed_count >= 10, "{}", f.display());
    }
}

/// The results table: the paper's columns and sizes at the paper's budgets (DDPG and TD3 1M
/// steps, every PBCS method twice the paper's PBCS steps for its maze), and the `fast` preset
/// as an extra column.
#[test]
fn the_table_has_the_papers_columns_sizes_and_budgets_and_the_fast_column() {
    use pbcs::experiment::Job;
    let exp = Experiment::load(Path::new("experiments/table.toml"), None).unwrap();
    assert_eq!(exp.mazes, [2, 5, 7, 10, 15]);
    let methods: Vec<&str> = exp.methods.iter().map(|(m, _)| m.as_str()).collect();
    assert_eq!(
        methods,
        ["ddpg", "td3", "pbcs_no_chaining", "pbcs", "pbcs_fast"]
    );
    let pbcs2 = exp.cell("pbcs-maze2").unwrap();
    assert_eq!(
        (pbcs2.paper_steps, pbcs2.paper_solved),
        (Some(321_000), Some(true))
    );
    for c in &exp.cells {
        match &c.job {
            Job::Vanilla(j) => assert_eq!(j.train.steps, 1_000_000, "{}", c.id),
            Job::Pbcs(j) => {
                let pbcs = exp.cell(&format!("pbcs-maze{}", c.maze)).unwrap();
                assert_eq!(
                    j.phase2.max_env_steps,
                    2 * pbcs.paper_steps.unwrap(),
                    "{}",
                    c.id
                );
                assert_eq!(j.maze.size, c.maze);
            }
        }
    }
    // The added column runs the fast preset and the paper's column the paper preset, with
    // nothing changed but the maze size and the budget.
    for (method, file) in [
        ("pbcs_fast", "experiments/pbcs_fast.toml"),
        ("pbcs", "experiments/pbcs_paper.toml"),
    ] {
        let preset: pbcs::config::PbcsJob =
            toml::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
        for &n in &exp.mazes {
            let mut want = preset.clone();
            want.seed = 0;
            want.maze.size = n;
            want.phase2.max_env_steps = 2 * exp
                .cell(&format!("pbcs-maze{n}"))
                .unwrap()
                .paper_steps
                .unwrap();
            assert_eq!(
                exp.cell(&format!("{method}-maze{n}")).unwrap().job,
                Job::Pbcs(want),
                "{method}-maze{n}"
            );
        }
    }
}

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn a_method_may_run_a_subset_of_the_sizes() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy("experiments/pbcs_paper.toml", dir.path().join("base.toml")).unwrap();
    let text = |own: &str| {
        format!(
            "title = \"t\"\nseeds = 1\nmazes = [2, 3]\n\
             [[method]]\nname = \"a\"\nkind = \"pbcs\"\nbase = \"base.toml\"\n\
             [[method]]\nname = \"b\"\nkind = \"pbcs\"\nbase = \"base.toml\"\nmazes = {own}\n"
        )
    };
    let exp = Experiment::load(&write(dir.path(), "sub.toml", &text("[3]")), None).unwrap();
    let ids: Vec<&str> = exp.cells.iter().map(|c| c.id.as_str()).collect();
    assert_eq!(ids, ["a-maze2", "a-maze3", "b-maze3"]);
    for bad in ["[5]", "[]"] {
        let err = Experiment::load(&write(dir.path(), "bad.toml", &text(bad)), None)
            .unwrap_err()
            .to_string();
        assert!(err.contains("method.mazes") && err.contains("`b`"), "{err}");
    }
}

#[test]
fn bad_experiment_files_name_the_problem() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy("experiments/pbcs_paper.toml", dir.path().join("base.toml")).unwrap();
    let head = "title = \"t\"\nseeds = 2\nmazes = [2]\n";
    let method = |name: &str, set: &str| {
        format!("[[method]]\nname = \"{name}\"\nkind = \"pbcs\"\nbase = \"base.toml\"\nset = {{ {set} }}\n")
    };
    let cases = [
        (
            format!("{head}{}", method("a", "phase2.epsilom = 0.1")),
            "epsilom",
        ),
        (
            format!("{head}{}{}", method("a", ""), method("a", "")),
            "appears twice",
        ),
        (
            format!("{head}{}", method("a", "phase2.beta = 0")),
            "phase2.beta",
        ),
        (format!("{head}{}", method("a b", "")), "method.name"),
        (
            format!("title = \"t\"\nseeds = 0\nmazes = [2]\n{}", method("a", "")),
            "seeds",
        ),
        (
            format!("title = \"t\"\nseeds = 1\nmazes = [1]\n{}", method("a", "")),
            "maze.size",
        ),
        (
            format!(
                "title = \"t\"\nseeds = 1\nmazes = [2, 2]\n{}",
                method("a", "")
            ),
            "mazes",
        ),
        (
            format!(
                "{head}{}",
                method("a", "").replace("base.toml", "nowhere.toml")
            ),
            "nowhere.toml",
        ),
        (
            format!(
                "{head}{}[by_maze]\n\"3\" = {{ pbcs = {{ phase2.beta = 5 }} }}\n",
                method("a", "")
            ),
            "`3` is not one of the maze sizes",
        ),
        (
            format!(
                "{head}{}[by_maze]\n\"2\" = {{ pbcs = {{ phase2.epsilom = 5 }} }}\n",
                method("a", "")
            ),
            "maze 2",
        ),
    ];
    let figure = |body: &str| format!("{head}{}[[figure]]\n{body}\n", method("a", ""));
    let figure_cases = [
        (
            figure("kind = \"mazes\"\nname = \"m\"\nmethod = \"b\""),
            "no method `b`",
        ),
        (figure("kind = \"pie\"\nname = \"p\""), "pie"),
        (figure("kind = \"bars\"\nname = \"../x\""), "figure[0].name"),
        (
            figure("kind = \"panels\"\nname = \"p\"\nmethods = [\"a\"]"),
            "figure[0].methods",
        ),
        (
            format!(
                "{}[[figure]]\nkind = \"bars\"\nname = \"g\"\n",
                figure("kind = \"grid\"\nname = \"g\"")
            ),
            "used twice",
        ),
        (
            figure("kind = \"bars\"\nname = \"b\"\ncolour = 1"),
            "colour",
        ),
        (
            format!(
                "{head}{}[report]\nsettings = {{ pbcs = \"a\", vanilla = \"a\" }}\n",
                method("a", "")
            ),
            "report.settings.vanilla",
        ),
    ];
    for (i, (text, needle)) in cases.iter().chain(&figure_cases).enumerate() {
        let path = write(dir.path(), &format!("bad{i}.toml"), text);
        let err = Experiment::load(&path, None).unwrap_err().to_string();
        assert!(
            err.contains(needle),
            "case {i}: `{err}` does not name `{needle}`"
        );
    }
    // A profile's per-maze fields are validated like the rest, when the profile is used.
    let profiled = write(
        dir.path(),
        "profiled.toml",
        &format!(
            "{head}{}[profile.p.by_maze]\n\"2\" = {{ pbcs = {{ phase2.beta = 0 }} }}\n",
            method("a", "")
        ),
    );
    assert!(Experiment::load(&profiled, None).is_ok());
    let err = Experiment::load(&profiled, Some("p"))
        .unwrap_err()
        .to_string();
    assert!(err.contains("phase2.beta"), "{err}");
    // The file's per-maze fields may name a size a profile leaves out (a smoke profile runs
    // one size of the file's grid); they apply where the size is run, under the profile's own
    // fields.
    let narrowed = write(
        dir.path(),
        "narrowed.toml",
        &format!(
            "title = \"t\"\nseeds = 1\nmazes = [2, 3]\n{}[by_maze]\n\"3\" = {{ pbcs = {{ phase2.beta = 7 }} }}\n\"2\" = {{ pbcs = {{ phase2.beta = 6 }} }}\n[profile.small]\nmazes = [2]\npbcs = {{ phase2.beta = 5 }}\n",
            method("a", "")
        ),
    );
    let beta = |profile: Option<&str>, id: &str| match &Experiment::load(&narrowed, profile)
        .unwrap()
        .cell(id)
        .unwrap()
        .job
    {
        pbcs::experiment::Job::Pbcs(j) => j.phase2.beta,
        _ => unreachable!(),
    };
    assert_eq!((beta(None, "a-maze2"), beta(None, "a-maze3")), (6, 7));
    assert_eq!(beta(Some("small"), "a-maze2"), 5);
    let ok = write(dir.path(), "ok.toml", &format!("{head}{}", method("a", "")));
    let err = Experiment::load(&ok, Some("nope")).unwrap_err().to_string();
    assert!(err.contains("profile") && err.contains("nope"), "{err}");
    let exp = Experiment::load(&ok, None).unwrap();
    assert!(plan(&exp, Some("a-maze3"), None)
        .unwrap_err()
        .to_string()
        .contains("a-maze2"));
    assert!(plan(&exp, None, Some(7))
        .unwrap_err()
        .to_string()
        .contains("seed"));
}

/// The smoke profile of every experiment, run twice into two folders with 1 and 2 jobs: the
/// same bytes; a third sweep finds everything finished; then tables, figures and LaTeX.
#[test]
fn smoke_profile_runs_end_to_end_deterministically() {
    let a = tempfile::tempdir().unwrap();
    let b = tempfile::tempdir().unwrap();
    let mut loaded = Vec::new();
    for f in files() {
        let exp = Experiment::load(&f, Some("smoke")).unwrap();
        let runs = plan(&exp, None, None).unwrap();
        let ran_a = sweep(
            &exp,
            &runs,
            a.path(),
            1,
            pbcs::nn::kernel::Kernel::detect(),
            |_, _| {},
        )
        .unwrap();
        let ran_b = sweep(
            &exp,
            &runs,
            b.path(),
            2,
            pbcs::nn::kernel::Kernel::detect(),
            |_, _| {},
        )
        .unwrap();
        assert_eq!(ran_a, ran_b);
        for p in &runs {
            for suffix in ["csv", "toml"] {
                let name = format!("s{}.{suffix}", p.seed);
                let read =
                    |root: &Path| std::fs::read(exp.cell_dir(root, p.cell).join(&name)).unwrap();
                assert_eq!(read(a.path()), read(b.path()), "{} {name}", p.cell.id);
            }
        }
        let skipped = Mutex::new(0);
        sweep(
            &exp,
            &runs,
            a.path(),
            2,
            pbcs::nn::kernel::Kernel::detect(),
            |_, e| {
                if matches!(e, Event::Skipped(_)) {
                    *skipped.lock().unwrap() += 1;
                }
            },
        )
        .unwrap();
        assert_eq!(
            *skipped.lock().unwrap(),
            runs.len(),
            "{}: resume re-ran a run",
            exp.name
        );
        let rows = read_raw(&exp, a.path()).unwrap();
        let stats = pbcs::tables::cell_stats(&exp, &rows);
        assert_eq!(stats.len(), exp.cells.len());
        pbcs::pipeline::write_tables(&exp, a.path(), &stats, &rows).unwrap();
        let back =
            pbcs::tables::read_table(&pbcs::tables::table_path(a.path(), &exp.name)).unwrap();
        assert_eq!(back, stats);
        loaded.push((exp, stats));
    }
    let figures = a.path().join("figures");
    let tex = a.path().join("tex");
    let tables: Vec<(String, Vec<pbcs::tables::CellStats>)> = loaded
        .iter()
        .map(|(e, s)| (e.name.clone(), s.clone()))
        .collect();
    let specs = pbcs::claims::load_claims(Path::new("experiments/claims.toml")).unwrap();
    let claims = pbcs::claims::claims(&specs, &tables);
    let files = pbcs::pipeline::render_all(&loaded, &claims, a.path(), &figures, &tex).unwrap();
    for name in [
        "results_grid.png",
        "results_grid.svg",
        "results_maze2.png",
        "curves.png",
        "gamma.png",
        "unseen.png",
        "unseen_bars.png",
    ] {
        let path = figures.join(name);
        assert!(files.contains(&path), "{name} not written");
        assert!(
            std::fs::metadata(&path).unwrap().len() > 1000,
            "{name} is empty"
        );
    }
    for name in ["table.tex", "numbers.tex", "claims.tex", "gamma_cells.tex"] {
        let text = std::fs::read_to_string(tex.join(name)).unwrap();
        assert!(text.starts_with("% Generated"), "{name}");
    }
}

/// A finished run of another config is never mixed with the experiment's: the sweep refuses.
#[test]
fn a_changed_experiment_refuses_to_resume_over_old_runs() {
    let dir = tempfile::tempdir().unwrap();
    let exp = Experiment::load(Path::new("experiments/unseen.toml"), Some("smoke")).unwrap();
    let runs = plan(&exp, Some("exact-maze2"), None).unwrap();
    sweep(
        &exp,
        &runs,
        dir.path(),
        1,
        pbcs::nn::kernel::Kernel::detect(),
        |_, _| {},
    )
    .unwrap();
    let mut changed = exp.clone();
    if let pbcs::experiment::Job::Pbcs(j) = &mut changed.cells[1].job {
        j.phase2.epsilon = 0.2;
    }
    let runs = plan(&changed, Some("exact-maze2"), None).unwrap();
    let err = sweep(
        &changed,
        &runs,
        dir.path(),
        1,
        pbcs::nn::kernel::Kernel::detect(),
        |_, _| {},
    )
    .unwrap_err();
    assert!(err.to_string().contains("another config"), "{err}");
}

/// Two sweeps into one results folder: a run that another process holds (its lock file) is
/// refused with a message naming the lock, and nothing of it is written; once released, the
/// run goes ahead and leaves no lock behind.
#[test]
fn a_run_another_sweep_holds_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let exp = Experiment::load(Path::new("experiments/unseen.toml"), Some("smoke")).unwrap();
    let runs = plan(&exp, Some("exact-maze2"), Some(0)).unwrap();
    let cell_dir = exp.cell_dir(dir.path(), runs[0].cell);
    let lock = pbcs::record::WorkLock::acquire(&cell_dir.join("s0.lock")).unwrap();
    let err = sweep(
        &exp,
        &runs,
        dir.path(),
        1,
        pbcs::nn::kernel::Kernel::detect(),
        |_, _| {},
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("s0.lock") && err.contains("another process"),
        "{err}"
    );
    assert!(!cell_dir.join("s0.csv").exists());
    drop(lock);
    sweep(
        &exp,
        &runs,
        dir.path(),
        1,
        pbcs::nn::kernel::Kernel::detect(),
        |_, _| {},
    )
    .unwrap();
    assert!(cell_dir.join("s0.csv").exists());
    assert!(!cell_dir.join("s0.lock").exists());
}

/// The sweep's pool starts items in their order (so an interrupted sweep has done a prefix of
/// its plan: whole mazes, smallest first), returns results in the items' order, and starts
/// nothing new after an error.
#[test]
fn parallel_runs_start_in_order_and_stop_at_an_error() {
    use pbcs::experiment::run_parallel;
    let items: Vec<usize> = (0..24).collect();
    let started = Mutex::new(Vec::new());
    let out = run_parallel(&items, 3, |&i| {
        started.lock().unwrap().push(i);
        std::thread::sleep(std::time::Duration::from_millis(2 + (i % 3) as u64));
        Ok(i * 10)
    })
    .unwrap();
    assert_eq!(out, items.iter().map(|i| i * 10).collect::<Vec<_>>());
    let started = started.into_inner().unwrap();
    for (p, &i) in started.iter().enumerate() {
        // Three threads take items in turn: an item starts at most two places off its rank.
        assert!(p.abs_diff(i) <= 2, "item {i} started {p}th: {started:?}");
    }
    let ran = Mutex::new(0);
    let err = run_parallel(&items, 1, |&i| {
        *ran.lock().unwrap() += 1;
        if i == 5 {
            Err(pbcs::Error::invalid("item", "five"))
        } else {
            Ok(i)
        }
    })
    .unwrap_err();
    assert!(err.to_string().contains("five"));
    assert_eq!(*ran.lock().unwrap(), 6, "items after the error ran");
}

/// A lock file left behind by an interrupted run (whatever it says: a process that has ended,
/// another host) blocks nothing: no process holds its OS lock, so the resumed sweep takes it
/// over and names itself in it; while that claim lives, a second one is refused, and once
/// dropped the file is gone.
#[test]
fn an_interrupted_runs_lock_file_blocks_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s0.lock");
    for stale in ["pid = 999999\nhost = \"elsewhere\"\n", "pid = 1\n", ""] {
        std::fs::write(&path, stale).unwrap();
        let lock = pbcs::record::WorkLock::acquire(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.starts_with(&format!("pid = {}\n", std::process::id())),
            "{stale:?} → {text}"
        );
        let err = pbcs::record::WorkLock::acquire(&path)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("another process") && err.contains("s0.lock"),
            "{err}"
        );
        drop(lock);
        assert!(!path.exists());
    }
}

/// Stored configs are compared by value: a setting added after a run was stored, absent from
/// its file, takes its default (the older run's behaviour); a changed value is another job.
#[test]
fn stored_configs_compare_by_value() {
    let exp = Experiment::load(Path::new("experiments/unseen.toml"), Some("smoke")).unwrap();
    let job = exp.cells[0].job.with_seed(3);
    let text = job.to_toml();
    assert!(job.same_as(&text));
    let older: String = text
        .lines()
        .filter(|l| !l.starts_with("fast_tests") && !l.starts_with("restarts"))
        .map(|l| format!("{l}\n"))
        .collect();
    assert_ne!(older, text);
    assert!(job.same_as(&older));
    assert!(!job.same_as(&text.replace("fast_tests = false", "fast_tests = true")));
    assert!(!job.same_as("not toml ["));
    assert!(!exp.cells[0].job.with_seed(4).same_as(&text));
    // Phase 1's budget was stored as `explore.max_steps` before it was renamed.
    assert!(text.contains("\nbudget = "), "{text}");
    assert!(job.same_as(&text.replace("\nbudget = ", "\nmax_steps = ")));
}

/// The paper's figures have one source, `experiments/table.toml`, which `pbcs table` reads
/// too: the chained PBCS's and the unchained one's, by size.
#[test]
fn the_papers_step_counts_come_from_the_table_experiment() {
    use pbcs::experiment::paper_run;
    use pbcs::phase2::Variant;
    let steps: Vec<Option<u64>> = [2, 5, 7, 10, 15, 3]
        .iter()
        .map(|&n| paper_run(Variant::Pbcs, n).0)
        .collect();
    assert_eq!(
        steps,
        [
            Some(321_000),
            Some(5_000_000),
            Some(6_000_000),
            Some(8_000_000),
            Some(22_000_000),
            None
        ]
    );
    assert_eq!(paper_run(Variant::Pbcs, 15).1, Some(true));
    assert_eq!(
        paper_run(Variant::PbcsNoChaining, 10),
        (Some(694_000), Some(false))
    );
    let exp = Experiment::load(Path::new("experiments/table.toml"), None).unwrap();
    for c in exp
        .cells
        .iter()
        .filter(|c| c.method == "pbcs" || c.method == "pbcs_no_chaining")
    {
        let variant = if c.method == "pbcs" {
            Variant::Pbcs
        } else {
            Variant::PbcsNoChaining
        };
        assert_eq!(
            paper_run(variant, c.maze),
            (c.paper_steps, c.paper_solved),
            "{}",
            c.id
        );
    }
}

/// A malformed CSV file is an error naming the file (before: "csv: …" without a path).
#[test]
fn a_bad_csv_file_is_named_in_the_error() {
    let dir = tempfile::tempdir().unwrap();
    let row = dir.path().join("s0.csv");
    std::fs::write(&row, "experiment,cell\ntable\n").unwrap();
    let e = pbcs::experiment::read_row(&row).unwrap_err().to_string();
    assert!(e.contains("s0.csv"), "{e}");
    let picture = dir.path().join("s0.picture.csv");
    std::fs::write(&picture, "layer,index,x,y,r\nred,0,not-a-number,1,0\n").unwrap();
    let e = pbcs::plot::PictureData::read_csv(&picture)
        .unwrap_err()
        .to_string();
    assert!(e.contains("s0.picture.csv"), "{e}");
}

/// Figures are declared by the experiment files (no experiment name in the Rust): the
/// committed ones declare the paper's figures, and a file without `[[figure]]` gets bars.
#[test]
fn experiments_declare_their_figures() {
    use pbcs::experiment::FigureSpec;
    let names = |file: &str| -> Vec<String> {
        Experiment::load(Path::new(file), None)
            .unwrap()
            .figures
            .iter()
            .map(|f| f.name().to_string())
            .collect()
    };
    assert_eq!(
        names("experiments/table.toml"),
        [
            "results_grid",
            "results_maze",
            "curves",
            "table_chains",
            "table_profile"
        ]
    );
    assert_eq!(
        names("experiments/ablations.toml"),
        ["ablations", "ablations_chains", "ablations_routes"]
    );
    assert_eq!(names("experiments/gamma.toml"), ["gamma"]);
    assert_eq!(names("experiments/unseen.toml"), ["unseen", "unseen_bars"]);
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy("experiments/pbcs_paper.toml", dir.path().join("base.toml")).unwrap();
    let path = write(
        dir.path(),
        "mine.toml",
        "title = \"t\"\nseeds = 1\nmazes = [2]\n[[method]]\nname = \"a\"\nkind = \"pbcs\"\nbase = \"base.toml\"\n",
    );
    assert_eq!(
        Experiment::load(&path, None).unwrap().figures,
        [FigureSpec::Bars {
            name: "mine".into(),
            baseline: None
        }]
    );
}

/// `pbcs exp list --slurm`: one array task per (cell, seed), and task i runs exactly the i-th
/// (cell, seed) of the grid (checked by running the script with `PBCS=echo`).
#[test]
fn the_slurm_script_runs_one_cell_seed_per_array_task() {
    use pbcs::launch::Launch;
    let file = Path::new("experiments/table.toml");
    let exp = Experiment::load(file, Some("smoke")).unwrap();
    let results = Path::new("/scratch/results");
    let launch = Launch::new(&exp, file, Some("smoke"), Some(results));
    let runs = launch.runs();
    assert_eq!(runs.len(), exp.cells.len() * exp.seeds().len());
    let script = launch.slurm(results);
    assert!(script.starts_with("#!/bin/bash\n"));
    assert!(
        script.contains(&format!("#SBATCH --array=0-{}\n", runs.len() - 1)),
        "{script}"
    );
    // Every #SBATCH line comes before the first command (sbatch stops reading there).
    let first_command = script
        .lines()
        .position(|l| !l.is_empty() && !l.starts_with('#'))
        .unwrap();
    assert!(script
        .lines()
        .skip(first_command)
        .all(|l| !l.starts_with("#SBATCH")));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("runs.sbatch");
    std::fs::write(&path, &script).unwrap();
    for (i, p) in runs.iter().enumerate() {
        let o = std::process::Command::new("bash")
            .arg(&path)
            .env("PBCS", "echo")
            .env("SLURM_ARRAY_TASK_ID", i.to_string())
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert_eq!(
            String::from_utf8_lossy(&o.stdout).trim(),
            format!(
                "exp run experiments/table.toml --profile smoke --results /scratch/results --cell {} --seed {} --jobs 1",
                p.cell.id, p.seed
            )
        );
        assert_eq!(launch.args(p), String::from_utf8_lossy(&o.stdout).trim());
    }
    // The makefile: one rule per run, its target the run's raw row.
    let mk = launch.makefile(results);
    for p in &runs {
        let target = exp
            .cell_dir(results, p.cell)
            .join(format!("s{}.csv", p.seed));
        assert!(
            mk.contains(&format!(
                "{}:\n\t$(PBCS) {} >/dev/null",
                target.display(),
                launch.args(p)
            )),
            "{mk}"
        );
    }
}

/// The committed raw rows read and written back give the same bytes: the row's enums (kind,
/// starts, failure) keep the strings the files hold, empty where they do not apply. Every
/// enum value but one occurs in the committed rows; that one (`budget`: no run at the paper's
/// budgets ran out) is written and read back here, spelled as its `name()`, with the others.
#[test]
fn committed_raw_rows_round_trip_byte_for_byte() {
    use pbcs::experiment::{read_row, Kind};
    use pbcs::phase2::{Failure, StartMode};
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    let mut stack = vec![root.join("results/raw")];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        for e in entries {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            if p.is_dir() {
                stack.push(p);
            } else if name.starts_with('s')
                && name.ends_with(".csv")
                && name.matches('.').count() == 1
            {
                files.push(p);
            }
        }
    }
    assert!(files.len() > 100, "{} raw rows", files.len());
    let tmp = tempfile::tempdir().unwrap();
    let mut seen = BTreeSet::new();
    for f in &files {
        let row = read_row(f).unwrap();
        let back = tmp.path().join("row.csv");
        pbcs::record::write_record(&back, &row).unwrap();
        assert_eq!(
            std::fs::read(&back).unwrap(),
            std::fs::read(f).unwrap(),
            "{}",
            f.display()
        );
        seen.insert(format!("{:?} {:?} {:?}", row.kind, row.starts, row.failure));
        seen.insert(format!("{:?}", row.kind));
        seen.insert(format!("{:?}", row.starts));
        seen.insert(format!("{:?}", row.failure));
    }
    for want in [
        format!("{:?}", Kind::Vanilla),
        format!("{:?}", Kind::Pbcs),
        format!("{:?}", None::<StartMode>),
        format!("{:?}", Some(StartMode::Ball)),
        format!("{:?}", Some(StartMode::Exact)),
        format!("{:?}", None::<Failure>),
        format!("{:?}", Some(Failure::NoChaining)),
        // No committed run at the paper's budgets ran out of budget (the 400k-step grids'
        // did); `Budget` round-trips below on a written row.
        format!("{:?}", Some(Failure::BackplayFailed)),
    ] {
        assert!(seen.contains(&want), "no committed row has {want}");
    }
    let mut row = read_row(&files[0]).unwrap();
    for f in [
        Failure::BackplayFailed,
        Failure::NoChaining,
        Failure::Budget,
    ] {
        row.failure = Some(f);
        let path = tmp.path().join("failure.csv");
        pbcs::record::write_record(&path, &row).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.trim_end().ends_with(&format!(",{}", f.name())),
            "{text}"
        );
        assert_eq!(read_row(&path).unwrap(), row);
    }
}

/// `beyond` compares two layouts on each size: they must be two different mazes on every size.
/// Layouts 0 and 1 of the 3×3 maze are the same maze (the file once used them).
#[test]
fn the_beyond_experiment_has_two_different_layouts_on_every_size() {
    use pbcs::maze::Layout;
    assert_eq!(Layout::generate(3, 0), Layout::generate(3, 1));
    let exp = Experiment::load(Path::new("experiments/beyond.toml"), None).unwrap();
    for &n in &exp.mazes {
        let layouts: Vec<Layout> = exp
            .cells
            .iter()
            .filter(|c| c.maze == n)
            .map(|c| {
                pbcs::tables::scaling::cell_maze(c)
                    .unwrap()
                    .layout()
                    .clone()
            })
            .collect();
        assert_eq!(layouts.len(), 2, "maze {n}");
        assert_ne!(layouts[0], layouts[1], "maze {n}");
    }
}

/// Every committed raw row was computed from its experiment file as it is now: each
/// `results/raw/<experiment>/<cell>/s<seed>.toml` is the job the file resolves for that cell
/// and seed, every folder there is a cell of the file, and every cell has all its seeds. A
/// changed experiment file (a budget, a preset) without re-run rows fails here, not silently
/// in `make figures`.
/// The experiments whose every (cell, seed) is committed. `ablations` is under way: its rows
/// are committed as they finish (the sweep resumes), each checked here like the others.
const COMPLETE: [&str; 4] = ["table", "gamma", "unseen", "beyond"];

#[test]
fn committed_rows_were_computed_from_the_experiment_files_as_they_are() {
    let raw = Path::new("results/raw");
    let mut checked = 0;
    for f in files() {
        let exp = Experiment::load(&f, None).unwrap();
        for e in std::fs::read_dir(raw.join(&exp.name)).unwrap() {
            let dir = e.unwrap().path();
            let id = dir.file_name().unwrap().to_string_lossy().into_owned();
            exp.cell(&id).unwrap_or_else(|e| {
                panic!("{}: not a cell of {}: {e}", dir.display(), f.display())
            });
        }
        for cell in &exp.cells {
            for seed in exp.seeds() {
                let path = exp
                    .cell_dir(Path::new("results"), cell)
                    .join(format!("s{seed}.toml"));
                if !COMPLETE.contains(&exp.name.as_str()) && !path.exists() {
                    continue;
                }
                let text = std::fs::read_to_string(&path)
                    .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                assert!(
                    cell.job.with_seed(seed).same_as(&text),
                    "{}: not the job {} resolves",
                    path.display(),
                    f.display()
                );
                checked += 1;
            }
        }
    }
    // table 250, gamma 80, unseen 40, beyond 100.
    assert!(checked >= 470, "only {checked} committed jobs");
}

/// The report quotes the scaling figure's fit from `numbers.tex`: on made-up medians that
/// follow steps = 500 · L^1.5 exactly on `beyond`'s cells, the generated numbers give back the
/// exponent and the factor, and every cell's path length (at least 2(N − 1) moves on N × N).
#[test]
fn the_scaling_fit_in_the_reports_numbers_recovers_a_known_power_law() {
    use pbcs::tables::{read_table, table_path};
    let exp = Experiment::load(Path::new("experiments/beyond.toml"), None).unwrap();
    let paths = pbcs::tables::scaling::path_lengths(&exp).unwrap();
    assert_eq!(paths.len(), exp.cells.len());
    let mut stats = read_table(&table_path(Path::new("results"), "beyond")).unwrap();
    assert_eq!(stats.len(), exp.cells.len());
    for s in &mut stats {
        let l = &paths.iter().find(|p| p.cell == s.cell).unwrap().path_cells;
        assert!(*l >= 2 * (s.maze - 1), "{}: L = {l}", s.cell);
        s.steps_median = 500.0 * (*l as f64).powf(1.5);
        (s.steps_q1, s.steps_q3) = (s.steps_median, s.steps_median);
    }
    let tex = pbcs::report::scaling_numbers_tex(&exp, &stats, &paths);
    assert!(
        tex.contains("\\csname res:beyond:scaling:exponent\\endcsname{1.50}"),
        "{tex}"
    );
    assert!(
        tex.contains("\\csname res:beyond:scaling:factor\\endcsname{500}"),
        "{tex}"
    );
    let (cell, l) = (&paths[0].cell, paths[0].path_cells);
    assert!(tex.contains(&format!("res:beyond:{cell}:pathlen\\endcsname{{{l}}}")));
    // An experiment without a scaling figure adds nothing.
    let table = Experiment::load(Path::new("experiments/table.toml"), None).unwrap();
    assert_eq!(pbcs::report::scaling_numbers_tex(&table, &[], &[]), "");
}

/// The routes table of the committed ablation rows: no chain beats the fewest steps possible
/// (a successful episode takes at least `Maze::fewest_steps`), each run's successful episodes
/// are its row's success rate, and phase 1's τ, recomputed from the seed, is never shorter
/// than the fewest steps either.
#[test]
fn routes_respect_the_fewest_steps_and_agree_with_the_rows() {
    let exp = Experiment::load(Path::new("experiments/ablations.toml"), None).unwrap();
    let rows = read_raw(&exp, Path::new("results")).unwrap();
    let routes = pbcs::tables::routes::routes(&exp, Path::new("results"), &rows).unwrap();
    assert!(routes.len() >= 20, "only {} routes", routes.len());
    for r in &routes {
        let row = rows
            .iter()
            .find(|w| w.cell == r.cell && w.seed == r.seed)
            .unwrap();
        assert_eq!(r.successes as f32, (row.success_rate * 100.0).round());
        if let Some(c) = r.chain_steps {
            assert!(c >= r.fewest_steps as f64, "{} s{}: {c}", r.cell, r.seed);
        }
        assert!(r.tau_steps >= r.fewest_steps && r.phase2_tau_steps <= r.tau_steps);
    }
}
