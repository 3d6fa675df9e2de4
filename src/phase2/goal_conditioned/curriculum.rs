//! Where a goal-conditioned chain's training episodes start ([`Curriculum`]): the memory of
//! each start's last tries, the draw it weights, and Backplay's frontier.

use super::settings::{Curriculum, GoalConditioned};
use crate::env::Env;
use crate::phase2::{FirstStarts, Phase2Inputs};
use crate::rng::Rng;
use rand::Rng as _;
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// The curriculum's memory over the starts j = 0 … M − 1 (τ_0, then each sub-goal but the last).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub(super) struct Starts {
    /// Per start j: its last `window` tries (reached g_{j+1}; with Backplay's order, reached
    /// the final goal).
    tries: Vec<VecDeque<bool>>,
    /// Backplay's frontier: the earliest start drawn (M − 1 at first).
    frontier: usize,
}

impl Starts {
    /// No try yet at any of `m` starts, the frontier at the last.
    pub fn new(m: usize) -> Self {
        Starts {
            tries: vec![VecDeque::new(); m],
            frontier: m.saturating_sub(1),
        }
    }

    /// M.
    pub fn len(&self) -> usize {
        self.tries.len()
    }

    /// Backplay's frontier.
    pub fn frontier(&self) -> usize {
        self.frontier
    }

    /// Whether this memory could be a run's with `m` starts (a checkpoint's is checked).
    pub fn fits(&self, m: usize) -> bool {
        self.tries.len() == m && self.frontier < m
    }

    /// The start j of the next episode, drawn from `rng`: with failure-weighted starts, j with
    /// weight 1 / (success rate of its last tries), 10 while that rate is at most 0.1 (and
    /// before any try); with Backplay's order, uniformly at or after the frontier.
    pub fn draw(&self, curriculum: Curriculum, rng: &mut Rng) -> usize {
        let m = self.len();
        match curriculum {
            Curriculum::Backplay => rng.random_range(self.frontier..m),
            Curriculum::FailureWeighted => {
                let weight = |tries: &VecDeque<bool>| {
                    let rate = tries.iter().filter(|&&t| t).count() as f64 / tries.len() as f64;
                    if tries.is_empty() || rate <= 0.1 {
                        10.0
                    } else {
                        1.0 / rate
                    }
                };
                let weights: Vec<f64> = self.tries.iter().map(weight).collect();
                let mut u = rng.random::<f64>() * weights.iter().sum::<f64>();
                for (j, w) in weights.iter().enumerate() {
                    if u < *w {
                        return j;
                    }
                    u -= w;
                }
                m - 1
            }
        }
    }

    /// Remembers a try from `start` that `won` (forgetting tries past `settings.window`); with
    /// Backplay's order, moves the frontier back one once `advance_at` of the frontier's last
    /// `window` tries won.
    pub fn record(&mut self, settings: &GoalConditioned, start: usize, won: bool) {
        let tries = &mut self.tries[start];
        tries.push_back(won);
        if tries.len() > settings.window {
            tries.pop_front();
        }
        let rate = tries.iter().filter(|&&t| t).count() as f32 / settings.window as f32;
        let at_frontier = start == self.frontier && self.frontier > 0;
        if settings.curriculum == Curriculum::Backplay && at_frontier && rate >= settings.advance_at
        {
            self.frontier -= 1;
        }
    }
}

/// The state a training episode from start `j` begins in, τ's state `at` there: at j = 0 with
/// `phase2.first_starts = "drawn"`, the environment's own draw; otherwise `at` (with
/// `rest_starts` at j ≥ 1, the body at rest where `at` stands) moved in B_ε where the
/// environment can.
pub(super) fn start_state<E: Env>(
    inputs: &Phase2Inputs<'_, E>,
    settings: &GoalConditioned,
    j: usize,
    at: &E::State,
    rng: &mut Rng,
) -> E::State {
    let (env, config) = (inputs.env, inputs.config());
    let rest = (settings.rest_starts && j > 0)
        .then(|| env.drawn_starts().and_then(|d| d.at_rest_like(at)))
        .flatten();
    let at = rest.as_ref().unwrap_or(at);
    match (
        j,
        config.first_starts,
        env.drawn_starts(),
        env.ball_starts(),
    ) {
        (0, FirstStarts::Drawn, Some(d), _) => d.drawn_start(at, rng),
        (_, _, _, Some(ball)) => ball.sample_ball(at, config.epsilon, rng),
        _ => at.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::{Seeds, Stream};

    /// Backplay's frontier moves back one start once half of its last tries (of a window of 4)
    /// won, and never below τ_0; its draws stay at or after it.
    #[test]
    fn backplays_frontier_moves_back_as_its_tries_win() {
        let settings = GoalConditioned {
            curriculum: Curriculum::Backplay,
            window: 4,
            advance_at: 0.5,
            ..GoalConditioned::default()
        };
        let mut starts = Starts::new(3);
        assert_eq!(starts.frontier(), 2);
        starts.record(&settings, 2, true);
        assert_eq!(starts.frontier(), 2, "1 of a window of 4 is a quarter");
        starts.record(&settings, 2, true);
        assert_eq!(starts.frontier(), 1);
        let mut rng = Seeds::new(0).stream(Stream::Start);
        assert!((0..100).all(|_| starts.draw(Curriculum::Backplay, &mut rng) >= 1));
        for _ in 0..2 {
            starts.record(&settings, 1, true);
        }
        assert_eq!(starts.frontier(), 0);
        for _ in 0..4 {
            starts.record(&settings, 0, true);
        }
        assert_eq!(starts.frontier(), 0);
    }

    /// Failure-weighted draws favour the start that fails: with start 0 winning every try and
    /// start 1 none, weights 1 and 10 (1/11 and 10/11 of the draws).
    #[test]
    fn failure_weighted_draws_favour_the_failing_start() {
        let settings = GoalConditioned::default();
        let mut starts = Starts::new(2);
        for _ in 0..settings.window {
            starts.record(&settings, 0, true);
            starts.record(&settings, 1, false);
        }
        let mut rng = Seeds::new(0).stream(Stream::Start);
        let n = 11_000;
        let ones = (0..n)
            .filter(|_| starts.draw(Curriculum::FailureWeighted, &mut rng) == 1)
            .count();
        let share = ones as f64 / n as f64;
        assert!((share - 10.0 / 11.0).abs() < 0.01, "{share}");
    }
}
