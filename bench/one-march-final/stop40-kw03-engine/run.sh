#!/usr/bin/env bash
# KW03 `rc_a` over `sbvr` on the engine, opaque TF (the one ratio of stop40-tables below the old
# one): the release binaries of 05041dd (its own checkout) and of this checkout alternating three
# times, kw2003-table1 settings, ms and ratios only.
set -u
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp/xdg-root} VOLGRAPH_DATA=${VOLGRAPH_DATA:-/work/shared/data}
root=$(pwd)
old=${OLD_WORKTREE:-/tmp/volgraph-05041dd}
out=$root/bench/one-march-final/stop40-kw03-engine
for i in 1 2 3; do
    for side in old new; do
        dir=$([ $side = old ] && echo $old || echo $root)
        (cd $dir && ./target/release/volgraph-bench bench graphs --quiet --preset kw2003-table1 --spp-size 0 --no-gpu-count \
            --graphs graphs/kruger_westermann_2003/sbvr.ron,graphs/kruger_westermann_2003/rc_a.ron \
            --datasets engine_vollib --tf opaque --json $out/$side-$i.json --markdown $out/$side-$i.md > /dev/null 2>&1)
        echo "$side $i: $(grep -E '^\| (sbvr|rc_a) ' $out/$side-$i.md | awk -F'|' '{printf "%s %s %s; ", $2, $6, $8}')"
    done
done
