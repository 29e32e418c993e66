#!/usr/bin/env bash
# The paper presets before and after this stop's shader changes, alternating: "before" runs the
# same binary with the shaders of 09e7f8f (the stop's start, extracted to $BEFORE), "after" the
# working tree's. Each preset at its own settings.
set -u
source "$(dirname "$0")/before-shaders.sh"
OUT=bench/one-march-final/llvmpipe-profile/tables
run() { # preset side
    local s=(); [ "$2" = before ] && s=(--shaders "$BEFORE/shaders")
    ./target/release/volgraph bench graphs --preset "$1" --no-gpu-count --spp-size 0 --quiet "${s[@]}" ${EXTRA:-} \
        --json "$OUT/$1-$2.json" --markdown "$OUT/$1-$2.md" > "$OUT/$1-$2.txt" 2>&1
    echo "$(date +%T) $1 $2 exit $?"
}
for preset in ${PRESETS:-klein2005 ruijters2006 kw2003-table1}; do
    run "$preset" before; run "$preset" after
done
