//! Issue 35's learner baselines: our DDPG or TD3 alone (no PBCS) on PointMaze's sparse task,
//! the same task PBCS's grid solves (`experiments/pointmaze.toml`: start and goal cells
//! farthest apart, success within 0.45 of every goal gymnasium-robotics' reset may draw; reward
//! 1 there, and the episode ends).
//!
//! Settings: `experiments/baseline.toml` (the maze's vanilla baselines: networks 64×64, γ 0.99,
//! learning rates 1e-3, batch 64, Gaussian noise σ 0.1, 10 000 random steps first, one update
//! per step), the algorithm and step budget from the command line, episodes of the env's own
//! time limit (300, 300, 600, 800 steps), a greedy evaluation from the start every 10 000 steps
//! (one episode: the start and the policy are deterministic).
//!
//! `cargo run --release --features mujoco --example pointmaze_vanilla -- <map> <algo> <first
//! seed> <last seed> <out> [steps]` writes `<out>/<algo>-pointmaze_<map>/s<seed>.csv` (the
//! summary, [`pbcs::tables::outside::VanillaRun`], which `pbcs aggregate` reads back checked),
//! `s<seed>.evals.csv` (every evaluation) and `s<seed>.timing.toml`; a seed whose
//! summary exists is skipped (sweeps resume).

use pbcs::config::TrainJob;
use pbcs::envs::pointmaze::{MapName, PointMaze, GOAL_NOISE};
use pbcs::learner::Algo;
use pbcs::nn::kernel::Kernel;
use pbcs::rng::Seeds;
use pbcs::tables::outside::VanillaRun;
use std::path::{Path, PathBuf};
use strum::IntoEnumIterator;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: pointmaze_vanilla <umaze|open|medium|large> <ddpg|td3> <first seed> \
                 <last seed> <out> [steps]";
    anyhow::ensure!((5..=6).contains(&args.len()), "{usage}");
    let map = MapName::iter()
        .find(|m| <&str>::from(*m).eq_ignore_ascii_case(&args[0]))
        .ok_or_else(|| anyhow::anyhow!("unknown map {:?}; {usage}", args[0]))?;
    let algo = match args[1].as_str() {
        "ddpg" => Algo::Ddpg,
        "td3" => Algo::Td3,
        other => anyhow::bail!("unknown algo {other:?}; {usage}"),
    };
    let (first, last): (u64, u64) = (args[2].parse()?, args[3].parse()?);
    let out = PathBuf::from(&args[4]);
    let steps: u64 = args.get(5).map_or(Ok(1_000_000), |s| s.parse())?;
    let env = PointMaze::named(map)?.for_goal_noise(GOAL_NOISE)?;
    let name = format!("pointmaze_{}", <&str>::from(map).to_lowercase());
    let mut job: TrainJob = pbcs::validate::load(Path::new("experiments/baseline.toml"))?;
    job.learner.algo = algo;
    job.train.steps = steps;
    job.train.max_episode_steps = map.time_limit();
    let kernel = Kernel::from_env()?;
    let dir = out.join(format!("{}-{name}", algo.name()));
    std::fs::create_dir_all(&dir)?;
    for seed in first..=last {
        let row_path = dir.join(format!("s{seed}.csv"));
        if row_path.exists() {
            continue;
        }
        let clock = std::time::Instant::now();
        let r = pbcs::vanilla::train_vanilla(
            &env,
            &job.learner,
            &job.train,
            &Seeds::new(seed),
            kernel,
            |_, _| {},
        )?;
        let seconds = clock.elapsed().as_secs_f64();
        let row = VanillaRun {
            algo: algo.name().to_string(),
            env: name.clone(),
            seed,
            steps,
            episodes: r.episodes,
            final_success: r.evals.last().map_or(0.0, |e| e.success),
            best_success: r.evals.iter().map(|e| e.success).fold(0.0, f32::max),
            first_success_steps: r.evals.iter().find(|e| e.success > 0.0).map(|e| e.steps),
            terminal_transitions: r.terminal_transitions,
        };
        pbcs::record::write_records(&dir.join(format!("s{seed}.evals.csv")), &r.evals)?;
        pbcs::runs::write_timing(
            &dir.join(format!("s{seed}.timing.toml")),
            seconds,
            steps,
            Some(kernel),
        )?;
        pbcs::record::write_record(&row_path, &row)?;
        println!(
            "{} {name} seed {seed}: best greedy success {}, first at {:?} steps ({seconds:.0} s)",
            algo.name(),
            row.best_success,
            row.first_success_steps
        );
    }
    Ok(())
}
