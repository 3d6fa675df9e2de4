//! AntMaze's model, as gymnasium-robotics 1.4.2 builds it (`ant_maze_v5.py`, `maze_v4.py`):
//! PointMaze's maps ([`PointMap`]) with cells of [`SCALE`] = 4 m, walls [`SCALE`] ×
//! [`WALL_HEIGHT`] = 2 m high, around gymnasium's `ant.xml`. Needs no MuJoCo: the XML is text.
//!
//! ```
//! use pbcs::envs::antmaze::model::{cell_xy, xml, xy_cell};
//! use pbcs::envs::pointmaze::{MapName, PointMap};
//! let u = PointMap::named(MapName::UMaze);
//! // Cell (i, j) is centred at x = 4(j + 0.5) − 4W/2, y = 4H/2 − 4(i + 0.5).
//! assert_eq!(cell_xy(&u, (1, 1)), [-4.0, 4.0]);
//! assert_eq!(xy_cell(&u, [-5.9, 2.1]), Some((1, 1)));
//! assert!(xml(&u).contains("<geom name=\"block_0_0\" pos=\"-8.0 8.0 1.0\" size=\"2.0 2.0 1.0\""));
//! ```

use crate::envs::pointmaze::{MapName, PointMap};

/// gymnasium's ant (`gymnasium/envs/mujoco/assets/ant.xml`, with an attribution comment).
const ANT_XML: &str = include_str!("ant.xml");

/// Side of a cell, metres (`maze_size_scaling` of `AntMazeEnv`).
pub const SCALE: f64 = 4.0;

/// `maze_height`: the walls are `maze_height` × [`SCALE`] = 2 m high.
pub const WALL_HEIGHT: f64 = 0.5;

/// `position_noise_range`: a reset moves the start and the goal from their cells' centres by
/// a uniform draw in ±`POSITION_NOISE` × [`SCALE`] = ±1 m along each axis.
pub const POSITION_NOISE: f64 = 0.25;

/// How far the ant reaches from its torso's centre, in the plane, in any pose: each leg is
/// three capsules along one diagonal (0.2, 0.2 and 0.4 m along each axis in `ant.xml`, the
/// hinges turning them at most to that length), of radius 0.08: 0.8·√2 + 0.08 ≈ 1.21 m. A
/// torso farther than this from every wall cannot touch one.
pub const REACH: f64 = 0.8 * std::f64::consts::SQRT_2 + 0.08;

/// The environment id in gymnasium-robotics: `AntMaze_UMaze-v5`, ….
pub fn gym_id(map: MapName) -> String {
    format!("AntMaze_{}-v5", <&str>::from(map))
}

/// The time limit gymnasium-robotics registers for `AntMaze_<map>-v5` (`max_episode_steps`).
pub fn time_limit(map: MapName) -> usize {
    match map {
        MapName::UMaze | MapName::Open => 700,
        MapName::Medium | MapName::Large => 1000,
    }
}

/// The centre of cell (i, j) (`cell_rowcol_to_xy`): x = (j + 0.5)·s − W/2·s,
/// y = H/2·s − (i + 0.5)·s, with the same operations in the same order.
pub fn cell_xy(map: &PointMap, (i, j): (usize, usize)) -> [f64; 2] {
    let (xc, yc) = (
        map.cols() as f64 / 2.0 * SCALE,
        map.rows() as f64 / 2.0 * SCALE,
    );
    [(j as f64 + 0.5) * SCALE - xc, yc - (i as f64 + 0.5) * SCALE]
}

/// The cell a point lies in (`cell_xy_to_rowcol`), `None` outside the map.
pub fn xy_cell(map: &PointMap, [x, y]: [f64; 2]) -> Option<(usize, usize)> {
    let (xc, yc) = (
        map.cols() as f64 / 2.0 * SCALE,
        map.rows() as f64 / 2.0 * SCALE,
    );
    let (i, j) = (((yc - y) / SCALE).floor(), ((x + xc) / SCALE).floor());
    (i >= 0.0 && j >= 0.0 && (i as usize) < map.rows() && (j as usize) < map.cols())
        .then_some((i as usize, j as usize))
}

/// Distance in metres from the point `xy` to the nearest wall cell (0 inside one):
/// [`PointMap::clearance`] in cells of [`SCALE`].
pub fn clearance(map: &PointMap, [x, y]: [f64; 2]) -> f64 {
    map.clearance([x / SCALE, y / SCALE]) * SCALE
}

/// The model: `ant.xml` with, at the end of its world body, one box per wall cell, row by row
/// (`block_<i>_<j>`, 4 × 4 × 2 m, centred 1 m up), then the target site, as `Maze.make_maze`
/// writes them ([`PointMap::maze_xml`] at scale 4).
pub fn xml(map: &PointMap) -> String {
    map.maze_xml(ANT_XML, SCALE, WALL_HEIGHT)
}

/// What pictures draw of the task from cell `start` to cell `goal` with success within
/// `target_radius` of the goal: PointMaze's scene of the map ([`PointMap::scene`]) in metres,
/// the map spanning [0, 4W] × [0, 4H]. Needs no MuJoCo.
pub fn scene(
    map: &PointMap,
    start: (usize, usize),
    goal: (usize, usize),
    target_radius: f32,
) -> crate::env::Scene {
    let s = SCALE as f32;
    let cells = map.scene(start, goal, target_radius / s);
    let scaled = |(x, y): (f32, f32)| (x * s, y * s);
    crate::env::Scene {
        width: cells.width * s,
        height: cells.height * s,
        walls: cells.walls.iter().map(|w| w.map(scaled)).collect(),
        target: (scaled(cells.target.0), target_radius),
        start: scaled(cells.start),
    }
}

/// A position shifted so that the map spans [0, 4W] × [0, 4H] (how pictures draw it).
pub fn drawn(map: &PointMap, [x, y]: [f64; 2]) -> (f32, f32) {
    let (w, h) = (map.cols() as f64 * SCALE, map.rows() as f64 * SCALE);
    ((x + w / 2.0) as f32, (y + h / 2.0) as f32)
}

/// The goal seen from the ant ([`crate::env::Goals::body_frame`]), in a network input of the observation
/// (29 numbers: the torso's x, y, then z, its orientation quaternion w, x, y, z, …) followed by
/// the goal (x, y): the torso's (x, y) is replaced by the goal's offset d = goal − (x, y) turned
/// by minus the torso's heading (its yaw: the offset in the frame that turns with the ant, x
/// ahead), and the goal by d itself. Nothing absolute is left of the position: the input is the
/// same wherever the ant and its goal stand together. The rest (the torso's orientation, its
/// velocities) stays in the world's frame.
///
/// ```
/// use pbcs::envs::antmaze::model::body_frame;
/// let mut input = [0.0_f32; 31];
/// input[..2].copy_from_slice(&[1.0, 2.0]); // the torso at (1, 2)
/// // Turned a quarter left (yaw π/2: quaternion cos π/4, 0, 0, sin π/4).
/// let h = std::f32::consts::FRAC_1_SQRT_2;
/// input[3..7].copy_from_slice(&[h, 0.0, 0.0, h]);
/// input[29..].copy_from_slice(&[1.0, 5.0]); // the goal 3 m north of it
/// body_frame(&mut input);
/// // Ahead of the ant (which faces north), 3 m; and 3 m north.
/// assert!((input[0] - 3.0).abs() < 1e-6 && input[1].abs() < 1e-6);
/// assert_eq!(&input[29..], &[0.0, 3.0]);
/// ```
pub fn body_frame(input: &mut [f32]) {
    debug_assert_eq!(
        input.len(),
        31,
        "the ant's 29 observed numbers, then the goal's 2"
    );
    let g = input.len() - 2;
    let (dx, dy) = (input[g] - input[0], input[g + 1] - input[1]);
    let [w, x, y, z] = [input[3], input[4], input[5], input[6]];
    let yaw = (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z));
    let (sin, cos) = yaw.sin_cos();
    input[0] = cos * dx + sin * dy;
    input[1] = -sin * dx + cos * dy;
    input[g] = dx;
    input[g + 1] = dy;
}

#[cfg(test)]
mod tests {
    use super::*;
    use strum::IntoEnumIterator;

    /// `ngeom` of gymnasium-robotics' compiled `AntMaze_<map>-v5` models (the floor, the ant's
    /// 13 geoms, one box per wall cell), read from its env.
    #[test]
    fn models_have_the_geom_counts_of_gymnasium_robotics() {
        let geoms: Vec<usize> = MapName::iter()
            .map(|m| {
                // Less the `<default>` element's `<geom>`, a class rather than a geom.
                let xml = xml(&PointMap::named(m));
                xml.matches("<geom ").count() - 1
            })
            .collect();
        assert_eq!(geoms, [32, 34, 52, 76]);
        let limits: Vec<usize> = MapName::iter().map(time_limit).collect();
        assert_eq!(limits, [700, 700, 1000, 1000]);
    }

    /// The input of an ant at `xy` heading `yaw` (level) toward `goal`, the rest of the
    /// observation `rest`, after [`body_frame`].
    fn framed(xy: [f32; 2], yaw: f32, goal: [f32; 2], rest: f32) -> Vec<f32> {
        let mut input = vec![rest; 31];
        input[..2].copy_from_slice(&xy);
        let (s, c) = (yaw / 2.0).sin_cos();
        input[3..7].copy_from_slice(&[c, 0.0, 0.0, s]);
        input[29..].copy_from_slice(&goal);
        body_frame(&mut input);
        input
    }

    proptest::proptest! {
        /// The goal seen from the body (the first two numbers): the same wherever the ant and
        /// its goal stand together, the same when the ant's heading and the goal's bearing turn
        /// alike, at the goal's distance; the rest of the observation untouched.
        #[test]
        fn the_body_frame_sees_only_the_goal_from_the_ant(
            x in -20.0f32..20.0, y in -20.0f32..20.0, yaw in -3.1f32..3.1,
            r in 0.0f32..4.0, bearing in -3.1f32..3.1, shift in -10.0f32..10.0,
            turn in -3.1f32..3.1, rest in -5.0f32..5.0,
        ) {
            let goal = |x: f32, y: f32, b: f32| [x + r * b.cos(), y + r * b.sin()];
            let a = framed([x, y], yaw, goal(x, y, bearing), rest);
            let moved = framed([x + shift, y - shift], yaw, goal(x + shift, y - shift, bearing), rest);
            let turned = framed([x, y], yaw + turn, goal(x, y, bearing + turn), rest);
            for (p, q) in a[..2].iter().zip(&moved[..2]).chain(a[..2].iter().zip(&turned[..2])) {
                proptest::prop_assert!((p - q).abs() < 1e-3, "{a:?} {moved:?} {turned:?}");
            }
            proptest::prop_assert!((a[0].hypot(a[1]) - r).abs() < 1e-3);
            proptest::prop_assert!((a[29].hypot(a[30]) - r).abs() < 1e-3);
            // Bearing relative to the heading: ahead is +x, a quarter left is +y.
            let rel = (bearing - yaw).sin_cos();
            proptest::prop_assert!(r < 1e-2 || (a[1] / r - rel.0).abs() < 1e-2);
            proptest::prop_assert!(r < 1e-2 || (a[0] / r - rel.1).abs() < 1e-2);
            proptest::prop_assert!(a[2] == rest && a[7..29].iter().all(|&v| v == rest));
        }
    }

    #[test]
    fn cells_and_points_convert_both_ways() {
        for m in MapName::iter() {
            let map = PointMap::named(m);
            for i in 0..map.rows() {
                for j in 0..map.cols() {
                    let [x, y] = cell_xy(&map, (i, j));
                    let [px, py] = map.cell_xy((i, j));
                    assert_eq!([x, y], [px * SCALE, py * SCALE]);
                    for (dx, dy) in [(0.0, 0.0), (1.99, 1.99), (-1.99, -1.99)] {
                        assert_eq!(xy_cell(&map, [x + dx, y + dy]), Some((i, j)));
                    }
                }
            }
            assert_eq!(xy_cell(&map, [-100.0, 0.0]), None);
        }
    }

    #[test]
    fn clearance_is_in_metres() {
        let map = PointMap::named(MapName::UMaze);
        // UMaze's cell (1, 1) has walls on three sides: 2 m from its centre.
        let c = cell_xy(&map, (1, 1));
        assert_eq!(clearance(&map, c), 2.0);
        assert_eq!(clearance(&map, [c[0] - 1.5, c[1]]), 0.5);
        assert_eq!(clearance(&map, [c[0] - 3.0, c[1]]), 0.0);
        assert!((REACH - 1.2114).abs() < 1e-4);
    }

    #[test]
    fn the_scene_is_the_point_mazes_in_metres() {
        let map = PointMap::named(MapName::UMaze);
        let s = scene(&map, (1, 1), (3, 1), 0.45);
        assert_eq!((s.width, s.height), (20.0, 20.0));
        assert_eq!(s.start, drawn(&map, cell_xy(&map, (1, 1))));
        assert_eq!(s.target, (drawn(&map, cell_xy(&map, (3, 1))), 0.45));
        assert_eq!(s.walls.len(), 18);
        assert!(s.walls.contains(&[(0.0, 16.0), (4.0, 20.0)]));
    }
}
