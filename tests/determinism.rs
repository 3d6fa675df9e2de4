//! Same seed, same bytes: every result file of a job is byte-identical across runs.

use pbcs::config::ExploreJob;
use pbcs::runs::run_explore;
use std::path::Path;

const FILES: [&str; 6] = [
    "config.toml",
    "summary.csv",
    "trajectory.csv",
    "archive.csv",
    "explore.png",
    "explore.svg",
];

fn run(job: &ExploreJob, dir: &Path) {
    run_explore(
        &pbcs::validate::Check::valid(job.clone()).unwrap(),
        dir,
        &pbcs::plot::draw_run,
        |_, _| {},
    )
    .unwrap();
}

#[test]
fn same_seed_gives_byte_identical_files() {
    let mut job = ExploreJob::default();
    job.maze.size = 7;
    job.seed = 11;
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    run(&job, a.path());
    run(&job, b.path());
    for f in FILES {
        let (x, y) = (
            std::fs::read(a.path().join(f)).unwrap(),
            std::fs::read(b.path().join(f)).unwrap(),
        );
        assert!(!x.is_empty(), "{f} is empty");
        assert!(x == y, "{f} differs between two runs of one seed");
    }
    // Nothing is left over from the atomic writes.
    let leftovers: Vec<_> = std::fs::read_dir(a.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|n| n.starts_with(".tmp-"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

#[test]
fn other_seeds_give_other_trajectories() {
    let mut job = ExploreJob::default();
    job.maze.size = 7;
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    run(&job, a.path());
    job.seed = 12;
    run(&job, b.path());
    let read = |d: &Path| std::fs::read(d.join("trajectory.csv")).unwrap();
    assert_ne!(read(a.path()), read(b.path()));
}

#[test]
fn the_maze_seed_changes_the_layout_not_the_run_seed() {
    // Same maze seed, other run seeds: the maze (walls in the SVG) is unchanged; only the
    // exploration differs. Same run seed, other maze seed: another layout.
    use pbcs::config::MazeConfig;
    use pbcs::envs::maze::Maze;
    let base = MazeConfig {
        size: 7,
        ..MazeConfig::default()
    };
    let m1 = Maze::new(&base).unwrap();
    let m2 = Maze::new(&base).unwrap();
    assert_eq!(m1.layout(), m2.layout());
    let m3 = Maze::new(&MazeConfig { seed: 1, ..base }).unwrap();
    assert_ne!(m1.layout(), m3.layout());
}

#[test]
fn vanilla_training_is_byte_identical_per_seed() {
    use pbcs::config::TrainJob;
    use pbcs::runs::run_train;
    let mut job = TrainJob::default();
    job.maze.size = 2;
    job.seed = 3;
    job.train.steps = 3_000;
    job.train.learning_starts = 1_000;
    job.train.eval_every = 1_000;
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    run_train(
        &pbcs::validate::Check::valid(job.clone()).unwrap(),
        pbcs::nn::kernel::Kernel::detect(),
        a.path(),
        &pbcs::plot::draw_run,
        |_, _| {},
    )
    .unwrap();
    run_train(
        &pbcs::validate::Check::valid(job.clone()).unwrap(),
        pbcs::nn::kernel::Kernel::detect(),
        b.path(),
        &pbcs::plot::draw_run,
        |_, _| {},
    )
    .unwrap();
    for f in [
        "config.toml",
        "summary.csv",
        "evals.csv",
        "visited.csv",
        "actor.safetensors",
        "train.png",
        "train.svg",
    ] {
        let (x, y) = (
            std::fs::read(a.path().join(f)).unwrap(),
            std::fs::read(b.path().join(f)).unwrap(),
        );
        assert!(
            !x.is_empty() && x == y,
            "{f} differs between two runs of one seed"
        );
    }
    let evals = std::fs::read_to_string(a.path().join("evals.csv")).unwrap();
    assert_eq!(evals.lines().count(), 4, "header + 3 evaluations:\n{evals}");
}

/// A run folder's leftovers from a killed process of the same job (a temporary file, a
/// staging folder) go when the job is run there again, and the files come out the same; while
/// a process works in a folder, a second one of that job into it is refused, naming the lock.
#[test]
fn a_rerun_removes_a_killed_runs_leftovers_and_a_concurrent_one_is_refused() {
    let mut job = ExploreJob::default();
    job.maze.size = 3;
    let dir = tempfile::tempdir().unwrap();
    run(&job, dir.path());
    let first = std::fs::read(dir.path().join("trajectory.csv")).unwrap();
    let tmp = dir.path().join(".tmp-trajectory.csv.q8Zr1x");
    let stage = dir.path().join(".writing-Ab12Cd");
    std::fs::write(&tmp, "half a file").unwrap();
    std::fs::create_dir_all(stage.join("chain")).unwrap();
    std::fs::write(stage.join("summary.csv"), "staged").unwrap();
    run(&job, dir.path());
    assert!(!tmp.exists() && !stage.exists(), "the leftovers are gone");
    assert_eq!(
        std::fs::read(dir.path().join("trajectory.csv")).unwrap(),
        first
    );
    let held = pbcs::record::WorkLock::acquire(&dir.path().join(pbcs::record::RUN_LOCK)).unwrap();
    let e = run_explore(
        &pbcs::validate::Check::valid(job.clone()).unwrap(),
        dir.path(),
        &pbcs::plot::draw_run,
        |_, _| {},
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("another process") && e.contains(".lock"), "{e}");
    drop(held);
}
