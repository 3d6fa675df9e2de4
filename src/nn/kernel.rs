//! The arithmetic of a dense layer on whichever SIMD unit this CPU has.
//!
//! A learner update is ten or so small matrix products (batch 64–256, widths 2–256) plus a few
//! element-wise loops, once per environment step. This module does them without packing
//! operands, without allocating, and with bias, ReLU and ReLU-mask fused into the product's
//! epilogue. A [`Kernel`] is one implementation of these operations:
//!
//! | kernel | where | arithmetic |
//! | --- | --- | --- |
//! | [`Kernel::Avx512`] | x86-64 with AVX-512F | fused multiply-add, the order below |
//! | [`Kernel::Avx2`] | x86-64 with AVX2 and FMA | the same, bit for bit |
//! | [`Kernel::Portable`] | everywhere | plain `a·b + c` (two roundings), same order |
//! | [`Kernel::Matrixmultiply`] | everywhere | the `matrixmultiply` crate (the package's earlier path) |
//!
//! The best available kernel is chosen at run time ([`Kernel::detect`]); the environment
//! variable `PBCS_KERNEL` (`auto`, `avx512`, `avx2`, `portable`, `matrixmultiply`) overrides
//! it ([`Kernel::from_env`]).
//!
//! **The order of the arithmetic is part of the contract**, so that which SIMD unit ran does
//! not change a single bit of a result: the AVX-512 and AVX2 kernels give identical bytes
//! (tested), and each equals a naive loop written with [`f32::mul_add`] in this order:
//! - [`Kernel::gemm_nn`], C = A·B: every C\[i, j\] starts at +0, takes one fused multiply-add
//!   per k in increasing k, then + bias\[j\], then the epilogue ([`Post`]).
//! - [`Kernel::gemm_nt`], C = A·Bᵀ (a dot product per output): sixteen partial sums, sum l
//!   taking the k ≡ l (mod 16) in increasing k, then added as a tree (8, 4, 2, 1 apart),
//!   then + bias\[j\], then the epilogue.
//! - Element-wise loops (Adam, Polyak averaging, bias gradients) are the same scalar
//!   expressions in every kernel (Rust does not contract `a * b + c` into an FMA), so they
//!   agree bit for bit too (matrixmultiply keeps the earlier Adam expression: [`Kernel::adam`]).
//!
//! The portable kernel rounds each product separately (an FMA in software would be two orders
//! of magnitude slower), so its results differ from the SIMD kernels' by float rounding only
//! (tested against the naive loop without FMA, bit for bit, and against candle's autograd).
//! `matrixmultiply` sums in its own blocked order; it reproduces results computed before this
//! module existed (the committed `results/` of issue 9 and earlier).
//!
//! ```
//! use pbcs::nn::kernel::{Kernel, Post};
//!
//! // C (2 × 3) = A (2 × 2) · B (2 × 3) + bias, then ReLU.
//! let a = [1.0, 2.0, 3.0, 4.0];
//! let b = [1.0, 0.0, -1.0, 0.0, 1.0, -1.0];
//! let mut c = [0.0; 6];
//! let k = Kernel::detect();
//! k.gemm_nn(2, 2, 3, &a, (2, 1), &b, 3, &mut c, Some(&[0.5, 0.5, 0.5]), Post::Relu);
//! assert_eq!(c, [1.5, 2.5, 0.0, 3.5, 4.5, 0.0]);
//! ```

use crate::error::{Error, Result};
use std::sync::atomic::{AtomicU8, Ordering};

/// One implementation of the layer arithmetic (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Kernel {
    /// Plain Rust loops (the compiler vectorises what it can for the baseline target).
    Portable,
    /// The `matrixmultiply` crate plus separate element-wise loops: the earlier path.
    Matrixmultiply,
    /// 8-lane AVX2 with FMA (x86-64).
    Avx2,
    /// 16-lane AVX-512F (x86-64).
    Avx512,
}

/// What happens to each output value after its bias.
#[derive(Debug, Clone, Copy)]
pub enum Post<'a> {
    /// Nothing.
    Identity,
    /// max(v, 0) (a NaN becomes 0, as `maxps` does).
    Relu,
    /// 0 where the same element of this matrix (laid out as C) is ≤ 0, else v: the
    /// derivative of the ReLU that produced it.
    KeepWherePositive(&'a [f32]),
}

/// Runs an element-wise body compiled for the kernel's instruction set (the body is plain
/// Rust; the compiler vectorises it at that width without changing its results).
macro_rules! elementwise {
    ($k:expr, $body:ident($($arg:expr),*)) => {{
        $k.check_available();
        match $k {
            #[cfg(target_arch = "x86_64")]
            // SAFETY: `check_available` verified the instruction set.
            Kernel::Avx512 => unsafe { x86::avx512_elementwise(|| $body($($arg),*)) },
            #[cfg(target_arch = "x86_64")]
            // SAFETY: as above.
            Kernel::Avx2 => unsafe { x86::avx2_elementwise(|| $body($($arg),*)) },
            _ => $body($($arg),*),
        }
    }};
}

const UNSET: u8 = u8::MAX;
static ACTIVE: AtomicU8 = AtomicU8::new(UNSET);

impl Kernel {
    /// Every kernel, in the order the bench prints them.
    pub const ALL: [Kernel; 4] = [
        Kernel::Portable,
        Kernel::Matrixmultiply,
        Kernel::Avx2,
        Kernel::Avx512,
    ];

    /// The spelling in `PBCS_KERNEL` and in `timing.toml`.
    pub fn name(self) -> &'static str {
        match self {
            Kernel::Portable => "portable",
            Kernel::Matrixmultiply => "matrixmultiply",
            Kernel::Avx2 => "avx2",
            Kernel::Avx512 => "avx512",
        }
    }

    /// Whether the kernels named `a` and `b` (as in `timing.toml`) compute the same bytes:
    /// the same kernel, or AVX2 and AVX-512, which sum in the same order (`tests/kernel.rs`).
    pub fn same_bytes(a: &str, b: &str) -> bool {
        let fma = |k: &str| k == Kernel::Avx2.name() || k == Kernel::Avx512.name();
        a == b || (fma(a) && fma(b))
    }

    /// Whether this CPU can run the kernel.
    pub fn available(self) -> bool {
        match self {
            Kernel::Portable | Kernel::Matrixmultiply => true,
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 => is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"),
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 => is_x86_feature_detected!("avx512f"),
            #[cfg(not(target_arch = "x86_64"))]
            Kernel::Avx2 | Kernel::Avx512 => false,
        }
    }

    /// The fastest kernel this CPU can run: AVX-512, else AVX2, else portable.
    pub fn detect() -> Kernel {
        [Kernel::Avx512, Kernel::Avx2]
            .into_iter()
            .find(|k| k.available())
            .unwrap_or(Kernel::Portable)
    }

    /// The kernel `PBCS_KERNEL` names (`auto` or unset: [`Kernel::detect`]). An unknown name,
    /// or a kernel this CPU cannot run, is an error naming the variable.
    pub fn from_env() -> Result<Kernel> {
        match std::env::var("PBCS_KERNEL") {
            Err(std::env::VarError::NotPresent) => Ok(Kernel::detect()),
            Err(std::env::VarError::NotUnicode(_)) => Err(Error::invalid(
                "PBCS_KERNEL",
                "is not valid UTF-8; use auto, avx512, avx2, portable or matrixmultiply",
            )),
            Ok(s) => Kernel::parse(&s),
        }
    }

    /// Parses a kernel name (`auto` → [`Kernel::detect`]) and checks this CPU can run it.
    pub fn parse(s: &str) -> Result<Kernel> {
        let s = s.trim();
        if s.is_empty() || s == "auto" {
            return Ok(Kernel::detect());
        }
        let k = Kernel::ALL
            .into_iter()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                Error::invalid(
                    "PBCS_KERNEL",
                    format!(
                        "unknown kernel {s:?}; use auto, avx512, avx2, portable or matrixmultiply"
                    ),
                )
            })?;
        if !k.available() {
            return Err(Error::invalid(
                "PBCS_KERNEL",
                format!("this CPU cannot run the {s} kernel"),
            ));
        }
        Ok(k)
    }

    /// The kernel new networks' workspaces and optimisers use: the one set by
    /// [`Kernel::set_active`], else `PBCS_KERNEL`, else [`Kernel::detect`].
    ///
    /// # Panics
    /// If `PBCS_KERNEL` is invalid and no kernel was set (the `pbcs` binary checks the
    /// variable first and reports the error instead).
    pub fn active() -> Kernel {
        match ACTIVE.load(Ordering::Relaxed) {
            UNSET => {
                let k = Kernel::from_env().unwrap_or_else(|e| panic!("{e}"));
                ACTIVE.store(k as u8, Ordering::Relaxed);
                k
            }
            i => Kernel::ALL[Kernel::ALL.iter().position(|k| *k as u8 == i).unwrap()],
        }
    }

    /// Makes `self` the kernel of networks created from now on (errors if this CPU cannot run
    /// it).
    pub fn set_active(self) -> Result<()> {
        if !self.available() {
            return Err(Error::invalid(
                "PBCS_KERNEL",
                format!("this CPU cannot run the {} kernel", self.name()),
            ));
        }
        ACTIVE.store(self as u8, Ordering::Relaxed);
        Ok(())
    }

    fn check_available(self) {
        assert!(
            self.available(),
            "the {} kernel does not run on this CPU",
            self.name()
        );
    }

    /// C (m × n, row-major, row stride `ldc`) = A·B + bias, then `post`. A is m × k with
    /// strides `(rsa, csa)` (so Aᵀ of a row-major matrix is `(1, cols)`), B is k × n
    /// row-major with row stride `ldb`, `bias` has n values, a `KeepWherePositive` matrix is
    /// laid out as C.
    ///
    /// # Panics
    /// If an operand is too short for its shape, or this CPU cannot run the kernel.
    #[allow(clippy::too_many_arguments)]
    pub fn gemm_nn(
        self,
        m: usize,
        k: usize,
        n: usize,
        a: &[f32],
        (rsa, csa): (usize, usize),
        b: &[f32],
        ldb: usize,
        c: &mut [f32],
        bias: Option<&[f32]>,
        post: Post,
    ) {
        let ldc = n;
        if m == 0 || n == 0 {
            return;
        }
        assert!(
            k == 0 || a.len() > (m - 1) * rsa + (k - 1) * csa,
            "gemm_nn: A too short"
        );
        assert!(
            k == 0 || b.len() >= (k - 1) * ldb + n,
            "gemm_nn: B too short"
        );
        assert!(ldb >= n, "gemm_nn: ldb < n");
        check_epilogue(m, n, ldc, c, bias, post);
        self.check_available();
        let p = Raw::new(a, b, c, bias, post);
        match self {
            Kernel::Portable => unsafe {
                // SAFETY: the asserts above keep every index the generic kernel reads or
                // writes inside the slices.
                generic::gemm_nn::<Portable>(
                    m, k, n, p.a, rsa, csa, p.b, ldb, p.c, ldc, p.bias, p.post,
                )
            },
            Kernel::Matrixmultiply => {
                // SAFETY: as above; sgemm reads A and B and writes C within the asserted
                // bounds.
                unsafe {
                    matrixmultiply::sgemm(
                        m,
                        k,
                        n,
                        1.0,
                        p.a,
                        rsa as isize,
                        csa as isize,
                        p.b,
                        ldb as isize,
                        1,
                        0.0,
                        p.c,
                        ldc as isize,
                        1,
                    );
                }
                scalar_epilogue(m, n, ldc, c, bias, post);
            }
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 => unsafe {
                // SAFETY: bounds as above; `check_available` verified AVX2 and FMA.
                x86::gemm_nn_avx2(m, k, n, p.a, rsa, csa, p.b, ldb, p.c, ldc, p.bias, p.post)
            },
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 => unsafe {
                // SAFETY: bounds as above; `check_available` verified AVX-512F.
                x86::gemm_nn_avx512(m, k, n, p.a, rsa, csa, p.b, ldb, p.c, ldc, p.bias, p.post)
            },
            #[cfg(not(target_arch = "x86_64"))]
            Kernel::Avx2 | Kernel::Avx512 => unreachable!(),
        }
    }

    /// C (m × n, row-major) = A·Bᵀ + bias, then `post`: C\[i, j\] is the dot product of row i
    /// of A (m × k, row stride `lda`) and row j of B (n × k, row stride `ldb`). For outputs
    /// only a few columns wide, where [`Kernel::gemm_nn`] would waste its vector lanes.
    ///
    /// # Panics
    /// As [`Kernel::gemm_nn`].
    #[allow(clippy::too_many_arguments)]
    pub fn gemm_nt(
        self,
        m: usize,
        k: usize,
        n: usize,
        a: &[f32],
        lda: usize,
        b: &[f32],
        ldb: usize,
        c: &mut [f32],
        bias: Option<&[f32]>,
        post: Post,
    ) {
        let ldc = n;
        if m == 0 || n == 0 {
            return;
        }
        assert!(lda >= k && ldb >= k, "gemm_nt: row stride shorter than k");
        assert!(a.len() >= (m - 1) * lda + k, "gemm_nt: A too short");
        assert!(b.len() >= (n - 1) * ldb + k, "gemm_nt: B too short");
        check_epilogue(m, n, ldc, c, bias, post);
        self.check_available();
        let p = Raw::new(a, b, c, bias, post);
        match self {
            Kernel::Portable => unsafe {
                // SAFETY: the asserts above bound every index.
                generic::gemm_nt::<Portable, 2>(
                    m, k, n, p.a, lda, p.b, ldb, p.c, ldc, p.bias, p.post,
                )
            },
            Kernel::Matrixmultiply => {
                // SAFETY: as above; Bᵀ is B read with strides (1, ldb).
                unsafe {
                    matrixmultiply::sgemm(
                        m,
                        k,
                        n,
                        1.0,
                        p.a,
                        lda as isize,
                        1,
                        p.b,
                        1,
                        ldb as isize,
                        0.0,
                        p.c,
                        ldc as isize,
                        1,
                    );
                }
                scalar_epilogue(m, n, ldc, c, bias, post);
            }
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 => unsafe {
                // SAFETY: bounds as above; AVX2 and FMA verified.
                x86::gemm_nt_avx2(m, k, n, p.a, lda, p.b, ldb, p.c, ldc, p.bias, p.post)
            },
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 => unsafe {
                // SAFETY: bounds as above; AVX-512F verified.
                x86::gemm_nt_avx512(m, k, n, p.a, lda, p.b, ldb, p.c, ldc, p.bias, p.post)
            },
            #[cfg(not(target_arch = "x86_64"))]
            Kernel::Avx2 | Kernel::Avx512 => unreachable!(),
        }
    }

    /// One dense layer forward: Y (batch × fan_out) = X·W + b, then ReLU if `relu`. W is
    /// fan_in × fan_out row-major. `scratch` holds Wᵀ when the output is too narrow for
    /// vector lanes.
    #[allow(clippy::too_many_arguments)]
    pub fn dense_forward(
        self,
        x: &[f32],
        w: &[f32],
        b: &[f32],
        (batch, fan_in, fan_out): (usize, usize, usize),
        relu: bool,
        y: &mut [f32],
        scratch: &mut Vec<f32>,
    ) {
        let post = if relu { Post::Relu } else { Post::Identity };
        if fan_out < NARROW && self != Kernel::Matrixmultiply {
            let wt = room(scratch, fan_in * fan_out);
            self.transpose(fan_in, fan_out, w, wt);
            self.gemm_nt(
                batch,
                fan_in,
                fan_out,
                x,
                fan_in,
                wt,
                fan_in,
                y,
                Some(b),
                post,
            );
        } else {
            self.gemm_nn(
                batch,
                fan_in,
                fan_out,
                x,
                (fan_in, 1),
                w,
                fan_out,
                y,
                Some(b),
                post,
            );
        }
    }

    /// A dense layer's parameter gradients: ∂W (fan_in × fan_out) = Xᵀ·δ and ∂b = Σ_rows δ.
    #[allow(clippy::too_many_arguments)]
    pub fn dense_param_grad(
        self,
        x: &[f32],
        delta: &[f32],
        (batch, fan_in, fan_out): (usize, usize, usize),
        gw: &mut [f32],
        gb: &mut [f32],
        scratch: &mut Vec<f32>,
    ) {
        if fan_out < NARROW && fan_in >= NARROW && self != Kernel::Matrixmultiply {
            // ∂Wᵀ (fan_out × fan_in) = δᵀ·X has wide rows; transpose it back.
            let gwt = room(scratch, fan_out * fan_in);
            self.gemm_nn(
                fan_out,
                batch,
                fan_in,
                delta,
                (1, fan_out),
                x,
                fan_in,
                gwt,
                None,
                Post::Identity,
            );
            self.transpose(fan_out, fan_in, gwt, gw);
        } else {
            self.gemm_nn(
                fan_in,
                batch,
                fan_out,
                x,
                (1, fan_in),
                delta,
                fan_out,
                gw,
                None,
                Post::Identity,
            );
        }
        self.column_sums(delta, fan_out, gb);
    }

    /// A dense layer's input gradient: ∂X (batch × fan_in) = δ·Wᵀ, zeroed where `below` (the
    /// previous layer's ReLU output, batch × fan_in) is ≤ 0.
    #[allow(clippy::too_many_arguments)]
    pub fn dense_input_grad(
        self,
        delta: &[f32],
        w: &[f32],
        (batch, fan_in, fan_out): (usize, usize, usize),
        below: Option<&[f32]>,
        dx: &mut [f32],
        scratch: &mut Vec<f32>,
    ) {
        let post = below.map_or(Post::Identity, Post::KeepWherePositive);
        if self == Kernel::Matrixmultiply {
            // δ·Wᵀ with W read through strides: no transpose.
            assert!(w.len() >= fan_in * fan_out && delta.len() >= batch * fan_out);
            assert!(dx.len() >= batch * fan_in);
            // SAFETY: the asserts bound every index sgemm touches.
            unsafe {
                matrixmultiply::sgemm(
                    batch,
                    fan_out,
                    fan_in,
                    1.0,
                    delta.as_ptr(),
                    fan_out as isize,
                    1,
                    w.as_ptr(),
                    1,
                    fan_out as isize,
                    0.0,
                    dx.as_mut_ptr(),
                    fan_in as isize,
                    1,
                );
            }
            scalar_epilogue(batch, fan_in, fan_in, dx, None, post);
        } else if fan_in < NARROW {
            // Rows of δ against rows of W: dot products, no transpose.
            self.gemm_nt(
                batch, fan_out, fan_in, delta, fan_out, w, fan_out, dx, None, post,
            );
        } else {
            let wt = room(scratch, fan_in * fan_out);
            self.transpose(fan_in, fan_out, w, wt);
            self.gemm_nn(
                batch,
                fan_out,
                fan_in,
                delta,
                (fan_out, 1),
                wt,
                fan_in,
                dx,
                None,
                post,
            );
        }
    }

    /// `dst` (cols × rows) = `src` (rows × cols)ᵀ, both row-major (8 × 8 blocks in AVX
    /// registers on x86-64 kernels; a copy, so every kernel gives the same bytes).
    pub fn transpose(self, rows: usize, cols: usize, src: &[f32], dst: &mut [f32]) {
        assert!(src.len() >= rows * cols, "transpose: source too short");
        assert!(dst.len() >= rows * cols, "transpose: destination too short");
        match self {
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 | Kernel::Avx512 => {
                self.check_available();
                // SAFETY: AVX (implied by both) verified; the asserts bound every index.
                unsafe { x86::transpose_avx(rows, cols, src.as_ptr(), dst.as_mut_ptr()) }
            }
            _ => transpose(rows, cols, src, dst),
        }
    }

    /// `out[j] = Σ_rows m[row][j]` for a row-major matrix of `cols` columns, summed in row
    /// order (the bias gradient).
    pub fn column_sums(self, m: &[f32], cols: usize, out: &mut [f32]) {
        assert_eq!(out.len(), cols, "column_sums: output width");
        elementwise!(self, column_sums_body(m, cols, out))
    }

    /// One Adam step over all parameters (see [`super::Adam::step`] for the formula): the same
    /// expressions in every kernel but `matrixmultiply`, which keeps the earlier form
    /// θ −= s·m / (√v / √c2 + ε) so that it reproduces earlier results; the others use Kingma
    /// and Ba's equivalent θ −= (s·√c2)·m / (√v + ε·√c2), one division fewer per parameter.
    #[allow(clippy::too_many_arguments)]
    pub fn adam(
        self,
        params: &mut [f32],
        grad: &[f32],
        m: &mut [f32],
        v: &mut [f32],
        (b1, b2, eps): (f32, f32, f32),
        step: f32,
        c2_sqrt: f32,
    ) {
        assert!(grad.len() == params.len() && m.len() == params.len() && v.len() == params.len());
        if self == Kernel::Matrixmultiply {
            adam_body::<false>(params, grad, m, v, b1, b2, eps, step, c2_sqrt)
        } else {
            elementwise!(
                self,
                adam_folded(params, grad, m, v, b1, b2, eps, step, c2_sqrt)
            )
        }
    }

    /// Polyak averaging θ' ← θ' + τ·(θ − θ').
    pub fn polyak(self, target: &mut [f32], online: &[f32], tau: f32) {
        assert_eq!(target.len(), online.len(), "polyak: sizes");
        elementwise!(self, polyak_body(target, online, tau))
    }
}

/// The first `n` elements of `v`, grown (never shrunk) to hold them, so a buffer that serves
/// several sizes is not refilled with zeros on every call.
fn room(v: &mut Vec<f32>, n: usize) -> &mut [f32] {
    if v.len() < n {
        v.resize(n, 0.0);
    }
    &mut v[..n]
}

/// Outputs narrower than this go through the dot-product kernel.
const NARROW: usize = 8;

#[inline(always)]
fn column_sums_body(m: &[f32], cols: usize, out: &mut [f32]) {
    // Columns in blocks held in registers across the rows (each column still sums its rows in
    // order from 0.0, so every block width gives the same bits).
    let mut j = 0;
    j = column_block::<64>(m, cols, out, j);
    j = column_block::<16>(m, cols, out, j);
    column_block::<1>(m, cols, out, j);
}

/// Column sums of the blocks of W columns from `j` on; returns the first column not done.
#[inline(always)]
fn column_block<const W: usize>(m: &[f32], cols: usize, out: &mut [f32], mut j: usize) -> usize {
    while j + W <= cols {
        let mut acc = [0.0f32; W];
        for row in m.chunks_exact(cols) {
            for (a, x) in acc.iter_mut().zip(&row[j..j + W]) {
                *a += x;
            }
        }
        out[j..j + W].copy_from_slice(&acc);
        j += W;
    }
    j
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn adam_folded(
    params: &mut [f32],
    grad: &[f32],
    m: &mut [f32],
    v: &mut [f32],
    b1: f32,
    b2: f32,
    eps: f32,
    step: f32,
    c2_sqrt: f32,
) {
    adam_body::<true>(params, grad, m, v, b1, b2, eps, step, c2_sqrt)
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn adam_body<const FOLDED: bool>(
    params: &mut [f32],
    grad: &[f32],
    m: &mut [f32],
    v: &mut [f32],
    b1: f32,
    b2: f32,
    eps: f32,
    step: f32,
    c2_sqrt: f32,
) {
    let (folded_step, folded_eps) = (step * c2_sqrt, eps * c2_sqrt);
    for (((p, g), m), v) in params
        .iter_mut()
        .zip(grad)
        .zip(m.iter_mut())
        .zip(v.iter_mut())
    {
        let mi = b1 * *m + (1.0 - b1) * g;
        let vi = b2 * *v + (1.0 - b2) * g * g;
        // Flush moments that would turn subnormal (see `Adam`).
        let mi = if mi.abs() < f32::MIN_POSITIVE {
            0.0
        } else {
            mi
        };
        let vi = if vi < f32::MIN_POSITIVE { 0.0 } else { vi };
        *m = mi;
        *v = vi;
        if FOLDED {
            *p -= folded_step * mi / (vi.sqrt() + folded_eps);
        } else {
            *p -= step * mi / (vi.sqrt() / c2_sqrt + eps);
        }
    }
}

#[inline(always)]
fn polyak_body(target: &mut [f32], online: &[f32], tau: f32) {
    for (t, o) in target.iter_mut().zip(online) {
        *t += tau * (o - *t);
    }
}

/// `dst` (cols × rows) = `src` (rows × cols)ᵀ, both row-major: the portable loop
/// ([`Kernel::transpose`] picks a faster one where it can).
pub fn transpose(rows: usize, cols: usize, src: &[f32], dst: &mut [f32]) {
    assert!(src.len() >= rows * cols, "transpose: source too short");
    assert!(dst.len() >= rows * cols, "transpose: destination too short");
    const B: usize = 8;
    for i0 in (0..rows).step_by(B) {
        for j0 in (0..cols).step_by(B) {
            for i in i0..(i0 + B).min(rows) {
                for j in j0..(j0 + B).min(cols) {
                    dst[j * rows + i] = src[i * cols + j];
                }
            }
        }
    }
}

fn check_epilogue(m: usize, n: usize, ldc: usize, c: &[f32], bias: Option<&[f32]>, post: Post) {
    let need = (m - 1) * ldc + n;
    assert!(c.len() >= need, "gemm: C too short");
    if let Some(b) = bias {
        assert!(b.len() >= n, "gemm: bias too short");
    }
    if let Post::KeepWherePositive(act) = post {
        assert!(act.len() >= need, "gemm: mask too short");
    }
}

/// Bias and `post` applied after a product (the matrixmultiply kernel's epilogue).
fn scalar_epilogue(
    m: usize,
    n: usize,
    ldc: usize,
    c: &mut [f32],
    bias: Option<&[f32]>,
    post: Post,
) {
    for i in 0..m {
        for j in 0..n {
            let at = i * ldc + j;
            let mut y = c[at];
            if let Some(b) = bias {
                y += b[j];
            }
            c[at] = generic::post_scalar(y, post, at);
        }
    }
}

/// Raw pointers of the operands, taken once the bounds are checked.
struct Raw {
    a: *const f32,
    b: *const f32,
    c: *mut f32,
    bias: *const f32,
    post: generic::PostPtr,
}

impl Raw {
    fn new(a: &[f32], b: &[f32], c: &mut [f32], bias: Option<&[f32]>, post: Post) -> Raw {
        Raw {
            a: a.as_ptr(),
            b: b.as_ptr(),
            c: c.as_mut_ptr(),
            bias: bias.map_or(std::ptr::null(), <[f32]>::as_ptr),
            post: match post {
                Post::Identity => generic::PostPtr::Identity,
                Post::Relu => generic::PostPtr::Relu,
                Post::KeepWherePositive(m) => generic::PostPtr::Keep(m.as_ptr()),
            },
        }
    }
}

/// The instruction-set-independent kernels, written once over [`Simd`].
mod generic {
    use super::Post;

    /// A vector unit: the handful of operations the kernels need.
    pub(super) trait Simd {
        type V: Copy;
        type M: Copy;
        const LANES: usize;
        /// Rows of the register tile of `gemm_nn`.
        const MR: usize;
        /// Vectors per row of the register tile.
        const NR: usize;
        unsafe fn zero() -> Self::V;
        unsafe fn splat(x: f32) -> Self::V;
        /// The first `n` lanes (n ≤ LANES).
        unsafe fn mask(n: usize) -> Self::M;
        unsafe fn load(p: *const f32) -> Self::V;
        /// Loads the masked lanes; the others are 0 and not read.
        unsafe fn load_m(p: *const f32, m: Self::M) -> Self::V;
        unsafe fn store(p: *mut f32, v: Self::V);
        unsafe fn store_m(p: *mut f32, v: Self::V, m: Self::M);
        /// a·b + c (fused in the SIMD kernels).
        unsafe fn mul_add(a: Self::V, b: Self::V, c: Self::V) -> Self::V;
        unsafe fn add(a: Self::V, b: Self::V) -> Self::V;
        /// max(v, 0), NaN → 0.
        unsafe fn relu(v: Self::V) -> Self::V;
        /// v where act is not ≤ 0, else 0.
        unsafe fn keep(v: Self::V, act: Self::V) -> Self::V;
        /// The sixteen partial sums held in `acc` (16 / LANES vectors) added as
        /// [`tree16`] does, bit for bit.
        unsafe fn reduce16(acc: &[Self::V]) -> f32;
    }

    #[derive(Clone, Copy)]
    pub(super) enum PostPtr {
        Identity,
        Relu,
        Keep(*const f32),
    }

    /// The epilogue on one scalar at offset `at` of C.
    #[inline(always)]
    pub(super) fn post_scalar(y: f32, post: Post, at: usize) -> f32 {
        match post {
            Post::Identity => y,
            Post::Relu => relu(y),
            Post::KeepWherePositive(act) => keep(y, act[at]),
        }
    }

    #[inline(always)]
    pub(super) fn relu(y: f32) -> f32 {
        if y > 0.0 {
            y
        } else {
            0.0
        }
    }

    #[inline(always)]
    pub(super) fn keep(y: f32, act: f32) -> f32 {
        if act <= 0.0 {
            0.0
        } else {
            y
        }
    }

    /// Sum of sixteen partial sums as a tree: 8 apart, then 4, 2, 1.
    #[inline(always)]
    pub(super) fn tree16(mut x: [f32; 16]) -> f32 {
        for w in [8, 4, 2, 1] {
            for l in 0..w {
                x[l] += x[l + w];
            }
        }
        x[0]
    }

    /// See [`super::Kernel::gemm_nn`]: column panels of NR vectors, row blocks of MR rows,
    /// each an MR × NR register tile over the whole k.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) unsafe fn gemm_nn<S: Simd>(
        m: usize,
        k: usize,
        n: usize,
        a: *const f32,
        rsa: usize,
        csa: usize,
        b: *const f32,
        ldb: usize,
        c: *mut f32,
        ldc: usize,
        bias: *const f32,
        post: PostPtr,
    ) {
        let panel = S::NR * S::LANES;
        let mut j = 0;
        while j < n {
            let width = (n - j).min(panel);
            let nv = width.div_ceil(S::LANES);
            let tail = width - (nv - 1) * S::LANES;
            let bias_j = if bias.is_null() { bias } else { bias.add(j) };
            let mut i = 0;
            while i < m {
                let mr = (m - i).min(S::MR);
                let post_ij = match post {
                    PostPtr::Keep(p) => PostPtr::Keep(p.add(i * ldc + j)),
                    other => other,
                };
                let args = Tile {
                    k,
                    a: a.add(i * rsa),
                    rsa,
                    csa,
                    b: b.add(j),
                    ldb,
                    c: c.add(i * ldc + j),
                    ldc,
                    tail,
                    bias: bias_j,
                    post: post_ij,
                };
                // A tile whose last vector is full is compiled without masks, so its inner
                // loop holds no branch on the tail (measured: the AVX2 loop had one per k).
                let full = tail == S::LANES;
                macro_rules! pick {
                    ($(($r:literal, $v:literal)),*) => {
                        match (mr, nv, full) {
                            $(
                                ($r, $v, true) => tile::<S, $r, $v, true>(args),
                                ($r, $v, false) => tile::<S, $r, $v, false>(args),
                            )*
                            _ => unreachable!("tile {mr} × {nv} larger than the kernel's"),
                        }
                    };
                }
                pick!(
                    (1, 1),
                    (2, 1),
                    (3, 1),
                    (4, 1),
                    (5, 1),
                    (6, 1),
                    (1, 2),
                    (2, 2),
                    (3, 2),
                    (4, 2),
                    (5, 2),
                    (6, 2),
                    (1, 3),
                    (2, 3),
                    (3, 3),
                    (4, 3),
                    (5, 3),
                    (6, 3),
                    (1, 4),
                    (2, 4),
                    (3, 4),
                    (4, 4),
                    (5, 4),
                    (6, 4)
                );
                i += mr;
            }
            j += width;
        }
    }

    #[derive(Clone, Copy)]
    pub(super) struct Tile {
        k: usize,
        a: *const f32,
        rsa: usize,
        csa: usize,
        b: *const f32,
        ldb: usize,
        c: *mut f32,
        ldc: usize,
        /// Lanes used in the tile's last vector.
        tail: usize,
        bias: *const f32,
        post: PostPtr,
    }

    /// One MR × (NR vectors) block of C: MR·NR accumulators in registers, one fused
    /// multiply-add each per k, then bias and epilogue on the way out. `FULL`: the last vector
    /// has all its lanes (no masked loads or stores).
    #[inline(always)]
    unsafe fn tile<S: Simd, const MR: usize, const NR: usize, const FULL: bool>(t: Tile) {
        debug_assert_eq!(FULL, t.tail == S::LANES);
        let full = FULL;
        let last = S::mask(t.tail);
        let load = |p: *const f32, v: usize| {
            if v + 1 < NR || full {
                S::load(p)
            } else {
                S::load_m(p, last)
            }
        };
        let mut acc = [[S::zero(); NR]; MR];
        let (mut ak, mut bk) = (t.a, t.b);
        for _ in 0..t.k {
            let mut bv = [S::zero(); NR];
            for (v, x) in bv.iter_mut().enumerate() {
                *x = load(bk.add(v * S::LANES), v);
            }
            for (r, row) in acc.iter_mut().enumerate() {
                let x = S::splat(*ak.add(r * t.rsa));
                for (acc, b) in row.iter_mut().zip(&bv) {
                    *acc = S::mul_add(x, *b, *acc);
                }
            }
            ak = ak.add(t.csa);
            bk = bk.add(t.ldb);
        }
        for (r, row) in acc.iter().enumerate() {
            for (v, &y) in row.iter().enumerate() {
                let off = r * t.ldc + v * S::LANES;
                let mut y = y;
                if !t.bias.is_null() {
                    y = S::add(y, load(t.bias.add(v * S::LANES), v));
                }
                y = match t.post {
                    PostPtr::Identity => y,
                    PostPtr::Relu => S::relu(y),
                    PostPtr::Keep(act) => S::keep(y, load(act.add(off), v)),
                };
                if v + 1 < NR || full {
                    S::store(t.c.add(off), y);
                } else {
                    S::store_m(t.c.add(off), y, last);
                }
            }
        }
    }

    /// See [`super::Kernel::gemm_nt`]: DV vectors of LANES lanes hold the sixteen partial
    /// sums (DV · LANES = 16); RB rows of A at a time share each load of a row of B.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) unsafe fn gemm_nt<S: Simd, const DV: usize>(
        m: usize,
        k: usize,
        n: usize,
        a: *const f32,
        lda: usize,
        b: *const f32,
        ldb: usize,
        c: *mut f32,
        ldc: usize,
        bias: *const f32,
        post: PostPtr,
    ) {
        let mut i = 0;
        while i < m {
            let rows = (m - i).min(4);
            match rows {
                4 => nt_rows::<S, DV, 4>(i, k, n, a, lda, b, ldb, c, ldc, bias, post),
                3 => nt_rows::<S, DV, 3>(i, k, n, a, lda, b, ldb, c, ldc, bias, post),
                2 => nt_rows::<S, DV, 2>(i, k, n, a, lda, b, ldb, c, ldc, bias, post),
                _ => nt_rows::<S, DV, 1>(i, k, n, a, lda, b, ldb, c, ldc, bias, post),
            }
            i += rows;
        }
    }

    /// Rows i..i + RB of C = A·Bᵀ.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    unsafe fn nt_rows<S: Simd, const DV: usize, const RB: usize>(
        i: usize,
        k: usize,
        n: usize,
        a: *const f32,
        lda: usize,
        b: *const f32,
        ldb: usize,
        c: *mut f32,
        ldc: usize,
        bias: *const f32,
        post: PostPtr,
    ) {
        debug_assert_eq!(DV * S::LANES, 16);
        let whole = k / 16 * 16;
        for j in 0..n {
            let bj = b.add(j * ldb);
            let mut acc = [[S::zero(); DV]; RB];
            let mut kk = 0;
            while kk < whole {
                for d in 0..DV {
                    let o = kk + d * S::LANES;
                    let bv = S::load(bj.add(o));
                    for (r, acc) in acc.iter_mut().enumerate() {
                        let av = S::load(a.add((i + r) * lda + o));
                        acc[d] = S::mul_add(av, bv, acc[d]);
                    }
                }
                kk += 16;
            }
            for d in 0..DV {
                let o = kk + d * S::LANES;
                if o < k {
                    let mk = S::mask((k - o).min(S::LANES));
                    let bv = S::load_m(bj.add(o), mk);
                    for (r, acc) in acc.iter_mut().enumerate() {
                        let av = S::load_m(a.add((i + r) * lda + o), mk);
                        acc[d] = S::mul_add(av, bv, acc[d]);
                    }
                }
            }
            for (r, acc) in acc.iter().enumerate() {
                let mut y = S::reduce16(acc);
                if !bias.is_null() {
                    y += *bias.add(j);
                }
                let at = (i + r) * ldc + j;
                y = match post {
                    PostPtr::Identity => y,
                    PostPtr::Relu => relu(y),
                    PostPtr::Keep(act) => keep(y, *act.add(at)),
                };
                *c.add(at) = y;
            }
        }
    }
}

use generic::Simd;

/// The portable unit: 8 lanes as plain arrays, unfused multiply-add.
struct Portable;

impl Simd for Portable {
    type V = [f32; 8];
    type M = usize;
    const LANES: usize = 8;
    const MR: usize = 4;
    const NR: usize = 2;
    #[inline(always)]
    unsafe fn zero() -> [f32; 8] {
        [0.0; 8]
    }
    #[inline(always)]
    unsafe fn splat(x: f32) -> [f32; 8] {
        [x; 8]
    }
    #[inline(always)]
    unsafe fn mask(n: usize) -> usize {
        n
    }
    #[inline(always)]
    unsafe fn load(p: *const f32) -> [f32; 8] {
        p.cast::<[f32; 8]>().read_unaligned()
    }
    #[inline(always)]
    unsafe fn load_m(p: *const f32, m: usize) -> [f32; 8] {
        let mut v = [0.0; 8];
        for (l, x) in v.iter_mut().enumerate().take(m) {
            *x = *p.add(l);
        }
        v
    }
    #[inline(always)]
    unsafe fn store(p: *mut f32, v: [f32; 8]) {
        p.cast::<[f32; 8]>().write_unaligned(v)
    }
    #[inline(always)]
    unsafe fn store_m(p: *mut f32, v: [f32; 8], m: usize) {
        for (l, x) in v.iter().enumerate().take(m) {
            *p.add(l) = *x;
        }
    }
    #[inline(always)]
    unsafe fn mul_add(a: [f32; 8], b: [f32; 8], c: [f32; 8]) -> [f32; 8] {
        std::array::from_fn(|l| a[l] * b[l] + c[l])
    }
    #[inline(always)]
    unsafe fn add(a: [f32; 8], b: [f32; 8]) -> [f32; 8] {
        std::array::from_fn(|l| a[l] + b[l])
    }
    #[inline(always)]
    unsafe fn relu(v: [f32; 8]) -> [f32; 8] {
        v.map(generic::relu)
    }
    #[inline(always)]
    unsafe fn keep(v: [f32; 8], act: [f32; 8]) -> [f32; 8] {
        std::array::from_fn(|l| generic::keep(v[l], act[l]))
    }
    #[inline(always)]
    unsafe fn reduce16(acc: &[[f32; 8]]) -> f32 {
        let mut lanes = [0.0; 16];
        lanes[..8].copy_from_slice(&acc[0]);
        lanes[8..].copy_from_slice(&acc[1]);
        generic::tree16(lanes)
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    //! AVX2 and AVX-512 units, and the `#[target_feature]` entry points that compile the
    //! generic kernels for them.

    use super::generic::{self, PostPtr, Simd};
    use std::arch::x86_64::*;

    pub(super) struct Avx2;

    impl Simd for Avx2 {
        type V = __m256;
        type M = __m256i;
        const LANES: usize = 8;
        const MR: usize = 6;
        const NR: usize = 2;
        #[inline(always)]
        unsafe fn zero() -> __m256 {
            _mm256_setzero_ps()
        }
        #[inline(always)]
        unsafe fn splat(x: f32) -> __m256 {
            _mm256_set1_ps(x)
        }
        #[inline(always)]
        unsafe fn mask(n: usize) -> __m256i {
            _mm256_cmpgt_epi32(
                _mm256_set1_epi32(n as i32),
                _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7),
            )
        }
        #[inline(always)]
        unsafe fn load(p: *const f32) -> __m256 {
            _mm256_loadu_ps(p)
        }
        #[inline(always)]
        unsafe fn load_m(p: *const f32, m: __m256i) -> __m256 {
            _mm256_maskload_ps(p, m)
        }
        #[inline(always)]
        unsafe fn store(p: *mut f32, v: __m256) {
            _mm256_storeu_ps(p, v)
        }
        #[inline(always)]
        unsafe fn store_m(p: *mut f32, v: __m256, m: __m256i) {
            _mm256_maskstore_ps(p, m, v)
        }
        #[inline(always)]
        unsafe fn mul_add(a: __m256, b: __m256, c: __m256) -> __m256 {
            _mm256_fmadd_ps(a, b, c)
        }
        #[inline(always)]
        unsafe fn add(a: __m256, b: __m256) -> __m256 {
            _mm256_add_ps(a, b)
        }
        #[inline(always)]
        unsafe fn relu(v: __m256) -> __m256 {
            // maxps returns its second operand when either is NaN: NaN → 0.
            _mm256_max_ps(v, _mm256_setzero_ps())
        }
        #[inline(always)]
        unsafe fn keep(v: __m256, act: __m256) -> __m256 {
            _mm256_andnot_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(act, _mm256_setzero_ps()), v)
        }
        #[inline(always)]
        unsafe fn reduce16(acc: &[__m256]) -> f32 {
            // Lanes 0..8 in acc[0], 8..16 in acc[1]: x[l] + x[l + 8], then as AVX-512 does.
            reduce8(_mm256_add_ps(acc[0], acc[1]))
        }
    }

    /// x[l] + x[l + 4], then + 2 apart, then + 1 apart: the last three levels of the tree.
    #[inline(always)]
    unsafe fn reduce8(s8: __m256) -> f32 {
        let s4 = _mm_add_ps(_mm256_castps256_ps128(s8), _mm256_extractf128_ps::<1>(s8));
        let s2 = _mm_add_ps(s4, _mm_movehl_ps(s4, s4));
        let s1 = _mm_add_ss(s2, _mm_shuffle_ps::<0b01>(s2, s2));
        _mm_cvtss_f32(s1)
    }

    pub(super) struct Avx512;

    impl Simd for Avx512 {
        type V = __m512;
        type M = __mmask16;
        const LANES: usize = 16;
        const MR: usize = 4;
        const NR: usize = 4;
        #[inline(always)]
        unsafe fn zero() -> __m512 {
            _mm512_setzero_ps()
        }
        #[inline(always)]
        unsafe fn splat(x: f32) -> __m512 {
            _mm512_set1_ps(x)
        }
        #[inline(always)]
        unsafe fn mask(n: usize) -> __mmask16 {
            if n >= 16 {
                0xffff
            } else {
                (1u16 << n) - 1
            }
        }
        #[inline(always)]
        unsafe fn load(p: *const f32) -> __m512 {
            _mm512_loadu_ps(p)
        }
        #[inline(always)]
        unsafe fn load_m(p: *const f32, m: __mmask16) -> __m512 {
            _mm512_maskz_loadu_ps(m, p)
        }
        #[inline(always)]
        unsafe fn store(p: *mut f32, v: __m512) {
            _mm512_storeu_ps(p, v)
        }
        #[inline(always)]
        unsafe fn store_m(p: *mut f32, v: __m512, m: __mmask16) {
            _mm512_mask_storeu_ps(p, m, v)
        }
        #[inline(always)]
        unsafe fn mul_add(a: __m512, b: __m512, c: __m512) -> __m512 {
            _mm512_fmadd_ps(a, b, c)
        }
        #[inline(always)]
        unsafe fn add(a: __m512, b: __m512) -> __m512 {
            _mm512_add_ps(a, b)
        }
        #[inline(always)]
        unsafe fn relu(v: __m512) -> __m512 {
            _mm512_max_ps(v, _mm512_setzero_ps())
        }
        #[inline(always)]
        unsafe fn keep(v: __m512, act: __m512) -> __m512 {
            let le = _mm512_cmp_ps_mask::<_CMP_LE_OQ>(act, _mm512_setzero_ps());
            _mm512_mask_mov_ps(v, le, _mm512_setzero_ps())
        }
        #[inline(always)]
        unsafe fn reduce16(acc: &[__m512]) -> f32 {
            // Lanes 8..16 moved down (128-bit blocks 2, 3 → 0, 1): x[l] + x[l + 8].
            let v = acc[0];
            let s8 = _mm512_add_ps(v, _mm512_shuffle_f32x4::<0b11_10_11_10>(v, v));
            reduce8(_mm512_castps512_ps256(s8))
        }
    }

    /// An 8 × 8 block transpose in AVX registers: rows of `src` (stride `ls`) become columns
    /// of `dst` (stride `ld`).
    #[inline(always)]
    unsafe fn t8x8(src: *const f32, ls: usize, dst: *mut f32, ld: usize) {
        let r: [__m256; 8] = std::array::from_fn(|i| _mm256_loadu_ps(src.add(i * ls)));
        let t0 = _mm256_unpacklo_ps(r[0], r[1]);
        let t1 = _mm256_unpackhi_ps(r[0], r[1]);
        let t2 = _mm256_unpacklo_ps(r[2], r[3]);
        let t3 = _mm256_unpackhi_ps(r[2], r[3]);
        let t4 = _mm256_unpacklo_ps(r[4], r[5]);
        let t5 = _mm256_unpackhi_ps(r[4], r[5]);
        let t6 = _mm256_unpacklo_ps(r[6], r[7]);
        let t7 = _mm256_unpackhi_ps(r[6], r[7]);
        // Columns (0 | 4), (1 | 5), (2 | 6), (3 | 7) of rows 0–3 and of rows 4–7.
        let u0 = _mm256_shuffle_ps::<0x44>(t0, t2);
        let u1 = _mm256_shuffle_ps::<0xee>(t0, t2);
        let u2 = _mm256_shuffle_ps::<0x44>(t1, t3);
        let u3 = _mm256_shuffle_ps::<0xee>(t1, t3);
        let u4 = _mm256_shuffle_ps::<0x44>(t4, t6);
        let u5 = _mm256_shuffle_ps::<0xee>(t4, t6);
        let u6 = _mm256_shuffle_ps::<0x44>(t5, t7);
        let u7 = _mm256_shuffle_ps::<0xee>(t5, t7);
        let cols = [
            _mm256_permute2f128_ps::<0x20>(u0, u4),
            _mm256_permute2f128_ps::<0x20>(u1, u5),
            _mm256_permute2f128_ps::<0x20>(u2, u6),
            _mm256_permute2f128_ps::<0x20>(u3, u7),
            _mm256_permute2f128_ps::<0x31>(u0, u4),
            _mm256_permute2f128_ps::<0x31>(u1, u5),
            _mm256_permute2f128_ps::<0x31>(u2, u6),
            _mm256_permute2f128_ps::<0x31>(u3, u7),
        ];
        for (j, c) in cols.iter().enumerate() {
            _mm256_storeu_ps(dst.add(j * ld), *c);
        }
    }

    /// `dst` (cols × rows) = `src` (rows × cols)ᵀ: 8 × 8 blocks in registers, the ragged
    /// edges element by element.
    ///
    /// # Safety
    /// AVX must be available; `src` and `dst` must hold rows · cols values.
    #[target_feature(enable = "avx")]
    pub(super) unsafe fn transpose_avx(rows: usize, cols: usize, src: *const f32, dst: *mut f32) {
        let (r8, c8) = (rows / 8 * 8, cols / 8 * 8);
        for i in (0..r8).step_by(8) {
            for j in (0..c8).step_by(8) {
                t8x8(src.add(i * cols + j), cols, dst.add(j * rows + i), rows);
            }
        }
        for i in 0..rows {
            let from = if i < r8 { c8 } else { 0 };
            for j in from..cols {
                *dst.add(j * rows + i) = *src.add(i * cols + j);
            }
        }
    }

    macro_rules! entry {
        ($feat:literal, $unit:ty, $nn:ident, $nt:ident, $dv:literal, $ew:ident) => {
            #[allow(clippy::too_many_arguments)]
            #[target_feature(enable = $feat)]
            pub(super) unsafe fn $nn(
                m: usize,
                k: usize,
                n: usize,
                a: *const f32,
                rsa: usize,
                csa: usize,
                b: *const f32,
                ldb: usize,
                c: *mut f32,
                ldc: usize,
                bias: *const f32,
                post: PostPtr,
            ) {
                generic::gemm_nn::<$unit>(m, k, n, a, rsa, csa, b, ldb, c, ldc, bias, post)
            }

            #[allow(clippy::too_many_arguments)]
            #[target_feature(enable = $feat)]
            pub(super) unsafe fn $nt(
                m: usize,
                k: usize,
                n: usize,
                a: *const f32,
                lda: usize,
                b: *const f32,
                ldb: usize,
                c: *mut f32,
                ldc: usize,
                bias: *const f32,
                post: PostPtr,
            ) {
                generic::gemm_nt::<$unit, $dv>(m, k, n, a, lda, b, ldb, c, ldc, bias, post)
            }

            /// Runs `f` (inlined) compiled for this instruction set.
            #[target_feature(enable = $feat)]
            #[inline]
            pub(super) unsafe fn $ew<R>(f: impl FnOnce() -> R) -> R {
                f()
            }
        };
    }

    entry!(
        "avx2,fma",
        Avx2,
        gemm_nn_avx2,
        gemm_nt_avx2,
        2,
        avx2_elementwise
    );
    entry!(
        "avx512f",
        Avx512,
        gemm_nn_avx512,
        gemm_nt_avx512,
        1,
        avx512_elementwise
    );
}
