//! Measures greedy success on the 1-D toy after a step budget, over seeds (used to choose the
//! budget of the learning tests). `cargo run --release --example toy_sweep -- STEPS [ALGO...]`
//! (default: ddpg td3; `sac` is SAC at widths 64 and batch 64, as tests/sac.rs trains it).
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
    let mut names: Vec<String> = std::env::args().skip(2).collect();
    if names.is_empty() {
        names = vec!["ddpg".into(), "td3".into()];
    }
    for name in &names {
        let cfg: LearnerConfig = match name.as_str() {
            "sac" => pbcs::learner::sac::SacConfig {
                hidden: vec![64, 64],
                batch_size: 64,
                ..Default::default()
            }
            .into(),
            // sac_<α>: α fixed; sac_auto_<α₀>: learned from α₀.
            fixed if fixed.starts_with("sac_") => pbcs::learner::sac::SacConfig {
                hidden: vec![64, 64],
                batch_size: 64,
                ent_coef: match fixed[4..].parse() {
                    Ok(a) => pbcs::learner::sac::EntCoef::Fixed(a),
                    Err(_) => pbcs::learner::sac::EntCoef::Learned(fixed[4..].into()),
                },
                ..Default::default()
            }
            .into(),
            other => LearnerConfig::preset(other).expect("a learner"),
        };
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
