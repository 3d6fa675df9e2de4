"""The numbers of the AntMaze arms' table (results/dev/issue79/README.md) from their committed
files: per arm folder, the training rounds' success (the fraction of tries that reached their
next sub-goal) over the first 10 and the last 50 rounds and by quarters, the greedy tests passed
(success ≥ 95 %) and the best, the chain's `pbcs eval` successes, and from `play.txt` the
episodes upside down for at least half their steps and the furthest hand-over.

    python3 results/dev/issue79/antmaze/summary.py [arm ...]
"""
import csv
import re
import statistics
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def arm(folder):
    rows = list(csv.DictReader(open(folder / "trace.csv")))
    train = [float(r["success"]) for r in rows if r["event"] == "train"]
    tests = [float(r["success"]) for r in rows if r["event"] == "test"]
    q = max(len(train) // 4, 1)
    quarters = [statistics.mean(train[i * q:(i + 1) * q]) for i in range(4) if train[i * q:(i + 1) * q]]
    line = (f"{folder.name}: {len(train)} rounds, first 10 {statistics.mean(train[:10]):.0%} → last 50 "
            f"{statistics.mean(train[-50:]):.0%} (quarters {', '.join(f'{x:.0%}' for x in quarters)}); "
            f"tests passed {sum(t >= 0.95 for t in tests)} of {len(tests)} (best {max(tests, default=0):.0%})")
    ev = folder / "eval-s100.csv"
    if ev.exists():
        wins = [r["success"] for r in csv.DictReader(open(ev))]
        line += f"; chain {sum(w == 'true' for w in wins)} of {len(wins)}"
    play = folder / "play.txt"
    if play.exists():
        text = play.read_text()
        flips = [int(x) for x in re.findall(r"upside down (\d+)%", text)]
        furthest = [int(x) for x in re.findall(r"furthest skill (\d+)", text)]
        line += (f"; played: {sum(f >= 50 for f in flips)} of {len(flips)} upside down for half the "
                 f"steps, furthest skill {max(furthest)}")
    return line


names = sys.argv[1:] or sorted(p.parent.name for p in HERE.glob("*/trace.csv"))
for name in names:
    print(arm(HERE / name))
