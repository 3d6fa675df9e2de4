//! N DDPG updates on one fixed batch, for profiling the learner update:
//! `cargo build --release --example update_loop && perf record
//! target/release/examples/update_loop 64 64 50000` (hidden width, batch, updates).
//! `PBCS_KERNEL` picks the kernel. Prints µs per update.

use pbcs::learner::replay::Batch;
use pbcs::learner::td3::{Td3, Td3Config};
use pbcs::rng::{Seeds, Stream};
use rand::Rng;

fn main() -> anyhow::Result<()> {
    let arg = |i: usize, default: usize| -> anyhow::Result<usize> {
        match std::env::args().nth(i) {
            Some(s) => s.parse().map_err(|_| {
                anyhow::anyhow!("argument {i}: expected a positive integer, got {s:?}")
            }),
            None => Ok(default),
        }
    };
    let (h, b, n) = (arg(1, 64)?, arg(2, 64)?, arg(3, 50_000)?);
    let kernel = pbcs::nn::kernel::Kernel::from_env()?;
    let mut rng = Seeds::new(5).substream(Stream::Replay, 0);
    let mut v =
        |n: usize, s: f32| -> Vec<f32> { (0..n).map(|_| rng.random_range(-s..s)).collect() };
    let batch = Batch {
        len: b,
        obs: v(b * 2, 5.0),
        act: v(b * 2, 1.0),
        rew: v(b, 1.0),
        next_obs: v(b * 2, 5.0),
        done: vec![0.0; b],
    };
    let config = Td3Config {
        hidden: vec![h, h],
        batch_size: b,
        ..Td3Config::ddpg()
    };
    let mut l = Td3::new(&config, 2, &[1.0, 1.0], &Seeds::new(0), kernel)?;
    let t = std::time::Instant::now();
    for _ in 0..n {
        std::hint::black_box(l.update(&batch));
    }
    println!(
        "{:.1} µs per update (hidden {h}, batch {b}, kernel {})",
        t.elapsed().as_secs_f64() / n.max(1) as f64 * 1e6,
        l.kernel().name()
    );
    Ok(())
}
