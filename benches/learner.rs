//! Learner update cost: prints numbers, asserts nothing. `cargo bench --bench learner`.
//!
//! For hidden width H ∈ {64, 256} and batch B ∈ {64, 256}: µs per DDPG update (actor, critic,
//! targets; maze dimensions: 2-D observations and actions) with every kernel this CPU runs
//! (portable, matrixmultiply — the earlier path —, AVX2, AVX-512; see `pbcs::nn::kernel`) and
//! with a straightforward candle implementation, and the matmul FLOPs per second each reaches
//! as a percentage of this run's single-core f32 matmul rate (a 512³ product with
//! matrixmultiply). Then the learners side by side on the best kernel: µs per DDPG, TD3 and SAC
//! update at the same widths and batches. Then end-to-end environment steps per second of `pbcs run --maze 10
//! --seed 0` (the fast preset) over its first 200k steps with the earlier and the best kernel,
//! µs per single-state action, and the update cost over 100k updates (the subnormal-moment
//! hazard). One thread throughout. `PBCS_BENCH_QUICK=1` skips the end-to-end part.

use candle_core::{Device, Tensor, Var};
use candle_nn::{Module, Optimizer};
use pbcs::config::Preset;
use pbcs::learner::replay::{Batch, Replay};
use pbcs::learner::td3::{Td3, Td3Config};
use pbcs::nn::candle_ref::{self, CandleMlp};
use pbcs::nn::kernel::{Kernel, Matrix, Post};
use pbcs::nn::Mlp;
use pbcs::rng::{Seeds, Stream};
use rand::Rng;
use std::hint::black_box;
use std::time::Instant;

const OBS: usize = 2;
const ACT: usize = 2;

/// Best-of-`reps` seconds of `f`.
fn best_of(reps: usize, mut f: impl FnMut()) -> f64 {
    (0..reps)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

/// FLOP/s of a 512³ product with `kernel`.
fn matmul_rate(kernel: Kernel) -> f64 {
    let n = 512;
    let a: Vec<f32> = (0..n * n).map(|i| (i % 7) as f32 * 0.1).collect();
    let b = a.clone();
    let mut c = vec![0.0f32; n * n];
    let s = best_of(5, || {
        kernel.gemm_nn(
            (n, n, n),
            Matrix::rows(&a, n),
            Matrix::rows(&b, n),
            &mut c,
            None,
            Post::Identity,
        )
    });
    2.0 * (n * n * n) as f64 / s
}

/// Environment steps per second of the fast preset on maze 10, seed 0, for its first
/// `steps` steps (phase 1 included), on `kernel`; also the training and test steps
/// among them (kernels that round differently follow different runs, and test steps do no
/// update, so the mix is printed beside the rate).
fn end_to_end(kernel: Kernel, steps: u64) -> (f64, u64, u64) {
    let mut job = Preset::Fast.job().unwrap();
    job.maze.size = 10;
    job.seed = 0;
    job.phase2.max_env_steps = steps;
    // The run stops at the budget (maze 10 needs ~1M steps), so no evaluation is timed.
    let t = Instant::now();
    let run = pbcs::runs::PbcsRun::compute(
        pbcs::envs::maze::Maze::new(&job.maze).unwrap(),
        &pbcs::validate::Check::valid(job.clone()).unwrap(),
        kernel,
        |_, _| {},
    )
    .unwrap();
    let r = &run.record;
    (
        r.total_steps as f64 / t.elapsed().as_secs_f64(),
        r.train_steps,
        r.test_steps,
    )
}

/// Matmul FLOPs of one fused DDPG update, counted as the implementation performs them.
fn update_flops(h: usize, b: usize) -> f64 {
    let layers =
        |sizes: &[usize]| -> Vec<usize> { sizes.windows(2).map(|w| w[0] * w[1]).collect() };
    let actor = layers(&[OBS, h, h, ACT]);
    let critic = layers(&[OBS + ACT, h, h, 1]);
    let fwd = |l: &[usize]| 2 * b * l.iter().sum::<usize>();
    let dx_above_first = |l: &[usize]| 2 * b * l[1..].iter().sum::<usize>();
    let total = fwd(&actor)                                     // target actor π'(s')
        + fwd(&critic)                                          // target critic Q'(s', a')
        + fwd(&critic) + fwd(&critic) + dx_above_first(&critic) // critic step: fwd, ∂W, ∂X
        + fwd(&actor)                                           // π(s)
        + fwd(&critic) + fwd(&critic)                           // Q(s, π(s)) and ∂Q/∂input
        + fwd(&actor) + dx_above_first(&actor); // actor step: ∂W, ∂X
    total as f64
}

fn random_batch(b: usize, seed: u32) -> Batch {
    let mut rng = Seeds::new(5).substream(Stream::Replay, seed);
    let mut v =
        |n: usize, s: f32| -> Vec<f32> { (0..n).map(|_| rng.random_range(-s..s)).collect() };
    Batch {
        len: b,
        obs: v(b * OBS, 5.0),
        act: v(b * ACT, 1.0),
        rew: v(b, 1.0),
        next_obs: v(b * OBS, 5.0),
        done: vec![0.0; b],
    }
}

fn config(h: usize, b: usize) -> Td3Config {
    Td3Config {
        hidden: vec![h, h],
        batch_size: b,
        ..Td3Config::ddpg()
    }
}

/// µs per update of each learner family on `kernel`: DDPG, TD3 (its critic-only updates
/// included: the mean over a run of updates) and SAC, at widths 64 and 256, batches 64 and 256.
fn learners_side_by_side(kernel: Kernel) {
    use pbcs::learner::sac::SacConfig;
    use pbcs::learner::LearnerConfig;
    println!();
    println!(
        "learners, obs 2, act 2, {} kernel, one thread (best of 5 rounds): µs per update",
        kernel.name()
    );
    println!("| hidden | batch | ddpg | td3 | sac |");
    println!("| --- | --- | --- | --- | --- |");
    for h in [64, 256] {
        for b in [64, 256] {
            let batch = random_batch(b, 0);
            let configs: [LearnerConfig; 3] = [
                config(h, b).into(),
                Td3Config {
                    algo: pbcs::learner::td3::Algo::Td3,
                    ..config(h, b)
                }
                .into(),
                SacConfig {
                    hidden: vec![h, h],
                    batch_size: b,
                    ..SacConfig::default()
                }
                .into(),
            ];
            let mut row = format!("| {h} | {b} |");
            for c in &configs {
                let mut l = c.build(OBS, &[1.0, 1.0], &Seeds::new(0), kernel).unwrap();
                for _ in 0..20 {
                    l.update(&batch);
                }
                let n = if h * b >= 256 * 64 { 100 } else { 1000 };
                let t = best_of(5, || {
                    for _ in 0..n {
                        black_box(l.update(&batch));
                    }
                }) / n as f64;
                row += &format!(" {:.0} |", t * 1e6);
            }
            println!("{row}");
        }
    }
}

/// A straightforward DDPG update in candle, for comparison.
struct CandleDdpg {
    actor: (Mlp, Vec<(Var, Var)>),
    critic: (Mlp, Vec<(Var, Var)>),
    actor_t: CandleMlp,
    critic_t: CandleMlp,
    opt_a: candle_nn::AdamW,
    opt_c: candle_nn::AdamW,
}

impl CandleDdpg {
    fn new(l: &Td3) -> Self {
        let params =
            |v: &[(Var, Var)]| v.iter().flat_map(|(w, b)| [w.clone(), b.clone()]).collect();
        let adam = |v: &[(Var, Var)]| {
            candle_nn::AdamW::new(
                params(v),
                candle_nn::ParamsAdamW {
                    lr: 1e-3,
                    weight_decay: 0.0,
                    ..Default::default()
                },
            )
            .unwrap()
        };
        let av = candle_ref::vars(&l.actor);
        let cv = candle_ref::vars(&l.critics[0]);
        CandleDdpg {
            actor_t: CandleMlp::from_vars(&l.actor, &candle_ref::vars(&l.actor)),
            critic_t: CandleMlp::from_vars(&l.critics[0], &candle_ref::vars(&l.critics[0])),
            opt_a: adam(&av),
            opt_c: adam(&cv),
            actor: (l.actor.clone(), av),
            critic: (l.critics[0].clone(), cv),
        }
    }

    fn update(&mut self, b: &Batch) -> candle_core::Result<()> {
        let dev = &Device::Cpu;
        let t = |v: &[f32], c: usize| Tensor::from_slice(v, (b.len, c), dev);
        let (s, a, r, s2, d) = (
            t(&b.obs, OBS)?,
            t(&b.act, ACT)?,
            t(&b.rew, 1)?,
            t(&b.next_obs, OBS)?,
            t(&b.done, 1)?,
        );
        let actor = CandleMlp::from_vars(&self.actor.0, &self.actor.1);
        let critic = CandleMlp::from_vars(&self.critic.0, &self.critic.1);
        let q2 = self
            .critic_t
            .forward(&Tensor::cat(&[&s2, &self.actor_t.forward(&s2)?], 1)?)?;
        let y = (r + ((1.0 - d)? * 0.99)?.mul(&q2)?)?.detach();
        let q = critic.forward(&Tensor::cat(&[&s, &a], 1)?)?;
        self.opt_c.backward_step(&(q - y)?.sqr()?.mean_all()?)?;
        let qa = critic.forward(&Tensor::cat(&[&s, &actor.forward(&s)?], 1)?)?;
        let grads = qa.mean_all()?.neg()?.backward()?;
        self.opt_a.step(&grads)?;
        let tau = 0.005;
        let soft = |target: &mut CandleMlp, online: &[(Var, Var)]| -> candle_core::Result<()> {
            for ((tw, tb), (w, bb)) in target.layers.iter_mut().zip(online) {
                *tw = ((w.as_tensor() * tau)? + (&*tw * (1.0 - tau))?)?;
                *tb = ((bb.as_tensor() * tau)? + (&*tb * (1.0 - tau))?)?;
            }
            Ok(())
        };
        soft(&mut self.actor_t, &self.actor.1)?;
        soft(&mut self.critic_t, &self.critic.1)?;
        Ok(())
    }
}

fn main() {
    // One thread for candle (its CPU matmul reads these), as the project runs one process per
    // seed. Set before any candle call.
    std::env::set_var("RAYON_NUM_THREADS", "1");
    std::env::set_var("CANDLE_NUM_THREADS", "1");
    let kernels: Vec<Kernel> = Kernel::ALL.into_iter().filter(|k| k.available()).collect();
    let best = Kernel::detect();
    let rate = matmul_rate(Kernel::Matrixmultiply);
    println!(
        "single-core f32 matmul rate (512³, matrixmultiply): {:.1} GFLOP/s; {}: {:.1} GFLOP/s",
        rate / 1e9,
        best.name(),
        matmul_rate(best) / 1e9
    );
    println!(
        "kernels on this CPU: {}",
        kernels
            .iter()
            .map(|k| k.name())
            .collect::<Vec<_>>()
            .join(", ")
    );
    println!();
    println!("DDPG update, obs 2, act 2, one thread (best of 5 interleaved rounds; candle: best of 3): µs per update (% of the matmul rate)");
    let mut header = "| hidden | batch |".to_string();
    for k in &kernels {
        header += &format!(" {} |", k.name());
    }
    header += &format!(" candle | {} vs matrixmultiply |", best.name());
    println!("{header}");
    println!("{}", "| --- ".repeat(kernels.len() + 4) + "|");
    for h in [64, 256] {
        for b in [64, 256] {
            let flops = update_flops(h, b);
            let batch = random_batch(b, 0);
            let mut row = format!("| {h} | {b} |");
            // Kernels measured in interleaved rounds (each round times every kernel once), so a
            // slow spell of a shared machine hits them all alike; the best round counts.
            let mut learners: Vec<(Kernel, Td3, usize)> = kernels
                .iter()
                .map(|&k| {
                    // The portable kernel is slow enough that fewer updates give a stable number.
                    let scale = if k == Kernel::Portable { 10 } else { 1 };
                    let n = (if h * b >= 256 * 64 { 100 } else { 1000 }) / scale;
                    let mut l =
                        Td3::new(&config(h, b), OBS, &[1.0, 1.0], &Seeds::new(0), k).unwrap();
                    for _ in 0..20 {
                        l.update(&batch);
                    }
                    (k, l, n)
                })
                .collect();
            let mut times: std::collections::HashMap<Kernel, f64> =
                kernels.iter().map(|&k| (k, f64::INFINITY)).collect();
            for _round in 0..5 {
                for (k, l, n) in &mut learners {
                    let t = best_of(1, || {
                        for _ in 0..*n {
                            black_box(l.update(&batch));
                        }
                    }) / *n as f64;
                    let best = times.get_mut(k).unwrap();
                    *best = best.min(t);
                }
            }
            for k in &kernels {
                let t = times[k];
                row += &format!(" {:.0} ({:.0} %) |", t * 1e6, 100.0 * flops / t / rate);
            }
            let l0 = learners.pop().map(|(_, l, _)| l);
            let l = l0.unwrap();
            let mut c = CandleDdpg::new(&l);
            for _ in 0..5 {
                c.update(&batch).unwrap();
            }
            let nc = if h * b >= 256 * 64 { 25 } else { 250 };
            let cand = best_of(3, || {
                for _ in 0..nc {
                    c.update(&batch).unwrap();
                }
            }) / nc as f64;
            row += &format!(
                " {:.0} ({:.0} %) | {:.2}× |",
                cand * 1e6,
                100.0 * flops / cand / rate,
                times[&Kernel::Matrixmultiply] / times[&best]
            );
            println!("{row}");
        }
    }

    learners_side_by_side(best);

    if std::env::var_os("PBCS_BENCH_QUICK").is_none() {
        println!();
        println!(
            "end to end: `pbcs run --maze 10 --seed 0` (fast preset), first 200k environment steps (best of 2, alternating)"
        );
        // Alternating, twice each, the faster of each pair counting.
        let (mut before, mut after) = ((0.0, 0, 0), (0.0, 0, 0));
        for _ in 0..2 {
            let m = end_to_end(Kernel::Matrixmultiply, 200_000);
            let f = end_to_end(best, 200_000);
            if m.0 > before.0 {
                before = m;
            }
            if f.0 > after.0 {
                after = f;
            }
        }
        let ((before, tr0, te0), (after, tr1, te1)) = (before, after);
        println!(
            "  matrixmultiply: {before:.0} steps/s ({tr0} training, {te0} test); {}: {after:.0} \
             steps/s ({tr1} training, {te1} test); {:.2}×",
            best.name(),
            after / before
        );
    }

    // Action selection: one state, one forward pass.
    let mut l = Td3::new(&config(64, 64), OBS, &[1.0, 1.0], &Seeds::new(0), best).unwrap();
    let obs = [1.5f32, 2.5];
    let n = 100_000;
    let s = best_of(3, || {
        for _ in 0..n {
            black_box(l.act(black_box(&obs), 1));
        }
    });
    println!();
    println!(
        "single-state action (hidden 64): {:.2} µs",
        s / n as f64 * 1e6
    );
    let many: Vec<f32> = (0..2 * 50).map(|i| i as f32 * 0.05).collect();
    let s50 = best_of(3, || {
        for _ in 0..n / 10 {
            black_box(l.act(black_box(&many), 50));
        }
    });
    println!(
        "50 states in one batched pass (hidden 64): {:.2} µs",
        s50 / (n / 10) as f64 * 1e6
    );

    // Drift: 100k updates at hidden 64 / batch 64 on batches from a replay of random maze-like
    // transitions; cost per block of 10k updates.
    println!();
    println!("update cost over 100k updates (hidden 64, batch 64), µs/update per 10k block:");
    let mut replay = Replay::new(100_000, OBS, ACT);
    let mut rng = Seeds::new(1).stream(Stream::Replay);
    for _ in 0..100_000 {
        let s = [rng.random_range(0.0..10.0), rng.random_range(0.0..10.0)];
        let a = [rng.random_range(-0.1..0.1), rng.random_range(-0.1..0.1)];
        let r = if rng.random_range(0.0..1.0) < 0.05 {
            -1.0
        } else {
            0.0
        };
        replay.push(&s, &a, r, &[s[0] + a[0], s[1] + a[1]], false);
    }
    let mut l = Td3::new(&config(64, 64), OBS, &[1.0, 1.0], &Seeds::new(2), best).unwrap();
    let mut batch = Batch::default();
    let mut blocks = Vec::new();
    for _ in 0..10 {
        let t = Instant::now();
        for _ in 0..10_000 {
            replay.sample(64, &mut rng, &mut batch);
            l.update(&batch);
        }
        blocks.push(t.elapsed().as_secs_f64() / 10_000.0 * 1e6);
    }
    let text: Vec<String> = blocks.iter().map(|b| format!("{b:.0}")).collect();
    println!(
        "  {} (last / first = {:.2}; includes replay sampling)",
        text.join(", "),
        blocks[9] / blocks[0]
    );
}
