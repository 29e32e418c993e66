#!/usr/bin/env bash
# Interleaved A/B of KW03's rc / rc_a / sbvr: the release binary of 05041dd (its own checkout,
# built by bench/one-march.sh) and this checkout's. Run from the workspace root with the rounds
# as arguments, e.g. `run.sh old-1 new-1 new-2 old-2 new-3 old-3` (stop 39's order); then
# `python3 table.py DIR > table.md`.
set -u
export XDG_RUNTIME_DIR=/tmp/xdg-root VOLGRAPH_DATA=/work/shared/data
OUT=${OUT:-$(pwd)/bench/one-march-final/stop39-kw03}
run() { # side round
    local dir=$([ $1 = old ] && echo /tmp/volgraph-05041dd || echo /work/main)
    (cd $dir && ./target/release/volgraph-bench bench graphs \
        --graphs graphs/kruger_westermann_2003/rc.ron,graphs/kruger_westermann_2003/rc_a.ron,graphs/kruger_westermann_2003/sbvr.ron \
        --datasets engine_vollib,hydrogen_atom,lobster --tf opaque,sparse --size 512x512 --frames 12 --no-gpu-count --spp-size 0 \
        --quiet --json $OUT/$1-$2.json > $OUT/$1-$2.txt 2>&1)
    echo "$(date +%T) $1 $2 exit $?"
}
for r in "$@"; do run ${r%-*} ${r#*-}; done
