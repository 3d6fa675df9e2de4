//! One SAC update ([`Sac::update`]): a_π and α, the TD targets, the critics, the actor, the
//! targets; and the gradients it takes, by hand, for the tests against autograd
//! ([`Sac::gradients`]).

use super::{Sac, LOG_STD_BOUNDS, TANH_EPS};
use crate::learner::replay::Batch;
use crate::learner::{concat_rows, Losses};
use crate::nn::kernel::Kernel;
use crate::nn::Workspace;

/// A squashed sample of the actor for a batch: ε, σ, a = tanh(μ + σ·ε) and log π(a|s), and
/// whether ℓ was inside its clamp (else it gets no gradient).
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub(super) struct Sample {
    eps: Vec<f32>,
    sigma: Vec<f32>,
    a: Vec<f32>,
    logp: Vec<f32>,
    free: Vec<bool>,
}

impl Sample {
    /// From the actor's output rows [μ | ℓ] (n × 2d) and ε (n × d).
    fn squash(&mut self, out: &[f32], eps: &[f32], d: usize) {
        let half_log_2pi = 0.5 * (2.0 * std::f32::consts::PI).ln();
        let (lo, hi) = LOG_STD_BOUNDS;
        self.eps.clear();
        self.eps.extend_from_slice(eps);
        self.sigma.clear();
        self.a.clear();
        self.logp.clear();
        self.free.clear();
        for (row, e) in out.chunks_exact(2 * d).zip(eps.chunks_exact(d)) {
            let mut logp = 0.0;
            for j in 0..d {
                let l = row[d + j];
                let sigma = l.clamp(lo, hi).exp();
                let a = (row[j] + sigma * e[j]).tanh();
                logp += -0.5 * e[j] * e[j] - l.clamp(lo, hi) - half_log_2pi
                    - (1.0 - a * a + TANH_EPS).ln();
                self.sigma.push(sigma);
                self.a.push(a);
                self.free.push((lo..=hi).contains(&l));
            }
            self.logp.push(logp);
        }
    }
}

/// Scratch buffers of the update.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(super) struct Scratch {
    pub(super) ws_actor: Workspace,
    pub(super) ws_next: Workspace,
    pub(super) ws_critics: [Workspace; 2],
    pub(super) ws_act: Workspace,
    pub(super) eps: Vec<f32>,
    pub(super) pi: Sample,
    pub(super) next: Sample,
    pub(super) sa: Vec<f32>,
    pub(super) scaled: Vec<f32>,
    pub(super) q: [Vec<f32>; 2],
    pub(super) y: Vec<f32>,
    pub(super) dq: Vec<f32>,
    pub(super) dsa: Vec<f32>,
    pub(super) dout: Vec<f32>,
    pub(super) grad_actor: Vec<f32>,
    pub(super) grad_critics: [Vec<f32>; 2],
}

impl Scratch {
    pub(super) fn new(kernel: Kernel) -> Self {
        let ws = || Workspace::with_kernel(kernel);
        Scratch {
            ws_actor: ws(),
            ws_next: ws(),
            ws_critics: [ws(), ws()],
            ws_act: ws(),
            eps: Vec::new(),
            pi: Sample::default(),
            next: Sample::default(),
            sa: Vec::new(),
            scaled: Vec::new(),
            q: [Vec::new(), Vec::new()],
            y: Vec::new(),
            dq: Vec::new(),
            dsa: Vec::new(),
            dout: Vec::new(),
            grad_actor: Vec::new(),
            grad_critics: [Vec::new(), Vec::new()],
        }
    }
}

/// The gradients of one update's three losses, before any optimiser step (for tests).
#[derive(Debug, Clone, PartialEq)]
pub struct SacGradients {
    /// ∂/∂θ_π of mean(α·log π(a_π|s) − min_i Q_i(s, b ⊙ a_π)).
    pub actor: Vec<f32>,
    /// ∂/∂θ_i of ½ Σ_i mean (Q_i(s, a) − y)², per critic.
    pub critics: [Vec<f32>; 2],
    /// ∂/∂log α of −mean(log α · (log π(a_π|s) + H̄)).
    pub log_alpha: f32,
    /// The TD targets y.
    pub y: Vec<f32>,
}

impl Sac {
    /// One SAC update on a mini-batch, as Stable-Baselines3's `SAC.train` step. Returns the
    /// losses.
    pub fn update(&mut self, b: &Batch) -> Losses {
        let n = b.len;
        // 1. a_π ~ π(·|s), reparameterised: ε drawn first, then ε' for the targets.
        self.draw(n);
        let eps = std::mem::take(&mut self.s.eps);
        self.draw(n);
        let eps_next = std::mem::take(&mut self.s.eps);
        self.sample_pi(&b.obs, n, &eps);
        // 2. α: a step on −mean(log α · (log π + H̄)); this update uses α from before it.
        let alpha = self.alpha();
        let g = self.alpha_gradient();
        if let Some(opt) = self.alpha_opt.as_mut() {
            let mut p = [self.log_alpha];
            opt.step(&mut p, &[g]);
            self.log_alpha = p[0];
        }
        // 3. y = r + γ(1 − done)(min_i Q'_i(s', b ⊙ a') − α log π(a'|s')), a' ~ π(·|s').
        self.td_targets(b, &eps_next, alpha);
        // 4. Critics: one step each on ½ Σ_i mean (Q_i(s, a) − y)².
        let critic = self.critic_gradients(b);
        for i in 0..2 {
            self.critic_opts[i].step(&mut self.critics[i].params, &self.s.grad_critics[i]);
        }
        // 5. Actor: one step on mean(α log π(a_π|s) − min_i Q_i(s, b ⊙ a_π)), updated critics.
        let actor = self.actor_gradient(&b.obs, n, alpha);
        self.actor_opt
            .step(&mut self.actor.net.params, &self.s.grad_actor);
        // 6. Targets: θ'_i ← τ·θ_i + (1 − τ)·θ'_i.
        for (t, c) in self.critic_targets.iter_mut().zip(&self.critics) {
            t.soft_update_from(c, self.config.tau, self.kernel);
        }
        self.s.eps = eps;
        self.updates += 1;
        Losses {
            critic,
            actor: Some(actor),
        }
    }

    /// The three losses' gradients on `b` with the given draws (ε for a_π, ε' for a'), no
    /// step taken: what [`Sac::update`] computes, for tests against autograd. The actor's is
    /// taken with the critics as they are (the update takes it after their step).
    pub fn gradients(&mut self, b: &Batch, eps: &[f32], eps_next: &[f32]) -> SacGradients {
        let n = b.len;
        self.sample_pi(&b.obs, n, eps);
        let alpha = self.alpha();
        let log_alpha = self.alpha_gradient();
        self.td_targets(b, eps_next, alpha);
        self.critic_gradients(b);
        self.actor_gradient(&b.obs, n, alpha);
        SacGradients {
            actor: self.s.grad_actor.clone(),
            critics: self.s.grad_critics.clone(),
            log_alpha,
            y: self.s.y.clone(),
        }
    }

    /// a_π and log π(a_π|s) for the batch's states, the actor's activations kept in
    /// `ws_actor` for its backward pass.
    fn sample_pi(&mut self, obs: &[f32], n: usize, eps: &[f32]) {
        let d = self.dim();
        let out = self.actor.net.forward(obs, n, &mut self.s.ws_actor);
        self.s.pi.squash(out, eps, d);
    }

    /// ∂/∂log α of −mean(log α · (log π(a_π|s) + H̄)).
    fn alpha_gradient(&self) -> f32 {
        let logp = &self.s.pi.logp;
        -logp.iter().map(|l| l + self.target_entropy).sum::<f32>() / logp.len() as f32
    }

    /// The TD targets into `s.y`.
    fn td_targets(&mut self, b: &Batch, eps_next: &[f32], alpha: f32) {
        let (n, o, d) = (b.len, self.obs_dim, self.dim());
        let s = &mut self.s;
        let out = self.actor.net.forward(&b.next_obs, n, &mut s.ws_next);
        s.next.squash(out, eps_next, d);
        scale_rows(&s.next.a, &self.actor.bounds, &mut s.scaled);
        concat_rows(&b.next_obs, o, &s.scaled, d, &mut s.sa);
        let [ws0, ws1] = &mut s.ws_critics;
        let q0 = self.critic_targets[0].forward(&s.sa, n, ws0);
        let q1 = self.critic_targets[1].forward(&s.sa, n, ws1);
        let gamma = self.config.gamma;
        s.y.clear();
        s.y.extend((0..n).map(|i| {
            let next = q0[i].min(q1[i]) - alpha * s.next.logp[i];
            b.rew[i] + gamma * (1.0 - b.done[i]) * next
        }));
    }

    /// The critics' gradients into `s.grad_critics`; returns mean (Q_1(s, a) − y)².
    fn critic_gradients(&mut self, b: &Batch) -> f32 {
        let (n, o, d) = (b.len, self.obs_dim, self.dim());
        let s = &mut self.s;
        concat_rows(&b.obs, o, &b.act, d, &mut s.sa);
        let mut loss = 0.0;
        for i in 0..2 {
            let critic = &self.critics[i];
            let q = critic.forward(&s.sa, n, &mut s.ws_critics[i]);
            if i == 0 {
                loss = q.iter().zip(&s.y).map(|(q, y)| (q - y) * (q - y)).sum::<f32>() / n as f32;
            }
            // ∂/∂Q_i of ½ mean (Q_i − y)².
            s.dq.clear();
            s.dq.extend(q.iter().zip(&s.y).map(|(q, y)| (q - y) / n as f32));
            s.grad_critics[i].resize(critic.params.len(), 0.0);
            critic.backward(&mut s.ws_critics[i], &s.dq, Some(&mut s.grad_critics[i]), None);
        }
        loss
    }

    /// The actor's gradient into `s.grad_actor` (a_π from [`Self::sample_pi`]); returns the
    /// loss mean(α log π(a_π|s) − min_i Q_i(s, b ⊙ a_π)).
    ///
    /// With u = μ + σε, a = tanh(u), g = 2a(1 − a²)/(1 − a² + δ) (∂/∂u of −log(1 − a² + δ))
    /// and q = ∂ min_i Q_i/∂(b ⊙ a), per sample and component:
    /// ∂L/∂μ = (α·g − q·b·(1 − a²))/n and ∂L/∂ℓ = (α·(g·σε − 1) − q·b·(1 − a²)·σε)/n inside
    /// ℓ's clamp, 0 outside (the Gaussian term's ε is fixed by the reparameterisation).
    fn actor_gradient(&mut self, obs: &[f32], n: usize, alpha: f32) -> f32 {
        let (o, d) = (self.obs_dim, self.dim());
        let bounds = &self.actor.bounds;
        let s = &mut self.s;
        scale_rows(&s.pi.a, bounds, &mut s.scaled);
        concat_rows(obs, o, &s.scaled, d, &mut s.sa);
        for i in 0..2 {
            let q = self.critics[i].forward(&s.sa, n, &mut s.ws_critics[i]);
            s.q[i].clear();
            s.q[i].extend_from_slice(q);
        }
        let loss = (0..n)
            .map(|k| alpha * s.pi.logp[k] - s.q[0][k].min(s.q[1][k]))
            .sum::<f32>()
            / n as f32;
        // q = ∂ min_i Q_i/∂(b ⊙ a): the smaller critic's input gradient (Q_1 on ties).
        s.dout.clear();
        s.dout.resize(n * d, 0.0);
        s.dsa.resize(n * (o + d), 0.0);
        for i in 0..2 {
            s.dq.clear();
            s.dq.extend((0..n).map(|k| {
                let first = s.q[0][k] <= s.q[1][k];
                if first == (i == 0) {
                    1.0
                } else {
                    0.0
                }
            }));
            self.critics[i].backward(&mut s.ws_critics[i], &s.dq, None, Some(&mut s.dsa));
            for (acc, row) in s.dout.chunks_exact_mut(d).zip(s.dsa.chunks_exact(o + d)) {
                for (x, g) in acc.iter_mut().zip(&row[o..]) {
                    *x += g;
                }
            }
        }
        // dout holds q per (k, j); turn it into [∂L/∂μ | ∂L/∂ℓ] rows.
        let inv_n = 1.0 / n as f32;
        let mut rows = std::mem::take(&mut s.scaled);
        rows.clear();
        for k in 0..n {
            for part in 0..2 {
                for (j, bound) in bounds.iter().enumerate() {
                    let idx = k * d + j;
                    let (a, sigma, e) = (s.pi.a[idx], s.pi.sigma[idx], s.pi.eps[idx]);
                    let one_minus = 1.0 - a * a;
                    let g = 2.0 * a * one_minus / (one_minus + TANH_EPS);
                    let dq_du = s.dout[idx] * bound * one_minus;
                    rows.push(if part == 0 {
                        (alpha * g - dq_du) * inv_n
                    } else if s.pi.free[idx] {
                        (alpha * (g * sigma * e - 1.0) - dq_du * sigma * e) * inv_n
                    } else {
                        0.0
                    });
                }
            }
        }
        s.grad_actor.resize(self.actor.net.params.len(), 0.0);
        self.actor
            .net
            .backward(&mut s.ws_actor, &rows, Some(&mut s.grad_actor), None);
        s.scaled = rows;
        loss
    }
}

/// `out` = each row of `a` times the bounds `b`.
fn scale_rows(a: &[f32], b: &[f32], out: &mut Vec<f32>) {
    out.clear();
    for row in a.chunks_exact(b.len()) {
        out.extend(row.iter().zip(b).map(|(x, b)| x * b));
    }
}

