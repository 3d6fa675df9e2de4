# Steps by trace event (and whether a test ended at 100 %, 0 % or between) of a run folder holding trace.csv and record.csv. Usage: python3 trace_steps.py DIR
import csv,collections,sys
path=sys.argv[1]
rows=list(csv.DictReader(open(path+'/trace.csv')))
rec=list(csv.DictReader(open(path+'/record.csv')))[0]
prev=int(rec['phase1_steps']); c=collections.defaultdict(lambda:[0,0])
for r in rows:
    s=int(r['env_steps']); d=s-prev; prev=s
    if r['event']!='train':
        key=(r['event'], 'full' if float(r['success'])==1 else ('zero' if float(r['success'])==0 else 'part'))
    else:
        key=('train','')
    c[key][0]+=1; c[key][1]+=d
for k,v in sorted(c.items()): print(k, v, v[1]//max(v[0],1))
