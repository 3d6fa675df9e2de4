//! PBCS on an environment of your own: implement [`pbcs::env::Env`], then call phase 1
//! ([`pbcs::explore::explore`]) and phase 2 ([`pbcs::phase2::chain_skills`]) yourself.
//!
//! The environment here is not the maze: two rooms side by side, [0, 1]² and [1, 2] × [0, 1],
//! joined by a door in the wall x = 1 at heights 0.8 – 1; the agent starts at (0.3, 0.2) and
//! must reach the ball of radius 0.2 around (1.7, 0.2), just across the wall from its start.
//! Everything else (the learner, α, β, ε, the budgets) comes from the `fast` preset.
//!
//! `cargo run --release --example own_env [SEED]`

use pbcs::config::Preset;
use pbcs::env::{Env, Step};
use pbcs::explore::explore;
use pbcs::phase2::{chain_skills, phase2_trajectory};
use pbcs::rng::{Rng, Seeds, Stream};
use rand::Rng as _;

/// Two rooms and a door; the state is the point (x, y).
struct TwoRooms;

const TARGET: [f32; 2] = [1.7, 0.2];
const TARGET_RADIUS: f32 = 0.2;
const DOOR: (f32, f32) = (0.8, 1.0);

impl TwoRooms {
    /// Whether the segment from `s` to `n` crosses the wall x = 1 outside the door.
    fn blocked(s: &[f32; 2], n: &[f32; 2]) -> bool {
        if (s[0] - 1.0) * (n[0] - 1.0) > 0.0 || s[0] == n[0] {
            return false; // both on one side
        }
        let t = (1.0 - s[0]) / (n[0] - s[0]);
        let y = s[1] + t * (n[1] - s[1]);
        !(DOOR.0 < y && y < DOOR.1)
    }
}

impl Env for TwoRooms {
    type State = [f32; 2];

    fn obs_dim(&self) -> usize {
        2
    }

    fn action_dim(&self) -> usize {
        2
    }

    fn action_bound(&self, _i: usize) -> f32 {
        0.1
    }

    fn start(&self) -> [f32; 2] {
        [0.3, 0.2]
    }

    /// Backplay's starts in B_ε(τ_K): uniform in the disc, kept inside the rooms (a start
    /// that lands across the wall from the centre is moved back to the centre).
    fn sample_ball(&self, center: &[f32; 2], radius: f32, rng: &mut Rng) -> [f32; 2] {
        let r = radius * rng.random::<f32>().sqrt();
        let phi = std::f32::consts::TAU * rng.random::<f32>();
        let p = [
            (center[0] + r * phi.cos()).clamp(0.0, 2.0),
            (center[1] + r * phi.sin()).clamp(0.0, 1.0),
        ];
        if Self::blocked(center, &p) {
            *center
        } else {
            p
        }
    }

    fn success_region(&self) -> Option<(Vec<f32>, f32)> {
        Some((TARGET.to_vec(), TARGET_RADIUS))
    }

    fn observe(&self, s: &[f32; 2], out: &mut [f32]) {
        out.copy_from_slice(s);
    }

    /// Pure: moves by the clipped action unless the wall blocks it; reward 1 and the end of
    /// the episode in the target ball.
    fn step(&self, s: &[f32; 2], a: &[f32]) -> Step<[f32; 2]> {
        let clip = |v: f32| if v.is_nan() { 0.0 } else { v.clamp(-0.1, 0.1) };
        let n = [
            (s[0] + clip(a[0])).clamp(0.0, 2.0),
            (s[1] + clip(a[1])).clamp(0.0, 1.0),
        ];
        let n = if Self::blocked(s, &n) { *s } else { n };
        let done = (n[0] - TARGET[0]).hypot(n[1] - TARGET[1]) < TARGET_RADIUS;
        Step {
            state: n,
            reward: f32::from(u8::from(done)),
            terminal: done,
        }
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let seed: u64 = match std::env::args().nth(1) {
        Some(s) => s
            .parse()
            .map_err(|_| format!("SEED must be a whole number, got `{s}`"))?,
        None => 0,
    };
    let env = TwoRooms;
    let job = Preset::Fast.job()?;
    let seeds = Seeds::new(seed);

    // Phase 1: explore until the reward, return τ.
    let found = explore(
        &env,
        &job.explore,
        &mut seeds.stream(Stream::Explore),
        |_, _| {},
    )?;
    let tau = phase2_trajectory(&env, &found.trajectory, &job.phase2).states;
    println!(
        "phase 1: τ of {} states found in {} environment steps",
        tau.len(),
        found.env_steps
    );

    // Phase 2: Backplay + shaped DDPG from starts in B_ε(τ_K), chaining skills.
    let out = chain_skills(
        &env,
        &tau,
        &job.learner,
        &job.phase2,
        &seeds,
        found.env_steps,
        pbcs::nn::kernel::Kernel::detect(),
        |_, _| {},
    )?;
    if let Some(f) = out.failure {
        println!("phase 2 stopped: {}", f.name());
        return Ok(());
    }
    println!(
        "phase 2: a chain of {} skill(s) in {} training + {} test steps",
        out.chain.skills.len(),
        out.steps.train,
        out.steps.test
    );

    // The chain from 100 starts in B_ε(s_0).
    let mut rng = seeds.stream(Stream::Eval);
    let wins = (0..100)
        .filter(|_| {
            let start = env.sample_ball(&env.start(), job.phase2.epsilon, &mut rng);
            out.chain.run(&env, start, 1000).success
        })
        .count();
    println!("the chain reaches the target from {wins} of 100 starts");
    Ok(())
}
