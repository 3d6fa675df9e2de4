//! Issue 49's development probe of the reach that a chain judged by gymnasium-robotics needs at
//! its ends: can a learner of ours teach the ant to reach a goal drawn ±1 m around a cell's
//! centre, from a start drawn ±1 m around the same centre (both as the env's reset draws them,
//! the ant at rest)? That is the last skill's problem under `phase2.last_goal = "drawn"` and the
//! first one's under `first_starts = "drawn"`, without the walk along τ around it.
//!
//! The env is `AntMaze::new(map, cell, cell, Resets::Gym)`: gymnasium-robotics' reset of one cell
//! for both the start and the goal, success within 0.45 of the drawn goal. The job is a `pbcs
//! train` job file (its `[learner]` and `[train]`, with `[train.her]` or not; its `env` must be a
//! `antmaze_<map>_goals` name, whose map is used).
//!
//! `antmaze_reach <job.toml> <seed> [row col]` (the cell; default: the map's goal cell) prints
//! the evaluations as CSV rows `seed,steps,episodes,success,mean_return,mean_length,wall_s`.

use anyhow::{bail, Context};
use pbcs::config::TrainJob;
use pbcs::envs::antmaze::AntMaze;
use pbcs::envs::pointmaze::{PointMap, Resets};
use pbcs::nn::kernel::Kernel;
use pbcs::rng::Seeds;
use pbcs::vanilla::train_vanilla;
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [file, seed, cell @ ..] = &args[..] else {
        bail!("usage: antmaze_reach <job.toml> <seed> [row col]");
    };
    let text = std::fs::read_to_string(file).with_context(|| format!("reading {file}"))?;
    let job: TrainJob = toml::from_str(&text).with_context(|| format!("parsing {file}"))?;
    pbcs::validate::Check::check(&job)?;
    let (Some(map), true) = (job.env.ant_map(), job.env.goal_resets()) else {
        bail!(
            "env must be an antmaze_<map>_goals name, not {}",
            job.env.name()
        );
    };
    let seed: u64 = seed.parse().context("seed")?;
    let map = PointMap::named(map);
    let cell = match cell {
        [] => map.farthest_cells().1,
        [r, c] => (r.parse().context("row")?, c.parse().context("col")?),
        _ => bail!("the cell is two numbers, row and col"),
    };
    let env = AntMaze::new(map, cell, cell, Resets::Gym)?;
    let clock = Instant::now();
    eprintln!("{} from and to cell {cell:?}, seed {seed}", job.env.name());
    let out = train_vanilla(
        &env,
        &job.learner,
        &job.train,
        &Seeds::new(seed),
        Kernel::from_env()?,
        |steps, success| {
            let s = clock.elapsed().as_secs_f64();
            eprintln!("[{s:.0} s] {steps} env steps: greedy success {success:.2}");
        },
    )?;
    println!("seed,steps,episodes,success,mean_return,mean_length,wall_s");
    let wall = clock.elapsed().as_secs_f64();
    for e in &out.evals {
        println!(
            "{seed},{},{},{},{},{},{wall:.0}",
            e.steps, e.episodes, e.success, e.mean_return, e.mean_length
        );
    }
    Ok(())
}
