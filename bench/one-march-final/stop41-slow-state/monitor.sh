#!/bin/bash
# Alternates a fixed CPU-only job (sha256 of 1.2 GB on both cores, python) and a fixed volgraph
# render (fastest, hydrogen, 512², median of 200 frames), logging both; if the slow state is the
# machine's, both slow down together. Usage: monitor.sh [SECONDS] (default 900), from anywhere;
# `st` is the kernel's steal-time counter (/proc/stat). monitor.log: stop 41, 08:13–08:24 UTC;
# from ~08:14:30 to ~08:17 release builds ran beside it (both columns doubled together).
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp/xdg-root} VOLGRAPH_DATA=${VOLGRAPH_DATA:-/work/shared/data}
cd "$(dirname "$0")/../../.."
end=$(( $(date +%s) + ${1:-900} ))
while [ $(date +%s) -lt $end ]; do
  t0=$(date +%s.%N)
  for c in 1 2; do python3 -c "
import hashlib
h=hashlib.sha256(); b=b'x'*(1<<20)
for i in range(1200): h.update(b)
" & done; wait
t1=$(date +%s.%N)
  ms=$(${VOLGRAPH:-target/release/volgraph} render graphs/modern/fastest.ron --volume $VOLGRAPH_DATA/volumes/hydrogen_atom_128x128x128_uint8.raw --tf graphs/tf/default.ron --size 512x512 --frames 200 -o /tmp/slow-state.png 2>&1 | grep -o "median of frames 2..200: [0-9.]*" | awk '{print $5}')
  echo "$(date +%T) cpu_s $(echo "$t1 - $t0" | bc) render_ms $ms st $(awk '/^cpu /{print $9}' /proc/stat)"
done
