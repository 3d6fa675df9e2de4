use pbcs::config::PbcsJob;
use pbcs::runs::run_pbcs;

fn job(seed: u64) -> PbcsJob {
    let mut job = PbcsJob::default();
    job.maze.size = 2;
    job.seed = seed;
    job
}

/// The default (faithful) preset solves the 2×2 maze: at least 2 of seeds 0, 1, 2 within a
/// budget of 1M environment steps (the paper used 321k on its one seed).
#[test]
#[ignore = "slow end to end: CI runs it (`cargo test --release --locked -- --ignored`)"]
fn pbcs_solves_maze_2_for_most_seeds() {
    let mut solved = 0;
    let mut report = Vec::new();
    for seed in 0..3 {
        let mut j = job(seed);
        j.phase2.max_env_steps = 1_000_000;
        let dir = tempfile::tempdir().unwrap();
        let (r, _) = run_pbcs(
            &pbcs::validate::Check::valid(j.clone()).unwrap(),
            pbcs::nn::kernel::Kernel::detect(),
            dir.path(),
            &pbcs::plot::draw_run,
            |_, _| {},
        )
        .unwrap();
        report.push(format!(
            "seed {seed}: solved {} success {} steps {} skills {} failure {:?}",
            r.solved, r.success_rate, r.total_steps, r.skills, r.failure
        ));
        solved += usize::from(r.solved);
    }
    assert!(solved >= 2, "{report:#?}");
}

/// `pbcs table`'s grid ([`Experiment::of_job`] through the sweep) gives each seed the row
/// of `pbcs run` on the same job, resumes (finished runs read back, same rows) and refuses
/// a folder of another config rather than mixing it in.
///
/// [`Experiment::of_job`]: pbcs::experiment::Experiment::of_job
#[test]
fn a_grid_gives_pbcs_runs_rows_resumes_and_refuses_another_config() {
    use pbcs::experiment::{plan, sweep, Experiment};
    let mut j = job(0);
    j.phase2.max_env_steps = 5_000;
    let dir = tempfile::tempdir().unwrap();
    let exp = Experiment::of_job("small", &j, &[2], 2).unwrap();
    let runs = plan(&exp, None, None).unwrap();
    let first = sweep(
        &exp,
        &runs,
        dir.path(),
        2,
        pbcs::nn::kernel::Kernel::detect(),
        |_, _| {},
    )
    .unwrap();
    assert_eq!(first.iter().map(|r| r.seed).collect::<Vec<_>>(), [0, 1]);
    for (seed, row) in [0, 1].into_iter().zip(&first) {
        let mut single = j.clone();
        single.seed = seed;
        let run_dir = tempfile::tempdir().unwrap();
        let (r, _) = run_pbcs(
            &pbcs::validate::Check::valid(single.clone()).unwrap(),
            pbcs::nn::kernel::Kernel::detect(),
            run_dir.path(),
            &pbcs::plot::draw_run,
            |_, _| {},
        )
        .unwrap();
        assert_eq!(
            pbcs::experiment::RawRow::pbcs(&exp, &exp.cells[0], &single, r),
            *row,
            "seed {seed}"
        );
    }
    let ran_again = std::sync::atomic::AtomicUsize::new(0);
    let again = sweep(
        &exp,
        &runs,
        dir.path(),
        1,
        pbcs::nn::kernel::Kernel::detect(),
        |_, e| {
            if matches!(e, pbcs::experiment::Event::Ran(..)) {
                ran_again.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
            }
        },
    )
    .unwrap();
    assert_eq!(first, again);
    assert_eq!(ran_again.into_inner(), 0);
    j.phase2.epsilon = 0.15;
    let other = Experiment::of_job("small", &j, &[2], 1).unwrap();
    let err = sweep(
        &other,
        &plan(&other, None, None).unwrap(),
        dir.path(),
        1,
        pbcs::nn::kernel::Kernel::detect(),
        |_, _| {},
    )
    .unwrap_err();
    assert!(err.to_string().contains("another config"), "{err}");
}

/// Same seed, same bytes: the whole pipeline (phase 1, phase 2, evaluation, files). A small
/// budget keeps it quick; the budget failure is itself deterministic.
#[test]
fn pbcs_run_is_byte_identical_per_seed() {
    let mut j = job(5);
    j.phase2.max_env_steps = 30_000;
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let (ra, _) = run_pbcs(
        &pbcs::validate::Check::valid(j.clone()).unwrap(),
        pbcs::nn::kernel::Kernel::detect(),
        a.path(),
        &pbcs::plot::draw_run,
        |_, _| {},
    )
    .unwrap();
    run_pbcs(
        &pbcs::validate::Check::valid(j.clone()).unwrap(),
        pbcs::nn::kernel::Kernel::detect(),
        b.path(),
        &pbcs::plot::draw_run,
        |_, _| {},
    )
    .unwrap();
    assert!(ra.total_steps > 0);
    same_files(
        a.path(),
        b.path(),
        &[
            "record.csv",
            "skills.csv",
            "trace.csv",
            "trajectory.csv",
            "config.toml",
            "run.png",
            "run.svg",
            "chain/manifest.toml",
        ],
    );
}

/// Each of `files` has the same bytes under `a` and under `b`.
fn same_files(a: &std::path::Path, b: &std::path::Path, files: &[&str]) {
    for f in files {
        let (x, y) = (
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
        );
        assert!(
            x == y,
            "{f} differs between {} and {}",
            a.display(),
            b.display()
        );
    }
}

/// A run is a function from its job to its outcome: `PbcsRun::compute` returns what
/// `run_pbcs` writes (the same record, and the same bytes once written).
#[test]
fn the_evaluation_episodes_are_written_and_a_saved_chain_gives_them_back() {
    let mut j = pbcs::config::Preset::Fast.job().unwrap();
    j.maze.size = 2;
    let dir = tempfile::tempdir().unwrap();
    let (record, _) = run_pbcs(
        &pbcs::validate::Check::valid(j.clone()).unwrap(),
        pbcs::nn::kernel::Kernel::detect(),
        dir.path(),
        &pbcs::plot::draw_run,
        |_, _| {},
    )
    .unwrap();
    assert!(record.solved, "{record:?}");
    let read = |path: &std::path::Path| -> Vec<pbcs::runs::EvalEpisode> {
        csv::Reader::from_path(path)
            .unwrap()
            .deserialize()
            .collect::<Result<_, _>>()
            .unwrap()
    };
    let episodes = read(&dir.path().join("evaluation.csv"));
    assert_eq!(episodes.len(), j.phase2.eval_episodes);
    let wins = episodes.iter().filter(|e| e.success).count();
    assert_eq!(wins as f32 / episodes.len() as f32, record.success_rate);
    // A successful episode takes at least the shortest path's steps.
    let maze = pbcs::envs::maze::Maze::new(&j.maze).unwrap();
    let fewest = maze.fewest_steps().unwrap();
    assert!(episodes
        .iter()
        .filter(|e| e.success)
        .all(|e| e.steps >= fewest));
    // `pbcs eval` on the saved chain, with the run's seed, is the same evaluation.
    let chain = dir.path().join("chain");
    let again = pbcs::runs::eval_chain(
        &chain,
        j.phase2.eval_episodes,
        None,
        pbcs::nn::kernel::Kernel::detect(),
    )
    .unwrap();
    assert_eq!(again.successes, wins);
    assert_eq!(again.rows, episodes);
    // Computing wrote nothing; writing puts the episodes where it is told.
    assert!(!chain.join(format!("eval-s{}.csv", j.seed)).exists());
    again.write(&chain, &pbcs::plot::draw_run).unwrap();
    assert_eq!(read(&chain.join(format!("eval-s{}.csv", j.seed))), episodes);
}

#[test]
fn a_computed_run_is_what_the_written_run_holds() {
    let mut j = job(5);
    j.phase2.max_env_steps = 30_000;
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let (written, _) = run_pbcs(
        &pbcs::validate::Check::valid(j.clone()).unwrap(),
        pbcs::nn::kernel::Kernel::detect(),
        a.path(),
        &pbcs::plot::draw_run,
        |_, _| {},
    )
    .unwrap();
    let run = pbcs::runs::PbcsRun::compute(
        pbcs::envs::maze::Maze::new(&j.maze).unwrap(),
        &pbcs::validate::Check::valid(j.clone()).unwrap(),
        pbcs::nn::kernel::Kernel::detect(),
        |_, _| {},
    )
    .unwrap();
    assert_eq!(run.record, written);
    // The record's enums are written as the names the CSVs have always held.
    let text = std::fs::read_to_string(a.path().join("record.csv")).unwrap();
    let row: Vec<&str> = text.lines().nth(1).unwrap().split(',').collect();
    assert_eq!((row[3], row[5]), ("pbcs", "ball"), "{text}");
    assert_eq!(row[3], written.variant.name());
    assert_eq!(run.tau.len(), written.phase2_trajectory_len);
    assert_eq!(run.phase2.chain.skills.len(), written.skills);
    run.write(&j, b.path(), &pbcs::plot::draw_run).unwrap();
    same_files(
        a.path(),
        b.path(),
        &[
            "record.csv",
            "trace.csv",
            "picture.csv",
            "chain/manifest.toml",
        ],
    );
}
