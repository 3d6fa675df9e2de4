//! The replay buffer: one flat `f32` array of transitions, a ring of fixed capacity, uniform
//! sampling.

use crate::rng::Rng;
use rand::Rng as _;

/// A sampled mini-batch, flat row-major arrays of `len` rows.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct Batch {
    /// Rows.
    pub len: usize,
    /// s (len × obs_dim).
    pub obs: Vec<f32>,
    /// a (len × act_dim).
    pub act: Vec<f32>,
    /// r (len).
    pub rew: Vec<f32>,
    /// s' (len × obs_dim).
    pub next_obs: Vec<f32>,
    /// 1 if s' is terminal (no bootstrapping), else 0. Time-limit truncation is not terminal.
    pub done: Vec<f32>,
}

/// A ring buffer of transitions (s, a, r, s', terminal).
///
/// Each transition is one row `[s, a, r, s', terminal]` of a single array, so sampling one
/// reads one place in memory (one cache line for the maze's 8 floats) rather than five: the
/// random reads of a million-transition buffer were 6 % of a PBCS run.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Replay {
    capacity: usize,
    obs_dim: usize,
    act_dim: usize,
    len: usize,
    next: usize,
    rows: Vec<f32>,
}

impl Replay {
    /// An empty buffer of `capacity` transitions.
    pub fn new(capacity: usize, obs_dim: usize, act_dim: usize) -> Self {
        Replay {
            capacity,
            obs_dim,
            act_dim,
            len: 0,
            next: 0,
            rows: vec![0.0; capacity * (2 * obs_dim + act_dim + 2)],
        }
    }

    /// Floats per stored transition.
    fn width(&self) -> usize {
        2 * self.obs_dim + self.act_dim + 2
    }

    /// Stored transitions.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether nothing is stored.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Stores a transition, overwriting the oldest when full.
    pub fn push(&mut self, obs: &[f32], act: &[f32], rew: f32, next_obs: &[f32], terminal: bool) {
        let (i, o, a, w) = (self.next, self.obs_dim, self.act_dim, self.width());
        assert!(
            obs.len() == o && next_obs.len() == o && act.len() == a,
            "replay: sizes"
        );
        let row = &mut self.rows[i * w..(i + 1) * w];
        row[..o].copy_from_slice(obs);
        row[o..o + a].copy_from_slice(act);
        row[o + a] = rew;
        row[o + a + 1..2 * o + a + 1].copy_from_slice(next_obs);
        row[2 * o + a + 1] = f32::from(u8::from(terminal));
        self.next = (i + 1) % self.capacity;
        self.len = (self.len + 1).min(self.capacity);
    }

    /// Samples `n` transitions uniformly (with replacement) into `out`.
    pub fn sample(&self, n: usize, rng: &mut Rng, out: &mut Batch) {
        assert!(!self.is_empty(), "sampling an empty replay buffer");
        let (o, a) = (self.obs_dim, self.act_dim);
        out.len = n;
        for v in [
            &mut out.obs,
            &mut out.act,
            &mut out.rew,
            &mut out.next_obs,
            &mut out.done,
        ] {
            v.clear();
        }
        let w = self.width();
        // Element-wise copies: rows are a few floats, where a `memmove` call per field costs
        // more than the copy.
        for _ in 0..n {
            let i = rng.random_range(0..self.len);
            let row = &self.rows[i * w..(i + 1) * w];
            out.obs.extend(row[..o].iter().copied());
            out.act.extend(row[o..o + a].iter().copied());
            out.rew.push(row[o + a]);
            out.next_obs
                .extend(row[o + a + 1..2 * o + a + 1].iter().copied());
            out.done.push(row[2 * o + a + 1]);
        }
    }
}
