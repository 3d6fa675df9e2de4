# The counts quoted in README.md, read from the long run's trace (run from the repository root).
import csv
rows=list(csv.DictReader(open('results/dev/issue49/phase2/long/trace.csv')))
# group by problem
from collections import defaultdict, OrderedDict
probs=OrderedDict()
for i,r in enumerate(rows):
    probs.setdefault(r['skill'],[]).append((i,r))
trained=0; capped=0
maxrun=0
below_steps=0; phase2_total=0
tests_after=[]
prev_steps=15222
for p,rs in probs.items():
    # trained Ks: sequences of train rows per K
    ks=defaultdict(int)
    for i,r in rs:
        if r['event']=='train': ks[int(r['k'])]+=1
    trained+=len(ks); capped+=sum(1 for k,n in ks.items() if n==3)
    ver=[r for i,r in rs if r['event']=='verify']
    keptk=int(ver[0]['k']) if ver else None
    # saves: test rows with success 1.0 (first test or after training)
    saves=[int(r['k']) for i,r in rs if r['event']=='test' and float(r['success'])>=1.0]
    # run of unsaved trained Ks ended later by a save
    run=0
    seq=[]
    last=None
    for i,r in rs:
        if r['event']=='train': last=int(r['k'])
        if r['event']=='test' and last is not None and int(r['k'])==last:
            seq.append((last,float(r['success'])>=1.0)); last=None
    run=0
    for k,s in seq:
        if s:
            maxrun=max(maxrun,run); run=0
        else: run+=1
    # steps below kept K: sum of step deltas of rows whose k < keptk
    for i,r in rs:
        st=int(r['env_steps']); d=st-prev_steps; prev_steps=st
        phase2_total+=d
        if keptk is None or int(r['k'])<keptk: below_steps+=d
    if keptk is not None:
        for k,s in seq:
            pass
print('trained Ks',trained,'capped at 3 rounds',capped)
print('longest run of unsaved trained Ks later ended by a save',maxrun)
print('steps below kept K',below_steps,'of phase2',phase2_total)
maxrun=0
for p,rs in probs.items():
    run=0; trained_k=None; runs=[]
    for i,r in rs:
        k=int(r['k'])
        if r['event']=='train': trained_k=k
        elif r['event']=='test':
            s=float(r['success'])>=1.0
            if trained_k==k:  # after training
                if s: runs.append(run); run=0
                else: run+=1
                trained_k=None
            elif s:
                runs.append(run); run=0
    if runs: maxrun=max(maxrun,max(runs))
print('v2 longest unsaved run ended by a save',maxrun)
import statistics
vals=[]
for p,rs in probs.items():
    ver=[r for i,r in rs if r['event']=='verify']
    keptk=int(ver[0]['k']) if ver else None
    trained_k=None
    for i,r in rs:
        k=int(r['k'])
        if r['event']=='train': trained_k=k
        elif r['event']=='test':
            if trained_k==k and (keptk is None or k<keptk): vals.append(float(r['success']))
            if trained_k==k: trained_k=None
print('tests after training below kept K',len(vals),'median',statistics.median(vals),'max',max(vals), '>=0.9',sum(v>=0.9 for v in vals))
