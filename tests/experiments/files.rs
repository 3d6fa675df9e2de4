//! Experiment files: every file parses with unique cells, bad files name their field, declared
//! figures and launch scripts.

use super::*;
use pbcs::experiment::Site;

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
            let ids: BTreeSet<String> = exp.cells.iter().map(|c| c.id.to_string()).collect();
            assert_eq!(
                ids.len(),
                exp.cells.len(),
                "{}: duplicate cells",
                f.display()
            );
            // Every cell is one (method, size) of the grid; the paper's experiments run every
            // method on every size (the ablations choose sizes per method).
            for c in &exp.cells {
                assert!(exp.sites.contains(&c.site), "{}: {}", f.display(), c.id);
                assert!(exp.methods.iter().any(|(m, _)| *m == c.method), "{}", c.id);
            }
            if exp.name.as_str() != "ablations" {
                assert_eq!(exp.cells.len(), exp.sites.len() * exp.methods.len());
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
    assert_eq!(exp.sites, [2, 5, 7, 10, 15].map(Site::Maze));
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
                let pbcs = exp.cell(&format!("pbcs-{}", c.site.id())).unwrap();
                assert_eq!(
                    j.phase2.max_env_steps,
                    2 * pbcs.paper_steps.unwrap(),
                    "{}",
                    c.id
                );
                assert_eq!(Some(j.maze.size), c.site.size());
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
        for n in exp.sites.iter().filter_map(|s| s.size()) {
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
    let ids: Vec<String> = exp.cells.iter().map(|c| c.id.to_string()).collect();
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
            "`3` is not one of the maze sizes or environments (2)",
        ),
        (
            format!(
                "{head}{}[by_maze]\n\"2\" = {{ pbcs = {{ phase2.epsilom = 5 }} }}\n",
                method("a", "")
            ),
            "maze 2",
        ),
        // Environments of the registry as a grid's rows.
        (
            format!(
                "title = \"t\"\nseeds = 1\nenvs = [\"hall\"]\n{}",
                method("a", "")
            ),
            "hall",
        ),
        (
            format!("title = \"t\"\nseeds = 1\n{}", method("a", "")),
            "at least one maze size (or an environment in `envs`)",
        ),
        (
            format!(
                "title = \"t\"\nseeds = 1\nenvs = [\"rooms\", \"rooms\"]\n{}",
                method("a", "")
            ),
            "must be unique",
        ),
        (
            format!("{head}envs = [\"maze\"]\n{}", method("a", "")),
            "`maze` is not one of `envs`: list its sizes in `mazes`",
        ),
        (
            format!(
                "{head}envs = [\"rooms\"]\n{}",
                method("a", "env = \"rooms\"")
            ),
            "list the environment in the experiment's `envs`",
        ),
        (
            format!(
                "{head}{}[by_maze]\nrooms = {{ pbcs = {{ phase2.beta = 5 }} }}\n",
                method("a", "")
            ),
            "`rooms` is not one of the maze sizes or environments (2)",
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
    assert!(plan(&exp, Some("a-maze3".parse().unwrap()), None)
        .unwrap_err()
        .to_string()
        .contains("a-maze2"));
    assert!(plan(&exp, None, Some(7))
        .unwrap_err()
        .to_string()
        .contains("seed"));
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
        .map(|&n| paper_run(Variant::Pbcs, Site::Maze(n)).0)
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
    assert_eq!(paper_run(Variant::Pbcs, Site::Maze(15)).1, Some(true));
    assert_eq!(
        paper_run(Variant::PbcsNoChaining, Site::Maze(10)),
        (Some(694_000), Some(false))
    );
    let exp = Experiment::load(Path::new("experiments/table.toml"), None).unwrap();
    for c in exp
        .cells
        .iter()
        .filter(|c| ["pbcs", "pbcs_no_chaining"].contains(&c.method.as_str()))
    {
        let variant = if c.method.as_str() == "pbcs" {
            Variant::Pbcs
        } else {
            Variant::PbcsNoChaining
        };
        assert_eq!(
            paper_run(variant, c.site),
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
    let e = pbcs::picture::PictureData::read_csv(&picture)
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
            baselines: Vec::new()
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
    // PBCS_STOP_AFTER becomes every run's deadline (`--stop-after`), one argument however it
    // is spelt (a program printing each argument in brackets shows the split).
    let args = dir.path().join("args.sh");
    std::fs::write(&args, "#!/bin/sh\nprintf '[%s]' \"$@\"\n").unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&args, std::fs::Permissions::from_mode(0o755)).unwrap();
    let o = std::process::Command::new("bash")
        .arg(&path)
        .env("PBCS", &args)
        .env("SLURM_ARRAY_TASK_ID", "0")
        .env("PBCS_STOP_AFTER", "3h 50m")
        .output()
        .unwrap();
    assert!(
        String::from_utf8_lossy(&o.stdout).ends_with("[--jobs][1][--stop-after][3h 50m]"),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    // The makefile: one rule per run, its target the run's raw row.
    let mk = launch.makefile(results).unwrap();
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

/// The Makefile's grids are the experiment files: `make results` runs each of them, and a new
/// file joins without an edit elsewhere.
#[test]
fn the_makefile_runs_every_experiment_file() {
    let names: BTreeSet<String> = files()
        .iter()
        .map(|f| Experiment::load(f, None).unwrap().name.to_string())
        .collect();
    let Ok(out) = std::process::Command::new("make")
        .args(["--no-print-directory", "-s", "experiments"])
        .output()
    else {
        eprintln!("skipped: no `make` on this machine");
        return;
    };
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let listed: BTreeSet<String> = String::from_utf8_lossy(&out.stdout)
        .split_whitespace()
        .map(String::from)
        .collect();
    assert_eq!(listed, names);
}

/// A grid of maze sizes and environments: a method's `envs` chooses the environments it runs
/// (a vanilla method, which runs the maze only, says `envs = []`), and a profile's `envs`
/// replaces the file's.
#[test]
fn methods_and_profiles_choose_their_environments() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy("experiments/pbcs_paper.toml", dir.path().join("base.toml")).unwrap();
    std::fs::copy("experiments/baseline.toml", dir.path().join("vanilla.toml")).unwrap();
    let text = "title = \"t\"\nseeds = 1\nmazes = [2]\nenvs = [\"rooms\"]\n\
        [[method]]\nname = \"p\"\nkind = \"pbcs\"\nbase = \"base.toml\"\n\
        [[method]]\nname = \"v\"\nkind = \"vanilla\"\nbase = \"vanilla.toml\"\nenvs = []\n\
        [profile.mazes_only]\nenvs = []\n";
    let path = write(dir.path(), "mixed.toml", text);
    let ids = |profile| -> Vec<String> {
        let exp = Experiment::load(&path, profile).unwrap();
        exp.cells.iter().map(|c| c.id.to_string()).collect()
    };
    assert_eq!(ids(None), ["p-maze2", "v-maze2", "p-rooms"]);
    assert_eq!(ids(Some("mazes_only")), ["p-maze2", "v-maze2"]);
    let bad = write(
        dir.path(),
        "bad.toml",
        &text.replace("envs = []\n[profile", "envs = [\"rooms\"]\n[profile"),
    );
    // Vanilla baselines run on any environment of the registry (issue 47), the site setting
    // the job's `env` as for PBCS.
    let exp = Experiment::load(&bad, None).unwrap();
    let v = exp.cell("v-rooms").unwrap();
    match &v.job {
        pbcs::experiment::Job::Vanilla(j) => assert_eq!(j.env, pbcs::envs::EnvName::Rooms),
        other => panic!("{other:?}"),
    }
}
