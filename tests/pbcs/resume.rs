//! A PBCS run cut between two of phase 2's learning problems, or two tests of its
//! goal-conditioned chain, goes on from its checkpoint (`runs::pbcs_resume`) to the bytes of
//! the run never cut; a checkpoint that cannot be this
//! run's is refused and left as it is.

use super::backplay::DeadTarget;
use super::skill_chaining;
use pbcs::checkpoint::Checkpoint;
use pbcs::config::PbcsJob;
use pbcs::envs::maze::Maze;
use pbcs::nn::kernel::Kernel;
use pbcs::phase2::TraceRow;
use pbcs::phase2::{DeadWalk, Ideas, Phase2Config};
use pbcs::runs::PbcsRun;
use pbcs::validate::{Check, Valid};
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

/// `job` run whole, and run again cut at every pause (a checkpoint that saves at each, its
/// deadline past), each process resuming from the last one's: the resumed run, the whole
/// one, the cuts, and the last save's head. Each cut moved on (no work repeated).
fn whole_and_cut_everywhere(
    job: &Valid<PbcsJob>,
    mut at_cut: impl FnMut(&Checkpoint),
) -> (PbcsRun<Maze>, PbcsRun<Maze>, usize, pbcs::checkpoint::Saved) {
    let whole = compute(job, None).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s1.resume");
    let checkpoint = cutting(&path, "maze 3, seed 1");
    let (mut cuts, mut last) = (0, None::<pbcs::checkpoint::Saved>);
    let resumed = loop {
        if let Some(run) = compute(job, Some(&checkpoint)) {
            break run;
        }
        cuts += 1;
        at_cut(&checkpoint);
        let saved = checkpoint.peek().unwrap().expect("a stopped run is saved");
        assert!(
            last.is_none_or(|l| saved.steps > l.steps && saved.seconds >= l.seconds),
            "cut {cuts} did not move on"
        );
        last = Some(saved);
        assert!(cuts < 100, "no end");
    };
    // Once the results are written the caller deletes the checkpoint: left in place until then.
    assert!(path.exists());
    (resumed, whole, cuts, last.expect("the run was cut"))
}

/// The resumed run is the uncut one: record, chain, trace, evaluation and picture; the wall
/// clock counts the earlier processes' (up to their saves) and never runs back.
fn assert_same_run(resumed: &PbcsRun<Maze>, whole: &PbcsRun<Maze>, last: &pbcs::checkpoint::Saved) {
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
    assert!(resumed.seconds >= last.seconds);
    let seconds: Vec<f64> = resumed.phase2.trace.iter().map(|r| r.seconds).collect();
    assert!(seconds.windows(2).all(|w| w[0] <= w[1]), "{seconds:?}");
}

/// The pauses of a per-skill run that ends at a verification of its chain: after each
/// learning problem of Algorithm 1 (none of them a hand-over try) and of the repairs, and
/// after each verification but the last.
fn pauses(run: &PbcsRun<Maze>) -> (usize, usize, usize) {
    use pbcs::phase2::EventKind::ChainVerify;
    let trace = &run.phase2.trace;
    let first_check = trace.iter().position(|r| r.event == ChainVerify).unwrap();
    assert_eq!(trace.last().unwrap().event, ChainVerify);
    let main = trace[first_check - 1].skill + 1;
    let checks = trace.iter().filter(|r| r.event == ChainVerify).count();
    let mut repairs: Vec<usize> = trace[first_check..]
        .iter()
        .filter(|r| r.event != ChainVerify)
        .map(|r| r.skill)
        .collect();
    repairs.dedup();
    (main, checks, repairs.len())
}

/// Cut after every learning problem and verification in turn, each process resuming from the
/// last one's checkpoint: the uncut run.
#[test]
fn a_pbcs_run_cut_after_every_learning_problem_ends_as_the_uncut_run() {
    let job = job();
    let (resumed, whole, cuts, last) = whole_and_cut_everywhere(&job, |_| {});
    let (main, checks, repairs) = pauses(&whole);
    assert!(main >= 5, "{main} learning problems");
    assert_eq!(cuts, main + checks - 1 + repairs);
    assert_same_run(&resumed, &whole, &last);
}

/// The paper preset's maze-2 chain of seed 0 with the chain's verification and repair (the
/// run `chain_repair_mends_the_weak_junction_of_a_paper_chain` reads: the first verification
/// fails and a skill is learned again), cut at every pause, the middle of the repair
/// included (after the verification that opened it, before its learning problems end): the
/// uncut run.
#[test]
#[ignore = "slow end to end: CI runs it (`cargo test --release --locked -- --ignored`)"]
fn a_pbcs_run_cut_in_the_middle_of_a_chain_repair_ends_as_the_uncut_run() {
    let job = Check::valid(super::switches::paper_maze2_with_repair()).unwrap();
    let tau = phase1(&job).4;
    let mut open_repairs = 0;
    let (resumed, whole, cuts, last) = whole_and_cut_everywhere(&job, |c| {
        let (state, _) =
            pbcs::runs::pbcs_resume::load::<parry2d::math::Point<f32>>(c, &tau, Kernel::detect())
                .unwrap()
                .unwrap();
        if state.repairs.is_some_and(|r| r.open.is_some()) {
            open_repairs += 1;
        }
    });
    let (main, checks, repairs) = pauses(&whole);
    assert!(
        checks >= 2 && repairs >= 1,
        "{checks} checks, {repairs} repairs"
    );
    assert_eq!(cuts, main + checks - 1 + repairs);
    assert_eq!(
        open_repairs, repairs,
        "one cut per learning problem of a repair under way"
    );
    assert_same_run(&resumed, &whole, &last);
}

/// The goal-conditioned chain (`phase2.chain = "goal_conditioned"`) on the same maze, cut after
/// every test of the chain but the one that passes, each process resuming from the last one's
/// checkpoint (the learner, the HER replay, the streams, the curriculum and the episode in
/// flight): the uncut run. A per-skill run of the same job name refuses its checkpoint.
#[test]
fn a_goal_conditioned_run_cut_after_every_test_ends_as_the_uncut_run() {
    let mut gc = (*job()).clone();
    gc.phase2.chain = pbcs::phase2::ChainStrategy::GoalConditioned(Box::default());
    let gc = Check::valid(gc).unwrap();
    let (resumed, whole, cuts, last) = whole_and_cut_everywhere(&gc, |_| {});
    let tests = whole
        .phase2
        .trace
        .iter()
        .filter(|r| r.event == pbcs::phase2::EventKind::Test)
        .count();
    assert!(tests >= 3, "{tests} tests");
    assert!(whole.phase2.failure.is_none(), "{:?}", whole.phase2.failure);
    assert_eq!(cuts, tests - 1);
    assert_same_run(&resumed, &whole, &last);
    // Its checkpoint is not a per-skill run's: refused by one, named.
    let dir = tempfile::tempdir().unwrap();
    let checkpoint = cutting(&dir.path().join("s1.resume"), "maze 3, seed 1");
    assert!(compute(&gc, Some(&checkpoint)).is_none(), "it stopped");
    let maze = Maze::new(&gc.maze).unwrap();
    let per_skill = job();
    let e = match PbcsRun::compute_resumable(
        maze,
        &per_skill,
        Kernel::detect(),
        &checkpoint,
        |_, _| {},
    ) {
        Ok(_) => panic!("not refused"),
        Err(e) => e.to_string(),
    };
    assert!(e.contains(pbcs::checkpoint::PBCS), "{e}");
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

/// A run saved on AVX-512 goes on on AVX2, which computes the same bytes: the learner the next
/// skill takes over is put on the resuming run's kernel (it would otherwise still run AVX-512
/// code). Where this CPU lacks either kernel there is nothing to check.
#[test]
fn a_pbcs_run_saved_on_avx512_goes_on_on_avx2_to_the_same_run() {
    if !(Kernel::Avx512.available() && Kernel::Avx2.available()) {
        eprintln!("this CPU does not run both AVX-512 and AVX2: nothing to check");
        return;
    }
    let job = job();
    let maze = || Maze::new(&job.maze).unwrap();
    let whole = PbcsRun::compute(maze(), &job, Kernel::Avx512, |_, _| {}).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let checkpoint = cutting(&dir.path().join("s1.resume"), "maze 3, seed 1");
    let cut = PbcsRun::compute_resumable(maze(), &job, Kernel::Avx512, &checkpoint, |_, _| {});
    assert!(cut.unwrap().is_none(), "it stopped");
    let state = pbcs::runs::pbcs_resume::load(&checkpoint, &phase1(&job).4, Kernel::Avx2)
        .unwrap()
        .unwrap()
        .0;
    let go_on = Checkpoint {
        stop_at: None,
        ..checkpoint
    };
    let resumed = PbcsRun::compute_resumable(maze(), &job, Kernel::Avx2, &go_on, |_, _| {})
        .unwrap()
        .unwrap();
    // The learner handed over at the resumed run's first pause is on AVX2.
    let (env, seeds, phase1_steps, tau, _) = phase1(&job);
    let ready = job.phase2.ready(&env).unwrap();
    let inputs =
        pbcs::phase2::Phase2Inputs::new(&env, &tau, ready, &job.learner, &seeds, Kernel::Avx2)
            .after(phase1_steps);
    let mut run = pbcs::phase2::Phase2Run::resume(inputs, state).unwrap();
    assert!(run.next_problem(&mut |_, _| {}).unwrap().is_continue());
    assert_eq!(run.warm_kernel(), Some(Kernel::Avx2));
    assert_eq!(resumed.record, whole.record);
    assert_eq!(resumed.phase2.chain.skills, whole.phase2.chain.skills);
    assert_eq!(resumed.evaluation, whole.evaluation);
}

/// Phase 1 of `job`: the maze, the run's seeds, phase 1's env steps, τ and the SHA-256 of τ's
/// observations (what a checkpoint is checked against).
fn phase1(
    job: &Valid<PbcsJob>,
) -> (
    Maze,
    pbcs::rng::Seeds,
    u64,
    Vec<parry2d::math::Point<f32>>,
    String,
) {
    use pbcs::env::Env;
    let env = Maze::new(&job.maze).unwrap();
    let seeds = pbcs::rng::Seeds::new(job.seed);
    let mut rng = seeds.stream(pbcs::rng::Stream::Explore);
    let found = pbcs::phase1::explore(&env, &job.explore, &mut rng, |_, _| {}).unwrap();
    let tau = pbcs::phase2::phase2_trajectory(&env, &found.trajectory, &job.phase2).unwrap();
    let obs: Vec<Vec<f32>> = tau
        .states
        .iter()
        .map(|s| {
            let mut o = vec![0.0; env.obs_dim()];
            env.observe(s, &mut o);
            o
        })
        .collect();
    let hash = pbcs::runs::pbcs_resume::tau_sha256(&obs);
    (env, seeds, found.env_steps, tau.states, hash)
}

/// Algorithm 1 stopped after every learning problem and resumed from where it stood
/// ([`pbcs::phase2::Between::step`], a copy of it kept each time): the same problems in the same order and
/// the same skills as a run never stopped, through a restart and a moved hand-over.
#[test]
fn skill_chaining_stopped_after_every_problem_resumes_to_the_same_skills() {
    use pbcs::phase2::{Between, Made};
    use std::ops::ControlFlow;
    let config = Phase2Config {
        alpha: 2,
        ideas: Ideas {
            restarts: 1,
            dead_walk: Some(DeadWalk {
                after: 5,
                retargets: 1,
            }),
            verify_skills: Some(100),
            ..Ideas::NONE
        },
        ..Phase2Config::default()
    };
    let calls = std::rc::Rc::new(std::cell::RefCell::new(Vec::new()));
    let problem = |made: &mut Vec<(usize, usize)>, n: usize, t: usize| {
        made.push((n, t));
        Ok(DeadTarget {
            t,
            dead: 25,
            from: 29,
            calls: calls.clone(),
        })
    };
    let mut whole_made = Vec::new();
    let whole = skill_chaining(35, &config, |n, t| problem(&mut whole_made, n, t), |_| {}).unwrap();
    let mut made = Vec::new();
    let (mut at, mut stops, mut seen) = (Between::start(35), 0, Vec::new());
    let resumed = loop {
        // Each time a new process: new problems, from the copy the last one left.
        let mut problems = Made::new(|n, t| problem(&mut made, n, t), |_| {});
        match at.step(&config, &mut problems).unwrap() {
            ControlFlow::Break(failure) => break (at.into_skills(), failure),
            ControlFlow::Continue(()) => {
                seen.push((at.made, at.t, at.restarts, at.moves));
                (at, stops) = (at.clone(), stops + 1);
            }
        }
    };
    assert_eq!(resumed, whole);
    assert_eq!(made, whole_made);
    // A stop after each problem but the last (the hand-over try is made in the same step as
    // the dead walk before it), one of them mid-restart, one after the move.
    assert_eq!(whole_made.len(), 7, "{whole_made:?}");
    assert_eq!(stops, whole_made.len() - 2);
    assert!(seen.contains(&(2, 25, 1, 0)), "{seen:?}");
    assert!(seen.contains(&(4, 30, 0, 1)), "{seen:?}");
}
