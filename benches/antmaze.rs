//! AntMaze speed (feature `mujoco`): prints numbers, asserts nothing. Run with
//! `cargo bench --features mujoco --bench antmaze` (after `make mujoco`).
//!
//! Env steps per second, one thread, on each map, two ways over the same walks (uniformly
//! random actions from the task's start, restarted every 1 000 steps, three repeats):
//! our pure [`Env::step`] (the whole state set, 5 × `mj_step`, the state read back), and
//! MuJoCo's raw cost for the same physics: one `MjData` stepped 5 × `mj_step` per env step,
//! nothing set or read. The ratio is what the pure step adds (issue 49's target: within 10 %).

use pbcs::env::{random_action, Env};
use pbcs::envs::antmaze::{model, AntMaze, FRAME_SKIP};
use pbcs::envs::pointmaze::{MapName, PointMap};
use pbcs::rng::{Seeds, Stream};
use std::hint::black_box;
use std::time::Instant;
use strum::IntoEnumIterator;

const STEPS: usize = 20_000;

/// Median of three rates (env steps per second) of `walk`.
fn median_rate(mut walk: impl FnMut(u64) -> f64) -> (f64, f64, f64) {
    let mut rates: Vec<f64> = (0..3).map(&mut walk).collect();
    rates.sort_by(f64::total_cmp);
    (rates[1], rates[0], rates[2])
}

fn main() {
    for map in MapName::iter() {
        let env = AntMaze::named(map).expect("the map's model compiles");
        let ours = median_rate(|repeat| {
            let mut rng = Seeds::new(repeat).stream(Stream::Explore);
            let mut action = [0.0f32; 8];
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
            STEPS as f64 / t.elapsed().as_secs_f64()
        });
        let mj = mujoco_rs::prelude::MjModel::from_xml_string(&model::xml(&PointMap::named(map)))
            .expect("the map's model compiles");
        let mut data = mujoco_rs::prelude::MjData::new(Box::new(mj));
        let start = env.start();
        let raw = median_rate(|repeat| {
            let mut rng = Seeds::new(repeat).stream(Stream::Explore);
            let mut action = [0.0f32; 8];
            let t = Instant::now();
            for i in 0..STEPS {
                if i % 1000 == 0 {
                    data.reset();
                    data.qpos_mut()[..2].copy_from_slice(&start.qpos[..2]);
                }
                random_action(&env, &mut rng, &mut action);
                for (c, a) in data.ctrl_mut().iter_mut().zip(action) {
                    *c = f64::from(a);
                }
                for _ in 0..FRAME_SKIP {
                    data.step();
                }
            }
            black_box(data.qpos()[0]);
            STEPS as f64 / t.elapsed().as_secs_f64()
        });
        println!(
            "{}: ours {:.0} env steps/s (min {:.0}, max {:.0}); raw mj_step {:.0} (min {:.0}, \
             max {:.0}); ours / raw = {:.3} (median of 3 × {STEPS} steps)",
            model::gym_id(map),
            ours.0,
            ours.1,
            ours.2,
            raw.0,
            raw.1,
            raw.2,
            ours.0 / raw.0
        );
    }
}
