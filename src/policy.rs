//! What acts. A skill of a chain, a chain's evaluation and a Python rollout need one thing of a
//! policy: greedy actions for a batch of observations. [`Policy`] says that and what a saved
//! chain records of it (its kind, its network's sizes and its actions' bounds, its weights
//! file); each learner's actor implements it. `crate::learner::load_policy` reads a saved one
//! back by its kind, through the learner family whose policy it is.
//!
//! ```
//! use pbcs::nn::{Head, Mlp, Workspace};
//! use pbcs::policy::Policy;
//! use pbcs::rng::{Seeds, Stream};
//! let actor = Mlp::new(&[2, 8, 2], Head::Tanh(vec![0.1, 0.1]), &mut Seeds::new(0).stream(Stream::Init));
//! let policy: Box<dyn Policy> = Box::new(actor.clone());
//! assert_eq!((policy.kind(), policy.obs_dim(), policy.action_dim()), ("mlp", 2, 2));
//! let mut ws = Workspace::with_kernel(pbcs::nn::kernel::Kernel::detect());
//! let a = policy.act(&[0.5, 0.5], 1, &mut ws).to_vec();
//! assert!(a.iter().all(|x| x.abs() <= 0.1));
//! assert_eq!(a, actor.forward(&[0.5, 0.5], 1, &mut ws));
//! assert!(policy == policy.clone());
//! ```

use crate::error::Result;
use crate::nn::{Head, Mlp, Workspace};
use std::any::Any;
use std::path::Path;

/// A policy: greedy actions for a batch of observations, and what a saved chain records of it.
pub trait Policy: std::fmt::Debug + Send + Sync + 'static {
    /// Its kind as a manifest names it (`crate::learner::load_policy` reads it back): `mlp`,
    /// `sac`.
    fn kind(&self) -> &'static str;
    /// Its network's layer sizes, input first and output last (the manifest's `sizes`).
    fn sizes(&self) -> &[usize];
    /// The bound of each action component (a tanh head's scale; the manifest's
    /// `action_bounds`), empty for an unbounded (linear) output.
    fn action_bounds(&self) -> &[f32];
    /// The actions it gives per observation.
    fn action_dim(&self) -> usize;
    /// The observations it takes.
    fn obs_dim(&self) -> usize {
        self.sizes()[0]
    }
    /// Greedy actions for `n` observations (row-major), computed in `ws`.
    fn act<'w>(&self, obs: &[f32], n: usize, ws: &'w mut Workspace) -> &'w [f32];
    /// Saves its parameters as safetensors at `path` (atomically).
    fn save(&self, path: &Path) -> Result<()>;
    /// A boxed copy.
    fn boxed(&self) -> Box<dyn Policy>;
    /// Whether `other` is the same policy (kind and parameters).
    fn same(&self, other: &dyn Policy) -> bool;
    /// As `Any` (for [`Policy::same`]).
    fn as_any(&self) -> &dyn Any;
}

impl Clone for Box<dyn Policy> {
    fn clone(&self) -> Self {
        self.boxed()
    }
}

impl PartialEq for Box<dyn Policy> {
    fn eq(&self, other: &Self) -> bool {
        self.same(other.as_ref())
    }
}

/// The TD3/DDPG/argmax actor: a deterministic MLP, its tanh head scaled to the action bounds.
impl Policy for Mlp {
    fn kind(&self) -> &'static str {
        "mlp"
    }
    fn sizes(&self) -> &[usize] {
        Mlp::sizes(self)
    }
    fn action_bounds(&self) -> &[f32] {
        match self.head() {
            Head::Tanh(b) => b,
            Head::Linear => &[],
        }
    }
    fn action_dim(&self) -> usize {
        *Mlp::sizes(self).last().expect("an MLP has an output layer")
    }
    fn act<'w>(&self, obs: &[f32], n: usize, ws: &'w mut Workspace) -> &'w [f32] {
        self.forward(obs, n, ws)
    }
    fn save(&self, path: &Path) -> Result<()> {
        Mlp::save(self, path)
    }
    fn boxed(&self) -> Box<dyn Policy> {
        Box::new(self.clone())
    }
    fn same(&self, other: &dyn Policy) -> bool {
        other.as_any().downcast_ref::<Mlp>() == Some(self)
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
}
