"""Before/after tables of stop39-tables/run.sh (and, given its folder as the argument, of
stop40-tables/run.sh): per preset, each row's ms and in-run ratio on the old (05041dd) and new
side; rounds given as PRESET-SIDE[-N].json."""
import glob, json, os, sys

here = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
for preset in ['klein2005', 'kw2003-table1', 'ruijters2006', 'thesis-tables', 'peer']:
    if not glob.glob(f'{here}/{preset}-*.json'):
        continue
    runs = {}
    for side in ['old', 'new']:
        for f in sorted(glob.glob(f'{here}/{preset}-{side}*.json'), key=lambda p: (len(p), p)):
            for r in json.load(open(f))['rows']:
                key = (r['graph'], r['dataset'], r['tf'], str(r.get('sweep_value') or ''),
                       'x'.join(map(str, r['viewport'])))
                runs.setdefault(key, {}).setdefault(side, []).append((r['median_ms'], r['speedup_vs_baseline']))
    print(f'\n### {preset}\n')
    print('| graph | dataset | TF | setting | viewport | ms before | ms after | ratio before | ratio after |')
    print('|---|---|---|---|---|---|---|---|---|')
    for key, v in runs.items():
        fmt = lambda xs, i, f: ', '.join(f % x[i] for x in xs) if xs else '—'
        o, n = v.get('old', []), v.get('new', [])
        print('| ' + ' | '.join(key) + f" | {fmt(o, 0, '%.1f')} | {fmt(n, 0, '%.1f')} | {fmt(o, 1, '%.2f×')} | {fmt(n, 1, '%.2f×')} |")
