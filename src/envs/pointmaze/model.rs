//! PointMaze's maps and its MuJoCo model, as gymnasium-robotics 1.4.2 builds them
//! (`gymnasium_robotics/envs/maze/maze_v4.py`, `maps.py`): the maps of 0 (free) and 1 (wall)
//! cells, the conversion between a cell and the point at its centre, and the model XML — the
//! point mass of `point.xml` with one box per wall cell and the target site, in the order
//! gymnasium-robotics adds them (the order of a model's geoms is part of its simulation).
//! Needs no MuJoCo: the XML is text.
//!
//! ```
//! use pbcs::envs::pointmaze::model::{MapName, PointMap};
//! let u = PointMap::named(MapName::UMaze);
//! assert_eq!((u.rows(), u.cols()), (5, 5));
//! // Cell (i, j) is centred at x = (j + 0.5) − W/2, y = H/2 − (i + 0.5).
//! assert_eq!(u.cell_xy((1, 1)), [-1.0, 1.0]);
//! assert_eq!(u.xy_cell([-1.2, 0.8]), Some((1, 1)));
//! // The task: the two free cells farthest apart along the maze.
//! assert_eq!(u.farthest_cells(), ((1, 1), (3, 1)));
//! assert_eq!(u.cell_distances((1, 1))[3][1], Some(6));
//! assert!(u.xml().contains("<geom name=\"block_0_0\" pos=\"-2.0 2.0 0.2\""));
//! ```

use crate::error::{Error, Result};

/// The point mass and its floor (gymnasium-robotics' `point.xml`, with an attribution comment).
const POINT_XML: &str = include_str!("point.xml");

/// Distance to the goal within which an episode succeeds (`compute_reward`'s 0.45).
pub const SUCCESS_DISTANCE: f64 = 0.45;

/// How far gymnasium-robotics' reset moves the goal from its cell's centre, along each axis
/// (`position_noise_range` 0.25 × `maze_size_scaling` 1): the goal is uniform in the square
/// of half-side 0.25 around the centre.
pub const GOAL_NOISE: f64 = 0.25;

/// The radius of the disc around the goal where the point is within [`SUCCESS_DISTANCE`] of
/// every goal of the square of half-side `noise` around it: 0.45 − noise·√2.
pub fn sure_radius(noise: f64) -> f64 {
    SUCCESS_DISTANCE - noise * std::f64::consts::SQRT_2
}

/// Height of the walls (`maze_height`), in metres.
const WALL_HEIGHT: f64 = 0.4;

/// The maps of gymnasium-robotics' `PointMaze_<name>-v3`.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, strum::EnumIter, strum::IntoStaticStr,
)]
pub enum MapName {
    /// `U_MAZE`, 5 × 5 cells; time limit 300 steps.
    UMaze,
    /// `OPEN`, 5 × 7; 300 steps.
    Open,
    /// `MEDIUM_MAZE`, 8 × 8; 600 steps.
    Medium,
    /// `LARGE_MAZE`, 9 × 12; 800 steps.
    Large,
}

/// A point uniform in the disc of radius `radius` around `centre`: r = radius·√u, then the
/// angle uniform (two draws, in that order). Ball starts in the plane (PointMaze, AntMaze).
pub fn disc_point(centre: [f64; 2], radius: f64, rng: &mut crate::rng::Rng) -> [f64; 2] {
    use rand::Rng as _;
    let r = radius * rng.random::<f64>().sqrt();
    let phi = std::f64::consts::TAU * rng.random::<f64>();
    [centre[0] + r * phi.cos(), centre[1] + r * phi.sin()]
}

impl MapName {
    /// The environment id in gymnasium-robotics: `PointMaze_UMaze-v3`, ….
    pub fn gym_id(self) -> String {
        format!("PointMaze_{}-v3", <&str>::from(self))
    }

    /// The time limit gymnasium-robotics registers for it (`max_episode_steps`).
    pub fn time_limit(self) -> usize {
        match self {
            MapName::UMaze | MapName::Open => 300,
            MapName::Medium => 600,
            MapName::Large => 800,
        }
    }

    /// Its rows of cells, 1 = wall (`maps.py`).
    fn rows(self) -> &'static [&'static [u8]] {
        match self {
            MapName::UMaze => &[
                &[1, 1, 1, 1, 1],
                &[1, 0, 0, 0, 1],
                &[1, 1, 1, 0, 1],
                &[1, 0, 0, 0, 1],
                &[1, 1, 1, 1, 1],
            ],
            MapName::Open => &[
                &[1, 1, 1, 1, 1, 1, 1],
                &[1, 0, 0, 0, 0, 0, 1],
                &[1, 0, 0, 0, 0, 0, 1],
                &[1, 0, 0, 0, 0, 0, 1],
                &[1, 1, 1, 1, 1, 1, 1],
            ],
            MapName::Medium => &[
                &[1, 1, 1, 1, 1, 1, 1, 1],
                &[1, 0, 0, 1, 1, 0, 0, 1],
                &[1, 0, 0, 1, 0, 0, 0, 1],
                &[1, 1, 0, 0, 0, 1, 1, 1],
                &[1, 0, 0, 1, 0, 0, 0, 1],
                &[1, 0, 1, 0, 0, 1, 0, 1],
                &[1, 0, 0, 0, 1, 0, 0, 1],
                &[1, 1, 1, 1, 1, 1, 1, 1],
            ],
            MapName::Large => &[
                &[1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1],
                &[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 1],
                &[1, 0, 1, 1, 0, 1, 0, 1, 0, 1, 0, 1],
                &[1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 1],
                &[1, 0, 1, 1, 1, 1, 0, 1, 1, 1, 0, 1],
                &[1, 0, 0, 1, 0, 1, 0, 0, 0, 0, 0, 1],
                &[1, 1, 0, 1, 0, 1, 0, 1, 0, 1, 1, 1],
                &[1, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1],
                &[1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1],
            ],
        }
    }
}

/// A map of cells 1 m wide, `true` = wall, with at least one free cell.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PointMap {
    walls: Vec<Vec<bool>>,
}

impl PointMap {
    /// One of gymnasium-robotics' maps.
    pub fn named(name: MapName) -> PointMap {
        PointMap {
            walls: name
                .rows()
                .iter()
                .map(|r| r.iter().map(|&c| c == 1).collect())
                .collect(),
        }
    }

    /// A map from rows of 0 (free) and 1 (wall), all of one length, with a free cell. The
    /// point cannot leave a map whose border is not all walls: such a map is refused.
    pub fn from_rows(rows: &[Vec<u8>]) -> Result<PointMap> {
        let field = "pointmaze.map";
        let cols = rows.first().map_or(0, Vec::len);
        if rows.len() < 3 || cols < 3 {
            return Err(Error::invalid(
                field,
                "needs at least 3 rows of at least 3 cells",
            ));
        }
        if let Some(i) = rows.iter().position(|r| r.len() != cols) {
            return Err(Error::invalid(
                field,
                format!("row {i} has {} cells, row 0 has {cols}", rows[i].len()),
            ));
        }
        if rows.iter().flatten().any(|&c| c > 1) {
            return Err(Error::invalid(field, "cells are 0 (free) or 1 (wall)"));
        }
        let map = PointMap {
            walls: rows
                .iter()
                .map(|r| r.iter().map(|&c| c == 1).collect())
                .collect(),
        };
        let border = (0..rows.len())
            .flat_map(|i| (0..cols).map(move |j| (i, j)))
            .filter(|&(i, j)| i == 0 || j == 0 || i + 1 == rows.len() || j + 1 == cols);
        if border.into_iter().any(|c| !map.is_wall(c)) {
            return Err(Error::invalid(field, "its border must be walls (1)"));
        }
        if map.free_cells().is_empty() {
            return Err(Error::invalid(field, "has no free cell"));
        }
        Ok(map)
    }

    /// The rows as a config writes them (`"10001"`, top first).
    pub fn to_rows(&self) -> Vec<String> {
        self.walls
            .iter()
            .map(|r| r.iter().map(|&w| if w { '1' } else { '0' }).collect())
            .collect()
    }

    /// Rows of cells (H).
    pub fn rows(&self) -> usize {
        self.walls.len()
    }

    /// Columns of cells (W).
    pub fn cols(&self) -> usize {
        self.walls[0].len()
    }

    /// Whether cell (row, column) is a wall (cells outside the map are).
    pub fn is_wall(&self, (i, j): (usize, usize)) -> bool {
        self.walls
            .get(i)
            .and_then(|r| r.get(j))
            .copied()
            .unwrap_or(true)
    }

    /// The free cells, row by row.
    pub fn free_cells(&self) -> Vec<(usize, usize)> {
        (0..self.rows())
            .flat_map(|i| (0..self.cols()).map(move |j| (i, j)))
            .filter(|&c| !self.is_wall(c))
            .collect()
    }

    /// The centre of cell (i, j): x = (j + 0.5) − W/2, y = H/2 − (i + 0.5)
    /// (`cell_rowcol_to_xy`).
    pub fn cell_xy(&self, (i, j): (usize, usize)) -> [f64; 2] {
        let (xc, yc) = (self.cols() as f64 / 2.0, self.rows() as f64 / 2.0);
        [(j as f64 + 0.5) - xc, yc - (i as f64 + 0.5)]
    }

    /// The cell a point lies in (`cell_xy_to_rowcol`), `None` outside the map.
    pub fn xy_cell(&self, [x, y]: [f64; 2]) -> Option<(usize, usize)> {
        let (xc, yc) = (self.cols() as f64 / 2.0, self.rows() as f64 / 2.0);
        let (i, j) = ((yc - y).floor(), (x + xc).floor());
        (i >= 0.0 && j >= 0.0 && (i as usize) < self.rows() && (j as usize) < self.cols())
            .then_some((i as usize, j as usize))
    }

    /// Distance from the point `xy` to the nearest wall cell (0 inside one).
    pub fn clearance(&self, [x, y]: [f64; 2]) -> f64 {
        (0..self.rows())
            .flat_map(|i| (0..self.cols()).map(move |j| (i, j)))
            .filter(|&c| self.is_wall(c))
            .map(|c| {
                let [cx, cy] = self.cell_xy(c);
                let dx = ((x - cx).abs() - 0.5).max(0.0);
                let dy = ((y - cy).abs() - 0.5).max(0.0);
                dx.hypot(dy)
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// Steps between every free cell and `from` along the maze (4-neighbour moves), `None`
    /// for walls and cells it cannot reach.
    pub fn cell_distances(&self, from: (usize, usize)) -> Vec<Vec<Option<usize>>> {
        let mut dist = vec![vec![None; self.cols()]; self.rows()];
        let mut queue = std::collections::VecDeque::from([from]);
        dist[from.0][from.1] = Some(0);
        while let Some((i, j)) = queue.pop_front() {
            let d = dist[i][j].unwrap_or(0);
            let next = [
                (i + 1, j),
                (i.wrapping_sub(1), j),
                (i, j + 1),
                (i, j.wrapping_sub(1)),
            ];
            for (a, b) in next {
                if !self.is_wall((a, b)) && dist[a][b].is_none() {
                    dist[a][b] = Some(d + 1);
                    queue.push_back((a, b));
                }
            }
        }
        dist
    }

    /// The task of this package on the map: the two free cells farthest apart along the maze
    /// (breadth-first search from every free cell, 4-neighbour moves); among pairs as far
    /// apart, the first in row-major order of (start, goal), the start being the earlier cell
    /// of the two in row-major order.
    pub fn farthest_cells(&self) -> ((usize, usize), (usize, usize)) {
        let free = self.free_cells();
        let mut best = (0, free[0], free[0]);
        for (n, &a) in free.iter().enumerate() {
            let dist = self.cell_distances(a);
            for &b in &free[n + 1..] {
                if let Some(d) = dist[b.0][b.1] {
                    if d > best.0 {
                        best = (d, a, b);
                    }
                }
            }
        }
        (best.1, best.2)
    }

    /// A position shifted so that the map spans [0, W] × [0, H] (how pictures draw it).
    pub fn drawn(&self, [x, y]: [f64; 2]) -> (f32, f32) {
        let (w, h) = (self.cols() as f64, self.rows() as f64);
        ((x + w / 2.0) as f32, (y + h / 2.0) as f32)
    }

    /// What pictures draw of the task from cell `start` to cell `goal` whose success region is
    /// the disc of `target_radius` around the goal: the map's wall cells, the start and the
    /// target, in [0, W] × [0, H] ([`PointMap::drawn`]). Needs no MuJoCo, so that figures of
    /// committed rows are drawn without it.
    pub fn scene(
        &self,
        start: (usize, usize),
        goal: (usize, usize),
        target_radius: f32,
    ) -> crate::env::Scene {
        let (w, h) = (self.cols() as f32, self.rows() as f32);
        let walls = (0..self.rows())
            .flat_map(|i| (0..self.cols()).map(move |j| (i, j)))
            .filter(|&c| self.is_wall(c))
            .map(|(i, j)| {
                let (x, y) = (j as f32, h - i as f32 - 1.0);
                [(x, y), (x + 1.0, y + 1.0)]
            })
            .collect();
        crate::env::Scene {
            width: w,
            height: h,
            walls,
            target: (self.drawn(self.cell_xy(goal)), target_radius),
            start: self.drawn(self.cell_xy(start)),
        }
    }

    /// The model: `point.xml` with, before the end of its world body, one box per wall cell,
    /// row by row (`block_<i>_<j>`, 1 × 1 × 0.4 m, centred 0.2 m up) and the target site —
    /// the elements, attributes and numbers gymnasium-robotics' `Maze.make_maze` writes
    /// (numbers as Python prints floats: `-2.0`, `0.2`).
    pub fn xml(&self) -> String {
        self.maze_xml(POINT_XML, 1.0, WALL_HEIGHT)
    }

    /// `Maze.make_maze` around an agent's model: before the end of `agent_xml`'s world body,
    /// one box per wall cell, row by row (`block_<i>_<j>`, cells of `scale` metres, walls
    /// `height` × `scale` high), then the target site, with its numbers computed as it computes
    /// them and printed as Python prints floats. The order of a model's geoms is part of its
    /// simulation. PointMaze's (scale 1) and AntMaze's (scale 4) models.
    pub fn maze_xml(&self, agent_xml: &str, scale: f64, height: f64) -> String {
        let py = |v: f64| format!("{v:?}");
        let h = height / 2.0 * scale;
        let half = 0.5 * scale;
        let (xc, yc) = (
            self.cols() as f64 / 2.0 * scale,
            self.rows() as f64 / 2.0 * scale,
        );
        let mut extra = String::new();
        for (i, j) in (0..self.rows()).flat_map(|i| (0..self.cols()).map(move |j| (i, j))) {
            if self.is_wall((i, j)) {
                let (x, y) = ((j as f64 + 0.5) * scale - xc, yc - (i as f64 + 0.5) * scale);
                extra += &format!(
                    "<geom name=\"block_{i}_{j}\" pos=\"{} {} {}\" size=\"{} {} {}\" type=\"box\" \
                     material=\"\" contype=\"1\" conaffinity=\"1\" rgba=\"0.7 0.5 0.3 1.0\" />",
                    py(x),
                    py(y),
                    py(h),
                    py(half),
                    py(half),
                    py(h),
                );
            }
        }
        extra += &format!(
            "<site name=\"target\" pos=\"0 0 {}\" size=\"{}\" rgba=\"1 0 0 0.7\" type=\"sphere\" />",
            py(h),
            py(0.2 * scale),
        );
        agent_xml.replacen("</worldbody>", &(extra + "</worldbody>"), 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use strum::IntoEnumIterator;

    #[test]
    fn maps_have_the_sizes_and_wall_counts_of_gymnasium_robotics() {
        // Geoms in gymnasium-robotics' compiled models: the floor, the ball and the blocks.
        let geoms: Vec<usize> = MapName::iter()
            .map(|m| {
                2 + PointMap::named(m)
                    .xml()
                    .matches("<geom name=\"block_")
                    .count()
            })
            .collect();
        assert_eq!(geoms, [20, 22, 40, 64]);
        let sizes: Vec<(usize, usize)> = MapName::iter()
            .map(|m| (PointMap::named(m).rows(), PointMap::named(m).cols()))
            .collect();
        assert_eq!(sizes, [(5, 5), (5, 7), (8, 8), (9, 12)]);
    }

    #[test]
    fn cells_and_points_convert_both_ways() {
        for m in MapName::iter() {
            let map = PointMap::named(m);
            for i in 0..map.rows() {
                for j in 0..map.cols() {
                    let [x, y] = map.cell_xy((i, j));
                    for (dx, dy) in [(0.0, 0.0), (0.49, 0.49), (-0.49, -0.49)] {
                        assert_eq!(map.xy_cell([x + dx, y + dy]), Some((i, j)));
                    }
                }
            }
            assert_eq!(map.xy_cell([-100.0, 0.0]), None);
        }
    }

    /// The expected pairs and distances were computed by an independent breadth-first search
    /// in Python over the maps as `maps.py` writes them.
    #[test]
    fn the_task_is_the_pair_farthest_apart_along_the_maze() {
        let tasks: Vec<_> = MapName::iter()
            .map(|m| {
                let map = PointMap::named(m);
                let (a, b) = map.farthest_cells();
                (a, b, map.cell_distances(a)[b.0][b.1])
            })
            .collect();
        assert_eq!(
            tasks,
            [
                ((1, 1), (3, 1), Some(6)),
                ((1, 1), (3, 5), Some(6)),
                ((1, 1), (6, 5), Some(11)),
                ((3, 10), (7, 1), Some(19)),
            ]
        );
    }

    #[test]
    fn bad_maps_are_refused_with_a_reason() {
        let rows = |r: &[&[u8]]| r.iter().map(|x| x.to_vec()).collect::<Vec<_>>();
        for (bad, says) in [
            (rows(&[&[1, 1, 1], &[1, 0, 1]]), "at least 3 rows"),
            (rows(&[&[1, 1, 1], &[1, 0], &[1, 1, 1]]), "row 1 has 2"),
            (rows(&[&[1, 1, 1], &[1, 2, 1], &[1, 1, 1]]), "0 (free) or 1"),
            (rows(&[&[1, 1, 1], &[0, 0, 1], &[1, 1, 1]]), "border"),
            (rows(&[&[1, 1, 1], &[1, 1, 1], &[1, 1, 1]]), "no free cell"),
        ] {
            let err = PointMap::from_rows(&bad).unwrap_err().to_string();
            assert!(err.contains(says), "{err}");
        }
        let ok = PointMap::from_rows(&rows(&[&[1, 1, 1], &[1, 0, 1], &[1, 1, 1]])).unwrap();
        assert_eq!(ok.farthest_cells(), ((1, 1), (1, 1)));
    }
}
