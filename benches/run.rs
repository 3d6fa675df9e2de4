//! Wall time of whole PBCS runs: prints numbers, asserts nothing. Run with
//! `cargo bench --bench run` (the target of issue 24: `pbcs run --maze 15`, the default `fast`
//! preset, median wall ≤ 45 s on one core over run seeds 0–9).
//!
//! Each run is `pbcs run --maze N --seed S` without the files: [`PbcsRun::compute`] on the
//! `fast` preset (phase 1, phase 2, the evaluation). `PBCS_BENCH_SIZES` (default `15`) and
//! `PBCS_BENCH_SEEDS` (default `10`: seeds 0..10) choose the runs.

use pbcs::config::Preset;
use pbcs::nn::kernel::Kernel;
use pbcs::runs::PbcsRun;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    }
}

fn env_or<T: std::str::FromStr>(name: &str, default: &str) -> Vec<T> {
    std::env::var(name)
        .unwrap_or_else(|_| default.into())
        .split(',')
        .map(|s| {
            s.trim()
                .parse()
                .unwrap_or_else(|_| panic!("{name}: not a list of numbers"))
        })
        .collect()
}

fn main() {
    let sizes: Vec<usize> = env_or("PBCS_BENCH_SIZES", "15");
    let seeds: u64 = match env_or::<u64>("PBCS_BENCH_SEEDS", "10")[..] {
        [n] => n,
        _ => panic!("PBCS_BENCH_SEEDS: one number, the count of seeds (0..N)"),
    };
    let kernel = Kernel::detect();
    println!("kernel {kernel:?}; fast preset; one thread");
    for size in sizes {
        let (mut walls, mut steps) = (Vec::new(), Vec::new());
        for seed in 0..seeds {
            let mut job = Preset::Fast.job().expect("the fast preset is valid");
            job.maze.size = size;
            job.seed = seed;
            let clock = Instant::now();
            let run = PbcsRun::compute(
                pbcs::envs::maze::Maze::new(&job.maze).unwrap(),
                &pbcs::validate::Check::valid(job.clone()).unwrap(),
                kernel,
                |_, _| {},
            )
            .expect("the run completes");
            let wall = clock.elapsed().as_secs_f64();
            let r = &run.record;
            println!(
                "maze {size} seed {seed}: solved {} (chain {:.2}), {} env steps, {} skills, {wall:.1} s",
                r.solved, r.success_rate, r.total_steps, r.skills
            );
            walls.push(wall);
            steps.push(r.total_steps as f64);
        }
        let (lo, hi) = walls
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &w| (a.min(w), b.max(w)));
        println!(
            "maze {size}: median wall {:.1} s [{lo:.1}, {hi:.1}], median env steps {:.0}, over {} seeds",
            median(walls),
            median(steps),
            seeds
        );
    }
}
