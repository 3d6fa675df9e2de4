"""Paired comparison of archive starts (this development grid) with the committed PointMaze grid
(experiments/pointmaze.toml, same seeds 0-9, same job but phase2.start): env steps, skills and
gymnasium-robotics' successes per seed, the seeds where archive starts used fewer steps, and a
two-sided exact sign test. Writes comparison.csv beside this file.

    python results/dev/issue35/archive_starts/compare.py      (from the repository root)
"""

import csv
from pathlib import Path

from math import comb

HERE = Path(__file__).parent
MAPS = ["umaze", "medium", "large"]


def sign_test(k, n):
    """Two-sided exact binomial test of k successes in n at p = 1/2."""
    tail = sum(comb(n, i) for i in range(min(k, n - k) + 1)) / 2**n
    return min(1.0, 2 * tail)


def row(path):
    with path.open() as f:
        return next(csv.DictReader(f))


rows = []
for m in MAPS:
    fewer = 0
    for seed in range(10):
        base = Path(f"results/raw/pointmaze/pbcs_pm-pointmaze_{m}/s{seed}")
        arch = HERE / f"raw/pointmaze_archive/pbcs_pm_archive-pointmaze_{m}/s{seed}"
        b, a = row(base.with_suffix(".csv")), row(arch.with_suffix(".csv"))
        gb, ga = row(Path(f"{base}.gym.csv")), row(Path(f"{arch}.gym.csv"))
        fewer += int(a["env_steps"]) < int(b["env_steps"])
        rows.append([m, seed, b["env_steps"], a["env_steps"], b["skills"], a["skills"],
                     gb["gym_successes"], ga["gym_successes"]])
    p = sign_test(fewer, 10)
    print(f"{m}: archive starts used fewer env steps in {fewer} of 10 seeds (sign test p = {p:.3f})")
with (HERE / "comparison.csv").open("w", newline="") as f:
    w = csv.writer(f)
    w.writerow(["map", "seed", "env_steps_ball", "env_steps_archive", "skills_ball",
                "skills_archive", "gym_successes_ball", "gym_successes_archive"])
    w.writerows(rows)
