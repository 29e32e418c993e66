#!/usr/bin/env bash
# Stop 41's Ruijters & Vilanova 2006 Table 1 before/after in one run: the release binary of
# 05041dd (before the fold, its own checkout, graphs and shaders: bench/one-march.sh builds it)
# against this checkout's, three times each, the sides alternating, at the preset's own settings
# but for the sample counts (--spp-size 0 --no-gpu-count: ms/frame and ratios only).
# Tables: python3 bench/one-march-final/stop39-tables/table.py bench/one-march-final/stop41-ruijters
set -u
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp/xdg-root} VOLGRAPH_DATA=${VOLGRAPH_DATA:-/work/shared/data}
root=$(pwd)
old=${OLD_WORKTREE:-/tmp/volgraph-05041dd}
out=${OUT:-$root/bench/one-march-final/stop41-ruijters}
run() { # side suffix
    local dir=$([ $1 = old ] && echo $old || echo $root)
    (cd $dir && ./target/release/volgraph-bench bench graphs --quiet --preset ruijters2006 --spp-size 0 --no-gpu-count \
        --json $out/ruijters2006-$1$2.json --markdown $out/ruijters2006-$1$2.md > /dev/null 2> $out/ruijters2006-$1$2.err)
    echo "$(date +%T) ruijters2006 $1$2 exit $?"
}
run old ""; run new ""; run new -2; run old -2; run old -3; run new -3
