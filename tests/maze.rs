//! Maze generation: perfect mazes, seeds, the fixed 2×2 U-shape, sizes beyond 15.

use pbcs::config::MazeConfig;
use pbcs::envs::maze::{Layout, Maze, Side};

#[test]
fn every_cell_is_reachable_and_the_maze_is_a_tree() {
    for size in [2usize, 3, 5, 7, 10, 15, 30, 50] {
        for seed in 0..5 {
            let l = Layout::generate(size, seed);
            assert_eq!(
                l.reachable_from_start(),
                size * size,
                "size {size} seed {seed}"
            );
            // A spanning tree of the N×N grid opens N² − 1 of its 2N(N − 1) interior sides.
            assert_eq!(
                l.interior_walls(),
                2 * size * (size - 1) - (size * size - 1),
                "size {size} seed {seed}: not a perfect maze"
            );
        }
    }
}

#[test]
fn same_seed_same_maze() {
    for size in [5, 15, 30] {
        assert_eq!(Layout::generate(size, 42), Layout::generate(size, 42));
    }
}

#[test]
fn different_seeds_give_different_mazes() {
    // A 3×3 grid has only 192 spanning trees, so two seeds may well share a layout there;
    // ask only for variety.
    let small: std::collections::HashSet<String> = (0..10)
        .map(|s| format!("{:?}", Layout::generate(3, s)))
        .collect();
    assert!(
        small.len() >= 5,
        "only {} layouts of size 3 from 10 seeds",
        small.len()
    );
    // From size 5 on (over 10^11 spanning trees), ten seeds must give ten layouts.
    for size in [5, 10, 15, 30] {
        let layouts: Vec<Layout> = (0..10).map(|s| Layout::generate(size, s)).collect();
        for i in 0..layouts.len() {
            for j in i + 1..layouts.len() {
                assert_ne!(
                    layouts[i], layouts[j],
                    "size {size}: seeds {i} and {j} collide"
                );
            }
        }
    }
}

#[test]
fn the_2x2_maze_is_the_u_shape_whatever_the_seed() {
    for seed in 0..5 {
        let l = Layout::generate(2, seed);
        assert!(
            l.has_wall(0, 0, Side::North),
            "wall between (0,0) and (0,1)"
        );
        assert!(!l.has_wall(0, 0, Side::East));
        assert!(!l.has_wall(1, 0, Side::North));
        assert!(!l.has_wall(1, 1, Side::West));
        assert_eq!(l.interior_walls(), 1);
    }
    let m = Maze::new(&MazeConfig {
        size: 2,
        ..MazeConfig::default()
    })
    .unwrap();
    assert_eq!((m.target().x, m.target().y), (0.5, 1.5));
}

#[test]
fn wall_counts_and_targets() {
    let m = Maze::new(&MazeConfig {
        size: 15,
        ..MazeConfig::default()
    })
    .unwrap();
    // 196 interior walls of a perfect 15×15 maze plus 60 unit border walls.
    assert_eq!(m.walls().walls().len(), 256);
    assert_eq!((m.target().x, m.target().y), (14.5, 14.5));
    for w in m.walls().walls() {
        let b = w.aabb();
        let (dx, dy) = (b.maxs.x - b.mins.x, b.maxs.y - b.mins.y);
        assert!((dx.min(dy) - 0.1).abs() < 1e-5, "thickness {dx} x {dy}");
        assert!((dx.max(dy) - 1.1).abs() < 1e-5, "length {dx} x {dy}");
    }
}

#[test]
fn start_and_target_are_free() {
    use pbcs::env::Env;
    for size in [2, 5, 30] {
        let m = Maze::new(&MazeConfig {
            size,
            seed: 9,
            ..MazeConfig::default()
        })
        .unwrap();
        assert!(!m.walls().contains_point(&m.start()));
        assert!(!m.walls().contains_point(&m.target()));
    }
}

/// Path lengths between cells: symmetric, at least the Manhattan distance and of its parity
/// (each move changes x + y by one), the start-to-target path of an N×N maze at least
/// 2(N − 1), and the 2×2 U three moves long.
#[test]
fn shortest_paths_between_cells() {
    let u = Maze::new(&MazeConfig {
        size: 2,
        ..MazeConfig::default()
    })
    .unwrap();
    assert_eq!(u.path_cells(), Some(3));
    for n in [3, 5, 9, 15] {
        for seed in 0..3 {
            let layout = Layout::generate(n, seed);
            let maze = Maze::new(&MazeConfig {
                size: n,
                seed,
                ..MazeConfig::default()
            })
            .unwrap();
            let l = maze.path_cells().unwrap();
            assert!(l >= 2 * (n - 1), "maze {n} seed {seed}: {l}");
            assert_eq!(Some(l), layout.path_length((0, 0), (n - 1, n - 1)));
            for (a, b) in [((0, 0), (n - 1, 0)), ((1, 2), (n - 1, n / 2))] {
                let d = layout.path_length(a, b).unwrap();
                assert_eq!(Some(d), layout.path_length(b, a));
                let manhattan = a.0.abs_diff(b.0) + a.1.abs_diff(b.1);
                assert!(
                    d >= manhattan && (d - manhattan).is_multiple_of(2),
                    "{a:?}→{b:?}: {d}"
                );
            }
            assert_eq!(layout.path_length((0, 0), (n, 0)), None);
        }
    }
}

/// The shortest path to the target disc lies between the straight line (less the disc) and the
/// path through the cell centres that the layout's breadth-first search finds (each move 1,
/// through a 0.9-wide opening, clear of walls), and a maze with more walls in the way never
/// makes it shorter than the straight line.
#[test]
fn shortest_path_lies_between_the_straight_line_and_the_cell_path() {
    use pbcs::env::Env;
    for size in [2, 3, 5, 7, 10] {
        for seed in 0..3 {
            let maze = Maze::new(&MazeConfig {
                size,
                seed,
                ..MazeConfig::default()
            })
            .unwrap();
            let l = maze.shortest_path().unwrap();
            let r = maze.config().target_radius;
            let straight = (maze.target() - maze.start()).norm() - r;
            let cells = maze.path_cells().unwrap() as f32 - r;
            assert!(
                straight - 1e-4 <= l && l <= cells + 1e-4,
                "maze {size} layout {seed}: {straight} <= {l} <= {cells}"
            );
            // Steps: a step covers at most 0.1 in the Chebyshev norm, at most 0.1·√2 of the
            // Euclidean length.
            let steps = maze.fewest_steps().unwrap() as f32;
            assert!(steps * 0.1 >= l / 2f32.sqrt() - 1e-3 && steps * 0.1 <= l + 0.1 + 1e-3);
            // A perfect maze bends at least once from (0.5, 0.5) to the far corner: strictly
            // longer than the straight line (the 2×2 U included).
            assert!(l > straight + 0.05, "maze {size} layout {seed}");
        }
    }
}
