# Env steps of Backplay's greedy tests by verdict (0 %, between, 100 %) in the development runs'
# traces: what docs/phase2.md (`test_lanes`) quotes. Run from the repository root.
import csv

RUNS = [
    "results/dev/issue49/starts/runs/ball15-s0",
    "results/dev/issue49/starts/runs/ball15-s2",
    "results/dev/issue49/starts/runs/ball15_l5-s0",
    "results/dev/issue49/patience/runs/base15-s0",
    "results/dev/issue49/phase2/long",
]
for run in RUNS:
    record = next(csv.DictReader(open(f"{run}/record.csv")))
    prev = int(record["phase1_steps"])
    steps = {"0": [0, 0], "between": [0, 0], "100": [0, 0]}
    for row in csv.DictReader(open(f"{run}/trace.csv")):
        spent, prev = int(row["env_steps"]) - prev, int(row["env_steps"])
        if row["event"] != "test":
            continue
        p = float(row["success"])
        verdict = "0" if p == 0 else ("100" if p >= 1 else "between")
        steps[verdict][0] += 1
        steps[verdict][1] += spent
    total = sum(s for _, s in steps.values())
    n, s = steps["between"]
    print(
        f"{run}: tests {sum(c for c, _ in steps.values())}, test steps {total}; between: "
        f"{n} tests, {s} steps ({100 * s / total:.0f} %), {s // max(n, 1)} each"
    )
