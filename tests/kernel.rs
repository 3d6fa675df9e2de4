//! The layer kernels against naive loops written in the order the kernels promise, against
//! each other, and whole learner updates across kernels.
//!
//! The AVX-512 and AVX2 kernels must equal the naive loop with fused multiply-adds bit for
//! bit, the portable kernel the naive loop with separate roundings bit for bit; the
//! matrixmultiply kernel sums in its own order and is held to a float tolerance. Tests of a
//! kernel this CPU cannot run are skipped (each says so on stderr).

use pbcs::learner::replay::Batch;
use pbcs::learner::td3::{Td3, Td3Config};
use pbcs::nn::kernel::{transpose, Kernel, Matrix, Post};
use pbcs::rng::{Seeds, Stream};
use proptest::prelude::*;
use rand::Rng;

fn kernels() -> Vec<Kernel> {
    let (run, skip): (Vec<Kernel>, Vec<Kernel>) =
        Kernel::ALL.into_iter().partition(|k| k.available());
    for k in skip {
        eprintln!("skipped: this CPU cannot run the {} kernel", k.name());
    }
    run
}

/// a·b + c as the kernel rounds it.
fn madd(kernel: Kernel, a: f32, b: f32, c: f32) -> f32 {
    match kernel {
        Kernel::Avx2 | Kernel::Avx512 => a.mul_add(b, c),
        _ => a * b + c,
    }
}

fn epilogue(y: f32, bias: Option<&[f32]>, j: usize, mask: Option<f32>, relu: bool) -> f32 {
    let mut y = y;
    if let Some(b) = bias {
        y += b[j];
    }
    if relu {
        y = if y > 0.0 { y } else { 0.0 };
    }
    if let Some(m) = mask {
        if m <= 0.0 {
            y = 0.0;
        }
    }
    y
}

/// The naive C = A·B (A with strides), in the promised order.
#[allow(clippy::too_many_arguments)]
fn naive_nn(
    kernel: Kernel,
    (m, k, n): (usize, usize, usize),
    a: &[f32],
    (rsa, csa): (usize, usize),
    b: &[f32],
    bias: Option<&[f32]>,
    mask: Option<&[f32]>,
    relu: bool,
) -> Vec<f32> {
    let mut c = vec![0.0; m * n];
    for i in 0..m {
        for j in 0..n {
            let mut acc = 0.0f32;
            for kk in 0..k {
                acc = madd(kernel, a[i * rsa + kk * csa], b[kk * n + j], acc);
            }
            c[i * n + j] = epilogue(acc, bias, j, mask.map(|m| m[i * n + j]), relu);
        }
    }
    c
}

/// The naive C = A·Bᵀ: sixteen partial sums by k mod 16, then the tree 8, 4, 2, 1.
fn naive_nt(
    kernel: Kernel,
    (m, k, n): (usize, usize, usize),
    a: &[f32],
    b: &[f32],
    bias: Option<&[f32]>,
    mask: Option<&[f32]>,
    relu: bool,
) -> Vec<f32> {
    let mut c = vec![0.0; m * n];
    for i in 0..m {
        for j in 0..n {
            let mut lanes = [0.0f32; 16];
            for kk in 0..k {
                lanes[kk % 16] = madd(kernel, a[i * k + kk], b[j * k + kk], lanes[kk % 16]);
            }
            for w in [8, 4, 2, 1] {
                for l in 0..w {
                    lanes[l] += lanes[l + w];
                }
            }
            c[i * n + j] = epilogue(lanes[0], bias, j, mask.map(|m| m[i * n + j]), relu);
        }
    }
    c
}

fn random(n: usize, seed: u32) -> Vec<f32> {
    let mut rng = Seeds::new(11).substream(Stream::Replay, seed);
    // Some exact zeros and negatives, so ReLU and the mask both bite.
    (0..n)
        .map(|_| {
            if rng.random_range(0..8) == 0 {
                0.0
            } else {
                rng.random_range(-2.0f32..2.0)
            }
        })
        .collect()
}

fn check(kernel: Kernel, got: &[f32], want: &[f32], what: &str) {
    if kernel == Kernel::Matrixmultiply {
        for (i, (x, y)) in got.iter().zip(want).enumerate() {
            assert!(
                (x - y).abs() <= 1e-4 * (1.0 + y.abs()),
                "{what} [{}][{i}]: {x} vs {y}",
                kernel.name()
            );
        }
    } else {
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(got), bits(want), "{what} [{}]", kernel.name());
    }
}

/// An epilogue: bias, mask, ReLU.
type Epilogue = (Option<Vec<f32>>, Option<Vec<f32>>, bool);

/// Every epilogue: none, bias, bias + ReLU, mask.
fn epilogues(m: usize, n: usize, seed: u32) -> Vec<Epilogue> {
    vec![
        (None, None, false),
        (Some(random(n, seed + 1)), None, false),
        (Some(random(n, seed + 2)), None, true),
        (None, Some(random(m * n, seed + 3)), false),
    ]
}

fn gemm_nn_matches_naive(m: usize, k: usize, n: usize, transposed_a: bool, seed: u32) {
    let a = random(m * k, seed);
    let b = random(k * n, seed + 10);
    let strides = if transposed_a { (1, m) } else { (k, 1) };
    for kernel in kernels() {
        for (bias, mask, relu) in epilogues(m, n, seed) {
            let post = match (&mask, relu) {
                (Some(m), _) => Post::KeepWherePositive(m),
                (None, true) => Post::Relu,
                _ => Post::Identity,
            };
            let mut c = vec![f32::NAN; m * n];
            let (a_m, b_m) = (Matrix::strided(&a, strides), Matrix::rows(&b, n));
            kernel.gemm_nn((m, k, n), a_m, b_m, &mut c, bias.as_deref(), post);
            let want = naive_nn(
                kernel,
                (m, k, n),
                &a,
                strides,
                &b,
                bias.as_deref(),
                mask.as_deref(),
                relu,
            );
            check(
                kernel,
                &c,
                &want,
                &format!("gemm_nn {m}×{k}×{n} t={transposed_a}"),
            );
        }
    }
}

fn gemm_nt_matches_naive(m: usize, k: usize, n: usize, seed: u32) {
    let a = random(m * k, seed);
    let b = random(n * k, seed + 10);
    for kernel in kernels() {
        for (bias, mask, relu) in epilogues(m, n, seed) {
            let post = match (&mask, relu) {
                (Some(m), _) => Post::KeepWherePositive(m),
                (None, true) => Post::Relu,
                _ => Post::Identity,
            };
            let mut c = vec![f32::NAN; m * n];
            let (a_m, b_m) = (Matrix::rows(&a, k), Matrix::rows(&b, k));
            kernel.gemm_nt((m, k, n), a_m, b_m, &mut c, bias.as_deref(), post);
            let want = naive_nt(
                kernel,
                (m, k, n),
                &a,
                &b,
                bias.as_deref(),
                mask.as_deref(),
                relu,
            );
            check(kernel, &c, &want, &format!("gemm_nt {m}×{k}×{n}"));
        }
    }
}

/// The shapes PBCS uses (batch 64/256, widths 2, 4, 64, 256) and ones that end in partial
/// vectors and partial register tiles.
#[test]
fn gemm_nn_equals_the_naive_loop_on_the_shapes_pbcs_uses() {
    for (m, k, n) in [
        (64, 2, 64),
        (64, 4, 64),
        (64, 64, 64),
        (64, 64, 2),
        (256, 256, 256),
        (64, 256, 256),
    ] {
        gemm_nn_matches_naive(m, k, n, false, 1);
        gemm_nn_matches_naive(m, k, n, true, 2);
    }
}

#[test]
fn gemm_nt_equals_the_naive_loop_on_the_shapes_pbcs_uses() {
    for (m, k, n) in [
        (64, 64, 1),
        (64, 64, 2),
        (64, 64, 4),
        (256, 256, 2),
        (64, 16, 4),
        (3, 17, 2),
    ] {
        gemm_nt_matches_naive(m, k, n, 3);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn gemm_nn_equals_the_naive_loop(m in 1usize..20, k in 0usize..40, n in 1usize..80, t: bool, seed in 0u32..1000) {
        gemm_nn_matches_naive(m, k, n, t, seed);
    }

    #[test]
    fn gemm_nt_equals_the_naive_loop(m in 1usize..12, k in 0usize..70, n in 1usize..10, seed in 0u32..1000) {
        gemm_nt_matches_naive(m, k, n, seed);
    }

    #[test]
    fn transpose_swaps_indices(rows in 1usize..40, cols in 1usize..40) {
        let src: Vec<f32> = (0..rows * cols).map(|i| i as f32).collect();
        let mut want = vec![0.0; rows * cols];
        for i in 0..rows {
            for j in 0..cols {
                want[j * rows + i] = src[i * cols + j];
            }
        }
        let mut dst = vec![0.0; rows * cols];
        transpose(rows, cols, &src, &mut dst);
        prop_assert_eq!(&dst, &want);
        for kernel in kernels() {
            dst.fill(-1.0);
            kernel.transpose(rows, cols, &src, &mut dst);
            prop_assert_eq!(&dst, &want, "{}", kernel.name());
        }
    }

    /// Bias gradients: each column summed over the rows in order, in every kernel.
    #[test]
    fn column_sums_add_rows_in_order(rows in 1usize..70, cols in 1usize..150, seed in 0u32..1000) {
        let m = random(rows * cols, seed);
        let want: Vec<f32> = (0..cols)
            .map(|j| (0..rows).fold(0.0f32, |s, i| s + m[i * cols + j]))
            .collect();
        for kernel in kernels() {
            let mut out = vec![f32::NAN; cols];
            kernel.column_sums(&m, cols, &mut out);
            check(Kernel::Portable, &out, &want, &format!("column sums [{}]", kernel.name()));
        }
    }
}

fn batch(n: usize, seed: u32) -> Batch {
    let mut rng = Seeds::new(3).substream(Stream::Replay, seed);
    let mut v =
        |len: usize, s: f32| -> Vec<f32> { (0..len).map(|_| rng.random_range(-s..s)).collect() };
    Batch {
        len: n,
        obs: v(n * 2, 3.0),
        act: v(n * 2, 1.0),
        rew: v(n, 1.0),
        next_obs: v(n * 2, 3.0),
        done: (0..n).map(|i| (i % 7 == 0) as u8 as f32).collect(),
    }
}

/// Parameters of actor and critics after `updates` updates with `kernel`.
fn trained(kernel: Kernel, config: &Td3Config, updates: u32) -> Vec<f32> {
    let mut l = Td3::new(
        config,
        2,
        &[1.0, 1.0],
        &Seeds::new(7),
        pbcs::nn::kernel::Kernel::detect(),
    )
    .unwrap();
    l.set_kernel(kernel);
    for i in 0..updates {
        l.update(&batch(config.batch_size, i));
    }
    let mut p = l.actor.params.clone();
    for c in &l.critics {
        p.extend(&c.params);
    }
    p
}

/// A learner switched to a kernel (`set_kernel`) is, bit for bit, the learner built on it:
/// every product, Adam step and soft update runs there, and `kernel()` says so.
#[test]
fn a_learner_switched_to_a_kernel_equals_one_built_on_it() {
    let config = Td3Config {
        hidden: vec![24, 40],
        batch_size: 37,
        ..Td3Config::td3()
    };
    for kernel in kernels() {
        let mut built = Td3::new(&config, 2, &[1.0, 1.0], &Seeds::new(7), kernel).unwrap();
        assert_eq!(built.kernel(), kernel);
        for i in 0..20 {
            built.update(&batch(config.batch_size, i));
        }
        // (the targets are private: their soft updates show in the critics' next updates)
        let params = |l: &Td3| -> Vec<f32> {
            let mut p = l.actor.params.clone();
            l.critics.iter().for_each(|c| p.extend(&c.params));
            p
        };
        let p = params(&built);
        let mut switched =
            Td3::new(&config, 2, &[1.0, 1.0], &Seeds::new(7), Kernel::detect()).unwrap();
        switched.set_kernel(kernel);
        assert_eq!(switched.kernel(), kernel, "{}", kernel.name());
        for i in 0..20 {
            switched.update(&batch(config.batch_size, i));
        }
        let q = params(&switched);
        assert!(
            p.iter().zip(&q).all(|(a, b)| a.to_bits() == b.to_bits()),
            "{}: a switched learner differs from a built one",
            kernel.name()
        );
    }
}

/// The AVX-512 and AVX2 kernels give the same bytes for whole DDPG and TD3 updates (so a run's
/// CSVs do not depend on which of the two a machine has); the portable kernel agrees up to
/// rounding.
#[test]
fn learner_updates_do_not_depend_on_the_kernel() {
    for config in [
        Td3Config {
            hidden: vec![64, 64],
            ..Td3Config::ddpg()
        },
        Td3Config {
            hidden: vec![24, 40],
            batch_size: 37,
            ..Td3Config::td3()
        },
    ] {
        let reference = trained(Kernel::Portable, &config, 30);
        let mut fma: Option<Vec<f32>> = None;
        for kernel in kernels() {
            let p = trained(kernel, &config, 30);
            for (x, y) in p.iter().zip(&reference) {
                assert!(
                    (x - y).abs() <= 1e-3 * (1.0 + y.abs()),
                    "{}: {x} vs {y}",
                    kernel.name()
                );
            }
            if matches!(kernel, Kernel::Avx2 | Kernel::Avx512) {
                if let Some(f) = &fma {
                    assert!(
                        f.iter().zip(&p).all(|(a, b)| a.to_bits() == b.to_bits()),
                        "AVX2 and AVX-512 differ"
                    );
                }
                fma = Some(p);
            }
        }
    }
}

#[test]
fn kernel_names_parse_and_bad_ones_are_clear_errors() {
    for k in kernels() {
        assert_eq!(Kernel::parse(k.name()).unwrap(), k);
    }
    assert_eq!(Kernel::parse("auto").unwrap(), Kernel::detect());
    let e = Kernel::parse("avx9000").unwrap_err().to_string();
    assert!(
        e.contains("PBCS_KERNEL") && e.contains("avx9000") && e.contains("portable"),
        "{e}"
    );
    for k in Kernel::ALL.into_iter().filter(|k| !k.available()) {
        let e = Kernel::parse(k.name()).unwrap_err().to_string();
        assert!(e.contains("cannot run"), "{e}");
    }
}
