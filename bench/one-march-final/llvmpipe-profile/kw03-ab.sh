#!/usr/bin/env bash
# KW03's rows that use the changed leap (rc_b's termination test, rc_b_leap's segments) and the
# slicer they are compared with, before (shaders of 09e7f8f) and after, alternating twice.
# (The whole kw2003-table1 preset takes ~27 minutes per side here.)
set -u
source "$(dirname "$0")/before-shaders.sh"
OUT=bench/one-march-final/llvmpipe-profile/tables
run() { # side round
    local s=(); [ "$1" = before ] && s=(--shaders "$BEFORE/shaders")
    ./target/release/volgraph bench graphs \
        --graphs graphs/kruger_westermann_2003/sbvr.ron,graphs/kruger_westermann_2003/rc_b.ron,graphs/kruger_westermann_2003/rc_b_leap.ron \
        --datasets engine_vollib,hydrogen_atom --tf sparse --size 512x512 --frames 6 --no-gpu-count --spp-size 0 --quiet "${s[@]}" \
        --json "$OUT/kw03-$1-$2.json" > "$OUT/kw03-$1-$2.txt" 2>&1
    echo "$(date +%T) $1 $2 exit $?"
}
run before 1; run after 1; run after 2; run before 2
