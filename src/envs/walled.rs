//! The geometry the rooms' environments share ([`super::rooms`], [`super::three_rooms`]): a
//! point in a box moved by a clipped displacement, straight walls that block a step crossing
//! them, a target disc. Each environment says where its walls are (`blocked`, `clear`); the
//! step, the ball starts and the straight connections are written once, here.

use crate::env::{Goals, Step};
use crate::rng::Rng;
use rand::Rng as _;

/// A box [0, `width`] × [0, `height`], moves of at most `max_action` per axis, and a target
/// disc.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Walled {
    pub width: f32,
    pub height: f32,
    pub max_action: f32,
    pub target: [f32; 2],
    pub target_radius: f32,
}

impl Walled {
    /// Pure: moves by the clipped action (NaN counts as 0), kept in the box, unless `blocked`
    /// says the segment crosses a wall; reward 1 and the end of the episode in the target disc.
    pub fn step(
        &self,
        s: &[f32; 2],
        a: &[f32],
        blocked: impl Fn(&[f32; 2], &[f32; 2]) -> bool,
    ) -> Step<[f32; 2]> {
        let clip = |v: f32| {
            if v.is_nan() {
                0.0
            } else {
                v.clamp(-self.max_action, self.max_action)
            }
        };
        let n = [
            (s[0] + clip(a[0])).clamp(0.0, self.width),
            (s[1] + clip(a[1])).clamp(0.0, self.height),
        ];
        let n = if blocked(s, &n) { *s } else { n };
        let done = self.in_disc(&n, &self.target);
        Step {
            state: n,
            reward: f32::from(u8::from(done)),
            terminal: done,
        }
    }

    /// Whether `p` lies in the target disc's radius around `center` (the target itself for the
    /// step; any goal for HER's [`crate::env::Goals::goal_reward`]).
    pub fn in_disc(&self, p: &[f32], center: &[f32]) -> bool {
        (p[0] - center[0]).hypot(p[1] - center[1]) < self.target_radius
    }

    /// Uniform in the disc (r = radius·√u, angle uniform), clamped to the box; a point across a
    /// wall from the centre (`blocked`) is replaced by the centre (a start is reachable from the
    /// ball's centre).
    pub fn sample_ball(
        &self,
        center: &[f32; 2],
        radius: f32,
        rng: &mut Rng,
        blocked: impl Fn(&[f32; 2], &[f32; 2]) -> bool,
    ) -> [f32; 2] {
        let r = radius * rng.random::<f32>().sqrt();
        let phi = std::f32::consts::TAU * rng.random::<f32>();
        let p = [
            (center[0] + r * phi.cos()).clamp(0.0, self.width),
            (center[1] + r * phi.sin()).clamp(0.0, self.height),
        ];
        if blocked(center, &p) {
            *center
        } else {
            p
        }
    }

    /// The straight line in equal steps of at most `max_action` per axis, when `clear` says it
    /// keeps `clearance` from every wall and it is at most 2 long (as the maze's).
    pub fn connect(
        &self,
        from: &[f32; 2],
        to: &[f32; 2],
        clearance: f32,
        clear: impl Fn(&[f32; 2], &[f32; 2], f32) -> bool,
    ) -> Option<Vec<Vec<f32>>> {
        let d = [to[0] - from[0], to[1] - from[1]];
        if d[0].hypot(d[1]) > 2.0 || !clear(from, to, clearance) {
            return None;
        }
        let steps = (d[0].abs().max(d[1].abs()) / self.max_action)
            .ceil()
            .max(1.0);
        Some(vec![vec![d[0] / steps, d[1] / steps]; steps as usize])
    }

    /// Whether both ends lie in the box at least `clearance` from its sides.
    pub fn inside(&self, p: &[f32; 2], clearance: f32) -> bool {
        (clearance..=self.width - clearance).contains(&p[0])
            && (clearance..=self.height - clearance).contains(&p[1])
    }
}

/// Goals: positions; the episode's goal is the target; the reward 1 within the target's radius
/// of the goal, by the step's own comparison ([`Walled::in_disc`]).
impl Goals<[f32; 2]> for Walled {
    fn goal_dim(&self) -> usize {
        2
    }
    fn achieved_goal(&self, obs: &[f32], out: &mut [f32]) {
        out.copy_from_slice(&obs[..2]);
    }
    fn desired_goal(&self, _: &[f32; 2], out: &mut [f32]) {
        out.copy_from_slice(&self.target);
    }
    fn goal_reward(&self, achieved: &[f32], desired: &[f32]) -> f32 {
        f32::from(u8::from(self.in_disc(achieved, desired)))
    }
}
