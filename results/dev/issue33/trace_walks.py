import csv, sys, collections
# For each run folder: per learning problem (skill), the depth T-K walked before its first
# success (a test or training round > 0); the run's worst such depth, and problems that never succeeded.
for d in sys.argv[1:]:
    rows = list(csv.DictReader(open(d + '/trace.csv')))
    probs = collections.OrderedDict()
    for r in rows:
        probs.setdefault(r['skill'], []).append(r)
    worst, dead, retarget = 0, 0, 0
    for s, rs in probs.items():
        depth, ok = 0, False
        for r in rs:
            if r['event'] == 'retarget':
                retarget += 1
            if r['event'] in ('test', 'train'):
                if float(r['success']) > 0:
                    ok = True
                    break
                depth = max(depth, int(r['t']) - int(r['k']))
        worst = max(worst, depth if True else 0)
        if not ok and any(r['event'] in ('test','train') for r in rs):
            dead += 1
    print(f"{d}: problems {len(probs)}, deepest walk before a first success {worst}, problems without any success {dead}, retarget rows {retarget}")
