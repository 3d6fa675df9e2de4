"""A PBCS run through the adapter on gymnasium-robotics' own PointMaze_UMaze-v3 beside our Rust
PointMaze's run of the same job and seed (issue 80, point 5): the env set to our
`pointmaze_umaze` task with our PointMaze's hooks written in Python
(python/tests/pointmaze_task.py, what the byte-equality test runs), the PointMaze grid's job
(experiments/pointmaze.toml's pbcs_pm), run seed ``--seed``. The two runs compute the same
files (the test checks it; this prints whether they did): their wall times are the cost of the
same work through Python and in Rust. Prints the record's numbers and both wall times.

    python python/benches/adapter_pointmaze.py --seed 1
"""

import argparse
import sys
import tempfile
import time
from pathlib import Path

import pbcs

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "python" / "tests"))
from pointmaze_task import OurPointMazeTask, pointmaze_job  # noqa: E402

# Not compared: the clocks, the pictures (not drawn through the adapter) and picture.csv (the
# picture's points: ours shifted by the map's half-size, which the adapter does not know).
SKIP = {"timing.toml", "trace.timing.csv", "run.png", "run.svg", "picture.csv"}


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seed", type=int, default=1)
    args = p.parse_args()
    if not pbcs.MUJOCO:
        raise SystemExit("this build of pbcs has no MuJoCo: build it with --features mujoco")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        job = pointmaze_job(tmp)
        env = OurPointMazeTask()
        settings = env.adapter_settings()
        t = time.perf_counter()
        gym_run = pbcs.run(env=env, **settings, config=job, seed=args.seed, out=tmp / "gym",
                           progress=False)
        through = time.perf_counter() - t
        t = time.perf_counter()
        rust_run = pbcs.run(config=job, seed=args.seed, out=tmp / "rust")
        rust = time.perf_counter() - t
        files = [f.relative_to(tmp / "rust") for f in (tmp / "rust").rglob("*")
                 if f.is_file() and f.name not in SKIP]
        same = all((tmp / "gym" / f).read_bytes() == (tmp / "rust" / f).read_bytes()
                   for f in files)
    keys = ["solved", "success_rate", "skills", "phase1_steps", "total_steps"]
    print("through the adapter:", {k: gym_run[k] for k in keys}, f"{through:.1f} s")
    print("our PointMaze:      ", {k: rust_run[k] for k in keys}, f"{rust:.1f} s")
    print(f"the same {len(files)} files: {same}; {through / rust:.2f} x the Rust run's wall time")


if __name__ == "__main__":
    main()
