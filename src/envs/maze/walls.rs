//! Wall geometry: parry2d boxes, and a uniform grid that finds the few walls near a segment.
//!
//! A step of the maze asks one question: does the segment [s, s + a] touch a wall? The walls
//! lie on the cell grid and a segment is at most 0.1·√2 long, so only the walls of the one to
//! four grid cells that the segment's bounding box overlaps can be touched. [`Walls`] stores,
//! for each grid cell, the bounding boxes of the walls that overlap it (a compressed sparse
//! row layout, contiguous in memory), and tests each candidate with parry2d's exact
//! segment-vs-box test ([`RayCast::intersects_local_ray`] on an [`Aabb`] over `t ∈ [0, 1]`).
//!
//! Walls are closed sets: a segment that merely touches a wall (ends on its face, slides along
//! it, passes through a corner point) is blocked.

use parry2d::bounding_volume::{Aabb, BoundingVolume};
use parry2d::math::{Isometry, Point};
use parry2d::query::{Ray, RayCast};
use parry2d::shape::Cuboid;

/// One wall: a parry2d box and its pose.
#[derive(Debug, Clone)]
pub struct Wall {
    /// The box shape (half-extents).
    pub shape: Cuboid,
    /// Where the box's centre is.
    pub pose: Isometry<f32>,
}

impl Wall {
    /// The wall covering the axis-aligned rectangle `[mins, maxs]`.
    pub fn from_corners(mins: Point<f32>, maxs: Point<f32>) -> Self {
        let half = (maxs - mins) / 2.0;
        let centre = mins + half;
        Wall {
            shape: Cuboid::new(half),
            pose: Isometry::translation(centre.x, centre.y),
        }
    }

    /// The wall's axis-aligned bounding box (the wall itself, since walls are axis-aligned).
    pub fn aabb(&self) -> Aabb {
        self.shape.aabb(&self.pose)
    }
}

/// A set of walls with a uniform grid over them for fast segment queries.
#[derive(Debug, Clone)]
pub struct Walls {
    walls: Vec<Wall>,
    origin: Point<f32>,
    cell: f32,
    cols: usize,
    rows: usize,
    /// `cell_aabbs[cell_start[c]..cell_start[c + 1]]`: boxes overlapping grid cell `c`.
    cell_start: Vec<u32>,
    cell_aabbs: Vec<Aabb>,
}

impl Walls {
    /// Indexes `walls` on a grid of `cols × rows` square cells of side `cell` whose lower-left
    /// corner is `origin`. Walls and segments beyond the grid are clamped to its border cells,
    /// so any placement stays correct; the grid only decides speed.
    ///
    /// ```
    /// use pbcs::envs::maze::{Wall, Walls};
    /// use parry2d::math::Point;
    ///
    /// let wall = Wall::from_corners(Point::new(1.0, 0.0), Point::new(1.5, 2.0));
    /// let walls = Walls::new(vec![wall], Point::new(0.0, 0.0), 1.0, 2, 2);
    /// assert!(walls.segment_hits(&Point::new(0.5, 1.0), &Point::new(1.25, 1.0)));
    /// assert!(!walls.segment_hits(&Point::new(0.5, 1.0), &Point::new(0.75, 1.0)));
    /// ```
    pub fn new(walls: Vec<Wall>, origin: Point<f32>, cell: f32, cols: usize, rows: usize) -> Self {
        assert!(cell > 0.0 && cols > 0 && rows > 0, "empty wall grid");
        let mut this = Walls {
            walls,
            origin,
            cell,
            cols,
            rows,
            cell_start: Vec::new(),
            cell_aabbs: Vec::new(),
        };
        let mut per_cell: Vec<Vec<Aabb>> = vec![Vec::new(); cols * rows];
        for wall in &this.walls {
            let aabb = wall.aabb();
            let (x0, x1, y0, y1) = this.cell_range(&aabb);
            for cy in y0..=y1 {
                for cx in x0..=x1 {
                    per_cell[cy * cols + cx].push(aabb);
                }
            }
        }
        this.cell_start.push(0);
        for boxes in per_cell {
            this.cell_aabbs.extend(boxes);
            this.cell_start.push(this.cell_aabbs.len() as u32);
        }
        this
    }

    /// All walls.
    pub fn walls(&self) -> &[Wall] {
        &self.walls
    }

    /// Grid cells overlapped by `aabb`, clamped to the grid: `(x0, x1, y0, y1)` inclusive.
    /// Clamping is monotone, so two overlapping boxes always share a cell.
    #[inline]
    fn cell_range(&self, aabb: &Aabb) -> (usize, usize, usize, usize) {
        let index = |v: f32, o: f32, n: usize| -> usize {
            let i = ((v - o) / self.cell).floor();
            if i <= 0.0 {
                0
            } else {
                (i as usize).min(n - 1)
            }
        };
        (
            index(aabb.mins.x, self.origin.x, self.cols),
            index(aabb.maxs.x, self.origin.x, self.cols),
            index(aabb.mins.y, self.origin.y, self.rows),
            index(aabb.maxs.y, self.origin.y, self.rows),
        )
    }

    /// Whether the closed segment `[from, to]` touches a wall (grid candidates only).
    #[inline]
    pub fn segment_hits(&self, from: &Point<f32>, to: &Point<f32>) -> bool {
        let bounds = Aabb::new(from.inf(to), from.sup(to));
        let (x0, x1, y0, y1) = self.cell_range(&bounds);
        let ray = Ray::new(*from, to - from);
        for cy in y0..=y1 {
            for cx in x0..=x1 {
                let c = cy * self.cols + cx;
                let (lo, hi) = (self.cell_start[c] as usize, self.cell_start[c + 1] as usize);
                // Boxes that do not overlap the segment's bounding box cannot touch it; the
                // comparison is exact and skips most of parry's slab tests (two divisions).
                if self.cell_aabbs[lo..hi]
                    .iter()
                    .any(|aabb| aabb.intersects(&bounds) && box_touches_segment(aabb, &ray, to))
                {
                    return true;
                }
            }
        }
        false
    }

    /// The same question as [`Walls::segment_hits`] asked of every wall, without the grid.
    /// Slow; kept as the reference that the grid is tested and benchmarked against.
    pub fn segment_hits_brute_force(&self, from: &Point<f32>, to: &Point<f32>) -> bool {
        let ray = Ray::new(*from, to - from);
        self.walls
            .iter()
            .any(|w| box_touches_segment(&w.aabb(), &ray, to))
    }

    /// Whether the segment touches a wall grown by `margin` on every side (a clearance test;
    /// not on the hot path).
    pub fn segment_hits_with_margin(
        &self,
        from: &Point<f32>,
        to: &Point<f32>,
        margin: f32,
    ) -> bool {
        let bounds = Aabb::new(from.inf(to), from.sup(to)).loosened(margin);
        let (x0, x1, y0, y1) = self.cell_range(&bounds);
        let ray = Ray::new(*from, to - from);
        (y0..=y1).any(|cy| {
            (x0..=x1).any(|cx| {
                let c = cy * self.cols + cx;
                let (lo, hi) = (self.cell_start[c] as usize, self.cell_start[c + 1] as usize);
                self.cell_aabbs[lo..hi]
                    .iter()
                    .any(|b| box_touches_segment(&b.loosened(margin), &ray, to))
            })
        })
    }

    /// Whether `p` lies inside or on a wall.
    pub fn contains_point(&self, p: &Point<f32>) -> bool {
        let aabb = Aabb::new(*p, *p);
        let (x0, _, y0, _) = self.cell_range(&aabb);
        let c = y0 * self.cols + x0;
        let (lo, hi) = (self.cell_start[c] as usize, self.cell_start[c + 1] as usize);
        self.cell_aabbs[lo..hi]
            .iter()
            .any(|b| b.contains_local_point(p))
    }
}

/// parry2d's slab test of the ray `from + t·(to − from)`, `t ∈ [0, 1]`, against the closed
/// box, plus an exact containment test of the end point so that the point the agent moves to
/// is never inside or on a wall, whatever the rounding of the slab test.
#[inline]
fn box_touches_segment(aabb: &Aabb, ray: &Ray, to: &Point<f32>) -> bool {
    aabb.intersects_local_ray(ray, 1.0) || aabb.contains_local_point(to)
}
