import json, sys, glob, statistics, os
d = sys.argv[1] if len(sys.argv) > 1 else __import__('os').path.dirname(__import__('os').path.abspath(__file__))
runs = {}
for f in sorted(glob.glob(d + '/*-*.json')):
    side = os.path.basename(f).split('-')[0]
    for r in json.load(open(f))['rows']:
        runs.setdefault((r['dataset'], r['tf'], r['graph']), {}).setdefault(side, []).append(r['median_ms'])
print('| graph | dataset | TF | before ms | after ms | after/before | ratio over sbvr before | after |')
print('|---|---|---|---|---|---:|---:|---:|')
keys = sorted(runs)
for (ds, tf, g) in keys:
    if g == 'sbvr': continue
    v = runs[(ds, tf, g)]; s = runs[(ds, tf, 'sbvr')]
    mo, mn = statistics.median(v.get('old', [0])), statistics.median(v.get('new', [0]))
    so, sn = statistics.median(s.get('old', [0])), statistics.median(s.get('new', [0]))
    fmt = lambda xs: ', '.join('%.1f' % x for x in xs)
    print(f"| {g} | {ds} | {tf} | {fmt(v.get('old',[]))} | {fmt(v.get('new',[]))} | {mn/mo:.2f} | {so/mo:.2f}× | {sn/mn:.2f}× |")
for (ds, tf, g) in keys:
    if g != 'sbvr': continue
    v = runs[(ds, tf, g)]
    print(f"| sbvr | {ds} | {tf} | {', '.join('%.1f'%x for x in v.get('old',[]))} | {', '.join('%.1f'%x for x in v.get('new',[]))} | {statistics.median(v['new'])/statistics.median(v['old']):.2f} | | |")
