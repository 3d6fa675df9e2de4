//! Phase-1 speed: prints numbers, asserts nothing. Run with `cargo bench --bench phase1`.
//!
//! 1. Environment steps per second: a random walk of random actions on maze 15 (the step
//!    includes the wall query), and the same queries answered by brute force over all walls.
//! 2. Phase-1 steps per second on maze 15, archive bookkeeping included.
//! 3. Phase-1 environment steps, trajectory length and wall time to reach the target for
//!    sizes 2, 5, 7, 10, 15 (maze seed 0) over run seeds 0..10: median, min, max.

use pbcs::config::{ExploreConfig, MazeConfig};
use pbcs::env::{random_action, Env};
use pbcs::envs::maze::Maze;
use pbcs::phase1::explore;
use pbcs::rng::{Seeds, Stream};
use std::hint::black_box;
use std::time::Instant;

fn maze(size: usize) -> Maze {
    Maze::new(&MazeConfig {
        size,
        ..MazeConfig::default()
    })
    .unwrap()
}

/// Median, min, max of a sample.
fn summary(mut v: Vec<f64>) -> (f64, f64, f64) {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let median = if n % 2 == 1 {
        v[n / 2]
    } else {
        (v[n / 2 - 1] + v[n / 2]) / 2.0
    };
    (median, v[0], v[n - 1])
}

fn env_steps_per_second() {
    let m = maze(15);
    let mut rng = Seeds::new(0).stream(Stream::Explore);
    const STEPS: usize = 2_000_000;
    // Pre-draw actions so that only the step is timed.
    let mut actions = vec![[0f32; 2]; STEPS];
    for a in actions.iter_mut() {
        random_action(&m, &mut rng, a);
    }
    let mut best = f64::INFINITY;
    let mut blocked = 0;
    for _ in 0..3 {
        let mut s = m.start();
        blocked = 0;
        let t = Instant::now();
        for a in &actions {
            let step = m.step(&s, a);
            blocked += usize::from(step.reward < 0.0);
            s = black_box(step.state);
        }
        best = best.min(t.elapsed().as_secs_f64());
    }
    println!(
        "maze 15 env step (grid + parry slab test): {:>7.1} ns/step, {:>6.1} M steps/s \
         ({STEPS} random steps, {:.0} % blocked, best of 3)",
        best / STEPS as f64 * 1e9,
        STEPS as f64 / best / 1e6,
        100.0 * blocked as f64 / STEPS as f64
    );
    let walls = m.walls();
    let mut s = m.start();
    let t = Instant::now();
    let n = 200_000;
    for a in &actions[..n] {
        let next = s + m.clip_action(a);
        if !black_box(walls.segment_hits_brute_force(&s, &next)) {
            s = next;
        }
    }
    println!(
        "maze 15 wall query by brute force ({} walls): {:>7.1} ns/query (reference)",
        walls.walls().len(),
        t.elapsed().as_secs_f64() / n as f64 * 1e9
    );
}

fn phase1_table() {
    println!();
    println!("phase 1 to the target, maze seed 0, run seeds 0..10 (median [min, max])");
    println!(
        "| maze | env steps | trajectory states | archive states | wall time (ms) | M steps/s |"
    );
    println!("| --- | --- | --- | --- | --- | --- |");
    for size in [2, 5, 7, 10, 15] {
        let m = maze(size);
        let (mut steps, mut lens, mut states, mut ms, mut rates) =
            (vec![], vec![], vec![], vec![], vec![]);
        for seed in 0..10 {
            let mut rng = Seeds::new(seed).stream(Stream::Explore);
            let t = Instant::now();
            let found = explore(&m, &ExploreConfig::default(), &mut rng, |_, _| {}).unwrap();
            let sec = t.elapsed().as_secs_f64();
            steps.push(found.env_steps as f64);
            lens.push(found.trajectory.len() as f64);
            states.push(found.archive.len() as f64);
            ms.push(sec * 1e3);
            rates.push(found.env_steps as f64 / sec / 1e6);
        }
        let f = |v: Vec<f64>, digits: usize| {
            let (md, lo, hi) = summary(v);
            format!("{md:.digits$} [{lo:.digits$}, {hi:.digits$}]")
        };
        println!(
            "| {size} | {} | {} | {} | {} | {} |",
            f(steps, 0),
            f(lens, 0),
            f(states, 0),
            f(ms, 1),
            f(rates, 2)
        );
    }
}

fn phase1_large_archive() {
    // Phase 1 on maze 15 with the target moved out of reach (radius tiny) is not possible
    // through the config, so instead run the 30×30 maze, whose archive grows much larger.
    let m = maze(30);
    let mut rng = Seeds::new(0).stream(Stream::Explore);
    let t = Instant::now();
    let found = explore(&m, &ExploreConfig::default(), &mut rng, |_, _| {}).unwrap();
    let sec = t.elapsed().as_secs_f64();
    println!();
    println!(
        "maze 30, seed 0: {} env steps, archive {} states in {} bins, {:.1} ms, {:.2} M steps/s",
        found.env_steps,
        found.archive.len(),
        found.archive.bins(),
        sec * 1e3,
        found.env_steps as f64 / sec / 1e6
    );
}

fn main() {
    // `cargo bench` passes `--bench`; any other argument filters nothing here.
    env_steps_per_second();
    phase1_table();
    phase1_large_archive();
}
