//! Multi-layer perceptrons on flat `f32` buffers: forward, backward, Adam, soft updates.
//!
//! Every learner update runs one actor and one or two critics forward and backward, once per
//! environment step, so this is the hot path of the project. The networks are plain ReLU MLPs
//! whose parameters live in one flat vector; a layer is one matrix product with its bias and
//! activation fused in ([`kernel`]: AVX-512 or AVX2, chosen at run time and giving the same
//! bytes, or the portable loops, which round each product separately), so a whole update does
//! no allocation and no per-operation bookkeeping. candle is kept for what it does well: its
//! autograd is the oracle the tests check these gradients against ([`candle_ref`]), and
//! safetensors is the file format of saved policies ([`Mlp::save`], [`Mlp::load`],
//! [`candle_ref::load_module`]).
//!
//! Layout of the parameters: for each layer l (fan-in `i`, fan-out `o`), the weight matrix
//! W_l (i × o, row-major, so a layer computes Y = X·W + b on row-major batches) then the bias
//! b_l (o).
//!
//! ```
//! use pbcs::nn::{kernel::Kernel, Head, Mlp, Workspace};
//! use pbcs::rng::{Seeds, Stream};
//!
//! let mut rng = Seeds::new(0).stream(Stream::Init);
//! let actor = Mlp::new(&[2, 16, 16, 2], Head::Tanh(vec![0.1, 0.1]), &mut rng);
//! let mut ws = Workspace::with_kernel(Kernel::detect()); // the kernel is always named
//! let a = actor.forward(&[0.5, 0.5, 1.5, 2.5], 2, &mut ws); // a batch of two states
//! assert_eq!(a.len(), 4);
//! assert!(a.iter().all(|x| x.abs() <= 0.1));
//! ```

pub mod candle_ref;
pub mod kernel;

use crate::error::{Error, Result};
use crate::rng::Rng;
use kernel::Kernel;
use rand::Rng as _;
use std::path::Path;

/// The output layer's activation.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Head {
    /// Identity (critics).
    Linear,
    /// `scale_i · tanh(z_i)` (actors: scaled to the action bounds).
    Tanh(Vec<f32>),
}

/// A ReLU multi-layer perceptron with flat parameters.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Mlp {
    sizes: Vec<usize>,
    head: Head,
    /// All weights and biases, layer by layer (see the module docs for the layout).
    pub params: Vec<f32>,
}

/// Activations kept by [`Mlp::forward`] for [`Mlp::backward`], and scratch buffers. One per
/// network and use, reused across calls so the hot path allocates nothing. It also names the
/// [`Kernel`] that does the arithmetic.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Workspace {
    /// `acts[0]` is the input batch, `acts[l]` the output of layer l.
    acts: Vec<Vec<f32>>,
    delta: Vec<f32>,
    delta_prev: Vec<f32>,
    scratch: Vec<f32>,
    /// Where a policy puts the actions it makes of the network's output ([`Workspace::output_and_buffer`]).
    out: Vec<f32>,
    batch: usize,
    kernel: Kernel,
}

impl Workspace {
    /// An empty workspace whose products run on `kernel`.
    pub fn with_kernel(kernel: Kernel) -> Self {
        Workspace {
            acts: Vec::new(),
            delta: Vec::new(),
            delta_prev: Vec::new(),
            scratch: Vec::new(),
            out: Vec::new(),
            batch: 0,
            kernel,
        }
    }

    /// The output of the last [`Mlp::forward`] run in this workspace and a buffer beside it:
    /// for a policy whose actions are a function of its network's output (SAC's tanh of the
    /// mean), so acting allocates nothing.
    pub fn output_and_buffer(&mut self) -> (&[f32], &mut Vec<f32>) {
        let last = self.acts.last().map_or(&[][..], |a| a.as_slice());
        (last, &mut self.out)
    }

    /// The kernel this workspace's products run on.
    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    /// Runs later products on `kernel`.
    pub fn set_kernel(&mut self, kernel: Kernel) {
        self.kernel = kernel;
    }
}

impl Mlp {
    /// A network with layer sizes `sizes` (input, hidden..., output), initialised as
    /// PyTorch's `nn.Linear` does — W and b uniform in ±1/√fan_in — from `rng`, so a seed
    /// fixes every weight.
    pub fn new(sizes: &[usize], head: Head, rng: &mut Rng) -> Self {
        assert!(
            sizes.len() >= 2 && sizes.iter().all(|&s| s > 0),
            "bad sizes"
        );
        if let Head::Tanh(scale) = &head {
            assert_eq!(scale.len(), *sizes.last().unwrap(), "one scale per output");
        }
        let n: usize = sizes.windows(2).map(|w| w[0] * w[1] + w[1]).sum();
        let mut params = Vec::with_capacity(n);
        for w in sizes.windows(2) {
            let bound = 1.0 / (w[0] as f32).sqrt();
            for _ in 0..w[0] * w[1] + w[1] {
                params.push(rng.random_range(-bound..bound));
            }
        }
        Mlp {
            sizes: sizes.to_vec(),
            head,
            params,
        }
    }

    /// Layer sizes (input, hidden..., output).
    pub fn sizes(&self) -> &[usize] {
        &self.sizes
    }

    /// The output activation.
    pub fn head(&self) -> &Head {
        &self.head
    }

    /// Input width.
    pub fn input_dim(&self) -> usize {
        self.sizes[0]
    }

    /// Output width.
    pub fn output_dim(&self) -> usize {
        *self.sizes.last().unwrap()
    }

    /// Number of layers (weight matrices).
    pub fn layers(&self) -> usize {
        self.sizes.len() - 1
    }

    /// Offsets of W_l and b_l in [`Mlp::params`].
    pub fn offsets(&self, l: usize) -> (usize, usize) {
        let before: usize = self.sizes[..l + 1]
            .windows(2)
            .map(|w| w[0] * w[1] + w[1])
            .sum();
        (before, before + self.sizes[l] * self.sizes[l + 1])
    }

    /// Runs the batch `x` (`batch` rows of [`Mlp::input_dim`]) forward; returns the output
    /// (`batch` rows of [`Mlp::output_dim`]) and keeps the activations in `ws` for
    /// [`Mlp::backward`].
    pub fn forward<'w>(&self, x: &[f32], batch: usize, ws: &'w mut Workspace) -> &'w [f32] {
        assert_eq!(x.len(), batch * self.input_dim(), "forward: input size");
        let layers = self.layers();
        ws.acts.resize_with(layers + 1, Vec::new);
        ws.batch = batch;
        ws.acts[0].clear();
        ws.acts[0].extend_from_slice(x);
        for l in 0..layers {
            let (fan_in, fan_out) = (self.sizes[l], self.sizes[l + 1]);
            let (w, b) = self.offsets(l);
            let (before, after) = ws.acts.split_at_mut(l + 1);
            let out = &mut after[0];
            out.resize(batch * fan_out, 0.0);
            // Y = relu(X·W + b) on hidden layers, X·W + b on the last.
            ws.kernel.dense_forward(
                &before[l],
                (&self.params[w..b], &self.params[b..b + fan_out]),
                (batch, fan_in, fan_out),
                l + 1 < layers,
                out,
                &mut ws.scratch,
            );
            if l + 1 == layers {
                if let Head::Tanh(scale) = &self.head {
                    for row in out.chunks_exact_mut(fan_out) {
                        for (v, s) in row.iter_mut().zip(scale) {
                            *v = s * v.tanh();
                        }
                    }
                }
            }
        }
        &ws.acts[layers]
    }

    /// Back-propagates `dy` = ∂L/∂output through the batch of the last [`Mlp::forward`] in
    /// `ws`. Writes ∂L/∂params into `grad` if given (overwritten, same layout as the
    /// parameters) and ∂L/∂input into `dx` if given.
    pub fn backward(
        &self,
        ws: &mut Workspace,
        dy: &[f32],
        mut grad: Option<&mut [f32]>,
        mut dx: Option<&mut [f32]>,
    ) {
        let batch = ws.batch;
        let layers = self.layers();
        assert_eq!(dy.len(), batch * self.output_dim(), "backward: dy size");
        if let Some(g) = &grad {
            assert_eq!(g.len(), self.params.len(), "backward: grad size");
        }
        // δ_L = ∂L/∂z_L.
        ws.delta.clear();
        ws.delta.extend_from_slice(dy);
        if let Head::Tanh(scale) = &self.head {
            let out = self.output_dim();
            for (drow, yrow) in ws
                .delta
                .chunks_exact_mut(out)
                .zip(ws.acts[layers].chunks_exact(out))
            {
                for ((d, y), s) in drow.iter_mut().zip(yrow).zip(scale) {
                    let t = y / s;
                    *d *= s * (1.0 - t * t);
                }
            }
        }
        for l in (0..layers).rev() {
            let shape = (batch, self.sizes[l], self.sizes[l + 1]);
            let (w, b) = self.offsets(l);
            if let Some(grad) = grad.as_deref_mut() {
                // ∂L/∂W_l = A_{l-1}ᵀ · δ_l ; ∂L/∂b_l = Σ_rows δ_l.
                let (gw, gb) = grad[w..].split_at_mut(b - w);
                ws.kernel.dense_param_grad(
                    &ws.acts[l],
                    &ws.delta,
                    shape,
                    gw,
                    &mut gb[..shape.2],
                    &mut ws.scratch,
                );
            }
            if l == 0 && dx.is_none() {
                break;
            }
            // ∂L/∂A_{l-1} = δ_l · W_lᵀ, through the ReLU of layer l-1 (none below layer 0).
            ws.delta_prev.resize(batch * shape.1, 0.0);
            let below = (l > 0).then_some(ws.acts[l].as_slice());
            ws.kernel.dense_input_grad(
                &ws.delta,
                &self.params[w..b],
                shape,
                below,
                &mut ws.delta_prev,
                &mut ws.scratch,
            );
            if l == 0 {
                if let Some(dx) = dx.take() {
                    dx.copy_from_slice(&ws.delta_prev);
                }
                break;
            }
            std::mem::swap(&mut ws.delta, &mut ws.delta_prev);
        }
    }

    /// Polyak averaging of a target network on `kernel`: θ' ← τ·θ + (1 − τ)·θ'.
    pub fn soft_update_from(&mut self, online: &Mlp, tau: f32, kernel: Kernel) {
        kernel.polyak(&mut self.params, &online.params, tau);
    }

    /// Tensor names and shapes in the safetensors file: `l{i}.weight` (fan-in × fan-out, as
    /// stored here) and `l{i}.bias`.
    fn tensor_names(&self) -> Vec<(String, Vec<usize>)> {
        (0..self.layers())
            .flat_map(|l| {
                [
                    (
                        format!("l{l}.weight"),
                        vec![self.sizes[l], self.sizes[l + 1]],
                    ),
                    (format!("l{l}.bias"), vec![self.sizes[l + 1]]),
                ]
            })
            .collect()
    }

    /// Saves the parameters as safetensors (atomically).
    pub fn save(&self, path: &Path) -> Result<()> {
        candle_ref::save(self, path)
    }

    /// Loads parameters saved by [`Mlp::save`] into a network of this shape. A missing file,
    /// a corrupt file, tensors of other names or shapes, or a non-finite weight are errors
    /// naming the file.
    pub fn load(&mut self, path: &Path) -> Result<()> {
        let params = candle_ref::load_params(path, &self.tensor_names())?;
        if params.len() != self.params.len() {
            return Err(Error::parse(
                path,
                "parameter count does not match the network",
            ));
        }
        if let Some(i) = params.iter().position(|x| !x.is_finite()) {
            return Err(Error::parse(
                path,
                format!("parameter {i} is not finite ({})", params[i]),
            ));
        }
        self.params = params;
        Ok(())
    }
}

/// Adam (Kingma & Ba) without weight decay.
///
/// Moments that decay below `f32::MIN_POSITIVE` are flushed to zero: the moments of dead ReLU
/// units shrink geometrically (×0.9 and ×0.999 per step), become subnormal after a few
/// thousand updates, and subnormal arithmetic is slow enough on x86 to slow the whole update
/// by 1.5–1.7×. A moment that small changes no parameter (lr·m̂/(√v̂ + ε) with ε = 1e-8 is
/// far below one ulp of any weight), so flushing it changes no result that matters.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Adam {
    /// Learning rate.
    pub lr: f32,
    /// β1.
    pub beta1: f32,
    /// β2.
    pub beta2: f32,
    /// ε.
    pub eps: f32,
    m: Vec<f32>,
    v: Vec<f32>,
    t: i32,
    /// The kernel the step's loop is compiled for (same results in every kernel).
    pub kernel: Kernel,
}

impl Adam {
    /// Adam for `n` parameters with the usual β1 = 0.9, β2 = 0.999, ε = 1e-8, its loop
    /// compiled for `kernel`.
    pub fn new(n: usize, lr: f32, kernel: Kernel) -> Self {
        Adam {
            lr,
            beta1: 0.9,
            beta2: 0.999,
            eps: 1e-8,
            m: vec![0.0; n],
            v: vec![0.0; n],
            t: 0,
            kernel,
        }
    }

    /// One step: θ ← θ − lr · m̂ / (√v̂ + ε).
    pub fn step(&mut self, params: &mut [f32], grad: &[f32]) {
        self.t += 1;
        let (b1, b2) = (self.beta1, self.beta2);
        let c1 = 1.0 - b1.powi(self.t);
        let c2 = 1.0 - b2.powi(self.t);
        let step = self.lr / c1;
        let c2_sqrt = c2.sqrt();
        let h = kernel::AdamStep {
            b1,
            b2,
            eps: self.eps,
            step,
            c2_sqrt,
        };
        self.kernel.adam(params, grad, &mut self.m, &mut self.v, h);
    }

    /// Number of subnormal values among the moments (the bench reports it).
    pub fn subnormal_moments(&self) -> usize {
        self.m
            .iter()
            .chain(&self.v)
            .filter(|x| x.is_subnormal())
            .count()
    }
}
