#!/bin/sh
# Klein et al. 2005's reprojection with the graphs' bypass (issue 22, item 4): its fixed cost on
# a view where every ray hits at its first sample (isovalue 0: the plain raycast takes one sample
# per pixel), the bypass threshold swept on the preset's four datasets, then the klein2005 preset.
# Writes bench/klein2005-bypass/*.json|md and bench/klein2005-bypass.md; run from the workspace
# root (~25 minutes on 2 cores).
set -eu
out=bench/klein2005-bypass
mkdir -p "$out"
cargo build -p volgraph-bench
bench=target/debug/volgraph-bench
{
  echo "# Klein 2005's reprojection and its bypass"
  echo
  echo "Made by \`bench/klein2005-bypass.sh\` ($(date -u +%Y-%m-%d)); \`volgraph bench graphs\`, dev profile (optimized), llvmpipe."
  echo
  echo "## Fixed cost: isovalue 0, every ray hits at its first sample (engine, 512², three rounds)"
  echo
  for round in 1 2 3; do
    $bench bench graphs --quiet --graphs graphs/klein_2005/baseline_iso.ron,graphs/klein_2005/leap_iso.ron \
      --datasets engine_vollib --tf engine_sparse --sweep input.iso_value=0.0 --frames 24 \
      --json "$out/fixed-$round.json" --markdown "$out/fixed-$round.md" > /dev/null
    echo "### Round $round"
    echo
    grep '^|' "$out/fixed-$round.md"
    echo
  done
  echo "## The threshold swept (input.reproject_below; 0.001: never bypass, 1000000: always)"
  echo
  for pair in engine_vollib:engine_sparse:0.3 lobster:default:0.2 hydrogen_atom:hydrogen:0.12 neghip:default:0.25; do
    d=${pair%%:*}; rest=${pair#*:}; t=${rest%%:*}; iso=${rest#*:}
    $bench bench graphs --quiet --graphs graphs/klein_2005/baseline_iso.ron,graphs/klein_2005/leap_iso.ron \
      --datasets "$d" --tf "$t" --frames 24 --set input.iso_value=$iso --no-gpu-count \
      --json "$out/base-$d.json" --markdown "$out/base-$d.md" > /dev/null
    $bench bench graphs --quiet --graphs graphs/klein_2005/leap_iso.ron --datasets "$d" --tf "$t" --frames 24 \
      --set input.iso_value=$iso --no-gpu-count --sweep input.reproject_below=0.001,24,32,40,48,64,1000000 \
      --json "$out/sweep-$d.json" --markdown "$out/sweep-$d.md" > /dev/null
    echo "### $d"
    echo
    grep '^|' "$out/base-$d.md"
    echo
    grep '^|' "$out/sweep-$d.md"
    echo
  done
} > bench/klein2005-bypass.md
$bench bench graphs --quiet --preset klein2005 --json bench/klein2005.json --markdown bench/klein2005.md > /dev/null
