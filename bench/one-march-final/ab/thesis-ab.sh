#!/usr/bin/env bash
set -u
export XDG_RUNTIME_DIR=/tmp/xdg-root VOLGRAPH_DATA=/work/shared/data
run() {
    local dir=$([ $1 = old ] && echo /tmp/volgraph-05041dd || echo /work/main)
    (cd $dir && ./target/release/volgraph bench graphs --preset thesis-tables --scale 0.25 --frames 12 --spp-size 0 \
        --no-gpu-count --quiet --json ${OUT:-/tmp/abth}/$1-$2.json > ${OUT:-/tmp/abth}/$1-$2.txt 2>&1)
    echo "$(date +%T) $1 $2 exit $?"
}
run old 1; run new 1; run new 2; run old 2
