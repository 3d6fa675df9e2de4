//! The element-wise loops of a learner update (transpose, bias gradient, Adam, Polyak),
//! the same scalar expressions in every kernel.

#[cfg(target_arch = "x86_64")]
use super::x86;
use super::Kernel;

impl Kernel {
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

    /// One Adam step over all parameters (see [`crate::nn::Adam::step`] for the formula): the same
    /// expressions in every kernel but `matrixmultiply`, which keeps the earlier form
    /// θ −= s·m / (√v / √c2 + ε) so that it reproduces earlier results; the others use Kingma
    /// and Ba's equivalent θ −= (s·√c2)·m / (√v + ε·√c2), one division fewer per parameter.
    pub fn adam(self, params: &mut [f32], grad: &[f32], m: &mut [f32], v: &mut [f32], h: AdamStep) {
        assert!(grad.len() == params.len() && m.len() == params.len() && v.len() == params.len());
        if self == Kernel::Matrixmultiply {
            adam_body::<false>(params, grad, m, v, h)
        } else {
            elementwise!(self, adam_folded(params, grad, m, v, h))
        }
    }

    /// Polyak averaging θ' ← θ' + τ·(θ − θ').
    pub fn polyak(self, target: &mut [f32], online: &[f32], tau: f32) {
        assert_eq!(target.len(), online.len(), "polyak: sizes");
        elementwise!(self, polyak_body(target, online, tau))
    }
}

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

/// The numbers of one Adam step ([`Kernel::adam`]): β₁, β₂, ε, the step lr / (1 − β₁ᵗ), and
/// √(1 − β₂ᵗ).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdamStep {
    /// β₁, the first moment's decay.
    pub b1: f32,
    /// β₂, the second moment's decay.
    pub b2: f32,
    /// ε.
    pub eps: f32,
    /// lr / (1 − β₁ᵗ).
    pub step: f32,
    /// √(1 − β₂ᵗ).
    pub c2_sqrt: f32,
}

#[inline(always)]
fn adam_folded(params: &mut [f32], grad: &[f32], m: &mut [f32], v: &mut [f32], h: AdamStep) {
    adam_body::<true>(params, grad, m, v, h)
}

#[inline(always)]
fn adam_body<const FOLDED: bool>(
    params: &mut [f32],
    grad: &[f32],
    m: &mut [f32],
    v: &mut [f32],
    h: AdamStep,
) {
    let AdamStep {
        b1,
        b2,
        eps,
        step,
        c2_sqrt,
    } = h;
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
