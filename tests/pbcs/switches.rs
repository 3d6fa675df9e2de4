use pbcs::config::{Check, PbcsJob};
use pbcs::env::Env;
use pbcs::envs::maze::Maze;
use pbcs::phase2::goal::{Goal, GoalKind};
use pbcs::phase2::{EventKind, InputMode, LastGoal};
use pbcs::runs::PbcsRun;

/// The whole PBCS run of `job` on its maze.
fn run_maze(job: &PbcsJob) -> PbcsRun<Maze> {
    let kernel = pbcs::nn::kernel::Kernel::detect();
    let maze = Maze::new(&job.maze).unwrap();
    let check = pbcs::validate::Check::valid(job.clone()).unwrap();
    PbcsRun::compute(maze, &check, kernel, |_, _| {}).unwrap()
}

#[test]
fn the_paper_as_written_aims_at_the_ball_with_raw_inputs() {
    let mut job = PbcsJob::default();
    job.maze.size = 2;
    let maze = Maze::new(&job.maze).unwrap();
    let obs = vec![vec![0.5, 0.5], vec![0.6, 0.5], vec![0.5, 1.32]];
    let p2 = &mut job.phase2;
    // The corrections (the default): the target disc, goal-relative unit actions.
    assert_eq!(p2.goal(&maze, &obs, 2).kind, GoalKind::EnvSuccess);
    let inputs = p2.inputs(&maze, &p2.goal(&maze, &obs, 2));
    assert_eq!(
        (inputs.origin, inputs.action_scale),
        (vec![0.5, 1.5], vec![0.1, 0.1])
    );
    assert_eq!(p2.learner_bounds(&maze), vec![1.0, 1.0]);
    // As written: B_ε(τ_N), raw coordinates, ±0.1 from the learner itself.
    p2.last_goal = LastGoal::Ball;
    p2.inputs = InputMode::Raw;
    assert_eq!(
        p2.goal(&maze, &obs, 2),
        Goal::ball(vec![0.5, 1.32], p2.epsilon)
    );
    let inputs = p2.inputs(&maze, &p2.goal(&maze, &obs, 2));
    assert_eq!(
        (inputs.origin, inputs.action_scale),
        (vec![0.0, 0.0], vec![1.0, 1.0])
    );
    assert_eq!(p2.learner_bounds(&maze), vec![maze.action_bound(0); 2]);
    // Other skills' goals do not depend on the switch.
    assert_eq!(
        p2.goal(&maze, &obs, 1),
        Goal::ball(vec![0.6, 0.5], p2.epsilon)
    );
}

#[test]
fn chain_repairs_need_a_chain_verification() {
    // Repairs live in the chain's check (`ChainCheck`); a file with repairs and no
    // verification is refused naming both.
    let bad: Result<PbcsJob, _> = toml::from_str("[phase2]\nchain_repairs = 2\n");
    let err = bad.unwrap_err().to_string();
    assert!(
        err.contains("phase2.chain_repairs") && err.contains("phase2.chain_verify_episodes"),
        "{err}"
    );
    let good: PbcsJob =
        toml::from_str("[phase2]\nchain_repairs = 2\nchain_verify_episodes = 50\n").unwrap();
    let check = good.phase2.ideas.chain_check;
    assert_eq!(
        check,
        Some(pbcs::phase2::ChainCheck {
            episodes: 50,
            repairs: 2
        })
    );
    good.check().unwrap();
    let bad: Result<PbcsJob, _> = toml::from_str("[phase2]\ninputs = \"pixels\"\n");
    assert!(bad.unwrap_err().to_string().contains("pixels"));
}

/// A chain verification that runs past the step budget ends the run like any other
/// work that does: with `budget`, not solved. The budget is set a few steps past the point
/// where seed 0's chain of the paper preset on maze 2 is complete (measured by the same run
/// without verification: the verification draws from a stream of its own), so that the
/// verification's 100 episodes cannot fit in it.
#[test]
#[ignore = "slow end to end: CI runs it (`cargo test --release --locked -- --ignored`)"]
fn a_chain_verification_past_the_budget_is_a_budget_failure() {
    let mut job = pbcs::config::Preset::Paper.job().unwrap();
    job.maze.size = 2;
    let complete = run_maze(&job);
    assert_eq!(
        complete.record.failure, None,
        "the run without verification completes its chain"
    );
    let budget = complete.record.total_steps + 10;
    job.phase2.max_env_steps = budget;
    job.phase2.ideas.chain_check = Some(pbcs::phase2::ChainCheck {
        episodes: 100,
        repairs: 0,
    });
    let run = run_maze(&job);
    assert_eq!(run.record.failure, Some(pbcs::phase2::Failure::Budget));
    assert!(!run.record.solved && run.record.total_steps > budget);
    let last = run.phase2.trace.last().unwrap();
    assert_eq!(last.event, EventKind::ChainVerify);
}

/// The paper preset on maze 2, seed 0, with the table's budget and the chain's verification
/// (100 episodes) and up to five repairs: the run whose first verification fails and whose
/// repair mends the chain (tests below, and `tests/pbcs/resume.rs` cutting it mid-repair).
pub(crate) fn paper_maze2_with_repair() -> PbcsJob {
    let mut job = pbcs::config::Preset::Paper.job().unwrap();
    job.maze.size = 2;
    job.phase2.max_env_steps = 642_000;
    job.phase2.ideas.chain_check = Some(pbcs::phase2::ChainCheck {
        episodes: 100,
        repairs: 5,
    });
    job
}

/// The paper preset's seed 0 on maze 2 builds a chain that reaches the target from 34 of
/// 100 evaluation starts (the committed table row). With the chain's verification and
/// repair, the first verification fails, the skill where the episodes stall is learned
/// again on its section, and the repaired chain passes its verification and solves the
/// maze.
#[test]
#[ignore = "slow end to end: CI runs it (`cargo test --release --locked -- --ignored`)"]
fn chain_repair_mends_the_weak_junction_of_a_paper_chain() {
    let run = run_maze(&paper_maze2_with_repair());
    let checks: Vec<_> = run
        .phase2
        .trace
        .iter()
        .filter(|r| r.event == EventKind::ChainVerify)
        .collect();
    assert!(checks.len() >= 2, "{checks:?}");
    assert!(checks[0].success < 1.0 && checks.last().unwrap().success == 1.0);
    // The failed check blames a skill by its position and section; the passing one none.
    assert!(checks[0].skill < 2 && checks[0].t > checks[0].k);
    let last = checks.last().unwrap();
    assert_eq!((last.skill, last.k), (run.record.skills, 0));
    assert!(run.record.solved, "{:?}", run.record);
    // Chain positions stay consecutive along τ after the splice.
    let skills = &run.phase2.chain.skills;
    assert_eq!(skills[0].start_index, 0);
    for w in skills.windows(2) {
        assert_eq!(w[0].target_index, w[1].start_index);
    }
    assert_eq!(skills.last().unwrap().target_index, run.tau.len() - 1);
    // Every step counts: the record's total is the last trace row's.
    assert_eq!(
        run.record.total_steps,
        run.phase2.trace.last().unwrap().env_steps
    );
}

/// `phase2.lookahead = 1` (ours) on the run of the test above (the table's budget), without the
/// chain's verification: its first skill (found second) is saved only at Ks from which the
/// second one, already found, carries every test episode on from its entry into the hand-over
/// ball. The paper preset's chain of maze 2, seed 0, that reached the target from 34 of 100
/// starts (the table's row) then reaches it from all 100, with two skills again; the rows of
/// both are `experiments/lookahead.toml`'s.
#[test]
#[ignore = "slow end to end: CI runs it (`cargo test --release --locked -- --ignored`)"]
fn a_lookahead_mends_the_weak_junction_of_a_paper_chain_as_it_is_made() {
    let mut job = pbcs::config::Preset::Paper.job().unwrap();
    job.maze.size = 2;
    job.phase2.max_env_steps = 642_000;
    job.phase2.ideas.lookahead = Some(1);
    let run = run_maze(&job);
    let r = &run.record;
    assert!(r.solved && r.success_rate == 1.0, "{r:?}");
    assert_eq!(r.skills, 2, "{r:?}");
    // Written into the run's settings, and read back.
    let text = toml::to_string(&job).unwrap();
    assert!(text.contains("lookahead = 1"), "{text}");
    let back: PbcsJob = toml::from_str(&text).unwrap();
    assert_eq!(back.phase2.ideas.lookahead, Some(1));
    // 0 is off, and off is not written (files written before the switch keep their bytes).
    job.phase2.ideas.lookahead = None;
    assert!(!toml::to_string(&job).unwrap().contains("lookahead"));
    let zero: PbcsJob = toml::from_str("[phase2]\nlookahead = 0\n").unwrap();
    assert_eq!(zero.phase2.ideas.lookahead, None);
}
