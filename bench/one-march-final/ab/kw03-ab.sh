#!/usr/bin/env bash
# Interleaved A/B of KW03's multipass rc / rc_b: the binary of 05041dd (its own checkout) and this one.
set -u
export XDG_RUNTIME_DIR=/tmp/xdg-root VOLGRAPH_DATA=/work/shared/data
run() { # side round
    local dir=$([ $1 = old ] && echo /tmp/volgraph-05041dd || echo /work/main)
    (cd $dir && ./target/release/volgraph bench graphs \
        --graphs graphs/kruger_westermann_2003/rc.ron,graphs/kruger_westermann_2003/rc_b.ron,graphs/kruger_westermann_2003/sbvr.ron \
        --datasets engine_vollib,hydrogen_atom --tf opaque,sparse --size 512x512 --frames 12 --no-gpu-count --spp-size 0 \
        --quiet --json ${OUT:-/tmp/abkw}/$1-$2.json > ${OUT:-/tmp/abkw}/$1-$2.txt 2>&1)
    echo "$(date +%T) $1 $2 exit $?"
}
run old 1; run new 1; run new 2; run old 2; run old 3; run new 3
