#!/usr/bin/env bash
# Stop 38: KW03 Table 1 and the thesis tables rerun after stops 37-38 (release binary, the
# presets' own settings), to compare their in-run ratios with one-march-final/tables.md.
set -u
cd "$(dirname "$0")/../../.."
OUT=bench/one-march-final/stop38-tables
for p in kw2003-table1 thesis-tables; do
    ./target/release/volgraph bench graphs --preset "$p" --quiet --json "$OUT/$p.json" --markdown "$OUT/$p.md" > /dev/null 2>"$OUT/$p.err"
    echo "$(date +%T) $p exit $?"
done
