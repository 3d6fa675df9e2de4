//! A raw row is trusted only where it agrees with its place: its file's experiment, cell and
//! seed, what the cell's job fixes, values in range, one record. Before, an edited row moved a
//! run into another cell (`pbcs aggregate` still counted "250 of 250 runs"), duplicated a seed
//! or carried NaN into the tables, and lines after the first record were ignored.

use super::*;
use pbcs::experiment::{read_run_row, run_file, Cell, Job, KindRow, PbcsRow, RawRow, VanillaRow};
use std::path::PathBuf;

/// Writes a made-up finished PBCS run of (`cell`, `seed`) of `exp` into `results` as a sweep
/// leaves it (its job file and its row; nothing is run): the path of the row.
fn write_run(exp: &Experiment, results: &Path, cell: &Cell, seed: u64) -> PathBuf {
    let dir = exp.cell_dir(results, cell);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        run_file(&dir, seed, ".toml"),
        cell.job.with_seed(seed).to_toml(),
    )
    .unwrap();
    let row = made_up_row(exp, cell, seed);
    // Its evaluation, as every run writes it: the row's rate over the job's episodes.
    let Job::Pbcs(j) = &cell.job else {
        unreachable!("made_up_row is a PBCS row")
    };
    let n = j.phase2.eval_episodes;
    let wins = (row.success_rate as f64 * n as f64).round() as usize;
    let episodes: Vec<pbcs::env::EvalEpisode> = (0..n)
        .map(|i| pbcs::env::EvalEpisode {
            success: i < wins,
            steps: 40,
        })
        .collect();
    pbcs::record::write_records(&run_file(&dir, seed, ".evaluation.csv"), &episodes).unwrap();
    let path = run_file(&dir, seed, ".csv");
    pbcs::record::write_record(&path, &row).unwrap();
    path
}

/// A made-up finished PBCS row of (`cell`, `seed`) of `exp`: 1000 steps of phase 1, 2000 of
/// training and 300 of tests.
fn made_up_row(exp: &Experiment, cell: &Cell, seed: u64) -> RawRow {
    let Job::Pbcs(j) = &cell.job else {
        panic!("{}: not a PBCS cell", cell.id)
    };
    RawRow {
        experiment: exp.name,
        cell: cell.id,
        method: cell.method,
        site: cell.site,
        maze_seed: j.maze.seed,
        seed,
        learner: j.learner.record_name(),
        gamma: j.learner.gamma(),
        solved: true,
        success_rate: 0.97,
        env_steps: 3300,
        budget: j.phase2.max_env_steps,
        kind: KindRow::Pbcs(PbcsRow {
            chaining: j.phase2.chaining,
            starts: j.phase2.start,
            phase1_steps: 1000,
            train_steps: 2000,
            test_steps: 300,
            skills: 2,
            failure: None,
        }),
    }
}

/// `path` with the value of `column` on the record's line (line 2) replaced by `value`.
fn edit(path: &Path, column: &str, value: &str) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let i = lines[0].split(',').position(|c| c == column).unwrap();
    let mut fields: Vec<&str> = lines[1].split(',').collect();
    fields[i] = value;
    lines[1] = fields.join(",");
    std::fs::write(path, lines.join("\n") + "\n").unwrap();
}

/// Each edit of a row is refused wherever rows are read (`aggregate`'s [`read_raw`], and a
/// sweep that resumes), naming the file, the line and the column by its name.
#[test]
fn an_edited_raw_row_is_refused_naming_its_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let results = dir.path();
    let exp = Experiment::load(Path::new("experiments/table.toml"), None).unwrap();
    let cell = exp.cell("pbcs-maze2").unwrap();
    let path = write_run(&exp, results, cell, 3);
    assert_eq!(
        read_raw(&exp, results).unwrap().len(),
        1,
        "the made-up row is valid"
    );
    for (column, value) in [
        // `sed -i '2s/,pbcs-maze2,/,pbcs-maze5,/'`: the run moved to another cell.
        ("cell", "pbcs-maze5"),
        // A second seed 4, a row filed under maze 7, under another experiment or method.
        ("seed", "4"),
        ("maze", "7"),
        ("experiment", "gamma"),
        ("method", "pbcs_fast"),
        ("kind", "vanilla"),
        ("budget", "5"),
        // Another job's value of a column the job fixes.
        ("gamma", "0.5"),
        ("maze_seed", "3"),
        ("chaining", "false"),
        ("learner", "sac"),
        // Values out of range, or that contradict each other.
        ("success_rate", "NaN"),
        ("success_rate", "inf"),
        ("success_rate", "1.5"),
        ("success_rate", "-0.1"),
        ("gamma", "NaN"),
        ("solved", "false"),
        ("env_steps", "1"),
        ("first_success_steps", "7"),
        // Not a value of its column: named by the column's name (before: "field 5").
        ("maze_seed", "x"),
        ("starts", "everywhere"),
    ] {
        edit(&path, column, value);
        let e = read_raw(&exp, results).unwrap_err().to_string();
        assert!(
            e.contains(&path.display().to_string())
                && e.contains("line 2")
                && e.contains(&format!("column `{column}`")),
            "{column} = {value}: {e}"
        );
        // A resumed sweep reads finished rows the same way: refused, not trusted (the run
        // is not re-run either).
        let runs = plan(&exp, Some("pbcs-maze2".parse().unwrap()), Some(3)).unwrap();
        let kernel = pbcs::nn::kernel::Kernel::detect();
        let e = sweep(&exp, &runs, results, 1, kernel, |_, _| {})
            .unwrap_err()
            .to_string();
        assert!(e.contains(&format!("column `{column}`")), "sweep: {e}");
        write_run(&exp, results, cell, 3);
    }
    // Lines after the first record: refused, naming the line (before: ignored).
    let text = std::fs::read_to_string(&path).unwrap();
    let record = text.lines().nth(1).unwrap().to_string();
    std::fs::write(&path, format!("{text}{record}\n")).unwrap();
    let e = read_raw(&exp, results).unwrap_err().to_string();
    assert!(e.contains("line 3") && e.contains("s3.csv"), "{e}");
    // A record short of a field, and a header without a record.
    let header = text.lines().next().unwrap();
    let short = record.rsplit_once(',').unwrap().0;
    std::fs::write(&path, format!("{header}\n{short}\n")).unwrap();
    let e = read_raw(&exp, results).unwrap_err().to_string();
    assert!(e.contains("line 2") && e.contains("s3.csv"), "{e}");
    std::fs::write(&path, format!("{header}\n")).unwrap();
    let e = read_raw(&exp, results).unwrap_err().to_string();
    assert!(e.contains("no record") && e.contains("s3.csv"), "{e}");
}

/// Every committed raw row is its run's row and holds values in range: the checks above hold
/// for all of them.
#[test]
fn every_committed_raw_row_agrees_with_its_place() {
    let results = Path::new("results");
    let mut checked = 0;
    for f in files() {
        let exp = Experiment::load(&f, None).unwrap();
        for cell in &exp.cells {
            for seed in exp.seeds() {
                let path = run_file(&exp.cell_dir(results, cell), seed, ".csv");
                if path.exists() {
                    read_run_row(&exp, cell, seed, &path)
                        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
                    checked += 1;
                }
            }
        }
    }
    // table 250, gamma 80, unseen 40, beyond 100, ablations and protocol.
    assert!(checked >= 590, "only {checked} committed rows");
}

/// The phases table splits each cell's env steps as its rows do: medians of phase 1, training,
/// tests and phase 1 + training, their extremes and the tests' share of all steps (known
/// values); cells without PBCS rows are left out; its numbers are the report's.
#[test]
fn the_phases_table_splits_env_steps_as_the_rows_do() {
    use pbcs::tables::phases::{cell_phases, phases_numbers, phases_path};
    let exp = Experiment::load(Path::new("experiments/table.toml"), None).unwrap();
    let cell = exp.cell("pbcs-maze2").unwrap();
    let rows: Vec<RawRow> = [(100, 1000, 900), (300, 4000, 1700), (200, 2000, 800)]
        .into_iter()
        .enumerate()
        .map(|(seed, (phase1, train, test))| {
            let row = made_up_row(&exp, cell, seed as u64);
            let KindRow::Pbcs(p) = row.kind else {
                unreachable!("a PBCS row")
            };
            RawRow {
                env_steps: phase1 + train + test,
                kind: KindRow::Pbcs(PbcsRow {
                    phase1_steps: phase1,
                    train_steps: train,
                    test_steps: test,
                    ..p
                }),
                ..row
            }
        })
        .chain([RawRow {
            cell: "ddpg-maze2".parse().unwrap(),
            method: "ddpg".parse().unwrap(),
            kind: KindRow::Vanilla(VanillaRow {
                first_success_steps: None,
            }),
            ..made_up_row(&exp, cell, 0)
        }])
        .collect();
    let table = cell_phases(&exp, &rows);
    assert_eq!(table.len(), 1, "only the cell with PBCS rows");
    let c = &table[0];
    assert_eq!((c.cell.to_string().as_str(), c.runs), ("pbcs-maze2", 3));
    assert_eq!(
        [
            c.phase1_median,
            c.train_median,
            c.test_median,
            c.env_steps_median
        ],
        [200.0, 2000.0, 900.0, 3000.0]
    );
    assert_eq!(
        (c.learning_median, c.learning_min, c.learning_max),
        (2200.0, 1100, 4300)
    );
    assert!((c.test_share - 3400.0 / 11000.0).abs() < 1e-12);
    let dir = tempfile::tempdir().unwrap();
    let path = phases_path(dir.path(), exp.name);
    std::fs::create_dir_all(path.parent().unwrap()).unwrap();
    pbcs::record::write_records(&path, &table).unwrap();
    let numbers = phases_numbers(exp.name, dir.path()).unwrap();
    let get = |k: &str| {
        let key = format!("pbcs-maze2:phases:{k}");
        numbers
            .iter()
            .find(|(n, _)| *n == key)
            .map(|(_, v)| v.clone())
    };
    assert_eq!(get("learning").as_deref(), Some("2k"));
    assert_eq!(get("learningmax").as_deref(), Some("4k"));
    assert_eq!(get("testshare").as_deref(), Some("31"));
}

/// `pbcs exp check --exact` names what differs: a committed row whose `skills` was edited is
/// re-run, and both the seed's comparison and the exact verdict name the column with its
/// committed and fresh values (before: "1 of 1 rows differ", and two summaries that read the
/// same).
#[test]
fn an_exact_check_names_the_columns_that_differ() {
    let exp = Experiment::load(Path::new("experiments/table.toml"), None).unwrap();
    let id: pbcs::experiment::CellKey = "pbcs_fast-maze2".parse().unwrap();
    let cell = exp.cell_at(id).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let (from, to) = (
        exp.cell_dir(Path::new("results"), cell),
        exp.cell_dir(tmp.path(), cell),
    );
    std::fs::create_dir_all(&to).unwrap();
    for ext in [
        ".csv",
        ".toml",
        ".timing.toml",
        ".evaluation.csv",
        ".picture.csv",
    ] {
        let name = format!("s0{ext}");
        if from.join(&name).exists() {
            std::fs::copy(from.join(&name), to.join(&name)).unwrap();
        }
    }
    let row = std::fs::read_to_string(to.join("s0.csv")).unwrap();
    let edited = row.replace(",13585,2,", ",13585,7,");
    assert_ne!(
        edited, row,
        "the committed row of seed 0 has 2 skills after 13585 test steps"
    );
    std::fs::write(to.join("s0.csv"), edited).unwrap();
    let check = pbcs::reproduce::check_cell(
        &exp,
        tmp.path(),
        id,
        Some(0),
        1,
        pbcs::nn::kernel::Kernel::detect(),
        |_, _| {},
    )
    .unwrap();
    let differing = &check.seeds[0].differing;
    assert!(
        differing.iter().any(|d| d.starts_with("skills: 7 → ")),
        "{differing:?}"
    );
    let err = check.verdict(id, true).unwrap_err().to_string();
    assert!(
        err.contains("seed 0: ") && err.contains("skills: 7 → "),
        "{err}"
    );
    assert!(check.report(id).contains("DIFFERENT (skills: 7 → "));
}

/// A figure refuses a picture seed whose row exists without its picture data, naming the file
/// (before: the grid drew "no runs yet" over ten runs, exit 0).
#[test]
fn a_figure_refuses_missing_picture_data_naming_the_file() {
    let exp = Experiment::load(Path::new("experiments/rooms.toml"), None).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let copy = |from: &Path, to: &Path| {
        std::fs::create_dir_all(to).unwrap();
        for entry in std::fs::read_dir(from).unwrap() {
            let path = entry.unwrap().path();
            std::fs::copy(&path, to.join(path.file_name().unwrap())).unwrap();
        }
    };
    for cell in &exp.cells {
        copy(
            &exp.cell_dir(Path::new("results"), cell),
            &exp.cell_dir(tmp.path(), cell),
        );
    }
    let rows = read_raw(&exp, tmp.path()).unwrap();
    let stats = pbcs::tables::cell_stats(&exp, &rows);
    let out = tmp.path().join("figures");
    std::fs::create_dir_all(&out).unwrap();
    pbcs::figures::render_experiment(&exp, tmp.path(), &stats, &out).unwrap();
    let cell = &exp.cells[0];
    let seed = exp.picture_seeds[0];
    let picture = pbcs::experiment::picture_file(&exp, tmp.path(), cell, seed);
    std::fs::remove_file(&picture).unwrap();
    let err = pbcs::figures::render_experiment(&exp, tmp.path(), &stats, &out)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains(&picture.display().to_string()) && err.contains("missing"),
        "{err}"
    );
}

/// `pbcs figures` writes its figures and LaTeX all or none: a picture file of the second
/// experiment missing stops it before any figure is replaced (before: the first experiment's
/// figures were new and the rest stale), and the staging folders are gone; with the file
/// back, it writes them all.
#[test]
fn figures_are_written_all_or_none() {
    let load = |name: &str| {
        Experiment::load(&Path::new("experiments").join(format!("{name}.toml")), None).unwrap()
    };
    // Two experiments: the first's figures are drawn before the second's missing file.
    let exps = [load("rooms"), load("three_rooms")];
    let tmp = tempfile::tempdir().unwrap();
    let results = tmp.path().join("results");
    for (exp, cell) in exps
        .iter()
        .flat_map(|e| e.cells.iter().map(move |c| (e, c)))
    {
        let (from, to) = (
            exp.cell_dir(Path::new("results"), cell),
            exp.cell_dir(&results, cell),
        );
        std::fs::create_dir_all(&to).unwrap();
        for entry in std::fs::read_dir(from).unwrap() {
            let path = entry.unwrap().path();
            std::fs::copy(&path, to.join(path.file_name().unwrap())).unwrap();
        }
    }
    std::fs::create_dir_all(results.join("tables")).unwrap();
    for table in [
        "rooms.csv",
        "rooms.chains.csv",
        "rooms.criteria.csv",
        "three_rooms.csv",
        "three_rooms.chains.csv",
        "three_rooms.criteria.csv",
    ] {
        let from = Path::new("results/tables").join(table);
        std::fs::copy(from, results.join("tables").join(table)).unwrap();
    }
    // The claims file, and the settings beside it: one claim on the rooms' table.
    let claims_dir = tmp.path().join("experiments");
    std::fs::create_dir_all(&claims_dir).unwrap();
    for file in ["settings.toml", "departures.toml"] {
        std::fs::copy(Path::new("experiments").join(file), claims_dir.join(file)).unwrap();
    }
    std::fs::write(
        claims_dir.join("claims.toml"),
        "[[claim]]\nid = \"rooms_solved\"\npaper = \"PBCS solves the rooms.\"\n\
         experiment = \"rooms\"\ntest = { kind = \"solves_everywhere\", method = \"pbcs\" }\n",
    )
    .unwrap();
    let (figures, tex) = (tmp.path().join("figures"), tmp.path().join("tex"));
    let render = || {
        pbcs::pipeline::render(
            exps.to_vec(),
            &claims_dir.join("claims.toml"),
            &results,
            &figures,
            &tex,
        )
    };
    // Stand-ins for an earlier `figures`: every file it writes, holding "old".
    let written = render().unwrap().files;
    assert!(written.len() > 4, "{written:?}");
    for f in &written {
        assert!(
            f.starts_with(&figures) || f.starts_with(&tex),
            "{}",
            f.display()
        );
        std::fs::write(f, "old").unwrap();
    }
    // The second experiment's grid draws every cell's picture; its last cell's is gone.
    let exp = &exps[1];
    let cell = exp.cells.last().unwrap();
    let picture = pbcs::experiment::picture_file(exp, &results, cell, exp.picture_seeds[0]);
    let kept = std::fs::read(&picture).unwrap();
    std::fs::remove_file(&picture).unwrap();
    let err = render().map(|_| ()).unwrap_err().to_string();
    assert!(err.contains(&picture.display().to_string()), "{err}");
    for f in &written {
        let kept_old = std::fs::read(f).unwrap() == b"old";
        assert!(kept_old, "{} was replaced", f.display());
    }
    for dir in [&figures, &tex] {
        let names: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        assert!(names.iter().all(|n| !n.starts_with('.')), "{names:?}");
    }
    std::fs::write(&picture, kept).unwrap();
    // What an earlier `figures` made and this one does not (a figure of a table since removed)
    // and a staging folder a killed run left go; a file of another kind stays.
    let stale = [figures.join("gone_bars.png"), tex.join("gone_cells.tex")];
    for f in &stale {
        std::fs::write(f, "old").unwrap();
    }
    std::fs::create_dir_all(figures.join(".writing-killed/sub")).unwrap();
    std::fs::write(figures.join("notes.txt"), "mine").unwrap();
    let again = render().unwrap().files;
    assert_eq!(again, written);
    assert!(written.iter().all(|f| std::fs::read(f).unwrap() != b"old"));
    assert!(stale.iter().all(|f| !f.exists()) && !figures.join(".writing-killed").exists());
    assert!(figures.join("notes.txt").exists());
    // A table that its raw rows do not hold: one of the rooms' cells edited from 10/10 to a
    // consistent 9/10 (its rate and interval with it) is refused, nothing drawn.
    let table = results.join("tables/rooms.csv");
    let text = std::fs::read_to_string(&table).unwrap();
    let mut stats = pbcs::tables::read_table(&table).unwrap();
    let (k, n) = (stats[0].successes - 1, stats[0].n);
    let (lo, hi) = pbcs::stats::wilson(k, n, pbcs::stats::Z95);
    stats[0].successes = k;
    stats[0].success_rate = k as f64 / n as f64;
    (stats[0].wilson_lo, stats[0].wilson_hi) = (lo, hi);
    pbcs::record::write_records(&table, &stats).unwrap();
    let err = render().map(|_| ()).unwrap_err().to_string();
    assert!(
        err.contains("raw rows give") && err.contains("rooms.csv"),
        "{err}"
    );
    // An inconsistent table is refused when it is read: more successes than runs, a rate
    // that is not their quotient.
    for (from, to) in [
        (",10,10,1.0,", ",10,12,1.0,"),
        (",10,10,1.0,", ",10,10,NaN,"),
    ] {
        assert!(text.contains(from), "{text}");
        std::fs::write(&table, text.replacen(from, to, 1)).unwrap();
        let err = pbcs::tables::read_table(&table).unwrap_err().to_string();
        assert!(err.contains("rooms.csv") && err.contains("line 2"), "{err}");
    }
}

/// A row is checked against what it summarises (issue 50's probes, which passed before): a
/// run stopped by its budget, its evaluation file empty, edited to "solved, rate 1, no
/// failure", is refused; so is a solved row whose rate is not its evaluation's wins over its
/// episodes (0.33 of 100 episodes), naming the column.
#[test]
fn a_row_is_checked_against_its_evaluation_file() {
    let exp = Experiment::load(Path::new("experiments/ablations.toml"), None).unwrap();
    let cell = exp.cell("as_written-maze5").unwrap();
    let from = exp.cell_dir(Path::new("results"), cell);
    for (seed, from_text, to_text, column) in [
        (
            4,
            ",false,0.0,10002242,10000000,,5954,8475035,1521253,0,budget",
            ",true,1.0,10002242,10000000,,5954,8475035,1521253,0,",
            "success_rate",
        ),
        (
            0,
            ",true,1.0,1237459,",
            ",false,0.33,1237459,",
            "success_rate",
        ),
    ] {
        let tmp = tempfile::tempdir().unwrap();
        let to = exp.cell_dir(tmp.path(), cell);
        std::fs::create_dir_all(&to).unwrap();
        for ext in [".csv", ".toml", ".timing.toml", ".evaluation.csv"] {
            let name = format!("s{seed}{ext}");
            std::fs::copy(from.join(&name), to.join(&name)).unwrap();
        }
        let path = run_file(&to, seed, ".csv");
        read_run_row(&exp, cell, seed, &path).unwrap();
        let row = std::fs::read_to_string(&path).unwrap();
        assert!(row.contains(from_text), "seed {seed}: {row}");
        std::fs::write(&path, row.replace(from_text, to_text)).unwrap();
        let err = read_run_row(&exp, cell, seed, &path)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains(&format!("column `{column}`")) && err.contains("evaluation"),
            "seed {seed}: {err}"
        );
    }
}

/// A row is read as its kind: a vanilla row holding a PBCS column, or a PBCS row without its
/// starts or with a vanilla column, is refused naming the kind and the column (the committed
/// rows read as they are, `committed_raw_rows_round_trip_byte_for_byte`).
#[test]
fn a_row_holding_the_other_kinds_columns_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let copy = |from: &str| {
        let to = dir.path().join("s0.csv");
        std::fs::copy(from, &to).unwrap();
        to
    };
    for (column, value) in [("skills", "2"), ("phase1_steps", "10"), ("starts", "ball")] {
        let path = copy("results/raw/table/ddpg-maze2/s0.csv");
        edit(&path, column, value);
        let e = pbcs::experiment::read_row(&path).unwrap_err().to_string();
        assert!(
            e.contains("line 2")
                && e.contains("column `kind`: vanilla")
                && e.contains(&format!("column `{column}` holds")),
            "{column}: {e}"
        );
    }
    for (column, value) in [("starts", ""), ("first_success_steps", "7")] {
        let path = copy("results/raw/table/pbcs-maze2/s0.csv");
        edit(&path, column, value);
        let e = pbcs::experiment::read_row(&path).unwrap_err().to_string();
        assert!(e.contains(&format!("column `{column}`: ")), "{column}: {e}");
    }
}

/// The scaling figure and the report read the fit written beside the paths table: a results
/// folder without it (aggregated before the fit was a table) is an error naming the file and
/// saying to aggregate again, not a figure without its line or a report without its numbers.
#[test]
fn a_paths_table_without_its_fit_is_refused() {
    let exp = Experiment::load(Path::new("experiments/beyond.toml"), None).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let tables = tmp.path().join("tables");
    std::fs::create_dir_all(&tables).unwrap();
    std::fs::copy(
        "results/tables/beyond.paths.csv",
        tables.join("beyond.paths.csv"),
    )
    .unwrap();
    let stats = pbcs::tables::read_table(Path::new("results/tables/beyond.csv")).unwrap();
    let out = tmp.path().join("figures");
    std::fs::create_dir_all(&out).unwrap();
    let refused = || {
        pbcs::figures::render_experiment(&exp, tmp.path(), &stats, &out)
            .unwrap_err()
            .to_string()
    };
    let err = refused();
    assert!(
        err.contains("beyond.scaling_fit.csv") && err.contains("pbcs aggregate"),
        "{err}"
    );
    assert!(std::fs::read_dir(&out).unwrap().next().is_none());
    // A fit through another number of cells than the tables give is refused too.
    let fit = std::fs::read_to_string("results/tables/beyond.scaling_fit.csv").unwrap();
    let (header, line) = fit.split_once('\n').unwrap();
    let (cells, rest) = line.split_once(',').unwrap();
    let other = format!("{header}\n{},{rest}", cells.parse::<u64>().unwrap() - 1);
    std::fs::write(tables.join("beyond.scaling_fit.csv"), other).unwrap();
    let err = refused();
    assert!(
        err.contains("beyond.scaling_fit.csv") && err.contains("the tables give"),
        "{err}"
    );
}
