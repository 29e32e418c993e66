#!/usr/bin/env bash
# Shader variants of the compute march on a lent GPU (see README.md here), through
# `--shaders` (no rebuild): `base` (shaders/ as committed), `prefetch` (the next sample's fetch
# issued before this one is classified), `sharedtf` (the TF copied into workgroup memory,
# interpolated by hand), `both`; base is run again at the end to see the drift of the clocks.
# Run like run.sh (carry: .gl .devcarry). The shader folders were removed once their technique
# became the `sample_loop` parameter (run.sh's *-sample-loop steps measure that); to rerun this
# script, restore them first:
#   git checkout 72c3885 -- bench/device/shaders-prefetch bench/device/shaders-sharedtf bench/device/shaders-both
set -u
SETUP_ONLY=1 source bench/device/run.sh
P=bench/device/march_probe.ron
F=graphs/modern/fastest.ron
for v in base prefetch sharedtf both base2; do
    shaders=()
    case $v in base|base2) ;; *) shaders=(--shaders bench/device/shaders-$v) ;; esac
    step "$v-probe" 60 graphs --graphs $P,$F --datasets vessels512,engine_vollib --tf sparse --size 1920x1080 \
        --frames 12 --full-turn --camera 0,0,3.2 --spp-size 0 --set march.threshold=1 --accuracy --quiet "${shaders[@]}" \
        --json "$RES/$v-probe.json" --markdown "$RES/$v-probe.md"
    step "$v-peer" 60 graphs --preset peer --no-peer --graphs $P,$F --size 1920x1080 --spp-size 0 --quiet \
        "${shaders[@]}" --json "$RES/$v-peer.json" --markdown "$RES/$v-peer.md"
done
log done
