#!/usr/bin/env bash
# Where a graph's frame goes on llvmpipe, by region of the JIT code (bench/one-march-final.md,
# "llvmpipe profile"): runs `volgraph bench graphs` for 400 frames, samples it with perf for 6 s
# once the pipelines are compiled, dumps the hottest JIT mapping with gdb, disassembles it and
# prints the share of the samples in each function the shader calls (llvmpipe's texture
# functions: the volume's trilinear fetch, the TF's 1D fetch, the distance map's texel fetch)
# and in each loop (backward jump).
#
# usage: bench/llvmpipe-profile/profile.sh NAME [volgraph bench graphs args...]
#   e.g. profile.sh fastest-hydrogen --preset peer --no-peer --graphs graphs/modern/fastest.ron \
#          --datasets hydrogen_atom --tf hydrogen --shaders shaders
# Needs perf (linux-perf), gdb and objdump (binutils); writes /tmp/volgraph-profile/NAME.*.
set -euo pipefail
NAME=$1; shift
DIR=/tmp/volgraph-profile; mkdir -p "$DIR"
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
"$ROOT/target/release/volgraph" bench graphs "$@" --quiet --spp-size 0 --no-gpu-count --frames 400 > "$DIR/$NAME.out" 2>&1 &
LAUNCHED=$!
sleep 14
# `volgraph bench` runs the volgraph-bench binary as its child.
PID=$(pgrep -P "$LAUNCHED" | head -1 || true)
PID=${PID:-$LAUNCHED}
trap 'kill "$PID" "$LAUNCHED" 2>/dev/null || true' EXIT
perf record -p "$PID" -o "$DIR/$NAME.perf" -F 1999 -- sleep 6 > /dev/null 2>&1
perf report -i "$DIR/$NAME.perf" --no-children --sort dso,sym 2>/dev/null | grep "JIT" \
  | awk '{gsub("%","",$1); print $1, $NF}' > "$DIR/$NAME.hot"
HOT=$(awk '$1 > best { best = $1; at = $2 } END { print at }' "$DIR/$NAME.hot")
read -r LO HI < <(python3 -c "
h = int('$HOT', 16)
for l in open('/proc/$PID/maps'):
    a, b = [int(x, 16) for x in l.split()[0].split('-')]
    if a <= h < b: print(hex(a), hex(b))")
gdb -p "$PID" -batch -ex "dump memory $DIR/$NAME.bin $LO $HI" > /dev/null 2>&1
objdump -D -b binary -m i386:x86-64 --adjust-vma="$LO" "$DIR/$NAME.bin" > "$DIR/$NAME.asm" 2>/dev/null
python3 "$ROOT/bench/llvmpipe-profile/regions.py" "$DIR/$NAME" "$LO" "$HI"
