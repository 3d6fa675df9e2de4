//! Measures greedy success on the 1-D toy after a step budget, over seeds (used to choose the
//! budget of the learning test). `cargo run --release --example toy_sweep -- STEPS`
use pbcs::envs::toy::Toy1D;
use pbcs::learner::LearnerConfig;
use pbcs::rng::Seeds;
use pbcs::vanilla::{train_vanilla, TrainConfig};

fn main() {
    let steps: u64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(3000);
    let train = TrainConfig {
        steps,
        max_episode_steps: 50,
        learning_starts: 500,
        eval_every: steps,
        eval_episodes: 100,
        visit_bin: 0.05,
        ..Default::default()
    };
    for (name, cfg) in [
        ("ddpg", LearnerConfig::ddpg()),
        ("td3", LearnerConfig::td3()),
    ] {
        let t = std::time::Instant::now();
        let rates: Vec<f32> = (0..10)
            .map(|seed| {
                let out = train_vanilla(
                    &Toy1D,
                    &cfg,
                    &train,
                    &Seeds::new(seed),
                    pbcs::nn::kernel::Kernel::detect(),
                    |_, _| {},
                )
                .unwrap();
                out.evals.last().unwrap().success
            })
            .collect();
        println!(
            "{name} {steps} steps: {rates:?} ({:.1} s)",
            t.elapsed().as_secs_f64()
        );
    }
}
