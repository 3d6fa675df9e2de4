//! Three rooms in a row (`three_rooms`): the environment issue 47 added to show what a new
//! environment costs — this file and five lines of the registry (`src/envs/mod.rs`), nothing
//! else — through `pbcs run`, `pbcs train`, an experiment with PBCS and vanilla cells
//! (`experiments/three_rooms.toml`), its table and figures, and Python
//! (`pbcs.make("three_rooms")`, a chain's rollouts).
//!
//! The rooms are [0, 1] × [0, 1], [1, 2] × [0, 1] and [2, 3] × [0, 1]. The wall x = 1 is open
//! only at heights 0.8 – 1 (top), the wall x = 2 only at heights 0 – 0.2 (bottom). The agent
//! starts at (0.3, 0.2) and must reach the disc of radius 0.2 around (2.7, 0.8): up, through
//! the top door, down, through the bottom door, up. Actions move the point by at most 0.1 per
//! axis; a step that would cross a wall outside its door does not move; reward 1 and the end
//! of the episode in the target disc, 0 otherwise. It offers every PBCS hook, so every switch
//! of the `fast` preset applies.
//!
//! ```
//! use pbcs::env::Env;
//! use pbcs::envs::three_rooms::ThreeRooms;
//!
//! // The bottom of the first wall is closed, its top open; the second wall the other way.
//! assert_eq!(ThreeRooms.step(&[0.95, 0.5], &[0.1, 0.0]).state, [0.95, 0.5]);
//! assert_eq!(ThreeRooms.step(&[0.95, 0.9], &[0.1, 0.0]).state, [1.05, 0.9]);
//! assert_eq!(ThreeRooms.step(&[1.95, 0.9], &[0.1, 0.0]).state, [1.95, 0.9]);
//! assert_eq!(ThreeRooms.step(&[1.95, 0.1], &[0.1, 0.0]).state, [2.05, 0.1]);
//! let done = ThreeRooms.step(&[2.7, 0.55], &[0.0, 0.1]);
//! assert_eq!((done.reward, done.terminal), (1.0, true));
//! ```

use super::walled::Walled;
use crate::env::{BallIsClear, Connect, Env, Goals, Planar, SampleBall, Scene, Step};
use crate::rng::Rng;
use parry2d::math::{Isometry, Point};
use parry2d::shape::Segment;

/// Three rooms in a row; the state is the point (x, y).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ThreeRooms;

/// The centre of the target disc.
pub const TARGET: [f32; 2] = [2.7, 0.8];
/// The radius of the target disc.
pub const TARGET_RADIUS: f32 = 0.2;
/// The walls between the rooms: x, and the heights of its door (open, exclusive).
pub const WALLS: [(f32, (f32, f32)); 2] = [(1.0, (0.8, 1.0)), (2.0, (0.0, 0.2))];
/// The largest move per axis.
pub const MAX_ACTION: f32 = 0.1;
const WIDTH: f32 = 3.0;
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
const START: [f32; 2] = [0.3, 0.2];

impl ThreeRooms {
    /// Whether the segment from `s` to `n` crosses a wall outside its door.
    pub fn blocked(s: &[f32; 2], n: &[f32; 2]) -> bool {
        WALLS.iter().any(|&(x, (lo, hi))| {
            if (s[0] - x) * (n[0] - x) > 0.0 || s[0] == n[0] {
                return false; // both on one side
            }
            let y = s[1] + (x - s[0]) / (n[0] - s[0]) * (n[1] - s[1]);
            !(lo < y && y < hi)
        })
    }

    /// The closed part of each wall, as segments.
    fn closed() -> impl Iterator<Item = Segment> {
        WALLS.iter().flat_map(|&(x, (lo, hi))| {
            [(0.0, lo), (hi, HEIGHT)]
                .into_iter()
                .filter(|(a, b)| b > a)
                .map(move |(a, b)| Segment::new(Point::new(x, a), Point::new(x, b)))
        })
    }

    /// Whether the segment from `a` to `b` stays inside and keeps `clearance` from every wall.
    fn clear_segment(a: &[f32; 2], b: &[f32; 2], clearance: f32) -> bool {
        let inside = |p: &[f32; 2]| ROOMS.inside(p, clearance);
        let path = Segment::new(Point::new(a[0], a[1]), Point::new(b[0], b[1]));
        let id = Isometry::identity();
        let far = |w: &Segment| {
            parry2d::query::distance(&id, w, &id, &path).is_ok_and(|d| d >= clearance)
        };
        inside(a) && inside(b) && Self::closed().all(|w| far(&w)) && !Self::blocked(a, b)
    }
}

impl Env for ThreeRooms {
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
        START
    }

    /// Every episode starts at s_0.
    fn sample_start(&self, _rng: &mut Rng) -> [f32; 2] {
        START
    }

    fn success_region(&self) -> Option<(Vec<f32>, f32)> {
        Some((TARGET.to_vec(), TARGET_RADIUS))
    }

    /// An action is a displacement clipped to ±[`MAX_ACTION`] per axis.
    fn step_reach(&self) -> Option<f32> {
        Some(MAX_ACTION)
    }

    fn observe(&self, s: &[f32; 2], out: &mut [f32]) {
        out.copy_from_slice(s);
    }

    /// Pure: moves by the clipped action (NaN counts as 0) unless a wall blocks it; reward 1
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

impl Planar for ThreeRooms {
    fn point(&self, s: &[f32; 2]) -> (f32, f32) {
        (s[0], s[1])
    }

    fn ball_point(&self, center: &[f32]) -> (f32, f32) {
        (center[0], center[1])
    }

    /// The 3 × 1 rectangle, its border and the closed parts of the walls, drawn 0.02 thick.
    fn scene(&self) -> Scene {
        let t = 0.02;
        let mut walls = vec![
            [(-t, -t), (WIDTH + t, 0.0)],
            [(-t, HEIGHT), (WIDTH + t, HEIGHT + t)],
            [(-t, 0.0), (0.0, HEIGHT)],
            [(WIDTH, 0.0), (WIDTH + t, HEIGHT)],
        ];
        walls.extend(Self::closed().map(|w| {
            let (x, y0, y1) = (w.a.x, w.a.y, w.b.y);
            [(x - t / 2.0, y0), (x + t / 2.0, y1)]
        }));
        Scene {
            width: WIDTH,
            height: HEIGHT,
            walls,
            target: ((TARGET[0], TARGET[1]), TARGET_RADIUS),
            start: (START[0], START[1]),
        }
    }
}

impl SampleBall<[f32; 2]> for ThreeRooms {
    /// Uniform in the disc (r = radius·√u, angle uniform), clamped to the rooms; a point across
    /// a wall from the centre is replaced by the centre (a start is reachable from the ball's
    /// centre).
    fn sample_ball(&self, center: &[f32; 2], radius: f32, rng: &mut Rng) -> [f32; 2] {
        ROOMS.sample_ball(center, radius, rng, Self::blocked)
    }
}

impl BallIsClear<[f32; 2]> for ThreeRooms {
    /// The disc lies inside the rooms and keeps its radius from every wall.
    fn ball_is_clear(&self, center: &[f32; 2], radius: f32) -> bool {
        Self::clear_segment(center, center, radius)
    }
}

impl Connect<[f32; 2]> for ThreeRooms {
    /// The straight line in equal steps of at most [`MAX_ACTION`] per axis, when it keeps
    /// `clearance` from every wall and is at most 2 long (as the maze's and the rooms').
    fn connect(&self, from: &[f32; 2], to: &[f32; 2], clearance: f32) -> Option<Vec<Vec<f32>>> {
        ROOMS.connect(from, to, clearance, Self::clear_segment)
    }
}
