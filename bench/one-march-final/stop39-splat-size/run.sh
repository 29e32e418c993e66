#!/usr/bin/env bash
# Klein 2005: leap_iso and leap_dvr with splats of 2, 3 and 4 pixels (klein2005 preset settings),
# twice (bench/one-march-final.md, "Splat size").
export XDG_RUNTIME_DIR=/tmp/xdg-root VOLGRAPH_DATA=/work/shared/data
cd "$(dirname "$0")/../../.."
for r in 1 2; do
  ./target/release/volgraph-bench bench graphs --preset klein2005 --graphs graphs/klein_2005/leap_iso.ron,graphs/klein_2005/leap_dvr.ron \
    --sweep splat.splat_size=2,3,4 --no-gpu-count --spp-size 0 --quiet --json bench/one-march-final/stop39-splat-size/sweep-$r.json > /dev/null 2>&1
  python3 -c "
import json;d=json.load(open('bench/one-march-final/stop39-splat-size/sweep-$r.json'))
for r in d['rows']: print($r, r['graph'], r['dataset'][:6], r.get('sweep_value'), round(r['median_ms'],2))"
done
