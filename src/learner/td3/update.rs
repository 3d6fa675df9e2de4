//! One TD3 update ([`Td3::update`]): the TD targets, the critics, the actor (by the
//! critic's gradient or the appendix's argmax), the target networks.

use super::{ActorUpdate, Td3};
use crate::learner::replay::Batch;
use crate::learner::{concat_rows, Losses};
use rand::Rng as _;

impl Td3 {
    /// One TD3 update on a mini-batch (DDPG when the knobs say so; argmax actor when
    /// configured). Returns the losses.
    pub fn update(&mut self, b: &Batch) -> Losses {
        let (_, policy_delay, ..) = self.config.knobs();
        // 1. TD target: y = r + γ·(1 − done)·min_i Q'_i(s', clip(π'(s') + clip(ε, −c, c))).
        self.compute_td_targets(b, true);
        // 2. Critics: minimise mean (Q_i(s, a) − y)².
        let critic = self.update_critics(b);
        self.updates += 1;
        if !self.updates.is_multiple_of(policy_delay as u64) {
            return Losses {
                critic,
                actor: None,
            };
        }
        // 3. Actor.
        let actor = self.update_actor(b);
        // 4. Targets: θ' ← τ·θ + (1 − τ)·θ'.
        let tau = self.config.tau;
        self.actor_target
            .soft_update_from(&self.actor, tau, self.kernel);
        for (t, c) in self.critic_targets.iter_mut().zip(&self.critics) {
            t.soft_update_from(c, tau, self.kernel);
        }
        Losses {
            critic,
            actor: Some(actor),
        }
    }

    /// Step 2 of [`Td3::update`]: one optimiser step of each critic on mean (Q_i(s, a) −
    /// y)², y the TD targets already computed. Returns the first critic's loss.
    fn update_critics(&mut self, b: &Batch) -> f32 {
        let (n, o, a) = (b.len, self.obs_dim, self.bounds.len());
        let s = &mut self.s;
        concat_rows(&b.obs, o, &b.act, a, &mut s.sa);
        let mut critic_loss = 0.0;
        for (i, (critic, opt)) in self
            .critics
            .iter_mut()
            .zip(&mut self.critic_opts)
            .enumerate()
        {
            let q = critic.forward(&s.sa, n, &mut s.ws_critic);
            s.dq.clear();
            s.dq.extend(q.iter().zip(&s.y).map(|(q, y)| 2.0 * (q - y) / n as f32));
            if i == 0 {
                critic_loss = q
                    .iter()
                    .zip(&s.y)
                    .map(|(q, y)| (q - y) * (q - y))
                    .sum::<f32>()
                    / n as f32;
            }
            s.grad_critic.resize(critic.params.len(), 0.0);
            critic.backward(&mut s.ws_critic, &s.dq, Some(&mut s.grad_critic), None);
            opt.step(&mut critic.params, &s.grad_critic);
        }
        critic_loss
    }

    /// Step 3 of [`Td3::update`]: one optimiser step of the actor, its gradient at π(s)
    /// from [`ActorUpdate`]. Returns the actor's loss.
    fn update_actor(&mut self, b: &Batch) -> f32 {
        let (n, a) = (b.len, self.bounds.len());
        let s = &mut self.s;
        s.pi.clear();
        s.pi.extend_from_slice(self.actor.forward(&b.obs, n, &mut s.ws_actor));
        s.da.clear();
        s.da.resize(n * a, 0.0);
        let mut actor_loss = match self.config.actor_update {
            ActorUpdate::Gradient => self.q_ascent_gradient(b),
            ActorUpdate::Argmax => self.argmax_gradient(b),
        };
        let s = &mut self.s;
        let lambda = self.config.action_l2;
        if lambda > 0.0 {
            // + λ · mean (π_i / b_i)², whose gradient at π_i is 2λ π_i / (b_i² · n · a).
            let m = (n * a) as f32;
            for (row, da) in s.pi.chunks_exact(a).zip(s.da.chunks_exact_mut(a)) {
                for ((p, d), b) in row.iter().zip(da.iter_mut()).zip(&self.bounds) {
                    actor_loss += lambda * (p / b) * (p / b) / m;
                    *d += 2.0 * lambda * p / (b * b * m);
                }
            }
        }
        s.grad_actor.resize(self.actor.params.len(), 0.0);
        self.actor
            .backward(&mut s.ws_actor, &s.da, Some(&mut s.grad_actor), None);
        self.actor_opt.step(&mut self.actor.params, &s.grad_actor);
        actor_loss
    }

    /// DDPG's and TD3's actor gradient: ascend Q_1(s, π(s)), so ∂(−mean Q)/∂π(s) =
    /// −(1/n)·∂Q_1/∂a, into `s.da`. Returns −mean Q_1(s, π(s)).
    fn q_ascent_gradient(&mut self, b: &Batch) -> f32 {
        let (n, o, a) = (b.len, self.obs_dim, self.bounds.len());
        let s = &mut self.s;
        concat_rows(&b.obs, o, &s.pi, a, &mut s.sa);
        let q = self.critics[0].forward(&s.sa, n, &mut s.ws_critic);
        let loss = -q.iter().sum::<f32>() / n as f32;
        s.dq.clear();
        s.dq.resize(n, -1.0 / n as f32);
        s.dsa.resize(n * (o + a), 0.0);
        self.critics[0].backward(&mut s.ws_critic, &s.dq, None, Some(&mut s.dsa));
        for (da, row) in s.da.chunks_exact_mut(a).zip(s.dsa.chunks_exact(o + a)) {
            da.copy_from_slice(&row[o..]);
        }
        loss
    }

    /// The appendix's argmax actor: a*(s) = argmax over k uniform actions of Q_1(s, a), and
    /// the gradient of mean ‖π(s) − a*‖² into `s.da`. Returns that loss.
    fn argmax_gradient(&mut self, b: &Batch) -> f32 {
        let (n, o, a) = (b.len, self.obs_dim, self.bounds.len());
        let k = self.config.argmax_samples;
        let s = &mut self.s;
        s.sa.clear();
        for obs in b.obs.chunks_exact(o) {
            for _ in 0..k {
                s.sa.extend_from_slice(obs);
                for &bound in &self.bounds {
                    s.sa.push(self.rng.random_range(-bound..=bound));
                }
            }
        }
        let q = self.critics[0].forward(&s.sa, n * k, &mut s.ws_critic);
        let mut loss = 0.0;
        for i in 0..n {
            let best = (0..k)
                .max_by(|&x, &y| q[i * k + x].total_cmp(&q[i * k + y]))
                .unwrap();
            let row = (i * k + best) * (o + a);
            for j in 0..a {
                let diff = s.pi[i * a + j] - s.sa[row + o + j];
                loss += diff * diff / n as f32;
                s.da[i * a + j] = 2.0 * diff / n as f32;
            }
        }
        loss
    }
}
