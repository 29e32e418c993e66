#!/usr/bin/env bash
# Shader compiles per frame on lavapipe, for every shipped graph (docs/writing_a_pass.md, "A count
# that shapes a loop is a pipeline constant"): counts LLVM modules created (a uprobe on
# LLVMModuleCreateWithNameInContext) in a 4-frame and a 20-frame run of `volgraph bench graphs`
# on hydrogen at 128², and prints (compiles of the 20-frame run − of the 4-frame run) / 16.
# Anything above 0 is a pipeline lavapipe rebuilds while it renders. The totals are small where
# Mesa's on-disk shader cache already holds a variant; the difference is what counts.
#
# usage: bench/llvmpipe-profile/recompiles.sh [volgraph bench graphs args...]
#   GRAPHS="graphs/klein_2005/*.ron" limits the graphs. Needs perf (linux-perf) and root for the
#   uprobe; uses target/release/volgraph.
set -u
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
cd "$ROOT"
LLVM=$(ldconfig -p | awk '/libLLVM-[0-9]+\.so/ { print $NF; exit }')
perf probe -q -x "$LLVM" LLVMModuleCreateWithNameInContext 2>/dev/null || true
EVENT=$(perf probe -l 2>/dev/null | awk '/LLVMModuleCreateWithNameInContext/ { print $1; exit }')
count() { # graph frames args...
    perf stat -x, -e "$EVENT" -- ./target/release/volgraph bench graphs --graphs "$1" --datasets hydrogen_atom \
        --size 128x128 --frames "$2" --quiet --spp-size 0 --no-gpu-count "${@:3}" 2>&1 >/dev/null \
        | awk -F, '/LLVMModuleCreate/ { print $1 }'
}
echo "| graph | compiles, 4 frames | compiles, 20 frames | per frame |"
echo "|---|---:|---:|---:|"
for g in ${GRAPHS:-graphs/*/*.ron}; do
    case "$g" in graphs/tf/*) continue ;; esac
    a=$(count "$g" 4 "$@"); b=$(count "$g" 20 "$@")
    echo "| $g | $a | $b | $(awk -v a="$a" -v b="$b" 'BEGIN { print (a ~ /^[0-9]+$/ && b ~ /^[0-9]+$/) ? (b - a) / 16 : "error" }') |"
done
