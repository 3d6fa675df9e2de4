//! Our TD3 or SAC on Pendulum-v1 (ported step for step: `pbcs::envs::pendulum`) with RL-Zoo's
//! tuned settings for Pendulum-v1.
//!
//! TD3: 20 000 steps, γ = 0.98, replay 200 000, 10 000 random warm-up
//! steps, learning rate 1e-3, networks [400, 300], Gaussian noise σ = 0.1, batch 256 (SB3's
//! TD3 default), τ = 0.005, and after each 200-step episode as many updates as its steps
//! (`train_freq = [1, "episode"], gradient_steps = -1`). Each seed's final greedy policy is
//! judged on its mean return over 10 episodes from random starts (RL-Zoo's benchmark: one
//! agent over 750 episodes, −151.9 ± 90.2: `results/outside/pendulum/published.toml`). Writes
//! one row per seed into `results/outside/pendulum/ours/` (a finished seed is skipped), its
//! wall clock beside it.
//!
//! SAC: 20 000 steps, learning rate 1e-3, everything else Stable-Baselines3's SAC defaults
//! ([256, 256], γ = 0.99, τ = 0.005, batch 256, replay 10⁶, 100 random warm-up steps, one
//! update per step, α learned towards −dim(A)); rows into `results/outside/pendulum/ours_sac/`.
//!
//! `cargo run --release --example pendulum -- [td3|sac] [FIRST_SEED LAST_SEED]` (default td3,
//! 0 9); the SB3 side is `python/benches/sb3_pendulum.py`.

use pbcs::envs::pendulum::{Pendulum, EPISODE_STEPS};
use pbcs::learner::sac::SacConfig;
use pbcs::learner::td3::Td3Config;
use pbcs::learner::LearnerConfig;
use pbcs::rng::Seeds;
use pbcs::vanilla::{train_vanilla, TrainConfig, Updates};
use std::path::Path;

fn main() -> anyhow::Result<()> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let algo = match args.first().map(String::as_str) {
        Some(a @ ("td3" | "sac")) => {
            let a = a.to_string();
            args.remove(0);
            a
        }
        _ => "td3".to_string(),
    };
    let args: Vec<u64> = args.iter().map(|a| a.parse()).collect::<Result<_, _>>()?;
    let (first, last) = match args[..] {
        [] => (0, 9),
        [a, b] if a <= b => (a, b),
        _ => anyhow::bail!("usage: pendulum [td3|sac] [FIRST_SEED LAST_SEED]"),
    };
    let td3 = algo == "td3";
    let learner: LearnerConfig = if td3 {
        Td3Config {
            hidden: vec![400, 300],
            actor_lr: 1e-3,
            critic_lr: 1e-3,
            gamma: 0.98,
            tau: 0.005,
            batch_size: 256,
            replay_size: 200_000,
            noise_sigma: 0.1,
            ..Td3Config::td3()
        }
        .into()
    } else {
        SacConfig {
            learning_rate: 1e-3,
            ..SacConfig::default()
        }
        .into()
    };
    let train = TrainConfig {
        steps: 20_000,
        max_episode_steps: EPISODE_STEPS,
        learning_starts: if td3 { 10_000 } else { 100 },
        eval_every: 20_000,
        eval_episodes: 10,
        updates: if td3 { Updates::Episode } else { Updates::Step },
        ..TrainConfig::default()
    };
    let dir = if td3 {
        Path::new("results/outside/pendulum/ours")
    } else {
        Path::new("results/outside/pendulum/ours_sac")
    };
    std::fs::create_dir_all(dir)?;
    let kernel = pbcs::nn::kernel::Kernel::from_env()?;
    for seed in first..=last {
        let row = dir.join(format!("s{seed}.csv"));
        if row.exists() {
            print!("{}", std::fs::read_to_string(&row)?);
            continue;
        }
        let clock = std::time::Instant::now();
        let out = train_vanilla(
            &Pendulum,
            &learner,
            &train,
            &Seeds::new(seed),
            kernel,
            |_, _| {},
        )?;
        let seconds = clock.elapsed().as_secs_f64();
        let eval = out.evals.last().expect("one evaluation at the end");
        let text = format!(
            "library,algo,seed,steps,eval_episodes,mean_return\npbcs,{algo},{seed},{},{},{}\n",
            eval.steps, train.eval_episodes, eval.mean_return
        );
        pbcs::record::write_atomic(&row.with_extension("timing.toml"), |w| {
            write!(
                w,
                "# wall clock (not deterministic)\nwall_seconds = {seconds:.3}\nkernel = \"{}\"\n",
                kernel.name()
            )
        })?;
        pbcs::record::write_atomic(&row, |w| w.write_all(text.as_bytes()))?;
        print!("{text}");
    }
    Ok(())
}
