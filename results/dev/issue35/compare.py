"""Paired comparison of one development grid of issue 35 with the committed PointMaze grid
(experiments/pointmaze.toml, same seeds 0-9, same job but the one field the grid changes):
env steps, skills and gymnasium-robotics' successes per seed, the seeds where the variant used
fewer steps, and a two-sided exact sign test. Writes <folder>/comparison.csv.

    python results/dev/issue35/compare.py archive_starts archive      (from the repository root)
    python results/dev/issue35/compare.py velocity_balls velocity

The first argument is the grid's folder under results/dev/issue35/ (its rows in
raw/<experiment>/<method>-pointmaze_<map>/), the second the name of its columns.
"""

import csv
import sys
from math import comb
from pathlib import Path

MAPS = ["umaze", "medium", "large"]


def sign_test(k, n):
    """Two-sided exact binomial test of k successes in n at p = 1/2."""
    tail = sum(comb(n, i) for i in range(min(k, n - k) + 1)) / 2**n
    return min(1.0, 2 * tail)


def row(path):
    with path.open() as f:
        return next(csv.DictReader(f))


def cell(here, m):
    """The variant's cell folder for map ``m`` (exactly one)."""
    found = sorted(here.glob(f"raw/*/*-pointmaze_{m}"))
    if len(found) != 1:
        sys.exit(f"{here}: expected one cell folder for {m}, found {found}")
    return found[0]


def main(folder, label):
    here = Path(__file__).parent / folder
    rows = []
    for m in MAPS:
        fewer = 0
        variant = cell(here, m)
        for seed in range(10):
            base = Path(f"results/raw/pointmaze/pbcs_pm-pointmaze_{m}/s{seed}")
            var = variant / f"s{seed}"
            b, a = row(base.with_suffix(".csv")), row(var.with_suffix(".csv"))
            gb, ga = row(Path(f"{base}.gym.csv")), row(Path(f"{var}.gym.csv"))
            fewer += int(a["env_steps"]) < int(b["env_steps"])
            rows.append([m, seed, b["env_steps"], a["env_steps"], b["skills"], a["skills"],
                         gb["gym_successes"], ga["gym_successes"]])
        p = sign_test(fewer, 10)
        print(f"{m}: {label} used fewer env steps in {fewer} of 10 seeds (sign test p = {p:.3f})")
    with (here / "comparison.csv").open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["map", "seed", "env_steps_ball", f"env_steps_{label}", "skills_ball",
                    f"skills_{label}", "gym_successes_ball", f"gym_successes_{label}"])
        w.writerows(rows)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
