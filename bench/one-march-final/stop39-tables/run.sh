#!/usr/bin/env bash
# Stop 39's before/after in one run: the release binary of 05041dd (before the fold, its own
# checkout, graphs and shaders: bench/one-march.sh builds it) against this checkout's, preset by
# preset at the presets' own settings, the sides alternating (old, new, then new, old).
set -u
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp/xdg-root} VOLGRAPH_DATA=${VOLGRAPH_DATA:-/work/shared/data}
root=$(pwd)
old=${OLD_WORKTREE:-/tmp/volgraph-05041dd}
out=${OUT:-$root/bench/one-march-final/stop39-tables}
run() { # side preset
    local dir=$([ $1 = old ] && echo $old || echo $root)
    (cd $dir && ./target/release/volgraph-bench bench graphs --quiet --preset $2 \
        --json $out/$2-$1.json --markdown $out/$2-$1.md > /dev/null 2> $out/$2-$1.err)
    echo "$(date +%T) $2 $1 exit $?"
}
run old klein2005; run new klein2005
run new ruijters2006; run old ruijters2006
run old thesis-tables; run new thesis-tables
