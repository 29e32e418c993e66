#!/usr/bin/env bash
# Issue 22's checks on a lent GPU machine (see bench/device/README.md): the fetch ceiling and a
# 512³ volume at 1920×1080, then the `peer`, `klein2005` and `ruijters2006` presets, with the
# release binaries built on the CI image. Run by the device tool from the repository root:
#   bash bench/device/run.sh        (carry: .gl .devcarry; results in $OUT/results.tgz)
# Every step has its own timeout and the results archive is rewritten after each, so a run that
# is stopped early still returns what it measured.
set -u
OUT=${OUT:-/tmp/out}
RES=/tmp/vg-results
mkdir -p "$OUT" "$RES" /tmp/vg
log() { echo "[$(date +%T)] $*" | tee -a "$RES/log.txt"; }
pack() { tar czf "$OUT/results.tgz" -C "$RES" . ; cp "$RES/log.txt" "$OUT/log.txt"; }

for f in .gl/*.deb; do dpkg -x "$f" /; done
ldconfig
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
[ -f "$icd" ] && export VK_DRIVER_FILES=$icd
tar xzf .devcarry/bin.tgz -C /tmp/vg
export PATH=/tmp/vg/bin:$PATH LD_LIBRARY_PATH=/tmp/vg/lib VOLGRAPH_DATA=/tmp/vg/data
export XDG_RUNTIME_DIR=/tmp/xdg && mkdir -p -m 0700 $XDG_RUNTIME_DIR

log "$(nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>&1)"
log "$(nproc) CPUs; $(uname -r)"
step() { # NAME SECONDS ARGS...: one bench command, its stdout/stderr in $RES/NAME.txt
    local name=$1 secs=$2; shift 2
    log "start $name"
    timeout "$secs" volgraph bench "$@" >"$RES/$name.txt" 2>&1
    log "end $name: exit $?"
    pack
}

[ -n "${SETUP_ONLY:-}" ] && return 0
G=graphs
step fetch 60 fetch --datasets ml512,vessels512,engine_vollib,hydrogen_atom --size 1920x1080,512x512 \
    --json "$RES/fetch.json" --markdown "$RES/fetch.md"
grep -q "NVIDIA" "$RES/fetch.txt" || { log "no NVIDIA adapter: stopping"; exit 1; }
# A 512³ volume at 1080p: compute (analytic rays, leaping), compute (rasterised rays), fragment.
step 1080p 90 graphs --graphs $G/modern/fastest.ron,$G/compute_raycast_2013/compute_shader.ron,$G/modern/single_pass_ess_ert.ron \
    --datasets ml512,vessels512,engine_vollib --tf default,sparse --size 1920x1080 --frames 24 --full-turn \
    --camera 0,0,3.2 --quiet --json "$RES/1080p.json" --markdown "$RES/1080p.md"
# What leaping and the workgroup width do there, with the error against the f64 reference.
step 1080p-leap 90 graphs --graphs $G/modern/fastest.ron --datasets ml512,vessels512 --tf sparse \
    --size 1920x1080 --frames 24 --full-turn --camera 0,0,3.2 --sweep march.leap=none,blocks,cubes \
    --quiet --json "$RES/1080p-leap.json" --markdown "$RES/1080p-leap.md"
step 1080p-workgroup 60 graphs --graphs $G/modern/fastest.ron --datasets ml512 --tf sparse \
    --size 1920x1080 --frames 24 --full-turn --camera 0,0,3.2 --sweep march.workgroup_x=8,16,32 \
    --quiet --json "$RES/1080p-workgroup.json" --markdown "$RES/1080p-workgroup.md"
# The compute march's sample loop, plain against pipelined (the default on GPUs): every sample
# (threshold 1) on the 512³ vessel tree, and the peer cases at 1080p.
step 1080p-sample-loop 60 graphs --graphs bench/device/march_probe.ron,$G/modern/fastest.ron \
    --datasets vessels512,engine_vollib --tf sparse --size 1920x1080 --frames 24 --full-turn --camera 0,0,3.2 \
    --set march.threshold=1 --sweep march.sample_loop=plain,pipelined --quiet \
    --json "$RES/1080p-sample-loop.json" --markdown "$RES/1080p-sample-loop.md"
step peer-sample-loop 60 graphs --preset peer --no-peer --graphs bench/device/march_probe.ron,$G/modern/fastest.ron \
    --size 1920x1080 --sweep march.sample_loop=plain,pipelined --quiet \
    --json "$RES/peer-sample-loop.json" --markdown "$RES/peer-sample-loop.md"
step ruijters-sample-loop 60 graphs --preset ruijters2006 --datasets vessels512 --tf $G/tf/vessels.ron \
    --size 1920x1080 --sweep march.sample_loop=plain,pipelined --quiet \
    --json "$RES/ruijters-sample-loop.json" --markdown "$RES/ruijters-sample-loop.md"
# The presets at their own settings (the paper tables' ratios) ...
step peer 60 graphs --preset peer --no-peer --quiet --json "$RES/peer.json" --markdown "$RES/peer.md"
step klein2005 90 graphs --preset klein2005 --quiet --json "$RES/klein2005.json" --markdown "$RES/klein2005.md"
step ruijters2006 60 graphs --preset ruijters2006 --quiet --json "$RES/ruijters2006.json" \
    --markdown "$RES/ruijters2006.md"
step kw2003-table1 60 graphs --preset kw2003-table1 --quiet --json "$RES/kw2003-table1.json" \
    --markdown "$RES/kw2003-table1.md"
step thesis-tables 60 graphs --preset thesis-tables --quiet --json "$RES/thesis-tables.json" \
    --markdown "$RES/thesis-tables.md"
# ... and at 1920×1080 (Ruijters on the 512³ vessel tree, its angiography case).
step peer-1080p 60 graphs --preset peer --no-peer --size 1920x1080 --quiet --json "$RES/peer-1080p.json" \
    --markdown "$RES/peer-1080p.md"
step klein2005-1080p 90 graphs --preset klein2005 --size 1920x1080 --quiet --json "$RES/klein2005-1080p.json" \
    --markdown "$RES/klein2005-1080p.md"
step ruijters2006-1080p 60 graphs --preset ruijters2006 --datasets vessels512 --tf $G/tf/vessels.ron \
    --size 1920x1080 --quiet --json "$RES/ruijters2006-1080p.json" --markdown "$RES/ruijters2006-1080p.md"
step workbench 60 workbench --json "$RES/workbench.json" --markdown "$RES/workbench.md"
step cuts 30 cuts --json "$RES/cuts.json" --markdown "$RES/cuts.md"
log done
