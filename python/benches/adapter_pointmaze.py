"""A PBCS run through the adapter on gymnasium-robotics' own PointMaze_UMaze-v3 (issue 80,
point 5): ``continuing_task=False``, reset to PBCS's task cells (1, 1) → (3, 1) with the env's
own noise, the success region its goal within 0.45, run seed ``--seed``. The job is the fast
preset with the PointMaze grid's settings for momentum (``max_steps = 150``, ``epsilon = 0.25``)
and the settings that need walls off (``shorten``, ``stop_at_failure``, ``retargets``,
``test_path_limit``); it is written to ``--job`` so that ``pbcs run --config <job> --env
pointmaze_umaze --seed <seed>`` (built with ``--features mujoco``) runs our PointMaze beside it.
Prints the record's numbers and the wall time.

    python python/benches/adapter_pointmaze.py --seed 0 --job /tmp/pm_job.toml
"""

import argparse
import re
import time
from pathlib import Path

import gymnasium as gym

import pbcs
from pbcs._judge import FixedCells

ROOT = Path(__file__).resolve().parents[2]


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--job", type=Path, required=True)
    p.add_argument("--out", type=Path, default=None)
    args = p.parse_args()
    text = (ROOT / "experiments" / "pbcs_fast.toml").read_text()
    for key, value in [("shorten", "false"), ("stop_at_failure", "false"), ("retargets", "0"),
                       ("test_path_limit", "0.0"), ("max_steps", "150"), ("epsilon", "0.25")]:
        text, n = re.subn(rf"(?m)^{key} = [^#\n]*", f"{key} = {value} ", text, count=1)
        if n != 1:
            raise SystemExit(f"experiments/pbcs_fast.toml has no `{key}` line")
    args.job.write_text(text)
    import gymnasium_robotics

    gym.register_envs(gymnasium_robotics)
    env = FixedCells(gym.make("PointMaze_UMaze-v3", continuing_task=False), [1, 1], [3, 1])
    env.reset(seed=0)
    goal = env.unwrapped.goal.copy()
    t = time.perf_counter()
    r = pbcs.run(env=env, position=slice(0, 2), observation_key="observation", seed=args.seed,
                 success_region=(goal, 0.45), config=args.job, out=args.out, progress=False)
    seconds = time.perf_counter() - t
    keys = ["solved", "success_rate", "skills", "phase1_steps", "total_steps"]
    print({k: r[k] for k in keys}, f"{seconds:.0f} s")


if __name__ == "__main__":
    main()
