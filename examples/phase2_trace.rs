//! Prints every Backplay event of one PBCS run (tests and training rounds), for diagnosis.
//! `cargo run --release --example phase2_trace -- MAZE SEED [CONFIG.toml]`
use pbcs::config::{self, PbcsJob};
use pbcs::env::Env;
use pbcs::envs::maze::Maze;
use pbcs::phase1::explore;
use pbcs::phase2::{chain_skills, Phase2Inputs};
use pbcs::rng::{Seeds, Stream};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let mut job: PbcsJob = match args.get(3) {
        Some(p) => config::load(std::path::Path::new(p))?,
        None => PbcsJob::default(),
    };
    job.maze.size = args.get(1).map_or(Ok(2), |s| s.parse())?;
    job.seed = args.get(2).map_or(Ok(0), |s| s.parse())?;
    let maze = Maze::new(&job.maze)?;
    let seeds = Seeds::new(job.seed);
    let found = explore(
        &maze,
        &job.explore,
        &mut seeds.stream(Stream::Explore),
        |_, _| {},
    )?;
    let tau = &pbcs::phase2::phase2_trajectory(&maze, &found.trajectory, &job.phase2)?.states;
    println!("phase 1: {} steps, |τ| = {}", found.env_steps, tau.len());
    let t0 = std::time::Instant::now();
    let out = chain_skills(
        Phase2Inputs::new(
            &maze,
            tau,
            job.phase2.ready(&maze)?,
            &job.learner,
            &seeds,
            pbcs::nn::kernel::Kernel::detect(),
        )
        .after(found.env_steps),
        |n, p| {
            println!(
                "{:7.1}s skill {n} K {:4} T {:4} {:?} {:.2} steps {}/{}",
                t0.elapsed().as_secs_f64(),
                p.k,
                p.t,
                p.kind,
                p.success,
                p.steps.train,
                p.steps.test
            );
        },
    )?;
    println!(
        "failure {:?}, skills {}",
        out.failure,
        out.chain.skills.len()
    );
    for s in &out.chain.skills {
        println!(
            "  K {} -> T {} at {:?}",
            s.start_index, s.target_index, s.activation.center
        );
    }
    let r = out.chain.run(&maze, maze.start(), 5000);
    println!(
        "chain from s0: success {} in {} steps",
        r.success,
        r.skill_used.len()
    );
    Ok(())
}
