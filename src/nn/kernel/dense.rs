//! One dense layer (forward, parameter and input gradients) on a kernel's products.

use super::{scalar_epilogue, Kernel, Matrix, Post, NARROW};

impl Kernel {
    /// One dense layer forward: Y (batch × fan_out) = X·W + b, then ReLU if `relu`. W is
    /// fan_in × fan_out row-major. `scratch` holds Wᵀ when the output is too narrow for
    /// vector lanes.
    pub fn dense_forward(
        self,
        x: &[f32],
        (w, b): (&[f32], &[f32]),
        (batch, fan_in, fan_out): (usize, usize, usize),
        relu: bool,
        y: &mut [f32],
        scratch: &mut Vec<f32>,
    ) {
        let post = if relu { Post::Relu } else { Post::Identity };
        if fan_out < NARROW && self != Kernel::Matrixmultiply {
            let wt = room(scratch, fan_in * fan_out);
            self.transpose(fan_in, fan_out, w, wt);
            let (x, wt) = (Matrix::rows(x, fan_in), Matrix::rows(wt, fan_in));
            self.gemm_nt((batch, fan_in, fan_out), x, wt, y, Some(b), post);
        } else {
            let (x, w) = (Matrix::rows(x, fan_in), Matrix::rows(w, fan_out));
            self.gemm_nn((batch, fan_in, fan_out), x, w, y, Some(b), post);
        }
    }

    /// A dense layer's parameter gradients: ∂W (fan_in × fan_out) = Xᵀ·δ and ∂b = Σ_rows δ.
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
            let (delta_t, x) = (
                Matrix::strided(delta, (1, fan_out)),
                Matrix::rows(x, fan_in),
            );
            self.gemm_nn(
                (fan_out, batch, fan_in),
                delta_t,
                x,
                gwt,
                None,
                Post::Identity,
            );
            self.transpose(fan_out, fan_in, gwt, gw);
        } else {
            let (x_t, delta) = (
                Matrix::strided(x, (1, fan_in)),
                Matrix::rows(delta, fan_out),
            );
            self.gemm_nn(
                (fan_in, batch, fan_out),
                x_t,
                delta,
                gw,
                None,
                Post::Identity,
            );
        }
        self.column_sums(delta, fan_out, gb);
    }

    /// A dense layer's input gradient: ∂X (batch × fan_in) = δ·Wᵀ, zeroed where `below` (the
    /// previous layer's ReLU output, batch × fan_in) is ≤ 0.
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
            let (delta, w) = (Matrix::rows(delta, fan_out), Matrix::rows(w, fan_out));
            self.gemm_nt((batch, fan_out, fan_in), delta, w, dx, None, post);
        } else {
            let wt = room(scratch, fan_in * fan_out);
            self.transpose(fan_in, fan_out, w, wt);
            let (delta, wt) = (Matrix::rows(delta, fan_out), Matrix::rows(wt, fan_in));
            self.gemm_nn((batch, fan_out, fan_in), delta, wt, dx, None, post);
        }
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
