#!/bin/sh
# Each ingredient of graphs/modern/fastest.ron measured on its own, on the peer comparison's
# cases, views and settings (`--preset peer`), with error against the converged f64 reference:
# block size, leap rule, run length between distance-map looks, classification, workgroup shape.
# Writes bench/peer-ablation.md and one JSON per sweep. Run from the workspace root after
# `cargo build --release -p volgraph-app`; VOLGRAPH overrides the binary.
set -eu
volgraph="${VOLGRAPH:-target/release/volgraph}"
out=bench/peer-ablation.md
printf '# graphs/modern/fastest.ron, one ingredient at a time\n\n' > "$out"
for sweep in input.block_size=4,8,16 march.leap=none,blocks,cubes march.check_every=1,4,16,64 \
    march.classify=exact,table march.workgroup_x=8,16,32; do
    key="${sweep%%=*}"
    "$volgraph" bench graphs --preset peer --graphs graphs/modern/fastest.ron --no-peer --quiet \
        --sweep "$sweep" --json "bench/peer-ablation-${key#*.}.json" >> "$out"
    printf '\n' >> "$out"
done
