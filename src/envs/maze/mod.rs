//! The continuous maze of the paper's appendix "Experimental Setup".
//!
//! A maze of size N is the MDP
//!
//! * S = [0, N]², start s_0 = (0.5, 0.5) (centre of cell (0, 0));
//! * A = [−0.1, 0.1]² (out-of-range actions are clipped; a NaN component counts as 0);
//! * step(s, a) = s if the segment [s, s + a] touches a wall, else s + a;
//! * R(s, a, s') = 1[‖s' − target‖ < 0.2] − 1[[s, s + a] touches a wall];
//! * the episode terminates when the target is reached.
//!
//! Walls are boxes of thickness 0.1 centred on the grid lines between cells, extended by
//! half the thickness at both ends so that corners are closed, plus the 4N border walls. The
//! target is (N − 0.5, N − 0.5), or (0.5, 1.5) for the 2×2 U-shaped maze.
//!
//! ```
//! use pbcs::config::MazeConfig;
//! use pbcs::env::Env;
//! use pbcs::envs::maze::Maze;
//!
//! let maze = Maze::new(&MazeConfig { size: 2, ..MazeConfig::default() }).unwrap();
//! let s0 = maze.start();
//! // Moving right is free...
//! let step = maze.step(&s0, &[0.1, 0.0]);
//! assert_eq!((step.state.x, step.state.y, step.reward), (0.6, 0.5, 0.0));
//! // ...but the U-shape's wall at y = 1 blocks the way up from (0.5, 0.9).
//! let near_wall = parry2d::math::Point::new(0.5, 0.9);
//! let step = maze.step(&near_wall, &[0.0, 0.1]);
//! assert_eq!((step.state, step.reward), (near_wall, -1.0));
//! ```

mod layout;
mod walls;

pub use layout::{Layout, Side};
pub use walls::{Wall, Walls};

use crate::env::{BallIsClear, Connect, Env, Goals, Planar, SampleBall, Scene, Step};
use crate::error::{Error, Result};
use crate::validate::{positive_finite, Check};
use parry2d::math::{Point, Vector};
use serde::{Deserialize, Serialize};

/// Largest maze size accepted. Phase 1 and the wall grid scale with N², so the bound keeps a
/// typo (`size = 1000`) from turning into hours of work; the paper's largest maze is 15.
pub const MAX_MAZE_SIZE: usize = 100;

/// The maze environment (appendix "Experimental Setup"): a layout named by its size and its
/// own maze seed, and the constants of the MDP.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MazeConfig {
    /// N: the maze has N×N cells and the state space is [0, N]². 2 ≤ N ≤ 100.
    pub size: usize,
    /// Seed of the layout, independent of the run seed, so that one layout can be held fixed
    /// while runs vary. Ignored for N = 2, whose layout is the fixed U-shape.
    pub seed: u64,
    /// Wall thickness (0.1 in the paper).
    pub wall_thickness: f32,
    /// Success radius around the target (0.2 in the paper).
    pub target_radius: f32,
    /// Largest absolute action component (0.1 in the paper).
    pub max_action: f32,
}

impl Default for MazeConfig {
    fn default() -> Self {
        MazeConfig {
            size: 5,
            seed: 0,
            wall_thickness: 0.1,
            target_radius: 0.2,
            max_action: 0.1,
        }
    }
}

impl Check for MazeConfig {
    fn check(&self) -> Result<()> {
        if !(2..=MAX_MAZE_SIZE).contains(&self.size) {
            return Err(Error::invalid(
                "maze.size",
                format!(
                    "must be between 2 and {MAX_MAZE_SIZE} cells, got {}",
                    self.size
                ),
            ));
        }
        positive_finite("maze.wall_thickness", self.wall_thickness, 0.5)?;
        positive_finite("maze.target_radius", self.target_radius, 0.5)?;
        positive_finite("maze.max_action", self.max_action, 0.5)?;
        Ok(())
    }
}

/// A maze environment: layout, wall geometry and the constants of the MDP.
#[derive(Debug, Clone)]
pub struct Maze {
    config: MazeConfig,
    layout: Layout,
    walls: Walls,
    start: Point<f32>,
    target: Point<f32>,
}

impl Maze {
    /// Builds the maze that `config` names (size and maze seed), after validating it.
    pub fn new(config: &MazeConfig) -> Result<Self> {
        config.check()?;
        let n = config.size;
        let layout = Layout::generate(n, config.seed);
        let half = config.wall_thickness / 2.0;
        let walls = layout
            .wall_segments()
            .into_iter()
            .map(|((x0, y0), (x1, y1))| {
                Wall::from_corners(
                    Point::new(x0 as f32 - half, y0 as f32 - half),
                    Point::new(x1 as f32 + half, y1 as f32 + half),
                )
            })
            .collect();
        // Half-cell grid: measured on maze 15 (benches/phase1.rs), a step costs 39 ns with
        // cells of 0.5, 60 ns with cells of 1 (more candidates) and 41 ns with cells of 0.25
        // (more cells per query).
        let walls = Walls::new(walls, Point::origin(), 0.5, 2 * n, 2 * n);
        let target = if n == 2 {
            Point::new(0.5, 1.5)
        } else {
            Point::new(n as f32 - 0.5, n as f32 - 0.5)
        };
        Ok(Maze {
            config: config.clone(),
            layout,
            walls,
            start: Point::new(0.5, 0.5),
            target,
        })
    }

    /// The configuration this maze was built from.
    pub fn config(&self) -> &MazeConfig {
        &self.config
    }

    /// Number of cells along a side (N).
    pub fn size(&self) -> usize {
        self.config.size
    }

    /// Which walls separate which cells.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// The wall geometry.
    pub fn walls(&self) -> &Walls {
        &self.walls
    }

    /// The target position.
    pub fn target(&self) -> Point<f32> {
        self.target
    }

    /// The length of the shortest path from the start's cell to the target's cell, in moves
    /// between cells (the 2×2 U: 3; a perfect N×N maze: at least 2(N − 1)).
    pub fn path_cells(&self) -> Option<usize> {
        let cell = |p: Point<f32>| (p.x.floor().max(0.0) as usize, p.y.floor().max(0.0) as usize);
        self.layout.path_length(cell(self.start), cell(self.target))
    }

    /// The length of the shortest collision-free path from the start to the target disc, in
    /// the maze's units (Euclidean).
    ///
    /// Computed on the visibility graph: its nodes are the start, the target and every wall
    /// corner pushed out diagonally by 10⁻³ (a path touching a wall is not allowed, so it
    /// bends just outside the corners); two nodes are joined when the straight segment between
    /// them touches no wall ([`Walls::segment_hits`], the step function's own test); Dijkstra
    /// gives the shortest path to the target's centre, whose last leg is straight, and the
    /// part of that leg inside the disc is taken off. The result exceeds the true infimum by
    /// at most about 1.5·10⁻³ per bend. `None` when the target cannot be reached.
    ///
    /// ```
    /// use pbcs::config::MazeConfig;
    /// use pbcs::envs::maze::Maze;
    ///
    /// // The 2×2 U: around the end of the wall at y = 1 (x ≤ 1.05), two legs of
    /// // √(0.55² + 0.45²) and 0.1 between the corners, less the 0.2 disc: 1.32.
    /// let maze = Maze::new(&MazeConfig { size: 2, ..MazeConfig::default() }).unwrap();
    /// let l = maze.shortest_path().unwrap();
    /// assert!((l - (2.0 * (0.55f32.powi(2) + 0.45f32.powi(2)).sqrt() + 0.1 - 0.2)).abs() < 3e-3);
    /// ```
    pub fn shortest_path(&self) -> Option<f32> {
        self.shortest(|v| v.norm())
    }

    /// The fewest steps that can take the start into the target disc: each action component
    /// is clipped to ±`max_action`, so a step covers at most `max_action` in the Chebyshev
    /// norm (a diagonal step moves 0.1·√2), and the answer is the shortest collision-free path
    /// measured in that norm (the visibility graph of [`Maze::shortest_path`] with
    /// max(|dx|, |dy|) as the length of a leg), divided by `max_action` and rounded up.
    ///
    /// ```
    /// use pbcs::config::MazeConfig;
    /// use pbcs::envs::maze::Maze;
    ///
    /// // The 2×2 U: legs of Chebyshev length 0.55, 0.1 and 0.55 less the disc's part of the
    /// // last (0.2 · 0.55 / √(0.55² + 0.45²)): 1.058, so 11 steps.
    /// let maze = Maze::new(&MazeConfig { size: 2, ..MazeConfig::default() }).unwrap();
    /// assert_eq!(maze.fewest_steps(), Some(11));
    /// ```
    pub fn fewest_steps(&self) -> Option<usize> {
        let l = self.shortest(|v| v.x.abs().max(v.y.abs()))?;
        Some((l / self.config.max_action - 1e-3).ceil().max(0.0) as usize)
    }

    /// The shortest collision-free path to the target disc with `length` as the length of a
    /// straight leg (a norm), on the visibility graph described at [`Maze::shortest_path`].
    fn shortest(&self, length: impl Fn(Vector<f32>) -> f32) -> Option<f32> {
        const PUSH: f32 = 1e-3;
        let n = self.size() as f32;
        let mut nodes = vec![self.start, self.target];
        for w in self.walls.walls() {
            let b = w.aabb();
            for (x, dx) in [(b.mins.x, -PUSH), (b.maxs.x, PUSH)] {
                for (y, dy) in [(b.mins.y, -PUSH), (b.maxs.y, PUSH)] {
                    let p = Point::new(x + dx, y + dy);
                    let inside = (0.0..=n).contains(&p.x) && (0.0..=n).contains(&p.y);
                    if inside && !self.walls.contains_point(&p) && !nodes.contains(&p) {
                        nodes.push(p);
                    }
                }
            }
        }
        // Dijkstra on the dense graph, visibility tested as nodes are settled.
        let mut dist = vec![f32::INFINITY; nodes.len()];
        let mut prev = vec![0; nodes.len()];
        let mut done = vec![false; nodes.len()];
        dist[0] = 0.0;
        loop {
            let u = (0..nodes.len())
                .filter(|&i| !done[i] && dist[i].is_finite())
                .min_by(|&a, &b| dist[a].total_cmp(&dist[b]))?;
            if u == 1 {
                // The last leg enters the disc: its share inside the disc is not travelled.
                let leg = nodes[1] - nodes[prev[1]];
                let inside = (self.config.target_radius / leg.norm().max(1e-9)).min(1.0);
                return Some((dist[1] - inside * length(leg)).max(0.0));
            }
            done[u] = true;
            for v in 0..nodes.len() {
                if done[v] {
                    continue;
                }
                let d = dist[u] + length(nodes[v] - nodes[u]);
                if d < dist[v] && !self.walls.segment_hits(&nodes[u], &nodes[v]) {
                    dist[v] = d;
                    prev[v] = u;
                }
            }
        }
    }

    /// Whether `p` is in the success region: ‖p − target‖ < radius (0.2 in the paper).
    #[inline]
    pub fn reached(&self, p: &Point<f32>) -> bool {
        self.within(p, &self.target)
    }

    /// Whether `p` lies within the target's radius of `goal` ([`Maze::reached`] for the
    /// target; HER's [`Goals::goal_reward`] for any goal).
    fn within(&self, p: &Point<f32>, goal: &Point<f32>) -> bool {
        let r = self.config.target_radius;
        (p - goal).norm_squared() < r * r
    }

    /// The action actually applied: each component clipped to [−max_action, max_action],
    /// NaN mapped to 0.
    #[inline]
    pub fn clip_action(&self, action: &[f32]) -> Vector<f32> {
        let m = self.config.max_action;
        let clip = |v: f32| if v.is_nan() { 0.0 } else { v.clamp(-m, m) };
        Vector::new(clip(action[0]), clip(action[1]))
    }
}

impl Env for Maze {
    type State = Point<f32>;

    fn obs_dim(&self) -> usize {
        2
    }

    fn action_dim(&self) -> usize {
        2
    }

    fn action_bound(&self, _i: usize) -> f32 {
        self.config.max_action
    }

    fn start(&self) -> Point<f32> {
        self.start
    }

    /// Every episode starts at s_0.
    fn sample_start(&self, _rng: &mut crate::rng::Rng) -> Point<f32> {
        self.start
    }

    /// An action is a displacement clipped to ±`max_action` per axis: a step's reach, as the
    /// path limits count it, is `max_action`.
    fn step_reach(&self) -> Option<f32> {
        Some(self.config.max_action)
    }

    #[inline]
    fn observe(&self, state: &Point<f32>, out: &mut [f32]) {
        out[0] = state.x;
        out[1] = state.y;
    }

    #[inline]
    fn step(&self, state: &Point<f32>, action: &[f32]) -> Step<Point<f32>> {
        let next = state + self.clip_action(action);
        let hit = self.walls.segment_hits(state, &next);
        let state = if hit { *state } else { next };
        let reached = self.reached(&state);
        Step {
            state,
            reward: f32::from(u8::from(reached)) - f32::from(u8::from(hit)),
            terminal: reached,
        }
    }

    fn obs_names(&self) -> Vec<String> {
        vec!["x".into(), "y".into()]
    }

    /// The target disc: centre `target`, radius `maze.target_radius`.
    fn success_region(&self) -> Option<(Vec<f32>, f32)> {
        Some((
            vec![self.target.x, self.target.y],
            self.config.target_radius,
        ))
    }

    fn ball_starts(&self) -> Option<&dyn SampleBall<Point<f32>>> {
        Some(self)
    }

    fn clear_balls(&self) -> Option<&dyn BallIsClear<Point<f32>>> {
        Some(self)
    }

    fn connector(&self) -> Option<&dyn Connect<Point<f32>>> {
        Some(self)
    }

    fn goals(&self) -> Option<&dyn Goals<Point<f32>>> {
        Some(self)
    }
}

/// Goals: positions; the episode's is the target; the goal's part of the reward is 1 inside
/// the target's radius of it (the −1 of a wall is not the goal's).
impl Goals<Point<f32>> for Maze {
    fn goal_dim(&self) -> usize {
        2
    }
    fn achieved_goal(&self, obs: &[f32], out: &mut [f32]) {
        out.copy_from_slice(&obs[..2]);
    }
    fn desired_goal(&self, _: &Point<f32>, out: &mut [f32]) {
        out.copy_from_slice(&[self.target.x, self.target.y]);
    }
    fn goal_reward(&self, achieved: &[f32], desired: &[f32]) -> f32 {
        let (p, g) = (
            Point::new(achieved[0], achieved[1]),
            Point::new(desired[0], desired[1]),
        );
        f32::from(u8::from(self.within(&p, &g)))
    }
}

impl Planar for Maze {
    fn point(&self, state: &Point<f32>) -> (f32, f32) {
        (state.x, state.y)
    }

    fn ball_point(&self, center: &[f32]) -> (f32, f32) {
        (center[0], center[1])
    }

    /// The N × N square, each wall's box, the target disc, s_0.
    fn scene(&self) -> Scene {
        let n = self.size() as f32;
        let walls = self.walls.walls().iter().map(|w| {
            let b = w.aabb();
            [(b.mins.x, b.mins.y), (b.maxs.x, b.maxs.y)]
        });
        Scene {
            width: n,
            height: n,
            walls: walls.collect(),
            target: ((self.target.x, self.target.y), self.config.target_radius),
            start: (self.start.x, self.start.y),
        }
    }
}

impl BallIsClear<Point<f32>> for Maze {
    /// Conservative: walls grown by `radius` in every axis direction (a square, not a disc)
    /// must not contain the centre.
    fn ball_is_clear(&self, center: &Point<f32>, radius: f32) -> bool {
        !self.walls.segment_hits_with_margin(center, center, radius)
    }
}

impl Connect<Point<f32>> for Maze {
    /// The straight line from `from` to `to` in equal steps of at most `max_action` per axis,
    /// when the whole segment stays `clearance` away from every wall (walls grown by the
    /// clearance on each side) and is at most 2 units long.
    fn connect(&self, from: &Point<f32>, to: &Point<f32>, clearance: f32) -> Option<Vec<Vec<f32>>> {
        let d = to - from;
        if d.norm_squared() > 4.0 || self.walls.segment_hits_with_margin(from, to, clearance) {
            return None;
        }
        let steps = (d.x.abs().max(d.y.abs()) / self.config.max_action)
            .ceil()
            .max(1.0);
        let a = vec![d.x / steps, d.y / steps];
        Some(vec![a; steps as usize])
    }
}

impl SampleBall<Point<f32>> for Maze {
    /// Uniform in the disc (r = radius·√u, angle uniform), clamped to [0, N]² so that a start
    /// never lies outside the outer walls (it may lie inside a wall, where it cannot move, as
    /// the paper notes).
    fn sample_ball(
        &self,
        center: &Point<f32>,
        radius: f32,
        rng: &mut crate::rng::Rng,
    ) -> Point<f32> {
        use rand::Rng as _;
        let r = radius * rng.random::<f32>().sqrt();
        let angle = rng.random::<f32>() * std::f32::consts::TAU;
        let n = self.size() as f32;
        Point::new(
            (center.x + r * angle.cos()).clamp(0.0, n),
            (center.y + r * angle.sin()).clamp(0.0, n),
        )
    }
}
