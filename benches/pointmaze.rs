//! PointMaze speed (feature `mujoco`): prints numbers, asserts nothing. Run with
//! `cargo bench --features mujoco --bench pointmaze` (after `make mujoco`).
//!
//! Environment steps per second, one thread, through the pure [`Env::step`] (the whole state
//! set, `mj_forward`, `mj_step`, the state read back): random walks of uniformly random
//! actions from each map's start, restarted every 1 000 steps, three repeats per map.

use pbcs::env::{random_action, Env};
use pbcs::envs::pointmaze::{MapName, PointMaze};
use pbcs::rng::{Seeds, Stream};
use std::hint::black_box;
use std::time::Instant;
use strum::IntoEnumIterator;

fn main() {
    const STEPS: usize = 1_000_000;
    for map in MapName::iter() {
        let env = PointMaze::named(map).expect("the map's model compiles");
        let mut rates = Vec::new();
        for repeat in 0..3 {
            let mut rng = Seeds::new(repeat).stream(Stream::Explore);
            let mut action = [0.0f32; 2];
            let mut s = env.start();
            let t = Instant::now();
            for i in 0..STEPS {
                if i % 1000 == 0 {
                    s = env.start();
                }
                random_action(&env, &mut rng, &mut action);
                s = env.step(&s, &action).state;
            }
            black_box(s);
            rates.push(STEPS as f64 / t.elapsed().as_secs_f64());
        }
        rates.sort_by(f64::total_cmp);
        println!(
            "{}: {:.0} env steps/s (median of 3 × {STEPS} steps; min {:.0}, max {:.0})",
            map.gym_id(),
            rates[1],
            rates[0],
            rates[2]
        );
    }
}
