//! Two rooms joined by a door: a second environment for PBCS, not the paper's maze.
//!
//! The rooms are [0, 1]² and [1, 2] × [0, 1], side by side; the wall x = 1 between them is
//! open only at heights 0.8 – 1 (the door). The agent starts at (0.3, 0.2) and must reach the
//! disc of radius 0.2 around (1.7, 0.2), just across the wall from its start, so the greedy
//! straight line fails and the path goes up through the door. Actions move the point by at
//! most 0.1 per axis; a step that would cross the wall outside the door does not move; reward
//! 1 and the end of the episode in the target disc, 0 otherwise.
//!
//! It offers every PBCS hook of [`Env`]: starts in a ball ([`SampleBall`]), clear balls
//! ([`BallIsClear`]) and straight paths ([`Connect`]), so every switch of the `fast` preset
//! applies to it.
//!
//! ```
//! use pbcs::env::Env;
//! use pbcs::envs::rooms::TwoRooms;
//!
//! let rooms = TwoRooms;
//! // Straight at the wall: blocked, the point stays where it was.
//! assert_eq!(rooms.step(&[0.95, 0.2], &[0.1, 0.0]).state, [0.95, 0.2]);
//! // Through the door.
//! assert_eq!(rooms.step(&[0.95, 0.9], &[0.1, 0.0]).state, [1.05, 0.9]);
//! let done = rooms.step(&[1.7, 0.35], &[0.0, -0.1]);
//! assert_eq!((done.reward, done.terminal), (1.0, true));
//! ```

use super::walled::Walled;
use crate::env::{BallIsClear, Connect, Env, Goals, Planar, SampleBall, Scene, Step};
use crate::rng::Rng;
use parry2d::math::{Isometry, Point};
use parry2d::shape::Segment;

/// Two rooms and a door; the state is the point (x, y).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TwoRooms;

/// The centre of the target disc.
pub const TARGET: [f32; 2] = [1.7, 0.2];
/// The radius of the target disc.
pub const TARGET_RADIUS: f32 = 0.2;
/// The door: heights of the wall x = 1 that are open.
pub const DOOR: (f32, f32) = (0.8, 1.0);
/// The largest move per axis.
pub const MAX_ACTION: f32 = 0.1;
/// The rooms' extent: x in [0, WIDTH], y in [0, HEIGHT].
const WIDTH: f32 = 2.0;
const HEIGHT: f32 = 1.0;
/// The box, the moves and the target ([`Walled`]: the step, ball starts and connections the
/// rooms' environments share).
static ROOMS: Walled = Walled {
    width: WIDTH,
    height: HEIGHT,
    max_action: MAX_ACTION,
    target: TARGET,
    target_radius: TARGET_RADIUS,
};

impl TwoRooms {
    /// Whether the segment from `s` to `n` crosses the wall x = 1 outside the door.
    pub fn blocked(s: &[f32; 2], n: &[f32; 2]) -> bool {
        if (s[0] - 1.0) * (n[0] - 1.0) > 0.0 || s[0] == n[0] {
            return false; // both on one side
        }
        let t = (1.0 - s[0]) / (n[0] - s[0]);
        let y = s[1] + t * (n[1] - s[1]);
        !(DOOR.0 < y && y < DOOR.1)
    }

    /// Whether the segment from `a` to `b` keeps `clearance` from the wall between the rooms
    /// and from the outer walls.
    fn clear_segment(a: &[f32; 2], b: &[f32; 2], clearance: f32) -> bool {
        let inside = |p: &[f32; 2]| ROOMS.inside(p, clearance);
        if !(inside(a) && inside(b)) {
            return false; // the rooms are convex: a segment between inside points stays inside
        }
        let wall = Segment::new(Point::new(1.0, 0.0), Point::new(1.0, DOOR.0));
        let path = Segment::new(Point::new(a[0], a[1]), Point::new(b[0], b[1]));
        let id = Isometry::identity();
        parry2d::query::distance(&id, &wall, &id, &path).is_ok_and(|d| d >= clearance)
            && !Self::blocked(a, b)
    }
}

impl Env for TwoRooms {
    type State = [f32; 2];

    fn obs_dim(&self) -> usize {
        2
    }

    fn action_dim(&self) -> usize {
        2
    }

    fn action_bound(&self, _i: usize) -> f32 {
        MAX_ACTION
    }

    fn start(&self) -> [f32; 2] {
        [0.3, 0.2]
    }

    /// Every episode starts at s_0.
    fn sample_start(&self, _rng: &mut crate::rng::Rng) -> [f32; 2] {
        self.start()
    }

    /// An action is a displacement clipped to ±`MAX_ACTION` per axis.
    fn step_reach(&self) -> Option<f32> {
        Some(MAX_ACTION)
    }

    fn success_region(&self) -> Option<(Vec<f32>, f32)> {
        Some((TARGET.to_vec(), TARGET_RADIUS))
    }

    fn observe(&self, s: &[f32; 2], out: &mut [f32]) {
        out.copy_from_slice(s);
    }

    /// Pure: moves by the clipped action (NaN counts as 0) unless the wall blocks it; reward 1
    /// and the end of the episode in the target disc.
    fn step(&self, s: &[f32; 2], a: &[f32]) -> Step<[f32; 2]> {
        ROOMS.step(s, a, Self::blocked)
    }

    fn obs_names(&self) -> Vec<String> {
        vec!["x".into(), "y".into()]
    }

    fn ball_starts(&self) -> Option<&dyn SampleBall<[f32; 2]>> {
        Some(self)
    }

    fn clear_balls(&self) -> Option<&dyn BallIsClear<[f32; 2]>> {
        Some(self)
    }

    fn connector(&self) -> Option<&dyn Connect<[f32; 2]>> {
        Some(self)
    }

    /// Positions; the episode's goal is the target ([`Walled`]'s goals).
    fn goals(&self) -> Option<&dyn Goals<[f32; 2]>> {
        Some(&ROOMS)
    }
}

impl Planar for TwoRooms {
    fn point(&self, s: &[f32; 2]) -> (f32, f32) {
        (s[0], s[1])
    }

    fn ball_point(&self, center: &[f32]) -> (f32, f32) {
        (center[0], center[1])
    }

    /// The 2 × 1 rectangle, its border and the wall below the door drawn 0.02 thick.
    fn scene(&self) -> Scene {
        let t = 0.02;
        Scene {
            width: WIDTH,
            height: HEIGHT,
            walls: vec![
                [(-t, -t), (WIDTH + t, 0.0)],
                [(-t, HEIGHT), (WIDTH + t, HEIGHT + t)],
                [(-t, 0.0), (0.0, HEIGHT)],
                [(WIDTH, 0.0), (WIDTH + t, HEIGHT)],
                [(1.0 - t / 2.0, 0.0), (1.0 + t / 2.0, DOOR.0)],
            ],
            target: ((TARGET[0], TARGET[1]), TARGET_RADIUS),
            start: self.point(&self.start()),
        }
    }
}

impl SampleBall<[f32; 2]> for TwoRooms {
    /// Uniform in the disc (r = radius·√u, angle uniform), clamped to the rooms; a point
    /// across the wall from the centre is replaced by the centre (a start is reachable from
    /// the ball's centre).
    fn sample_ball(&self, center: &[f32; 2], radius: f32, rng: &mut Rng) -> [f32; 2] {
        ROOMS.sample_ball(center, radius, rng, Self::blocked)
    }
}

impl BallIsClear<[f32; 2]> for TwoRooms {
    /// The disc lies inside the rooms and keeps its radius from the wall between them.
    fn ball_is_clear(&self, center: &[f32; 2], radius: f32) -> bool {
        Self::clear_segment(center, center, radius)
    }
}

impl Connect<[f32; 2]> for TwoRooms {
    /// The straight line in equal steps of at most [`MAX_ACTION`] per axis, when it keeps
    /// `clearance` from every wall and is at most 2 long (as the maze's).
    fn connect(&self, from: &[f32; 2], to: &[f32; 2], clearance: f32) -> Option<Vec<Vec<f32>>> {
        ROOMS.connect(from, to, clearance, Self::clear_segment)
    }
}
