# Writes results/dev/issue24/<name>.csv: each run of a dev config beside the committed `fast` row (at 18232de, before the re-run). Usage: python3 results/dev/issue24/compare.py c3
import csv,glob,os,re,statistics,sys
# per-run comparison of a dev config against the committed fast rows
name=sys.argv[1]; root=f'results/dev/issue24/{name}_raw/raw/{name}'
out=[]; 
for n in [2,5,7,10,15]:
    for s in range(10):
        f=f'{root}/{name}-maze{n}/s{s}.csv'
        if not os.path.exists(f): continue
        r=list(csv.DictReader(open(f)))[0]
        import subprocess,io; c=list(csv.DictReader(io.StringIO(subprocess.run(['git','show',f'18232de:results/raw/table/pbcs_fast-maze{n}/s{s}.csv'],capture_output=True,text=True).stdout)))[0]
        t=open(f'{root}/{name}-maze{n}/s{s}.timing.toml').read()
        w=float(re.search(r'wall_seconds = ([0-9.]+)',t).group(1))
        out.append(dict(maze=n,seed=s,fast_steps=c['env_steps'],new_steps=r['total_steps'] if 'total_steps' in r else r['env_steps'],
          ratio=round(int(r.get('total_steps',r.get('env_steps')))/int(c['env_steps']),3),new_success=r['success_rate'],new_skills=r['skills'],fast_skills=c['skills'],new_wall_s=round(w,1)))
w=csv.DictWriter(open(f'results/dev/issue24/{name}.csv','w'),fieldnames=list(out[0].keys())); w.writeheader(); w.writerows(out)
for n in [2,5,7,10,15]:
    rs=[o for o in out if o['maze']==n]
    if rs: print(n,len(rs),'median new',statistics.median(int(o['new_steps']) for o in rs),'fast',statistics.median(int(o['fast_steps']) for o in rs),'ratio med',statistics.median(o['ratio'] for o in rs),'all100',all(float(o['new_success'])==1.0 for o in rs),'wall med',statistics.median(o['new_wall_s'] for o in rs))
