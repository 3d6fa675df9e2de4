"""Paired comparison of experiments/switches.toml (issue 33): per (maze, seed), fast's
environment steps against fast with one switch off; the one-sided exact sign test over the
30 pairs (H1: turning the switch off costs more steps), as registered in the file's header.
Usage: python3 switches_paired.py <results folder>"""
import csv, sys, math
from pathlib import Path
root = Path(sys.argv[1]) / "raw" / "switches"
def rows(method):
    out = {}
    for f in sorted(root.glob(f"{method}-maze*/s*.csv")):
        if f.name.count(".") != 1:
            continue
        r = next(csv.DictReader(open(f)))
        out[(int(r["maze"]), int(r["seed"]))] = r
    return out
fast = rows("fast")
for off in ["no_adaptive_k", "no_early_stop"]:
    other = rows(off)
    keys = sorted(set(fast) & set(other))
    more = sum(int(other[k]["env_steps"]) > int(fast[k]["env_steps"]) for k in keys)
    less = sum(int(other[k]["env_steps"]) < int(fast[k]["env_steps"]) for k in keys)
    n = more + less
    p = sum(math.comb(n, i) for i in range(more, n + 1)) / 2 ** n
    solved_fast = sum(fast[k]["solved"] == "true" for k in keys)
    solved_off = sum(other[k]["solved"] == "true" for k in keys)
    print(f"{off}: {len(keys)} pairs; off costs more steps in {more}, fewer in {less}; "
          f"one-sided sign test p = {p:.4f}; solved fast {solved_fast}, off {solved_off}")
    for m in sorted({k[0] for k in keys}):
        ks = [k for k in keys if k[0] == m]
        ratio = sorted(int(other[k]["env_steps"]) / int(fast[k]["env_steps"]) for k in ks)
        med = (ratio[len(ratio) // 2 - 1] + ratio[len(ratio) // 2]) / 2
        print(f"  maze {m}: median steps off/fast {med:.3f} (range {ratio[0]:.3f}-{ratio[-1]:.3f})")
