//! The fused MLP against finite differences and against candle's autograd.

use candle_core::{Device, Tensor};
use candle_nn::{Module, Optimizer};
use pbcs::nn::candle_ref::{self, CandleMlp};
use pbcs::nn::kernel::Kernel;
use pbcs::nn::{Adam, Head, Mlp, Workspace};
use pbcs::rng::{Seeds, Stream};
use rand::Rng;

fn random_vec(n: usize, scale: f32, seed: u32) -> Vec<f32> {
    let mut rng = Seeds::new(99).substream(Stream::Eval, seed);
    (0..n).map(|_| rng.random_range(-scale..scale)).collect()
}

/// L = Σ_ij w_ij · net(x)_ij: a loss whose gradient exercises every output.
fn weighted_loss(net: &Mlp, x: &[f32], batch: usize, w: &[f32]) -> f64 {
    let mut ws = Workspace::with_kernel(pbcs::nn::kernel::Kernel::detect());
    let y = net.forward(x, batch, &mut ws);
    y.iter().zip(w).map(|(y, w)| f64::from(y * w)).sum()
}

/// Central differences of L in every parameter and input, against `backward`. Tolerance:
/// |fd − g| ≤ 1e-4 + 1e-2·|g|. (f32 evaluation of L rounds at ~1e-7 relative, ~1e-5 after
/// dividing by 2h with h = 1e-2; the tanh curvature adds ~h² ≈ 1e-4 relative; and h is small
/// enough that, for these seeds, no ReLU pre-activation crosses zero.)
#[allow(clippy::needless_range_loop)] // index i perturbs params[i] and reads grad[i]
fn check_gradients(net: &Mlp, batch: usize, seed: u32, input_scale: f32) {
    let x = random_vec(batch * net.input_dim(), input_scale, seed);
    let w = random_vec(batch * net.output_dim(), 1.0, seed + 1);
    let mut ws = Workspace::with_kernel(pbcs::nn::kernel::Kernel::detect());
    net.forward(&x, batch, &mut ws);
    let mut grad = vec![0.0; net.params.len()];
    let mut dx = vec![0.0; x.len()];
    net.backward(&mut ws, &w, Some(&mut grad), Some(&mut dx));
    let h = 1e-2f32;
    let close = |fd: f64, g: f32| (fd - f64::from(g)).abs() <= 1e-4 + 1e-2 * f64::from(g.abs());
    for i in 0..net.params.len() {
        let (mut plus, mut minus) = (net.clone(), net.clone());
        plus.params[i] += h;
        minus.params[i] -= h;
        let fd = (weighted_loss(&plus, &x, batch, &w) - weighted_loss(&minus, &x, batch, &w))
            / (2.0 * f64::from(h));
        assert!(
            close(fd, grad[i]),
            "param {i}: fd {fd} vs backward {}",
            grad[i]
        );
    }
    for i in 0..x.len() {
        let (mut xp, mut xm) = (x.clone(), x.clone());
        xp[i] += h;
        xm[i] -= h;
        let fd = (weighted_loss(net, &xp, batch, &w) - weighted_loss(net, &xm, batch, &w))
            / (2.0 * f64::from(h));
        assert!(close(fd, dx[i]), "input {i}: fd {fd} vs backward {}", dx[i]);
    }
}

#[test]
fn critic_gradients_match_finite_differences() {
    let mut rng = Seeds::new(3).stream(Stream::Init);
    let critic = Mlp::new(&[4, 6, 5, 1], Head::Linear, &mut rng);
    check_gradients(&critic, 3, 10, 1.0);
}

#[test]
fn actor_gradients_match_finite_differences() {
    let mut rng = Seeds::new(4).stream(Stream::Init);
    let actor = Mlp::new(&[2, 6, 5, 2], Head::Tanh(vec![0.1, 0.3]), &mut rng);
    // Inputs up to ±4 put the tanh head well into its curved region (|tanh| up to ~0.9), so
    // an error in its derivative shows.
    let mut ws = Workspace::with_kernel(pbcs::nn::kernel::Kernel::detect());
    let x = random_vec(3 * 2, 4.0, 20);
    let y = actor.forward(&x, 3, &mut ws);
    assert!(
        y.iter()
            .zip([0.1, 0.3].iter().cycle())
            .any(|(y, s)| (y / s).abs() > 0.5),
        "{y:?}"
    );
    check_gradients(&actor, 3, 20, 4.0);
}

fn tensor(v: &[f32], rows: usize, cols: usize) -> Tensor {
    Tensor::from_slice(v, (rows, cols), &Device::Cpu).unwrap()
}

fn assert_close(a: &[f32], b: &[f32], tol: f32, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: lengths");
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            (x - y).abs() <= tol * (1.0 + x.abs().max(y.abs())),
            "{what}[{i}]: {x} vs {y}"
        );
    }
}

/// candle's gradients of `vars`, flattened in the fused network's parameter layout.
fn flat_grads(
    grads: &candle_core::backprop::GradStore,
    vars: &[(candle_core::Var, candle_core::Var)],
) -> Vec<f32> {
    let mut out = Vec::new();
    for (w, b) in vars {
        out.extend(
            grads
                .get(w.as_tensor())
                .unwrap()
                .flatten_all()
                .unwrap()
                .to_vec1::<f32>()
                .unwrap(),
        );
        out.extend(grads.get(b.as_tensor()).unwrap().to_vec1::<f32>().unwrap());
    }
    out
}

/// The critic regression loss and the actor's DPG loss: fused gradients equal candle's
/// autograd on the same weights and batch, with every kernel this CPU runs, on widths that
/// fill whole vectors (32) and that end in partial ones (20, batch 13).
#[test]
fn fused_gradients_equal_candle_autograd() {
    for kernel in Kernel::ALL.into_iter().filter(|k| k.available()) {
        for (hidden, batch) in [(32, 16), (20, 13)] {
            gradients_equal_candle(kernel, hidden, batch);
        }
    }
}

fn gradients_equal_candle(kernel: Kernel, hidden: usize, batch: usize) {
    let (obs, act) = (3, 2);
    let mut rng = Seeds::new(5).stream(Stream::Init);
    let actor = Mlp::new(
        &[obs, hidden, hidden, act],
        Head::Tanh(vec![0.1, 0.1]),
        &mut rng,
    );
    let critic = Mlp::new(&[obs + act, hidden, hidden, 1], Head::Linear, &mut rng);
    let s = random_vec(batch * obs, 2.0, 1);
    let a = random_vec(batch * act, 0.1, 2);
    let y = random_vec(batch, 1.0, 3);
    let sa: Vec<f32> = (0..batch)
        .flat_map(|i| {
            s[i * obs..(i + 1) * obs]
                .iter()
                .chain(&a[i * act..(i + 1) * act])
        })
        .copied()
        .collect();

    // Critic: L = mean (Q(s, a) − y)².
    let mut ws = Workspace::with_kernel(kernel);
    let q = critic.forward(&sa, batch, &mut ws).to_vec();
    let dq: Vec<f32> = q
        .iter()
        .zip(&y)
        .map(|(q, y)| 2.0 * (q - y) / batch as f32)
        .collect();
    let mut g = vec![0.0; critic.params.len()];
    critic.backward(&mut ws, &dq, Some(&mut g), None);

    let cv = candle_ref::vars(&critic);
    let cm = CandleMlp::from_vars(&critic, &cv);
    let qt = cm.forward(&tensor(&sa, batch, obs + act)).unwrap();
    let loss = (qt - tensor(&y, batch, 1))
        .unwrap()
        .sqr()
        .unwrap()
        .mean_all()
        .unwrap();
    let grads = loss.backward().unwrap();
    let gc = flat_grads(&grads, &cv);
    assert_close(&g, &gc, 1e-4, &format!("critic grad ({})", kernel.name()));

    // Actor: L = −mean Q(s, π(s)), gradient into the actor through the critic.
    let mut wa = Workspace::with_kernel(kernel);
    let pi = actor.forward(&s, batch, &mut wa).to_vec();
    let spi: Vec<f32> = (0..batch)
        .flat_map(|i| {
            s[i * obs..(i + 1) * obs]
                .iter()
                .chain(&pi[i * act..(i + 1) * act])
        })
        .copied()
        .collect();
    let mut wc = Workspace::with_kernel(kernel);
    critic.forward(&spi, batch, &mut wc);
    let mut dsa = vec![0.0; batch * (obs + act)];
    critic.backward(
        &mut wc,
        &vec![-1.0 / batch as f32; batch],
        None,
        Some(&mut dsa),
    );
    let da: Vec<f32> = dsa
        .chunks(obs + act)
        .flat_map(|r| r[obs..].to_vec())
        .collect();
    let mut ga = vec![0.0; actor.params.len()];
    actor.backward(&mut wa, &da, Some(&mut ga), None);

    let av = candle_ref::vars(&actor);
    let am = CandleMlp::from_vars(&actor, &av);
    let st = tensor(&s, batch, obs);
    let pit = am.forward(&st).unwrap();
    let q = cm.forward(&Tensor::cat(&[&st, &pit], 1).unwrap()).unwrap();
    let loss = q.mean_all().unwrap().neg().unwrap();
    let grads = loss.backward().unwrap();
    let gac = flat_grads(&grads, &av);
    assert_close(&ga, &gac, 1e-4, &format!("actor grad ({})", kernel.name()));
}

/// Five Adam steps on the critic loss: our Adam and candle's AdamW with weight decay 0 end
/// at the same parameters.
#[test]
fn adam_steps_equal_candle_adamw_without_decay() {
    let (inp, batch) = (4, 8);
    let mut rng = Seeds::new(6).stream(Stream::Init);
    let mut critic = Mlp::new(&[inp, 16, 1], Head::Linear, &mut rng);
    let x = random_vec(batch * inp, 1.0, 4);
    let y = random_vec(batch, 1.0, 5);
    let cv = candle_ref::vars(&critic);
    let flat: Vec<_> = cv
        .iter()
        .flat_map(|(w, b)| [w.clone(), b.clone()])
        .collect();
    let mut copt = candle_nn::AdamW::new(
        flat,
        candle_nn::ParamsAdamW {
            lr: 1e-2,
            weight_decay: 0.0,
            ..Default::default()
        },
    )
    .unwrap();
    let mut adam = Adam::new(
        critic.params.len(),
        1e-2,
        pbcs::nn::kernel::Kernel::detect(),
    );
    let mut ws = Workspace::with_kernel(pbcs::nn::kernel::Kernel::detect());
    let mut g = vec![0.0; critic.params.len()];
    for _ in 0..5 {
        let q = critic.forward(&x, batch, &mut ws).to_vec();
        let dq: Vec<f32> = q
            .iter()
            .zip(&y)
            .map(|(q, y)| 2.0 * (q - y) / batch as f32)
            .collect();
        critic.backward(&mut ws, &dq, Some(&mut g), None);
        adam.step(&mut critic.params, &g);

        let cm = CandleMlp::from_vars(&critic, &cv);
        let loss = (cm.forward(&tensor(&x, batch, inp)).unwrap() - tensor(&y, batch, 1))
            .unwrap()
            .sqr()
            .unwrap()
            .mean_all()
            .unwrap();
        copt.backward_step(&loss).unwrap();
    }
    assert_close(
        &critic.params,
        &candle_ref::params_from_vars(&cv),
        1e-4,
        "params after 5 steps",
    );
}

#[test]
fn adam_flushes_subnormal_moments() {
    let mut adam = Adam::new(1, 1e-3, pbcs::nn::kernel::Kernel::detect());
    let mut p = [0.0f32];
    adam.step(&mut p, &[1e-30]);
    for _ in 0..20_000 {
        adam.step(&mut p, &[0.0]);
    }
    assert_eq!(adam.subnormal_moments(), 0);
}

#[test]
fn save_and_load_round_trip_and_bad_files_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = Seeds::new(7).stream(Stream::Init);
    let actor = Mlp::new(&[2, 8, 2], Head::Tanh(vec![0.1, 0.1]), &mut rng);
    let path = dir.path().join("actor.safetensors");
    actor.save(&path).unwrap();
    let mut other = Mlp::new(&[2, 8, 2], Head::Tanh(vec![0.1, 0.1]), &mut rng);
    assert_ne!(other.params, actor.params);
    other.load(&path).unwrap();
    assert_eq!(other.params, actor.params);

    // Mismatched shape.
    let mut wider = Mlp::new(&[2, 9, 2], Head::Tanh(vec![0.1, 0.1]), &mut rng);
    let msg = wider.load(&path).unwrap_err().to_string();
    assert!(
        msg.contains("actor.safetensors") && msg.contains("l0.weight"),
        "{msg}"
    );
    // Missing layer.
    let mut deeper = Mlp::new(&[2, 8, 8, 2], Head::Tanh(vec![0.1, 0.1]), &mut rng);
    let msg = deeper.load(&path).unwrap_err().to_string();
    assert!(
        msg.contains("missing") || msg.contains("l1.weight"),
        "{msg}"
    );
    // Corrupt file.
    let corrupt = dir.path().join("corrupt.safetensors");
    std::fs::write(&corrupt, b"this is not a safetensors file").unwrap();
    let msg = other.load(&corrupt).unwrap_err().to_string();
    assert!(
        msg.contains("corrupt.safetensors") && msg.contains("safetensors"),
        "{msg}"
    );
    // Missing file.
    let msg = other
        .load(&dir.path().join("none.safetensors"))
        .unwrap_err()
        .to_string();
    assert!(msg.contains("none.safetensors"), "{msg}");
}

/// A saved policy with a NaN or infinite weight is refused on load, naming the file.
#[test]
fn loading_non_finite_weights_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("p.safetensors");
    let mut rng = Seeds::new(1).stream(Stream::Init);
    let mut net = Mlp::new(&[2, 8, 2], Head::Tanh(vec![1.0, 1.0]), &mut rng);
    net.params[5] = f32::NAN;
    net.save(&path).unwrap();
    let mut fresh = Mlp::new(&[2, 8, 2], Head::Tanh(vec![1.0, 1.0]), &mut rng);
    let e = fresh.load(&path).unwrap_err().to_string();
    assert!(
        e.contains("p.safetensors") && e.contains("not finite"),
        "{e}"
    );
}
