#!/bin/sh
# Issue 22's before/after in one run: the binary of commit 05041dd (the raycasters before they
# were folded onto one sampling core; its own graphs and shaders, in a git worktree) and the
# binary of the checkout, preset by preset, one after the other, with the presets' settings.
# Then a focused A/B that alternates the two binaries three times on the rows that moved.
# Writes bench/one-march/*.json|md; bench/one-march.md is assembled from them
# (bench/one-march-table.py). Run from the workspace root; takes ~50 minutes on 2 cores.
# PROFILE=release builds both binaries with the release profile instead of dev (optimized);
# OUT=DIR writes the JSON there and TABLE=FILE the tables (then without the first run's text:
# `one-march-table.py --tables-only`), so a rerun leaves the first run's record as it is.
set -eu
root=$(pwd)
old=${OLD_WORKTREE:-/tmp/volgraph-05041dd}
[ -d "$old" ] || git worktree add -f "$old" 05041dd
profile=${PROFILE:-dev}
bin_dir=$([ "$profile" = dev ] && echo debug || echo "$profile")
# The old side builds in a target folder of its own: cargo names a workspace crate's artifacts
# by its path inside the workspace, the same in both checkouts, so one shared folder would link
# one side's binary against the other side's crates. Seeded from ours for the dependencies;
# each side's sources are touched so that its crates are rebuilt from them whatever the copy
# or an earlier run left.
[ -d "$old/target/$bin_dir" ] || { mkdir -p "$old/target"; cp -a "target/$bin_dir" "$old/target/"; }
find "$old/crates" -name '*.rs' -exec touch {} +
(cd "$old" && CARGO_TARGET_DIR="$old/target" cargo build --profile "$profile" -p volgraph-bench)
cp "$old/target/$bin_dir/volgraph-bench" /tmp/volgraph-bench-old
find crates -name '*.rs' -exec touch {} +
cargo build --profile "$profile" -p volgraph-bench
cp "target/$bin_dir/volgraph-bench" /tmp/volgraph-bench-new
out=${OUT:-"$root/bench/one-march"}
mkdir -p "$out"
run() { # side, then bench arguments
  side=$1; shift
  if [ "$side" = old ]; then dir=$old; else dir=$root; fi
  (cd "$dir" && /tmp/volgraph-bench-$side bench graphs --quiet "$@")
}
for preset in peer klein2005 ruijters2006 kw2003-table1 thesis-tables; do
  for side in old new; do
    run $side --preset $preset --json "$out/$preset-$side.json" --markdown "$out/$preset-$side.md" > /dev/null
  done
done
for round in 1 2 3; do
  for side in old new; do
    run $side --graphs graphs/klein_2005/baseline_dvr.ron,graphs/klein_2005/leap_dvr.ron \
      --datasets lobster,hydrogen_atom --tf default --frames 12 --no-gpu-count --json "$out/ab-klein-$side-$round.json"
    run $side --graphs graphs/klein_2005/baseline_iso.ron,graphs/klein_2005/leap_iso.ron \
      --datasets engine_vollib --tf engine_sparse --sweep input.iso_value=0.0 --frames 12 \
      --json "$out/ab-fixed-$side-$round.json"
    run $side --graphs graphs/ruijters_vilanova_2006/unoptimized.ron,graphs/ruijters_vilanova_2006/bricks_octree.ron \
      --datasets vessels256 --tf graphs/tf/vessels.ron --size 800x800 --frames 8 --no-gpu-count \
      --json "$out/ab-bricks-$side-$round.json"
  done
done > /dev/null
if [ -n "${TABLE:-}" ]; then
  python3 bench/one-march-table.py --tables-only "$out" > "$TABLE"
else
  python3 bench/one-march-table.py "$out" > bench/one-march.md
fi
