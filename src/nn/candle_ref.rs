//! The same networks on candle: the autograd oracle for [`super::Mlp`]'s hand-written
//! backward pass, the safetensors format of saved networks, and a candle [`Module`] for users
//! who want to run a trained policy with candle.
//!
//! ```
//! use pbcs::nn::{candle_ref, kernel::Kernel, Head, Mlp, Workspace};
//! use pbcs::rng::{Seeds, Stream};
//!
//! let mut rng = Seeds::new(1).stream(Stream::Init);
//! let actor = Mlp::new(&[2, 8, 2], Head::Tanh(vec![0.1, 0.1]), &mut rng);
//! let dir = tempfile::tempdir().unwrap();
//! let path = dir.path().join("actor.safetensors");
//! actor.save(&path).unwrap();
//!
//! // Run the saved policy with candle...
//! use candle_core::{Device, Tensor};
//! use candle_nn::Module;
//! let module = candle_ref::load_module(&path).unwrap();
//! let x = Tensor::new(&[[0.5f32, 0.5]], &Device::Cpu).unwrap();
//! let a: Vec<f32> = module.forward(&x).unwrap().flatten_all().unwrap().to_vec1().unwrap();
//! // ...and it agrees with the fused forward pass.
//! let fused = actor.forward(&[0.5, 0.5], 1, &mut Workspace::with_kernel(Kernel::detect())).to_vec();
//! assert!(a.iter().zip(&fused).all(|(x, y)| (x - y).abs() < 1e-6));
//! ```

use super::{Head, Mlp};
use crate::error::{Error, Result};
use candle_core::{DType, Device, Tensor, Var};
use candle_nn::Module;
use std::collections::HashMap;
use std::path::Path;

/// The parameters of `mlp` as candle variables: `(W_l, b_l)` per layer, W of shape
/// (fan-in, fan-out).
pub fn vars(mlp: &Mlp) -> Vec<(Var, Var)> {
    (0..mlp.layers())
        .map(|l| {
            let (w, b) = mlp.offsets(l);
            let (i, o) = (mlp.sizes()[l], mlp.sizes()[l + 1]);
            let wt = Tensor::from_slice(&mlp.params[w..b], (i, o), &Device::Cpu).unwrap();
            let bt = Tensor::from_slice(&mlp.params[b..b + o], o, &Device::Cpu).unwrap();
            (
                Var::from_tensor(&wt).unwrap(),
                Var::from_tensor(&bt).unwrap(),
            )
        })
        .collect()
}

/// Reads candle variables back into a flat parameter vector of `mlp`'s layout.
pub fn params_from_vars(vars: &[(Var, Var)]) -> Vec<f32> {
    let mut out = Vec::new();
    for (w, b) in vars {
        out.extend(
            w.as_tensor()
                .flatten_all()
                .unwrap()
                .to_vec1::<f32>()
                .unwrap(),
        );
        out.extend(b.as_tensor().to_vec1::<f32>().unwrap());
    }
    out
}

/// A ReLU MLP as a candle [`Module`].
#[derive(Debug, Clone)]
pub struct CandleMlp {
    /// `(W_l, b_l)`, W of shape (fan-in, fan-out).
    pub layers: Vec<(Tensor, Tensor)>,
    /// Output scales of a tanh head (`None`: linear head).
    pub tanh_scale: Option<Tensor>,
}

impl CandleMlp {
    /// The module computing the same function as `mlp`, sharing `vars` (so gradients flow
    /// into them).
    pub fn from_vars(mlp: &Mlp, vars: &[(Var, Var)]) -> Self {
        CandleMlp {
            layers: vars
                .iter()
                .map(|(w, b)| (w.as_tensor().clone(), b.as_tensor().clone()))
                .collect(),
            tanh_scale: match mlp.head() {
                Head::Linear => None,
                Head::Tanh(s) => Some(Tensor::from_slice(s, s.len(), &Device::Cpu).unwrap()),
            },
        }
    }
}

impl Module for CandleMlp {
    fn forward(&self, xs: &Tensor) -> candle_core::Result<Tensor> {
        let mut h = xs.clone();
        let last = self.layers.len() - 1;
        for (l, (w, b)) in self.layers.iter().enumerate() {
            h = h.matmul(w)?.broadcast_add(b)?;
            if l < last {
                h = h.relu()?;
            }
        }
        match &self.tanh_scale {
            Some(s) => h.tanh()?.broadcast_mul(s),
            None => Ok(h),
        }
    }
}

/// Saves `mlp` as safetensors: `l{i}.weight`, `l{i}.bias` and, for a tanh head,
/// `head.tanh_scale`.
pub fn save(mlp: &Mlp, path: &Path) -> Result<()> {
    let mut map: HashMap<String, Tensor> = HashMap::new();
    for (l, (w, b)) in vars(mlp).iter().enumerate() {
        map.insert(format!("l{l}.weight"), w.as_tensor().clone());
        map.insert(format!("l{l}.bias"), b.as_tensor().clone());
    }
    if let Head::Tanh(s) = mlp.head() {
        map.insert(
            "head.tanh_scale".into(),
            Tensor::from_slice(s, s.len(), &Device::Cpu).unwrap(),
        );
    }
    crate::record::write_atomic_via_path(path, |tmp| {
        candle_core::safetensors::save(&map, tmp).map_err(|e| Error::parse(path, e))
    })
}

fn read(path: &Path) -> Result<HashMap<String, Tensor>> {
    if !path.exists() {
        return Err(Error::io(
            path,
            std::io::Error::new(std::io::ErrorKind::NotFound, "no such file"),
        ));
    }
    candle_core::safetensors::load(path, &Device::Cpu)
        .map_err(|e| Error::parse(path, format!("not a valid safetensors file: {e}")))
}

/// Reads the tensors `names` (with their expected shapes) from a safetensors file into one
/// flat vector, in order. Missing tensors, other shapes or dtypes are errors naming the file.
pub fn load_params(path: &Path, names: &[(String, Vec<usize>)]) -> Result<Vec<f32>> {
    let map = read(path)?;
    let mut out = Vec::new();
    for (name, shape) in names {
        let t = map
            .get(name)
            .ok_or_else(|| Error::parse(path, format!("tensor `{name}` is missing")))?;
        if t.dims() != shape.as_slice() || t.dtype() != DType::F32 {
            return Err(Error::parse(
                path,
                format!(
                    "tensor `{name}` is {:?} {:?}, the network expects F32 {:?}",
                    t.dtype(),
                    t.dims(),
                    shape
                ),
            ));
        }
        out.extend(
            t.flatten_all()
                .and_then(|t| t.to_vec1::<f32>())
                .map_err(|e| Error::parse(path, e))?,
        );
    }
    Ok(out)
}

/// Loads a network saved by [`Mlp::save`] as a candle module, for inference with candle.
pub fn load_module(path: &Path) -> Result<CandleMlp> {
    let map = read(path)?;
    let mut layers = Vec::new();
    while let (Some(w), Some(b)) = (
        map.get(&format!("l{}.weight", layers.len())),
        map.get(&format!("l{}.bias", layers.len())),
    ) {
        layers.push((w.clone(), b.clone()));
    }
    if layers.is_empty() {
        return Err(Error::parse(path, "no layer `l0.weight` / `l0.bias` found"));
    }
    Ok(CandleMlp {
        layers,
        tanh_scale: map.get("head.tanh_scale").cloned(),
    })
}
