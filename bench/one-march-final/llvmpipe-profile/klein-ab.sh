#!/usr/bin/env bash
# Klein 2005's preset on lobster and hydrogen (the cases below 2× on llvmpipe), before (shaders
# of 09e7f8f) and after, alternating twice.
set -u
source "$(dirname "$0")/before-shaders.sh"
OUT=bench/one-march-final/llvmpipe-profile/tables
run() { # side round
    local s=(); [ "$1" = before ] && s=(--shaders "$BEFORE/shaders")
    ./target/release/volgraph bench graphs --preset klein2005 --datasets lobster,hydrogen_atom --no-gpu-count --spp-size 0 \
        --quiet "${s[@]}" --json "$OUT/klein-$1-$2.json" > "$OUT/klein-$1-$2.txt" 2>&1
    echo "$(date +%T) $1 $2 exit $?"
}
run before 1; run after 1; run after 2; run before 2
