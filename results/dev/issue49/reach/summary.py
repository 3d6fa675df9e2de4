"""Summarises the reach probe's rows (examples/antmaze_reach.rs): per file, the evaluations'
count, last step, first success >= 0.95 (if any), best success (and its step), last success and
mean of the last three. `python3 summary.py` prints a Markdown table."""
import csv
import glob
import os

print("| arm | seed | env steps | evaluations | best (at) | last | mean of last 3 | first >= 95 % |")
print("| --- | --- | --- | --- | --- | --- | --- | --- |")
for path in sorted(glob.glob(os.path.join(os.path.dirname(__file__) or ".", "*-s*.csv"))):
    arm, seed = os.path.basename(path)[:-4].rsplit("-s", 1)
    rows = list(csv.DictReader(open(path)))
    if not rows:
        continue
    s = [(int(r["steps"]), float(r["success"])) for r in rows]
    best = max(s, key=lambda x: (x[1], -x[0]))
    first = next((st for st, v in s if v >= 0.95), None)
    tail = [v for _, v in s[-3:]]
    print(
        f"| {arm} | {seed} | {s[-1][0]:,} | {len(s)} | {best[1]:.2f} ({best[0]:,}) | {s[-1][1]:.2f} | "
        f"{sum(tail) / len(tail):.2f} | {first if first is not None else 'none'} |".replace(",", " ")
    )
