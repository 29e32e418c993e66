#!/usr/bin/env bash
# Stop 40's before/after in one run: the release binary of 05041dd (before the fold, its own
# checkout, graphs and shaders: bench/one-march.sh builds it) against this checkout's, preset by
# preset at the presets' own settings but for the sample counts (--spp-size 0 --no-gpu-count:
# ms/frame and ratios only), the sides alternating. Tables: python3 stop39-tables/table.py stop40-tables.
set -u
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp/xdg-root} VOLGRAPH_DATA=${VOLGRAPH_DATA:-/work/shared/data}
root=$(pwd)
old=${OLD_WORKTREE:-/tmp/volgraph-05041dd}
out=${OUT:-$root/bench/one-march-final/stop40-tables}
run() { # side preset [suffix]
    local dir=$([ $1 = old ] && echo $old || echo $root)
    (cd $dir && ./target/release/volgraph-bench bench graphs --quiet --preset $2 --spp-size 0 --no-gpu-count \
        --json $out/$2-$1${3:-}.json --markdown $out/$2-$1${3:-}.md > /dev/null 2> $out/$2-$1${3:-}.err)
    echo "$(date +%T) $2 $1${3:-} exit $?"
}
run old klein2005; run new klein2005; run new klein2005 -2; run old klein2005 -2
run old kw2003-table1; run new kw2003-table1
run new thesis-tables; run old thesis-tables
run old ruijters2006; run new ruijters2006
run new peer; run old peer
