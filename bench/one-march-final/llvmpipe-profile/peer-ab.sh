#!/usr/bin/env bash
# Before/after on the peer preset with VTK, alternating: before = the shaders of 09e7f8f (the
# stop's start) with blocks of 4, as main rendered then; after = the working tree.
source "$(dirname "$0")/before-shaders.sh"
OUT=${OUT:-bench/one-march-final/llvmpipe-profile}
mkdir -p $OUT
for r in $(seq ${ROUNDS:-3}); do
  ./target/release/volgraph bench graphs --preset peer --graphs graphs/modern/fastest.ron --quiet --spp-size 0 --shaders $BEFORE/shaders --set input.block_size=4 --json $OUT/before-$r.json --markdown $OUT/before-$r.md > /dev/null 2>&1
  ./target/release/volgraph bench graphs --preset peer --graphs graphs/modern/fastest.ron --quiet --spp-size 0 --json $OUT/after-$r.json --markdown $OUT/after-$r.md > /dev/null 2>&1
  for w in before after; do python3 - $OUT/$w-$r.json $w $r <<'PY'
import json, sys
d = json.load(open(sys.argv[1])); rows = d['rows']
vtk = {(r['dataset'], r['tf']): r['median_ms'] for r in rows if r['graph'] == 'vtk_fixed_point'}
out = []
for r in rows:
    if r['graph'] == 'fastest':
        v = vtk.get((r['dataset'], r['tf']))
        out.append(f"{r['dataset'].split('_')[0]}/{r['tf']}: {r['median_ms']:.1f} ms, VTK {v:.1f}, {v / r['median_ms']:.2f}x, {r.get('gpu_samples_per_pixel') or 0:.1f} spp")
print(f"round {sys.argv[3]} {sys.argv[2]:6s} | " + " | ".join(out))
PY
  done
done
