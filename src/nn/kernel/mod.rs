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
//! A kernel is an explicit input: a learner runs on the kernel handed to
//! [`Learner::new`](crate::learner::Learner::new) (the run's: [`Kernel::detect`] unless
//! `PBCS_KERNEL` names one) or to [`Learner::set_kernel`](crate::learner::Learner::set_kernel),
//! a [`SkillChain`](crate::phase2::SkillChain) on its own, and `timing.toml` records which
//! ran. Nothing here is process-wide state: the `pbcs` command reads the environment variable
//! `PBCS_KERNEL` (`auto`, `avx512`, `avx2`, `portable`, `matrixmultiply`) once
//! ([`Kernel::from_env`]) and hands the kernel to every run it starts.
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
//! use pbcs::nn::kernel::{Kernel, Matrix, Post};
//!
//! // C (2 × 3) = A (2 × 2) · B (2 × 3) + bias, then ReLU.
//! let a = [1.0, 2.0, 3.0, 4.0];
//! let b = [1.0, 0.0, -1.0, 0.0, 1.0, -1.0];
//! let mut c = [0.0; 6];
//! let k = Kernel::detect();
//! let (a, b) = (Matrix::rows(&a, 2), Matrix::rows(&b, 3));
//! k.gemm_nn((2, 2, 3), a, b, &mut c, Some(&[0.5, 0.5, 0.5]), Post::Relu);
//! assert_eq!(c, [1.5, 2.5, 0.0, 3.5, 4.5, 0.0]);
//! ```

use crate::error::{Error, Result};

/// One implementation of the layer arithmetic (see the module docs).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Hash,
    strum::IntoStaticStr,
    serde::Serialize,
    serde::Deserialize,
)]
#[strum(serialize_all = "snake_case")]
#[serde(rename_all = "snake_case")]
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

/// [`Kernel::detect`]: the best kernel this CPU runs (`auto`).
impl Default for Kernel {
    fn default() -> Self {
        Kernel::detect()
    }
}

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
        self.into()
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

    fn check_available(self) {
        assert!(
            self.available(),
            "the {} kernel does not run on this CPU",
            self.name()
        );
    }

    /// C (m × n, row-major) = A·B + bias, then `post`. A is m × k with any strides (so Aᵀ of a
    /// row-major matrix is [`Matrix::strided`] `(1, cols)`), B is k × n row-major
    /// ([`Matrix::rows`]), `bias` has n values, a `KeepWherePositive` matrix is laid out as C.
    ///
    /// # Panics
    /// If an operand is too short for its shape, B is not row-major, or this CPU cannot run the
    /// kernel.
    pub fn gemm_nn(
        self,
        (m, k, n): (usize, usize, usize),
        a: Matrix<'_>,
        b: Matrix<'_>,
        c: &mut [f32],
        bias: Option<&[f32]>,
        post: Post,
    ) {
        let (
            Matrix {
                data: a,
                strides: (rsa, csa),
            },
            ldb,
        ) = (a, b.row_stride("gemm_nn: B"));
        let b = b.data;
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
    /// of A (m × k) and row j of B (n × k), both row-major ([`Matrix::rows`]). For outputs only
    /// a few columns wide, where [`Kernel::gemm_nn`] would waste its vector lanes.
    ///
    /// # Panics
    /// As [`Kernel::gemm_nn`], and where A is not row-major.
    pub fn gemm_nt(
        self,
        (m, k, n): (usize, usize, usize),
        a: Matrix<'_>,
        b: Matrix<'_>,
        c: &mut [f32],
        bias: Option<&[f32]>,
        post: Post,
    ) {
        let (lda, ldb) = (a.row_stride("gemm_nt: A"), b.row_stride("gemm_nt: B"));
        let (a, b) = (a.data, b.data);
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
}

/// A matrix operand of a product: its values and its strides (between rows, between columns).
#[derive(Debug, Clone, Copy)]
pub struct Matrix<'a> {
    /// The values.
    pub data: &'a [f32],
    /// (row stride, column stride).
    pub strides: (usize, usize),
}

impl<'a> Matrix<'a> {
    /// A row-major matrix whose rows are `row_stride` apart.
    pub fn rows(data: &'a [f32], row_stride: usize) -> Self {
        Matrix {
            data,
            strides: (row_stride, 1),
        }
    }

    /// A matrix of any strides (row, column).
    pub fn strided(data: &'a [f32], strides: (usize, usize)) -> Self {
        Matrix { data, strides }
    }

    /// The row stride of a row-major matrix; a panic naming `what` for another layout.
    fn row_stride(&self, what: &str) -> usize {
        assert_eq!(self.strides.1, 1, "{what} must be row-major");
        self.strides.0
    }
}

/// Outputs narrower than this go through the dot-product kernel.
const NARROW: usize = 8;

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

mod dense;
mod elementwise;
mod generic;
#[cfg(target_arch = "x86_64")]
mod x86;

pub use elementwise::{transpose, AdamStep};
use generic::Portable;
