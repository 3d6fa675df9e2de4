//! A PBCS run cut between two of phase 2's learning problems goes on from its checkpoint
//! (`runs::pbcs_resume`) to the bytes of the run never cut; a checkpoint that cannot be this
//! run's is refused and left as it is.

use pbcs::config::PbcsJob;
use pbcs::envs::maze::Maze;
use pbcs::nn::kernel::Kernel;
use pbcs::phase2::TraceRow;
use pbcs::runs::PbcsRun;
use pbcs::validate::{Check, Valid};
use pbcs::vanilla::resume::Checkpoint;
use std::path::Path;
use std::time::{Duration, Instant};

/// Maze 3, seed 1, the `fast` preset (`pbcs run`'s): phase 2 makes six learning problems, the
/// skill after a saved one taking over its learner (`phase2.warm_start`), then verifies the
/// chain.
fn job() -> Valid<PbcsJob> {
    let mut job = pbcs::config::Preset::Fast.job().unwrap();
    (job.maze.size, job.seed) = (3, 1);
    job.phase2.eval_episodes = 20;
    assert!(job.phase2.warm_start());
    Check::valid(job).unwrap()
}

fn compute(job: &Valid<PbcsJob>, checkpoint: Option<&Checkpoint>) -> Option<PbcsRun<Maze>> {
    let maze = Maze::new(&job.maze).unwrap();
    let kernel = Kernel::detect();
    match checkpoint {
        None => Some(PbcsRun::compute(maze, job, kernel, |_, _| {}).unwrap()),
        Some(c) => PbcsRun::compute_resumable(maze, job, kernel, c, |_, _| {}).unwrap(),
    }
}

/// A checkpoint at `path` of `job` that saves at every learning problem, with a deadline
/// already past: each run stops after its first learning problem, saved.
fn cutting(path: &Path, job: &str) -> Checkpoint {
    Checkpoint {
        every: Duration::ZERO,
        stop_at: Some(Instant::now()),
        ..Checkpoint::new(path, job)
    }
}

fn clockless(trace: &[TraceRow]) -> Vec<TraceRow> {
    trace
        .iter()
        .map(|r| TraceRow {
            seconds: 0.0,
            ..r.clone()
        })
        .collect()
}

/// Cut after every learning problem in turn, each process resuming from the last one's
/// checkpoint: the record, chain, trace, evaluation and picture are the uncut run's, the
/// wall clock counts every process, and each cut moved on (no learning problem repeated).
#[test]
fn a_pbcs_run_cut_after_every_learning_problem_ends_as_the_uncut_run() {
    let job = job();
    let whole = compute(&job, None).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s1.resume");
    let checkpoint = cutting(&path, "maze 3, seed 1");
    let (mut cuts, mut last_steps) = (0, 0);
    let resumed = loop {
        if let Some(run) = compute(&job, Some(&checkpoint)) {
            break run;
        }
        cuts += 1;
        let saved = checkpoint.peek().unwrap().expect("a stopped run is saved");
        assert!(saved.steps > last_steps, "cut {cuts} did not move on");
        last_steps = saved.steps;
        assert!(cuts < 100, "no end");
    };
    let problems = whole.phase2.trace.iter().map(|r| r.skill).max().unwrap() + 1;
    assert!(
        cuts >= 2,
        "{cuts} cuts of a run of {problems} learning problems"
    );
    assert_eq!(resumed.record, whole.record);
    assert_eq!(resumed.phase2.chain, whole.phase2.chain);
    assert_eq!(resumed.phase2.failure, whole.phase2.failure);
    assert_eq!(resumed.phase2.steps, whole.phase2.steps);
    assert_eq!(
        clockless(&resumed.phase2.trace),
        clockless(&whole.phase2.trace)
    );
    assert_eq!(resumed.evaluation, whole.evaluation);
    assert_eq!(resumed.picture, whole.picture);
    // The trace's wall clock goes on from the earlier processes' and never runs back.
    let seconds: Vec<f64> = resumed.phase2.trace.iter().map(|r| r.seconds).collect();
    assert!(seconds.windows(2).all(|w| w[0] <= w[1]), "{seconds:?}");
    // Once the results are written the caller deletes the checkpoint: left in place until then.
    assert!(path.exists());
}

/// A checkpoint of another job, one saved on another τ or computed on another kernel's bytes,
/// a damaged one and one cut short are refused, naming the file and saying why, and left
/// byte for byte as they were.
#[test]
fn a_pbcs_checkpoint_that_is_not_this_runs_is_refused_and_kept() {
    let job = job();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s1.resume");
    let checkpoint = cutting(&path, "maze 3, seed 1");
    assert!(compute(&job, Some(&checkpoint)).is_none(), "it stopped");
    let saved = std::fs::read(&path).unwrap();
    // Resuming `job` on `kernel` from `c`: the refusal, the file unchanged.
    let refusal = |job: &Valid<PbcsJob>, kernel: Kernel, c: &Checkpoint| {
        let before = std::fs::read(&path).unwrap();
        let maze = Maze::new(&job.maze).unwrap();
        let e = match PbcsRun::compute_resumable(maze, job, kernel, c, |_, _| {}) {
            Ok(_) => panic!("not refused"),
            Err(e) => e.to_string(),
        };
        assert_eq!(std::fs::read(&path).unwrap(), before, "the file changed");
        assert!(e.contains("s1.resume"), "{e}");
        e
    };
    let here = Kernel::detect();
    let e = refusal(&job, here, &Checkpoint::new(&path, "maze 3, seed 2"));
    assert!(e.contains("another job"), "{e}");
    // Another τ: the same job name on another run's phase 1 (seed 2).
    let mut seed2 = (*job).clone();
    seed2.seed = 2;
    let e = refusal(&Check::valid(seed2).unwrap(), here, &checkpoint);
    assert!(e.contains("another τ"), "{e}");
    // Another kernel, whose bytes are not the saved run's.
    let other_kernel = [Kernel::Portable, Kernel::Matrixmultiply]
        .into_iter()
        .find(|k| !Kernel::same_bytes(k.name(), here.name()))
        .unwrap();
    let e = refusal(&job, other_kernel, &checkpoint);
    assert!(e.contains("PBCS_KERNEL"), "{e}");
    // A byte of the state changed: its checksum catches it.
    let mut damaged = saved.clone();
    let last = damaged.len() - 1;
    damaged[last] ^= 1;
    std::fs::write(&path, &damaged).unwrap();
    let e = refusal(&job, here, &checkpoint);
    assert!(e.contains("damaged"), "{e}");
    // Cut short.
    std::fs::write(&path, &saved[..saved.len() / 2]).unwrap();
    let e = refusal(&job, here, &checkpoint);
    assert!(e.contains("cut short"), "{e}");
}
