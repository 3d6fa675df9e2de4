"""Issue 49, a development check of `phase2.last_goal = "drawn"` and `phase2.first_starts =
"drawn"` through gymnasium-robotics itself, on PointMaze UMaze (where runs take seconds).

For each seed, the committed job of the PointMaze grid's run (results/raw/pointmaze/
pbcs_pm-pointmaze_umaze/s<seed>.toml) with the two switches set is run with `pbcs run --config`,
and its chain is judged as python/benches/pointmaze_gym.py judges the grid's: 100 episodes in
gymnasium-robotics' PointMaze_UMaze-v3 from the env's own resets of the task's cells (start and
goal ±0.25), the first reset seeded with 1 000 000 + the seed, success its info["success"]. The
chain of the drawn run is told each episode's goal (desired_goal) by pbcs.Chain.rollout.

    python results/dev/issue49/drawn/pointmaze_check.py --pbcs <pbcs built with --features mujoco> --seeds 0 1 2 3 4

Writes pointmaze_umaze.csv here: per seed, the drawn run's env steps, skills, own-env success and
the judge's successes, beside the grid's committed row and judge row for the same seed.
"""

import argparse
import csv
import subprocess
import tempfile
from pathlib import Path

import pbcs
import pbcs.pointmaze as pm

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[3]
GRID = ROOT / "results/raw/pointmaze/pbcs_pm-pointmaze_umaze"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--pbcs", required=True)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    args = ap.parse_args()
    rows = []
    for seed in args.seeds:
        job = (GRID / f"s{seed}.toml").read_text()
        old = 'last_goal = "success_region"'
        assert job.count(old) == 1, "the grid's job names its last goal once"
        job = job.replace(old, 'last_goal = "drawn"\nfirst_starts = "drawn"')
        grid = next(csv.DictReader((GRID / f"s{seed}.csv").open()))
        gym = next(csv.DictReader((GRID / f"s{seed}.gym.csv").open()))
        with tempfile.TemporaryDirectory() as tmp:
            config = Path(tmp) / "job.toml"
            config.write_text(job)
            out = Path(tmp) / "run"
            subprocess.run([args.pbcs, "run", "--config", str(config), "--out", str(out),
                            "--quiet"], check=True, stdout=subprocess.DEVNULL)
            record = next(csv.DictReader((out / "record.csv").open()))
            chain = pbcs.load_chain(out / "chain")
            assert chain.needs_goal
            judged = pm.evaluate(chain, episodes=100, seed=1_000_000 + seed)
        rows.append({
            "seed": seed,
            "env_steps": record["total_steps"],
            "skills": record["skills"],
            "own_success_rate": record["success_rate"],
            "gym_successes": judged["successes"],
            "grid_env_steps": grid["env_steps"],
            "grid_skills": grid["skills"],
            "grid_gym_successes": gym["gym_successes"],
        })
        print(rows[-1], flush=True)
    with (HERE / "pointmaze_umaze.csv").open("w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


if __name__ == "__main__":
    main()
