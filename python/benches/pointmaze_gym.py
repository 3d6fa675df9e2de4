"""PBCS's PointMaze chains judged by gymnasium-robotics itself (issue 35, point 4).

For every finished run of the grid (``pbcs exp run experiments/pointmaze.toml``: rows in
``results/raw/pointmaze/<cell>/``), the run is done again from its own job file (``s<seed>.toml``) with
``pbcs run --config``, which saves the chain; the re-run must give the same env steps as the
grid's row (the runs are deterministic: a difference stops the script). The chain then acts in
gymnasium-robotics' ``PointMaze_<Map>-v3`` (``continuing_task=False``; a map of one's own,
experiments/pointmaze_own.toml: ``maze_map=`` its rows) for 100 episodes from
the env's own resets of the task's cells (start and goal within ±0.25 of the cells' centres),
each within the env's time limit; success is the env's ``info["success"]``
(:func:`pbcs.pointmaze.evaluate`, the first reset seeded with 1 000 000 + the run seed).
Solved = at least 95 of 100.

    python python/benches/pointmaze_gym.py --pbcs <pbcs built with --features mujoco>

Writes ``s<seed>.gym.csv`` beside each row (atomically; a seed already judged is skipped), and
``results/pointmaze/gym_cells.csv`` (``--summary``): per PBCS cell, the seeds solved by gymnasium-robotics and the env steps
(phase 1 included; median and quartiles, numpy's linear interpolation) of all seeds. Needs gymnasium-robotics and mujoco beside this package.
"""

import argparse
import csv
import hashlib
import os
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from common import write_atomic
import pbcs
import pbcs.pointmaze as pm

EPISODES = 100
SOLVED = 95




def judge(pbcs_bin, row_path):
    """The gym row of the run whose grid row is ``row_path`` (``s<seed>.csv``)."""
    row = next(csv.DictReader(row_path.open()))
    seed = int(row["seed"])
    job = row_path.with_suffix(".toml")
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run"
        subprocess.run(
            [pbcs_bin, "run", "--config", str(job), "--out", str(out), "--quiet"],
            check=True,
            stdout=subprocess.DEVNULL,
        )
        again = next(csv.DictReader((out / "record.csv").open()))
        if again["total_steps"] != row["env_steps"]:
            raise SystemExit(
                f"{row_path}: the re-run took {again['total_steps']} env steps, the row "
                f"{row['env_steps']}: not the same run"
            )
        chain = pbcs.load_chain(out / "chain")
        clock = time.perf_counter()
        r = pm.evaluate(chain, episodes=EPISODES, seed=1_000_000 + seed)
        seconds = time.perf_counter() - clock
    gym_id, start, goal, limit = chain.pointmaze
    own = chain.pointmaze_map
    if own is not None:
        # A map of one's own: that env class made with `maze_map=` the job's rows, named as
        # its run folders name it (`EnvSpec::folder_name`: size and the rows' SHA-256).
        rows = ["".join(str(c) for c in r) for r in own]
        digest = hashlib.sha256("\n".join(rows).encode()).hexdigest()[:8]
        gym_id += f" maze_map=pointmaze-{len(rows)}x{len(rows[0])}-{digest}"
    return (
        "cell,seed,gym_id,start_cell,goal_cell,time_limit,env_steps,skills,solved_own_env,"
        "own_success_rate,gym_successes,gym_episodes,gym_solved,gym_mean_steps\n"
        f"{row['cell']},{seed},{gym_id},{start[0]} {start[1]},{goal[0]} {goal[1]},{limit},"
        f"{row['env_steps']},{len(chain)},{row['solved']},{row['success_rate']},"
        f"{r['successes']},{EPISODES},{str(r['successes'] >= SOLVED).lower()},"
        f"{np.mean(r['steps']):.1f}\n"
    ), seconds


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--raw", default=Path("results/raw/pointmaze"), type=Path)
    p.add_argument("--summary", default=Path("results/pointmaze/gym_cells.csv"), type=Path)
    p.add_argument("--pbcs", default=os.environ.get("PBCS", "pbcs"))
    args = p.parse_args()
    cells = sorted(c for c in args.raw.glob("*") if c.is_dir())
    summary = []
    for cell in cells:
        rows = sorted(cell.glob("s[0-9]*.csv"), key=lambda p: int(p.stem[1:].split(".")[0]))
        rows = [r for r in rows if r.name.count(".") == 1]
        # PBCS cells on PointMaze only: a vanilla learner's run (a grid's DDPG cell) leaves no
        # chain, and a grid may hold maze cells too (experiments/sac_skills.toml).
        rows = [r for r in rows
                if (lambda row: row["kind"] == "pbcs" and row["maze"].startswith("pointmaze"))(
                    next(csv.DictReader(r.open())))]
        wins, steps = 0, []
        for row_path in rows:
            gym_path = row_path.with_suffix(".gym.csv")
            if not gym_path.exists():
                text, seconds = judge(args.pbcs, row_path)
                write_atomic(gym_path, text)
                print(f"{cell.name} {row_path.stem}: {text.splitlines()[1]} ({seconds:.0f} s)",
                      flush=True)
            g = next(csv.DictReader(gym_path.open()))
            wins += g["gym_solved"] == "true"
            steps.append(int(g["env_steps"]))
        if rows:
            q1, med, q3 = (round(v) for v in np.percentile(steps, [25, 50, 75]))
            summary.append(f"{cell.name},{wins},{len(rows)},{med},{q1},{q3}\n")
            print(f"{cell.name}: gymnasium-robotics solved {wins}/{len(rows)}, env steps median "
                  f"{med} [{q1}, {q3}]", flush=True)
    if not summary:
        # An experiment with no PBCS chain on PointMaze (the learners alone, with HER) has
        # nothing to judge and gets no summary.
        print(f"{args.raw}: no PBCS run on PointMaze to judge", flush=True)
        return
    write_atomic(
        args.summary,
        "cell,gym_solved,seeds,env_steps_median,env_steps_q1,env_steps_q3\n" + "".join(summary),
    )


if __name__ == "__main__":
    main()
