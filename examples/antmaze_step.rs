//! Steps our AntMaze (`src/envs/antmaze/`) for an outside program: the equality test
//! (`python/tests/test_antmaze.py`) sends the same states and actions to this and to
//! gymnasium-robotics' `AntMaze_*-v5`, and compares what comes back.
//!
//! Each line read is one request; numbers are written in Rust's shortest round-trip form
//! (Python's `float()` reads them back exactly):
//!
//! * `<map> goal gx gy <qpos 15> <qvel 14> <warm start 14> <actions 8 each ...>` — one episode
//!   (map: `umaze`, `open`, `medium`, `large`, or one added): for each action, a line of the
//!   43 numbers of the state after it, then `reward success terminal`; an empty line ends it.
//! * `task <map>` — the task's cells: `start_row start_col goal_row goal_col`.
//! * `reset <map> x y gx gy` — the state a reset to (x, y) toward (gx, gy) leaves: its 43
//!   numbers.
//! * `resets <map> <n> <seed>` — `n` lines `x y gx gy`: the starts and goals of `n` episodes
//!   with gymnasium-robotics' resets, drawn from one stream of `seed`.
//! * `map <name> <row> <row> ...` — adds a map of one's own (rows of `0` and `1`), answered
//!   with an empty line.
//!
//! Bad input ends the program with a message naming the line.
//!
//! `cargo run --release --features mujoco --example antmaze_step < episodes.txt`

use anyhow::{anyhow, bail, Context};
use pbcs::env::Env;
use pbcs::envs::antmaze::{AntMaze, AntState, NQ, NU, NV};
use pbcs::envs::pointmaze::{MapName, PointMap, PointMazeConfig};
use std::io::{BufRead, Write};
use strum::IntoEnumIterator;

/// The 43 numbers of a whole state, space-separated.
fn state_line(s: &AntState) -> String {
    s.qpos
        .iter()
        .chain(&s.qvel)
        .chain(&s.warmstart)
        .map(|v| format!("{v:?}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn numbers<'a>(words: impl Iterator<Item = &'a str>, line: usize) -> anyhow::Result<Vec<f64>> {
    words
        .map(|w| {
            w.parse::<f64>()
                .with_context(|| format!("line {line}: {w:?}"))
        })
        .collect()
}

fn main() -> anyhow::Result<()> {
    let mut envs: Vec<(String, AntMaze)> = MapName::iter()
        .map(|m| Ok((<&str>::from(m).to_lowercase(), AntMaze::named(m)?)))
        .collect::<pbcs::Result<_>>()?;
    let stdin = std::io::stdin();
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    for (n, line) in stdin.lock().lines().enumerate() {
        let (line, n) = (line?, n + 1);
        let mut words = line.split_whitespace();
        let Some(first) = words.next() else { continue };
        if first == "map" {
            let name = words.next().unwrap_or("").to_string();
            let own = PointMazeConfig {
                map: words.map(String::from).collect(),
                ..PointMazeConfig::default()
            };
            let env = AntMaze::on(PointMap::from_config(&own)?)?;
            envs.retain(|(m, _)| *m != name);
            envs.push((name, env));
            writeln!(out)?;
            out.flush()?;
            continue;
        }
        let map = match first {
            "task" | "reset" | "resets" => words.next().unwrap_or(""),
            map => map,
        };
        let env = envs.iter().find(|(m, _)| m == map).map(|(_, e)| e);
        let env = env.ok_or_else(|| {
            anyhow!("line {n}: unknown map {map:?} (umaze, open, medium, large, or one added)")
        })?;
        match first {
            "task" => {
                let ((a, b), (c, d)) = env.map().farthest_cells();
                writeln!(out, "{a} {b} {c} {d}")?;
            }
            "reset" => {
                let v = numbers(words, n)?;
                let [x, y, gx, gy] = v[..] else {
                    bail!("line {n}: reset <map> x y gx gy")
                };
                writeln!(out, "{}", state_line(&env.at_rest([x, y], [gx, gy])))?;
            }
            "resets" => {
                let v = numbers(words, n)?;
                let [episodes, seed] = v[..] else {
                    bail!("line {n}: resets <map> <n> <seed>")
                };
                let mut rng = pbcs::rng::Seeds::new(seed as u64).stream(pbcs::rng::Stream::Start);
                for _ in 0..episodes as usize {
                    let s = env.sample_start(&mut rng);
                    let ([x, y], [gx, gy]) = (s.xy(), s.goal);
                    writeln!(out, "{x:?} {y:?} {gx:?} {gy:?}")?;
                }
            }
            _ => {
                if words.next() != Some("goal") {
                    bail!("line {n}: <map> goal gx gy <state> <actions>");
                }
                let v = numbers(words, n)?;
                let whole = 2 + NQ + 2 * NV;
                if v.len() < whole || !(v.len() - whole).is_multiple_of(NU) {
                    bail!("line {n}: a goal, a state of 43 numbers and actions of {NU}");
                }
                let mut s = AntState {
                    goal: [v[0], v[1]],
                    qpos: v[2..2 + NQ].try_into()?,
                    qvel: v[2 + NQ..2 + NQ + NV].try_into()?,
                    warmstart: v[2 + NQ + NV..whole].try_into()?,
                };
                for a in v[whole..].chunks(NU) {
                    let a: Vec<f32> = a.iter().map(|&x| x as f32).collect();
                    let step = env.step(&s, &a);
                    s = step.state;
                    let success = env.success(&s);
                    let line = state_line(&s);
                    writeln!(out, "{line} {:?} {success} {}", step.reward, step.terminal)?;
                }
                writeln!(out)?;
            }
        }
        out.flush()?;
    }
    Ok(())
}
