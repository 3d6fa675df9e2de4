//! Sweeps: the smoke profile end to end, deterministic and resumable; locks; parallel runs.

use super::*;

/// The smoke profile of every experiment, run twice into two folders with 1 and 2 jobs: the
/// same bytes; a third sweep finds everything finished; then tables, figures and LaTeX.
#[test]
#[ignore = "slow end to end: CI runs it (`cargo test --release --locked -- --ignored`)"]
fn smoke_profile_runs_end_to_end_deterministically() {
    let a = tempfile::tempdir().unwrap();
    let b = tempfile::tempdir().unwrap();
    let mut loaded = Vec::new();
    for f in files() {
        let exp = Experiment::load(&f, Some("smoke")).unwrap();
        // PointMaze's runs need MuJoCo (feature `mujoco`): without it, its file is left out
        // (`cargo test --features mujoco` runs it too).
        if exp.unavailable().is_some() {
            continue;
        }
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
        pbcs::pipeline::write_tables(&exp, a.path(), &stats, &rows, &rows).unwrap();
        let back = pbcs::tables::read_table(&pbcs::tables::table_path(a.path(), exp.name)).unwrap();
        assert_eq!(back, stats);
        loaded.push((exp, stats));
    }
    let figures = a.path().join("figures");
    let tex = a.path().join("tex");
    let tables: Vec<_> = loaded.iter().map(|(e, s)| (e.name, s.clone())).collect();
    let specs = pbcs::claims::load_claims(Path::new("experiments/claims.toml")).unwrap();
    // The smoke grid judges the claims its cells allow (the maze-15 ablations it has not).
    let (claims, unjudged) = pbcs::claims::claims_partial(&specs, &tables);
    assert!(!claims.is_empty());
    for e in &unjudged {
        assert!(e.to_string().starts_with("claim ablation_"), "{e}");
    }
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
    let runs = plan(&exp, Some("exact-maze2".parse().unwrap()), None).unwrap();
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
    let runs = plan(&changed, Some("exact-maze2".parse().unwrap()), None).unwrap();
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
    // Read without the profile they were made under, the rows are refused with the hint.
    let committed = Experiment::load(Path::new("experiments/unseen.toml"), None).unwrap();
    let err = pbcs::experiment::read_raw(&committed, dir.path()).unwrap_err();
    assert!(err.to_string().contains("(--profile smoke)"), "{err}");
}

/// Two sweeps into one results folder: a run that another process holds (its lock file) is
/// refused with a message naming the lock, and nothing of it is written; once released, the
/// run goes ahead and leaves no lock behind.
#[test]
fn a_run_another_sweep_holds_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let exp = Experiment::load(Path::new("experiments/unseen.toml"), Some("smoke")).unwrap();
    let runs = plan(&exp, Some("exact-maze2".parse().unwrap()), Some(0)).unwrap();
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
/// its plan: whole mazes, smallest first), returns results in the items' order, and one
/// item's error or panic does not stop the others: every item runs, the failure is returned.
#[test]
fn parallel_runs_start_in_order_and_one_failure_stops_no_other() {
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
    assert_eq!(*ran.lock().unwrap(), items.len(), "every item ran");
    // A panic in one of two threads fails its item only; the other items all finish.
    let finished = Mutex::new(Vec::new());
    let err = run_parallel(&items, 2, |&i| {
        if i == 3 || i == 7 {
            panic!("item {i} met a bug");
        }
        finished.lock().unwrap().push(i);
        Ok(i)
    })
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("2 of 24 runs failed") && err.contains("item 3 met a bug"),
        "{err}"
    );
    let mut finished = finished.into_inner().unwrap();
    finished.sort_unstable();
    let others: Vec<usize> = items
        .iter()
        .copied()
        .filter(|&i| i != 3 && i != 7)
        .collect();
    assert_eq!(finished, others);
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

/// A registered grid whose preset file changed since its registration is refused before
/// anything runs or is written, the message naming the preset and both hashes; the preset as
/// registered runs.
#[test]
fn a_registered_grid_runs_only_with_the_preset_it_was_registered_for() {
    let dir = tempfile::tempdir().unwrap();
    for f in ["heldout.toml", "pbcs_fast.toml"] {
        std::fs::copy(Path::new("experiments").join(f), dir.path().join(f)).unwrap();
    }
    let preset = dir.path().join("pbcs_fast.toml");
    let registered = std::fs::read(&preset).unwrap();
    // One comment more: the jobs are the same, the file is not the one registered.
    let mut edited = registered.clone();
    edited.extend_from_slice(b"# edited after the registration\n");
    std::fs::write(&preset, &edited).unwrap();
    let exp = Experiment::load(&dir.path().join("heldout.toml"), Some("smoke")).unwrap();
    let reg = exp.registered.clone().unwrap();
    let now = reg.preset_sha256().unwrap();
    assert_ne!(now, reg.sha256);
    let runs = plan(&exp, None, None).unwrap();
    let results = dir.path().join("results");
    let kernel = pbcs::nn::kernel::Kernel::detect();
    let err = sweep(&exp, &runs, &results, 1, kernel, |_, _| {})
        .unwrap_err()
        .to_string();
    for needle in [
        reg.sha256.as_str(),
        now.as_str(),
        "pbcs_fast.toml",
        "registered",
    ] {
        assert!(err.contains(needle), "{needle} not in: {err}");
    }
    assert!(!results.join("raw").exists(), "nothing is written");
    // A missing preset is an error naming it, too.
    std::fs::remove_file(&preset).unwrap();
    let err = sweep(&exp, &runs, &results, 1, kernel, |_, _| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("pbcs_fast.toml"), "{err}");
    // The preset as registered: the grid runs.
    std::fs::write(&preset, &registered).unwrap();
    let rows = sweep(&exp, &runs, &results, 1, kernel, |_, _| {}).unwrap();
    assert_eq!(rows.len(), runs.len());
}

/// `--jobs 1000000` on three runs starts three threads, not a million (issue 47: it used to
/// start one per job, whatever the number of runs).
#[test]
fn a_sweep_starts_no_more_threads_than_runs() {
    let threads =
        pbcs::experiment::run_parallel(&[1, 2, 3], 1_000_000, |_| Ok(rayon::current_num_threads()))
            .unwrap();
    assert_eq!(threads, vec![3, 3, 3]);
}

/// A vanilla run cut short goes on from its checkpoint (`s<seed>.resume`, what `pbcs exp run`
/// saves every ten minutes): the same row, job and evaluations as the uncut run, the wall clock
/// counted from its first start, and the checkpoint gone once the row is written.
#[test]
fn a_cut_vanilla_run_resumes_from_its_checkpoint_to_the_same_row() {
    let exp = Experiment::load(Path::new("experiments/table.toml"), Some("smoke")).unwrap();
    assert!(
        cut_run::resumes_to_the_same_rows(&exp) > 0,
        "a vanilla cell"
    );
}

/// A deadline (`pbcs exp run --stop-after`): a vanilla run in progress stops at its first
/// evaluation past it, saved, with no row; run again it ends with the row of a run never
/// stopped. A sweep past its deadline begins nothing and counts the runs unfinished.
#[test]
fn a_vanilla_run_stopped_at_its_deadline_goes_on_to_the_same_row() {
    use pbcs::experiment::{run_cell_seed, sweep_until};
    use std::time::Instant;
    let exp = Experiment::load(Path::new("experiments/table.toml"), Some("smoke")).unwrap();
    let kernel = pbcs::nn::kernel::Kernel::detect();
    let cell = exp.cell_at("td3-maze2".parse().unwrap()).unwrap();
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let (dir_a, dir_b) = (exp.cell_dir(a.path(), cell), exp.cell_dir(b.path(), cell));
    let whole = run_cell_seed(&exp, cell, 0, &dir_a, kernel, None, |_, _| {})
        .unwrap()
        .unwrap();
    let mut seen = Vec::new();
    let stopped = run_cell_seed(
        &exp,
        cell,
        0,
        &dir_b,
        kernel,
        Some(Instant::now()),
        |s, _| seen.push(s),
    )
    .unwrap();
    assert!(stopped.is_none(), "the run did not stop");
    assert_eq!(seen.len(), 1, "it stopped at its first evaluation");
    assert!(dir_b.join("s0.resume").exists() && !dir_b.join("s0.csv").exists());
    // `pbcs exp list` says how far it got.
    let file = Path::new("experiments/table.toml");
    let listed = pbcs::launch::Launch::new(&exp, file, Some("smoke"), None)
        .commands(b.path())
        .unwrap();
    let line = format!(
        "--cell {} --seed 0 --jobs 1  # saved at {} env steps\n",
        cell.id, seen[0]
    );
    assert!(listed.contains(&line), "{listed}");
    let mut rest = Vec::new();
    let resumed = run_cell_seed(&exp, cell, 0, &dir_b, kernel, None, |s, _| rest.push(s))
        .unwrap()
        .unwrap();
    assert_eq!(
        rest.first().copied(),
        Some(2 * seen[0]),
        "work repeated or skipped"
    );
    assert_eq!(whole, resumed);
    for suffix in [".csv", ".evals.csv", ".toml"] {
        let read = |dir: &Path| std::fs::read(dir.join(format!("s0{suffix}"))).unwrap();
        assert_eq!(read(&dir_a), read(&dir_b), "s0{suffix}");
    }
    assert!(!dir_b.join("s0.resume").exists());
    // A sweep past its deadline: the finished run read back, the others not begun.
    let runs = plan(&exp, None, None).unwrap();
    assert!(runs.len() > 1);
    let events = Mutex::new(Vec::new());
    let swept = sweep_until(
        &exp,
        &runs,
        a.path(),
        2,
        kernel,
        Some(Instant::now()),
        |p, e| {
            events
                .lock()
                .unwrap()
                .push((p.cell.id, p.seed, e.is_final()))
        },
    )
    .unwrap();
    assert_eq!(
        (swept.rows, swept.unfinished),
        (vec![whole], runs.len() - 1)
    );
    assert_eq!(events.into_inner().unwrap(), vec![(cell.id, 0, true)]);
}

/// A deadline stops a PBCS run too, at the end of its first learning problem at or past it,
/// saved to `s<seed>.resume` with no row; run again (here once per learning problem) it ends
/// with the row, evaluation and job files of a run never stopped, and its checkpoint goes.
#[test]
fn a_pbcs_run_stopped_at_its_deadline_goes_on_to_the_same_row() {
    use pbcs::experiment::run_cell_seed;
    use std::time::Instant;
    let mut job = pbcs::config::Preset::Fast.job().unwrap();
    job.phase2.eval_episodes = 20;
    let exp = Experiment::of_job("small", &job, &[3], 1).unwrap();
    let kernel = pbcs::nn::kernel::Kernel::detect();
    let cell = &exp.cells[0];
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let (dir_a, dir_b) = (exp.cell_dir(a.path(), cell), exp.cell_dir(b.path(), cell));
    std::fs::create_dir_all(&dir_b).unwrap();
    let whole = run_cell_seed(&exp, cell, 0, &dir_a, kernel, None, |_, _| {})
        .unwrap()
        .unwrap();
    let mut stops = 0;
    let resumed = loop {
        let now = Some(Instant::now());
        if let Some(row) = run_cell_seed(&exp, cell, 0, &dir_b, kernel, now, |_, _| {}).unwrap() {
            break row;
        }
        stops += 1;
        assert!(dir_b.join("s0.resume").exists() && !dir_b.join("s0.csv").exists());
        assert!(stops < 100, "no end");
    };
    assert!(stops >= 2, "{stops} stops");
    assert_eq!(whole, resumed);
    for suffix in [".csv", ".evaluation.csv", ".toml"] {
        let read = |dir: &Path| std::fs::read(dir.join(format!("s0{suffix}"))).unwrap();
        assert_eq!(read(&dir_a), read(&dir_b), "s0{suffix}");
    }
    assert!(!dir_b.join("s0.resume").exists());
}
