#!/usr/bin/env bash
# Where the compute march stands against the fetch ceiling on a lent GPU (see README.md here):
# every sample of every ray (threshold 1) on the 512³ vessel tree at 1920×1080, workgroup shapes
# and classification of bench/device/march_probe.ron beside the thesis's compute raycaster.
# Run like run.sh (carry: .gl .devcarry); it sources run.sh's setup.
set -u
SETUP_ONLY=1 source bench/device/run.sh
P=bench/device/march_probe.ron
C=graphs/compute_raycast_2013/compute_shader.ron
common=(--datasets vessels512,ml512 --tf sparse --size 1920x1080 --frames 12 --full-turn --camera 0,0,3.2
    --spp-size 0 --set march.threshold=1 --quiet)
step probe-wg8 60 graphs --graphs $P,$C "${common[@]}" --set march.workgroup_y=8 \
    --sweep march.workgroup_x=8,16,32 --json "$RES/probe-wg8.json" --markdown "$RES/probe-wg8.md"
step probe-wg16 60 graphs --graphs $P,$C "${common[@]}" --set march.workgroup_y=16 \
    --sweep march.workgroup_x=8,16 --json "$RES/probe-wg16.json" --markdown "$RES/probe-wg16.md"
step probe-classify 60 graphs --graphs $P "${common[@]}" --sweep march.classify=exact,table \
    --json "$RES/probe-classify.json" --markdown "$RES/probe-classify.md"
log done
