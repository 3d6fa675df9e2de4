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
