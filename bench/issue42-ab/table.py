#!/usr/bin/env python3
"""Issue 42's before/after table from bench/issue42-ab/*.json (ab.sh): per row the median
ms/frame of each round, old (52eb093) and new (this checkout), the best of the three rounds a
side, and new / old of the best (below 1: the new binary is faster)."""
import collections
import glob
import json
import os
import sys

here = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.abspath(__file__))
runs = collections.defaultdict(lambda: {"old": [], "new": []})
order = []
for path in sorted(glob.glob(os.path.join(here, "*.json"))):
    group, side, _round = os.path.basename(path)[:-5].rsplit("-", 2)
    data = json.load(open(path))
    for row in data["rows"]:
        key = (group, row["graph"], row["dataset"], "{}×{}".format(*row["viewport"]))
        if key not in runs:
            order.append(key)
        runs[key][side].append(row["median_ms"])
adapter = data["adapter"]
print(f"Adapter: {adapter}. ms/frame = median of the run's frames (wall); three rounds a side, old and new alternating.\n")
print("| group | graph | dataset | viewport | old rounds (ms) | new rounds (ms) | old best | new best | new / old |")
print("|---|---|---|---|---|---|---|---|---|")
for key in order:
    old, new = runs[key]["old"], runs[key]["new"]
    if not old or not new:
        continue
    ratio = min(new) / min(old)
    fmt = lambda v: ", ".join(f"{x:.1f}" for x in v)
    print(f"| {key[0]} | {key[1]} | {key[2]} | {key[3]} | {fmt(old)} | {fmt(new)} | {min(old):.1f} | {min(new):.1f} | {ratio:.2f} |")
