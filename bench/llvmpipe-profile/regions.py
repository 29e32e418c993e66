"""Shares of perf samples by region of a dumped llvmpipe JIT mapping (see profile.sh).

usage: regions.py PREFIX LO HI — reads PREFIX.hot ("percent address" lines) and PREFIX.asm
(objdump of the mapping), writes PREFIX.annot (the disassembly with each instruction's share).
"""
import re
import sys

prefix, base, top = sys.argv[1], int(sys.argv[2], 16), int(sys.argv[3], 16)
hot = {}
for line in open(f"{prefix}.hot"):
    share, address = line.split()
    hot[int(address, 16)] = hot.get(int(address, 16), 0.0) + float(share)
ins = []
for line in open(f"{prefix}.asm"):
    m = re.match(r"\s*([0-9a-f]+):\s+(?:[0-9a-f]{2} )+\s*(.*)", line)
    if m:
        ins.append((int(m.group(1), 16), m.group(2).strip()))
# Functions the shader calls: llvmpipe loads their address with movabs before `call *%reg`.
starts = sorted({int(m.group(1), 16) for _, t in ins
                 if (m := re.match(r"movabs \$0x([0-9a-f]+),%r", t)) and base <= int(m.group(1), 16) < top})
with open(f"{prefix}.annot", "w") as f:
    for a, t in ins:
        f.write(("%5.2f " % hot[a] if a in hot else "      ") + hex(a) + "  " + t + "\n")
share = lambda lo, hi: sum(v for k, v in hot.items() if lo <= k < hi)
print(f"JIT samples {sum(hot.values()):.1f} %, this mapping {share(base, top):.1f} %")
for i, s in enumerate(starts):
    e = starts[i + 1] if i + 1 < len(starts) else top
    if share(s, e) >= 0.2:
        print(f"  code {hex(s)}..{hex(e)}: {share(s, e):.1f} %")
for a, t in ins:
    m = re.match(r"(j\w+)\s+0x([0-9a-f]+)", t)
    if m and 200 < a - int(m.group(2), 16) < 0x4000 and share(int(m.group(2), 16), a + 1) >= 0.2:
        print(f"  loop {m.group(2)}..{hex(a)[2:]}: {share(int(m.group(2), 16), a + 1):.1f} %")
