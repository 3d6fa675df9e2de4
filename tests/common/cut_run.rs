//! Shared by the experiment and PointMaze tests: each vanilla cell of an experiment, run whole
//! and run cut (at the middle of its budget, saved to its checkpoint as `pbcs exp run` saves,
//! then run again): the same row, job and evaluations, the wall clock before the cut counted,
//! the checkpoint gone once the row is written.

use pbcs::config::Located;
use pbcs::experiment::{checkpoint, run_cell_seed, Experiment, Job};
use std::path::Path;

/// Checks every vanilla cell of `exp` (seed 0); how many there were.
pub fn resumes_to_the_same_rows(exp: &Experiment) -> usize {
    let kernel = pbcs::nn::kernel::Kernel::detect();
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let mut checked = 0;
    for cell in &exp.cells {
        let Job::Vanilla(job) = cell.job.with_seed(0) else {
            continue;
        };
        let (dir_a, dir_b) = (exp.cell_dir(a.path(), cell), exp.cell_dir(b.path(), cell));
        let whole = run_cell_seed(exp, cell, 0, &dir_a, kernel, None, |_, _| {})
            .unwrap()
            .unwrap();
        let saved = checkpoint(cell, 0, &dir_b);
        let seeds = pbcs::rng::Seeds::new(0);
        pbcs::with_env!(job.env_spec().build().unwrap(), |env| {
            let (learner, train) = (&job.learner, &job.train);
            let mut run =
                pbcs::vanilla::VanillaRun::new(&env, learner, train, &seeds, kernel).unwrap();
            run.train_until(train.steps / 2 + 1, |_, _, _| Ok(()))
                .unwrap();
            run.save(&saved, 1000.0).unwrap();
        });
        let resumed = run_cell_seed(exp, cell, 0, &dir_b, kernel, None, |_, _| {})
            .unwrap()
            .unwrap();
        assert_eq!(whole, resumed, "{}", cell.id);
        let optional = [".picture.csv", ".evaluation.csv"];
        for suffix in [".csv", ".evals.csv", ".toml"].iter().chain(&optional) {
            let read = |dir: &Path| std::fs::read(dir.join(format!("s0{suffix}"))).ok();
            let whole = read(&dir_a);
            assert!(
                whole.is_some() || optional.contains(suffix),
                "{} s0{suffix}",
                cell.id
            );
            assert_eq!(whole, read(&dir_b), "{} s0{suffix}", cell.id);
        }
        assert!(
            !saved.path.exists(),
            "{}: the checkpoint outlived its row",
            cell.id
        );
        let timing: toml::Table = pbcs::validate::read_toml(&dir_b.join("s0.timing.toml")).unwrap();
        let wall = timing["wall_seconds"].as_float().unwrap();
        assert!(
            wall >= 1000.0,
            "{}: the wall clock before the cut was dropped: {wall}",
            cell.id
        );
        checked += 1;
    }
    checked
}
