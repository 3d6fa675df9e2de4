//! PBCS on an environment other than the maze, calling phase 1
//! ([`pbcs::phase1::explore`]) and phase 2 ([`pbcs::phase2::chain_skills`]) yourself.
//!
//! The environment is [`pbcs::envs::rooms::TwoRooms`] (`src/envs/rooms.rs`, a file of its own: an
//! implementation of [`pbcs::env::Env`] with its PBCS hooks): two rooms side by side joined by
//! a door, the target just across the wall from the start. Everything else (the learner, α,
//! β, ε, the budgets, every switch) comes from the `fast` preset; a switch that needs a hook
//! the environment lacks would be refused, not skipped.
//!
//! `cargo run --release --example own_env [SEED]`

use pbcs::config::Preset;
use pbcs::env::evaluation_starts;
use pbcs::envs::rooms::TwoRooms;
use pbcs::phase1::explore;
use pbcs::phase2::{chain_skills, phase2_trajectory, Phase2Inputs};
use pbcs::rng::{Seeds, Stream};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let seed: u64 = match std::env::args().nth(1) {
        Some(s) => s
            .parse()
            .map_err(|_| format!("SEED must be a whole number, got `{s}`"))?,
        None => 0,
    };
    let env = TwoRooms;
    let job = Preset::Fast.job()?;
    let seeds = Seeds::new(seed);

    // Phase 1: explore until the reward, return τ.
    let found = explore(
        &env,
        &job.explore,
        &mut seeds.stream(Stream::Explore),
        |_, _| {},
    )?;
    let tau = phase2_trajectory(&env, &found.trajectory, &job.phase2)?.states;
    println!(
        "phase 1: τ of {} states found in {} environment steps",
        tau.len(),
        found.env_steps
    );

    // Phase 2: Backplay + shaped DDPG from starts in B_ε(τ_K), chaining skills.
    let out = chain_skills(
        Phase2Inputs::new(
            &env,
            &tau,
            job.phase2.ready(&env)?,
            &job.learner,
            &seeds,
            pbcs::nn::kernel::Kernel::detect(),
        )
        .after(found.env_steps),
        |_, _| {},
    )?;
    if let Some(f) = out.failure {
        println!("phase 2 stopped: {}", f.name());
        return Ok(());
    }
    println!(
        "phase 2: a chain of {} skill(s) in {} training + {} test steps",
        out.chain.skills.len(),
        out.steps.train,
        out.steps.test
    );

    // The chain from 100 starts in B_ε(s_0) (the evaluation protocol's starts).
    let starts = evaluation_starts(&env, job.phase2.epsilon, 100, &seeds)?;
    let wins = starts
        .into_iter()
        .filter(|start| {
            out.chain
                .run(&env, *start, job.phase2.eval_max_steps)
                .success
        })
        .count();
    println!("the chain reaches the target from {wins} of 100 starts");
    Ok(())
}
