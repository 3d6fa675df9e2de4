//! Steps our PointMaze (`src/envs/pointmaze/`) for an outside program: the equality test
//! (`python/tests/test_pointmaze.py`) sends the same states and actions to this and to
//! gymnasium-robotics' `PointMaze_*-v3`, and compares what comes back.
//!
//! Each line read is one episode: `<map> [goal gx gy] x y vx vy w0 w1 a0 a1 [a0 a1 ...]` (map:
//! `umaze`, `open`, `medium`, `large`; the episode's goal, the task's goal cell's centre when
//! left out; the whole state, warm start included; then the actions). For each action, one
//! line is written: `x y vx vy w0 w1 reward success terminal`, numbers in Rust's shortest
//! round-trip form (Python's `float()` reads them back exactly), then an empty line ends the
//! episode. A line `task <map>` is answered with the task's cells instead:
//! `start_row start_col goal_row goal_col`. A line `resets <map> <n> <seed>` is answered with
//! `n` lines `x y gx gy`: the starts and goals of `n` episodes of the map with
//! gymnasium-robotics' resets (`Resets::Gym`), drawn from one stream of `seed`. A line `map <name> <row> <row> ...` (rows of `0`
//! and `1`, as a job's `[pointmaze] map`) adds a map of one's own under that name, answered
//! with an empty line. Bad input ends the program with a message naming the line.
//!
//! `cargo run --release --features mujoco --example pointmaze_step < episodes.txt`

use pbcs::env::Env;
use pbcs::envs::pointmaze::{MapName, PointMap, PointMaze, PointMazeConfig, PointState};
use std::io::{BufRead, Write};
use strum::IntoEnumIterator;

fn main() -> anyhow::Result<()> {
    let mut envs: Vec<(String, PointMaze)> = MapName::iter()
        .map(|m| Ok((<&str>::from(m).to_lowercase(), PointMaze::named(m)?)))
        .collect::<pbcs::Result<_>>()?;
    let stdin = std::io::stdin();
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let find = |envs: &[(String, PointMaze)], name: &str, line: usize| {
        let i = envs.iter().position(|(m, _)| m == name).ok_or_else(|| {
            anyhow::anyhow!(
                "line {line}: unknown map {name:?} (umaze, open, medium, large, or one added)"
            )
        })?;
        anyhow::Ok(i)
    };
    for (n, line) in stdin.lock().lines().enumerate() {
        let line = line?;
        let mut words = line.split_whitespace();
        let Some(map) = words.next() else { continue };
        if map == "map" {
            let name = words.next().unwrap_or("").to_string();
            let own = PointMazeConfig {
                map: words.map(String::from).collect(),
                ..PointMazeConfig::default()
            };
            let env = PointMaze::on(PointMap::from_config(&own)?)?;
            envs.retain(|(m, _)| *m != name);
            envs.push((name, env));
            writeln!(out)?;
            out.flush()?;
            continue;
        }
        if map == "task" {
            let env = &envs[find(&envs, words.next().unwrap_or(""), n + 1)?].1;
            let ((a, b), (c, d)) = env.map().farthest_cells();
            writeln!(out, "{a} {b} {c} {d}")?;
            out.flush()?;
            continue;
        }
        if map == "resets" {
            let env = &envs[find(&envs, words.next().unwrap_or(""), n + 1)?].1;
            let mut count = || -> anyhow::Result<u64> {
                let w = words.next().unwrap_or("");
                w.parse()
                    .map_err(|e| anyhow::anyhow!("line {}: {w:?}: {e}", n + 1))
            };
            let (episodes, seed) = (count()?, count()?);
            let gym = PointMaze::new(env.map().clone(), env.cells().0, env.cells().1)?
                .with_gym_resets()?;
            let mut rng = pbcs::rng::Seeds::new(seed).stream(pbcs::rng::Stream::Start);
            for _ in 0..episodes {
                let s = gym.sample_start(&mut rng);
                let [x, y, gx, gy] = [s.qpos[0], s.qpos[1], s.goal[0], s.goal[1]];
                writeln!(out, "{x:?} {y:?} {gx:?} {gy:?}")?;
            }
            out.flush()?;
            continue;
        }
        let env = &envs[find(&envs, map, n + 1)?].1;
        let mut goal = env.goal();
        let mut words = words.peekable();
        if words.next_if_eq(&"goal").is_some() {
            for g in &mut goal {
                let w = words.next().unwrap_or("");
                *g = w
                    .parse()
                    .map_err(|e| anyhow::anyhow!("line {}: goal {w:?}: {e}", n + 1))?;
            }
        }
        let numbers: Vec<f64> = words
            .map(|w| w.parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|e| anyhow::anyhow!("line {}: {e}", n + 1))?;
        if numbers.len() < 6 || !numbers.len().is_multiple_of(2) {
            anyhow::bail!("line {}: a state of 6 numbers and pairs of actions", n + 1);
        }
        let mut s = PointState {
            qpos: [numbers[0], numbers[1]],
            qvel: [numbers[2], numbers[3]],
            warmstart: [numbers[4], numbers[5]],
            goal,
        };
        for a in numbers[6..].chunks(2) {
            let step = env.step(&s, &[a[0] as f32, a[1] as f32]);
            s = step.state;
            writeln!(
                out,
                "{:?} {:?} {:?} {:?} {:?} {:?} {:?} {} {}",
                s.qpos[0],
                s.qpos[1],
                s.qvel[0],
                s.qvel[1],
                s.warmstart[0],
                s.warmstart[1],
                step.reward,
                env.success(&s),
                step.terminal,
            )?;
        }
        writeln!(out)?;
        out.flush()?;
    }
    Ok(())
}
