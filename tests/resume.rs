//! Checkpoints of vanilla runs (`pbcs::vanilla::resume`): a run cut anywhere and resumed from
//! its checkpoint ends with the uncut run's bytes, learner state included; a checkpoint that is
//! damaged, cut short, another job's, another kernel's or another learner's is refused, naming
//! the file, and left as it was.

use pbcs::checkpoint::Checkpoint;
use pbcs::env::Env;
use pbcs::envs::maze::{Maze, MazeConfig};
use pbcs::envs::toy::Toy1D;
use pbcs::learner::her::HerConfig;
use pbcs::learner::LearnerConfig;
use pbcs::nn::kernel::Kernel;
use pbcs::rng::Seeds;
use pbcs::vanilla::{train_vanilla, TrainConfig, TrainOutcome, Updates, VanillaRun};

fn maze() -> Maze {
    Maze::new(&MazeConfig {
        size: 2,
        ..MazeConfig::default()
    })
    .unwrap()
}

fn schedule(her: bool) -> TrainConfig {
    TrainConfig {
        steps: 1_500,
        max_episode_steps: 90,
        learning_starts: 300,
        eval_every: 500,
        eval_episodes: 2,
        her: her.then(HerConfig::default),
        // PBCS's protocol after training, on the runs without HER.
        final_eval_episodes: if her { 0 } else { 2 },
        ..TrainConfig::default()
    }
}

fn learner(text: &str) -> LearnerConfig {
    toml::from_str(text).unwrap()
}

/// Every part of two outcomes, the learners' whole states byte for byte.
fn assert_same(a: &TrainOutcome, b: &TrainOutcome, what: &str) {
    assert_eq!(a.evals, b.evals, "{what}: evaluations");
    assert_eq!(a.visited, b.visited, "{what}: visited bins");
    assert_eq!(
        (
            a.steps,
            a.episodes,
            a.terminal_transitions,
            a.truncated_episodes
        ),
        (
            b.steps,
            b.episodes,
            b.terminal_transitions,
            b.truncated_episodes
        ),
        "{what}: counts"
    );
    assert_eq!(a.final_eval, b.final_eval, "{what}: final evaluation");
    assert_eq!(
        a.learner.save_state().unwrap(),
        b.learner.save_state().unwrap(),
        "{what}: the learner's whole state"
    );
}

/// The run cut after `cut` steps, saved, dropped, and resumed as a new process would: a new
/// run of the same job made from the file (the environment is shared: the maze and the toy
/// hold no state; `tests/pointmaze.rs` resumes on a new MuJoCo environment).
fn cut_and_resume<E: Env>(
    env: &E,
    learner: &LearnerConfig,
    train: &TrainConfig,
    cut: u64,
    path: &std::path::Path,
) -> TrainOutcome {
    let (seeds, kernel) = (Seeds::new(5), Kernel::detect());
    let checkpoint = Checkpoint::new(path, "the job");
    let mut run = VanillaRun::new(env, learner, train, &seeds, kernel).unwrap();
    run.train_until(cut, |_, _, _| Ok(())).unwrap();
    assert_eq!(run.steps(), cut);
    run.save(&checkpoint, 2.0).unwrap();
    drop(run);
    let mut resumed = VanillaRun::resume(&checkpoint, env, learner, train, &seeds, kernel)
        .unwrap()
        .expect("a checkpoint was saved");
    assert_eq!(resumed.steps(), cut);
    resumed.train_until(u64::MAX, |_, _, _| Ok(())).unwrap();
    let out = resumed.finish().unwrap();
    assert_eq!(out.earlier_seconds, 2.0);
    out
}

/// Cuts before learning starts, mid-episode, at an evaluation and one step after it, for TD3
/// and SAC, with and without HER, on the maze; DDPG's Ornstein–Uhlenbeck noise with updates at
/// each episode's end on the toy: the same bytes as the uncut run each time.
#[test]
fn a_run_cut_anywhere_and_resumed_ends_as_the_uncut_run() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s5.resume");
    let maze = maze();
    let small = [
        "algo = \"td3\"\nhidden = [16, 16]\nbatch_size = 32\nreplay_size = 1000",
        "algo = \"sac\"\nhidden = [16, 16]\nbatch_size = 32\nreplay_size = 1000",
    ];
    for text in small {
        for her in [false, true] {
            let (l, train) = (learner(text), schedule(her));
            let whole = train_vanilla(
                &maze,
                &l,
                &train,
                &Seeds::new(5),
                Kernel::detect(),
                |_, _| {},
            )
            .unwrap();
            assert_eq!(whole.evals.len(), 3);
            for cut in [120, 437, 500, 501] {
                let out = cut_and_resume(&maze, &l, &train, cut, &path);
                assert_same(&whole, &out, &format!("{text:?}, HER {her}, cut at {cut}"));
            }
        }
    }
    let ddpg = learner(
        "algo = \"ddpg\"\nhidden = [8]\nbatch_size = 16\nreplay_size = 1000\nnoise = \"ornstein_uhlenbeck\"",
    );
    let train = TrainConfig {
        max_episode_steps: 25,
        updates: Updates::Episode,
        final_eval_episodes: 0,
        ..schedule(false)
    };
    let whole = train_vanilla(
        &Toy1D,
        &ddpg,
        &train,
        &Seeds::new(5),
        Kernel::detect(),
        |_, _| {},
    )
    .unwrap();
    for cut in [310, 1_013] {
        let out = cut_and_resume(&Toy1D, &ddpg, &train, cut, &path);
        assert_same(&whole, &out, &format!("DDPG on the toy, cut at {cut}"));
    }
}

/// A run stopped by `stop_at_successes` stays stopped once resumed, and no file means a fresh
/// run.
#[test]
fn a_stopped_run_stays_stopped_and_no_file_is_a_fresh_run() {
    let dir = tempfile::tempdir().unwrap();
    let checkpoint = Checkpoint::new(dir.path().join("s0.resume"), "toy");
    let (l, seeds, kernel) = (LearnerConfig::td3(), Seeds::new(0), Kernel::detect());
    let train = TrainConfig {
        steps: 4_000,
        eval_every: 200,
        eval_episodes: 1,
        stop_at_successes: Some(1),
        final_eval_episodes: 0,
        ..schedule(false)
    };
    assert!(
        VanillaRun::resume(&checkpoint, &Toy1D, &l, &train, &seeds, kernel)
            .unwrap()
            .is_none()
    );
    let mut run = VanillaRun::new(&Toy1D, &l, &train, &seeds, kernel).unwrap();
    run.train_until(u64::MAX, |_, _, _| Ok(())).unwrap();
    assert!(run.done() && run.steps() < train.steps, "stopped early");
    run.save(&checkpoint, 0.0).unwrap();
    let mut resumed = VanillaRun::resume(&checkpoint, &Toy1D, &l, &train, &seeds, kernel)
        .unwrap()
        .unwrap();
    assert!(resumed.done());
    let steps = resumed.steps();
    resumed.train_until(u64::MAX, |_, _, _| Ok(())).unwrap();
    assert_eq!(resumed.steps(), steps, "a stopped run took more steps");
}

/// Each bad checkpoint is refused with the file's name and what to do, and the file is left
/// byte for byte as it was.
#[test]
fn a_bad_checkpoint_is_refused_and_left_as_it_was() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s1.resume");
    let maze = maze();
    let l = learner("algo = \"td3\"\nhidden = [8]\nreplay_size = 1000");
    let (train, seeds) = (schedule(true), Seeds::new(1));
    let kernel = Kernel::detect();
    let checkpoint = Checkpoint::new(&path, "job A");
    let mut run = VanillaRun::new(&maze, &l, &train, &seeds, kernel).unwrap();
    run.train_until(600, |_, _, _| Ok(())).unwrap();
    run.save(&checkpoint, 0.0).unwrap();
    let good = std::fs::read(&path).unwrap();
    let refused = |bytes: &[u8], checkpoint: &Checkpoint, l: &LearnerConfig, kernel, want: &str| {
        std::fs::write(&path, bytes).unwrap();
        let err = VanillaRun::resume(checkpoint, &maze, l, &train, &seeds, kernel)
            .err()
            .unwrap_or_else(|| panic!("resumed, but wanted: {want}"))
            .to_string();
        assert!(
            err.contains(want) && err.contains("s1.resume"),
            "{want}: {err}"
        );
        assert!(err.contains("delete it to start the run afresh"), "{err}");
        assert_eq!(
            std::fs::read(&path).unwrap(),
            bytes,
            "{want}: the file changed"
        );
    };
    // A flipped byte in the learner's weights (past the header).
    let mut flipped = good.clone();
    let middle = good.len() / 3;
    flipped[middle] ^= 0x40;
    refused(&flipped, &checkpoint, &l, kernel, "damaged");
    refused(
        &good[..good.len() - 7],
        &checkpoint,
        &l,
        kernel,
        "cut short",
    );
    refused(b"not a checkpoint", &checkpoint, &l, kernel, "cut short");
    let other_job = Checkpoint::new(&path, "job B");
    refused(&good, &other_job, &l, kernel, "another job");
    // The same job's name but another learner's settings, or another kernel.
    let wider = learner("algo = \"td3\"\nhidden = [9]\nreplay_size = 1000");
    refused(&good, &checkpoint, &wider, kernel, "other settings");
    if kernel != Kernel::Portable {
        refused(&good, &checkpoint, &l, Kernel::Portable, "PBCS_KERNEL=");
    }
    // AVX2 and AVX-512 compute the same bytes: a run saved on one goes on on the other.
    std::fs::write(&path, &good).unwrap();
    for other in [Kernel::Avx2, Kernel::Avx512] {
        if other != kernel && other.available() && kernel != Kernel::Portable {
            let back = VanillaRun::resume(&checkpoint, &maze, &l, &train, &seeds, other)
                .unwrap()
                .unwrap();
            assert_eq!(back.steps(), 600);
        }
    }
    // And the good file still resumes.
    std::fs::write(&path, &good).unwrap();
    let back = VanillaRun::resume(&checkpoint, &maze, &l, &train, &seeds, kernel)
        .unwrap()
        .unwrap();
    assert_eq!(back.steps(), 600);
    checkpoint.remove().unwrap();
    assert!(!path.exists());
    checkpoint.remove().unwrap();
}

/// `train_vanilla_resumable` saves at evaluations (here at every one) and a run killed between
/// two (here: a panic in its progress callback, as a kill would stop it) goes on from the last
/// save to the uncut run's bytes; the seconds before the cut are counted.
#[test]
fn a_run_killed_after_its_periodic_saves_resumes_to_the_uncut_runs_bytes() {
    use pbcs::vanilla::resume::train_vanilla_resumable;
    let dir = tempfile::tempdir().unwrap();
    let maze = maze();
    let l = learner("algo = \"sac\"\nhidden = [16]\nbatch_size = 32\nreplay_size = 1000");
    let (train, seeds, kernel) = (schedule(true), Seeds::new(2), Kernel::detect());
    let checkpoint = Checkpoint {
        every: std::time::Duration::ZERO,
        ..Checkpoint::new(dir.path().join("s2.resume"), "the job")
    };
    let whole = train_vanilla(&maze, &l, &train, &seeds, kernel, |_, _| {}).unwrap();
    let killed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        train_vanilla_resumable(
            &maze,
            &l,
            &train,
            &seeds,
            kernel,
            &checkpoint,
            |steps, _| {
                assert!(steps < 1_000, "killed");
            },
        )
    }));
    assert!(killed.is_err(), "the run was not killed");
    // Saved at 500 steps; the callback at 1 000 ran before that evaluation's save.
    let saved = VanillaRun::resume(&checkpoint, &maze, &l, &train, &seeds, kernel)
        .unwrap()
        .unwrap();
    assert_eq!(saved.steps(), 500);
    drop(saved);
    let mut evaluations = Vec::new();
    let out = train_vanilla_resumable(&maze, &l, &train, &seeds, kernel, &checkpoint, |s, _| {
        evaluations.push(s)
    })
    .unwrap();
    assert_eq!(
        evaluations,
        [1_000, 1_500],
        "the resumed run repeated or skipped work"
    );
    let out = out.expect("without a deadline the run finishes");
    assert_same(&whole, &out, "killed at 1 000 steps");
    assert!(out.earlier_seconds > 0.0);
    // The last evaluation ends the run: no save there, the one at 1 000 stays.
    let last = VanillaRun::resume(&checkpoint, &maze, &l, &train, &seeds, kernel)
        .unwrap()
        .unwrap();
    assert_eq!(last.steps(), 1_000);
}

/// `Checkpoint::peek` reads how far a saved run got from the file's head alone (what `pbcs exp
/// list` and a resuming sweep print): the steps and seconds saved; no file is `None`; a file of
/// another job, not a checkpoint, or cut within its head is an error naming the file.
#[test]
fn a_checkpoints_head_says_how_far_its_run_got() {
    use pbcs::checkpoint::Saved;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s3.resume");
    let maze = maze();
    let l = learner("algo = \"td3\"\nhidden = [8]\nreplay_size = 1000");
    let (train, seeds) = (schedule(false), Seeds::new(3));
    let checkpoint = Checkpoint::new(&path, "job A");
    assert_eq!(checkpoint.peek().unwrap(), None);
    let mut run = VanillaRun::new(&maze, &l, &train, &seeds, Kernel::detect()).unwrap();
    run.train_until(700, |_, _, _| Ok(())).unwrap();
    run.save(&checkpoint, 12.5).unwrap();
    let saved = Saved {
        steps: 700,
        seconds: 12.5,
    };
    assert_eq!(checkpoint.peek().unwrap(), Some(saved));
    let good = std::fs::read(&path).unwrap();
    let refused = |bytes: &[u8], checkpoint: &Checkpoint| {
        std::fs::write(&path, bytes).unwrap();
        let err = checkpoint.peek().unwrap_err().to_string();
        assert!(
            err.contains("s3.resume") && err.contains("refused"),
            "{err}"
        );
    };
    refused(&good, &Checkpoint::new(&path, "job B"));
    refused(b"not a checkpoint", &checkpoint);
    refused(&good[..20], &checkpoint);
}

/// A deadline already past: a run whose deadline evaluation is its last finishes (here
/// `train.steps` = one evaluation interval); a run that cannot save there stops with an error
/// naming the file, since stopping unsaved would lose its work.
#[test]
fn a_run_at_its_deadline_finishes_if_done_and_fails_loudly_if_it_cannot_save() {
    use pbcs::vanilla::resume::train_vanilla_resumable;
    let dir = tempfile::tempdir().unwrap();
    let maze = maze();
    let l = learner("algo = \"td3\"\nhidden = [8]\nreplay_size = 1000");
    let (seeds, kernel) = (Seeds::new(4), Kernel::detect());
    let now = Some(std::time::Instant::now());
    let short = TrainConfig {
        steps: 500,
        ..schedule(false)
    };
    let checkpoint = Checkpoint {
        stop_at: now,
        ..Checkpoint::new(dir.path().join("s4.resume"), "job")
    };
    let done = train_vanilla_resumable(&maze, &l, &short, &seeds, kernel, &checkpoint, |_, _| {});
    let whole = train_vanilla(&maze, &l, &short, &seeds, kernel, |_, _| {}).unwrap();
    assert_same(
        &whole,
        &done.unwrap().expect("finished"),
        "done at the deadline",
    );
    assert!(!checkpoint.path.exists(), "a finished run saved");
    // Its folder is a file: the save at the deadline fails.
    let blocked = dir.path().join("not a folder");
    std::fs::write(&blocked, b"").unwrap();
    let unsaveable = Checkpoint {
        stop_at: now,
        ..Checkpoint::new(blocked.join("s4.resume"), "job")
    };
    let err = train_vanilla_resumable(
        &maze,
        &l,
        &schedule(false),
        &seeds,
        kernel,
        &unsaveable,
        |_, _| {},
    )
    .expect_err("stopped unsaved without an error")
    .to_string();
    assert!(err.contains("not a folder"), "{err}");
}
