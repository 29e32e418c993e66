#!/bin/sh
# Issue 42's before/after: the release binary of 52eb093 (the last commit before the issue's
# work: every effect in every raycaster, the runtime and viewer split, the crate lines, the
# parameter blocks) against this checkout's, one row per paper family, the two binaries
# alternating three rounds (old, new, old, new, …) so that a drift of the machine's load falls
# on both. Each side runs in its own checkout (its graphs and shaders). Writes
# bench/issue42-ab/*.json; bench/issue42-ab/table.py makes the table. ~20 min on 2 cores.
# OLD=/tmp/volgraph-52eb093 (a worktree of 52eb093 with target/release/volgraph-bench built).
set -eu
root=$(pwd)
old=${OLD:-/tmp/volgraph-52eb093}
out="$root/bench/issue42-ab"
run() { # side, round, name, then bench arguments
  side=$1; round=$2; name=$3; shift 3
  if [ "$side" = old ]; then dir=$old; bin=$old/target/release/volgraph-bench; else dir=$root; bin=$root/target/release/volgraph-bench; fi
  (cd "$dir" && "$bin" bench graphs --quiet "$@" --json "$out/$name-$side-$round.json") > /dev/null
}
for round in 1 2 3; do
  for side in old new; do
    # Krüger–Westermann 2003 (the multipass segments) and the single-pass fragment raycaster.
    run $side $round kw03 --graphs graphs/kruger_westermann_2003/rc.ron,graphs/kruger_westermann_2003/rc_b.ron,graphs/basic/fragment_raycast.ron \
      --datasets engine_vollib --tf default --size 512x512 --frames 8 --no-gpu-count
    # Klein et al. 2005 (the leap with tile bounds against its baseline).
    run $side $round klein --graphs graphs/klein_2005/baseline_dvr.ron,graphs/klein_2005/leap_dvr.ron \
      --datasets lobster,hydrogen_atom --tf default --size 512x512 --frames 12 --no-gpu-count
    # Ruijters & Vilanova 2006 (the brick raycaster).
    run $side $round bricks --graphs graphs/ruijters_vilanova_2006/unoptimized.ron,graphs/ruijters_vilanova_2006/bricks_octree.ron \
      --datasets vessels256 --tf graphs/tf/vessels.ron --size 800x800 --frames 8 --no-gpu-count
    # The DirectCompute thesis (pixel vs compute shader) and the fastest path.
    run $side $round compute --graphs graphs/compute_raycast_2013/pixel_shader.ron,graphs/compute_raycast_2013/compute_shader.ron,graphs/modern/fastest.ron \
      --datasets hydrogen_atom --tf default --size 800x600 --frames 12 --no-gpu-count
  done
done
