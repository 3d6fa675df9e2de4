# Training blocks (one K's rounds) of a run folder: how many ended in a passed test, their steps and rounds. Usage: python3 trace_blocks.py DIR [DIR ...]
import csv,collections,sys
def blocks_of(path):
    rows=list(csv.DictReader(open(path+'/trace.csv')))
    rec=list(csv.DictReader(open(path+'/record.csv')))[0]
    prev=int(rec['phase1_steps']); segs=[]
    for r in rows:
        s=int(r['env_steps']); d=s-prev; prev=s
        key=(r['skill'],r['k'],r['t'])
        if not segs or segs[-1]['key']!=key: segs.append({'key':key,'rows':[]})
        segs[-1]['rows'].append((r['event'],float(r['success']),d))
    out=[]
    for g in segs:
        tr=[x for x in g['rows'] if x[0]=='train']
        if not tr: continue
        tests=[x for x in g['rows'] if x[0]=='test']
        # index of train rounds at which a 100% test happened
        out.append({'succ':[x[1] for x in tr],'steps':sum(x[2] for x in tr),'final':tests[-1][1] if tests else None,'key':g['key']})
    return out
for path in sys.argv[1:]:
    b=blocks_of(path)
    ok=[x for x in b if x['final']==1.0]; bad=[x for x in b if x['final']!=1.0]
    print(path,'passed',len(ok),sum(x['steps'] for x in ok),'failed',len(bad),sum(x['steps'] for x in bad))
    print(' rounds of passed', sorted(collections.Counter(len(x['succ']) for x in ok).items()))
    print(' rounds of failed', sorted(collections.Counter(len(x['succ']) for x in bad).items()))
