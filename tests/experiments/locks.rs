//! One sweep per results folder. Before, a second sweep started while the first was between
//! two runs took a run the first had planned, and the first died ("another process is doing
//! this run") while the second finished: the locks were per (cell, seed), taken after each
//! sweep had planned.

use super::*;
use pbcs::experiment::Pending;
use pbcs::nn::kernel::Kernel;
use pbcs::record::FolderLock;

/// The smoke profile's two cheapest runs (the vanilla learners at 3000 steps: well under a
/// second each).
fn two_runs(exp: &Experiment) -> Vec<Pending<'_>> {
    let runs: Vec<Pending> = plan(exp, None, None)
        .unwrap()
        .into_iter()
        .filter(|p| ["ddpg-maze2", "td3-maze2"].contains(&p.cell.id.to_string().as_str()))
        .collect();
    assert_eq!(runs.len(), 2);
    runs
}

/// Whether the error `e` refuses the results folder `dir`, naming it.
fn refuses_folder(e: &str, dir: &Path) -> bool {
    e.contains(&dir.display().to_string()) && e.contains("in use")
}

/// A second sweep started between the first sweep's two runs (of the same plan, or of one of
/// its runs) is refused at its start, naming the folder, and runs nothing; the first goes on
/// unaffected and does both runs.
#[test]
fn a_second_sweep_on_a_results_folder_in_use_is_refused_at_its_start() {
    let dir = tempfile::tempdir().unwrap();
    let exp = Experiment::load(Path::new("experiments/table.toml"), Some("smoke")).unwrap();
    let runs = two_runs(&exp);
    let kernel = Kernel::detect();
    let second = Mutex::new(Vec::new());
    let ran = Mutex::new(0);
    let rows = sweep(&exp, &runs, dir.path(), 1, kernel, |_, e| {
        if !matches!(e, Event::Ran(..)) {
            return;
        }
        *ran.lock().unwrap() += 1;
        if *ran.lock().unwrap() > 1 {
            return;
        }
        for others in [&runs[..], &runs[1..]] {
            let done = sweep(&exp, others, dir.path(), 1, kernel, |_, _| {});
            second.lock().unwrap().push(match done {
                Ok(rows) => format!("the second sweep went ahead: {} rows", rows.len()),
                Err(e) => e.to_string(),
            });
        }
    })
    .unwrap();
    let second = second.into_inner().unwrap();
    assert_eq!(second.len(), 2);
    for e in &second {
        assert!(refuses_folder(e, dir.path()), "{e}");
    }
    assert_eq!(rows.len(), 2);
    assert_eq!(*ran.lock().unwrap(), 2, "the first sweep did both runs");
    // Once the first has finished, the folder is free: a sweep finds both runs done.
    let skipped = Mutex::new(0);
    sweep(&exp, &runs, dir.path(), 1, kernel, |_, e| {
        if matches!(e, Event::Skipped(_)) {
            *skipped.lock().unwrap() += 1;
        }
    })
    .unwrap();
    assert_eq!(*skipped.lock().unwrap(), 2);
}

/// Processes of one run each (`pbcs exp list --make`, `--slurm`) share a folder; a sweep of
/// several runs is refused beside them, and they beside it, before anything is read or run.
#[test]
fn single_runs_share_a_results_folder_and_a_sweep_of_several_does_not() {
    let dir = tempfile::tempdir().unwrap();
    let exp = Experiment::load(Path::new("experiments/table.toml"), Some("smoke")).unwrap();
    let runs = two_runs(&exp);
    let kernel = Kernel::detect();
    let row = |p: &Pending| {
        exp.cell_dir(dir.path(), p.cell)
            .join(format!("s{}.csv", p.seed))
    };
    // Another single run holds the folder (shared): this single run goes ahead beside it.
    let other = FolderLock::acquire(dir.path(), true).unwrap();
    sweep(&exp, &runs[..1], dir.path(), 1, kernel, |_, _| {}).unwrap();
    assert!(row(&runs[0]).exists());
    let e = sweep(&exp, &runs, dir.path(), 1, kernel, |_, _| {})
        .unwrap_err()
        .to_string();
    assert!(refuses_folder(&e, dir.path()), "{e}");
    assert!(!row(&runs[1]).exists(), "the refused sweep ran nothing");
    drop(other);
    // A sweep of several holds it (exclusive): a single run is refused too.
    let sweeping = FolderLock::acquire(dir.path(), false).unwrap();
    let e = sweep(&exp, &runs[1..], dir.path(), 1, kernel, |_, _| {})
        .unwrap_err()
        .to_string();
    assert!(refuses_folder(&e, dir.path()), "{e}");
    assert!(!row(&runs[1]).exists());
    drop(sweeping);
    assert_eq!(
        sweep(&exp, &runs, dir.path(), 1, kernel, |_, _| {})
            .unwrap()
            .len(),
        2
    );
}

/// A sweep in which one run fails (here its lock is held, as by another process) finishes the
/// others and writes their rows, and returns the failure naming the run. Before, a panic in
/// one worker took the whole sweep down, and a run finishing beside it was lost.
#[test]
fn a_sweep_with_one_failing_run_finishes_the_others() {
    let dir = tempfile::tempdir().unwrap();
    let exp = Experiment::load(Path::new("experiments/table.toml"), Some("smoke")).unwrap();
    let runs = two_runs(&exp);
    let file = |p: &Pending, suffix: &str| {
        exp.cell_dir(dir.path(), p.cell)
            .join(format!("s{}{suffix}", p.seed))
    };
    let held = pbcs::record::WorkLock::acquire(&file(&runs[0], ".lock")).unwrap();
    let e = sweep(&exp, &runs, dir.path(), 2, Kernel::detect(), |_, _| {})
        .unwrap_err()
        .to_string();
    assert!(
        e.contains(&runs[0].cell.id.to_string()) && e.contains("another process"),
        "{e}"
    );
    assert!(!file(&runs[0], ".csv").exists());
    assert!(
        file(&runs[1], ".csv").exists(),
        "the other run wrote its row"
    );
    drop(held);
}

/// What a process killed mid-write left in a cell folder (a checkpoint's temporary file,
/// `.tmp-s<seed>.resume.*`) is removed by the next run of that seed, which owns those names
/// through its lock; another seed's leftovers stay for that seed's run.
#[test]
fn a_killed_writers_temporary_files_go_with_the_next_run_of_that_seed() {
    let dir = tempfile::tempdir().unwrap();
    let exp = Experiment::load(Path::new("experiments/table.toml"), Some("smoke")).unwrap();
    let runs = two_runs(&exp);
    let cell = exp.cell_dir(dir.path(), runs[0].cell);
    std::fs::create_dir_all(&cell).unwrap();
    let seed = runs[0].seed;
    let mine = cell.join(format!(".tmp-s{seed}.resume.Xk3q9A"));
    let half_row = cell.join(format!(".tmp-s{seed}.csv.b7Rt2c"));
    let other = cell.join(format!(".tmp-s{}0.resume.Xk3q9A", seed));
    for f in [&mine, &half_row, &other] {
        std::fs::write(f, vec![0u8; 4096]).unwrap();
    }
    sweep(&exp, &runs[..1], dir.path(), 1, Kernel::detect(), |_, _| {}).unwrap();
    assert!(cell.join(format!("s{seed}.csv")).exists());
    assert!(
        !mine.exists() && !half_row.exists(),
        "this seed's leftovers are gone"
    );
    assert!(
        other.exists(),
        "seed {seed}0's are not this run's to remove"
    );
}
