"""The Python layer's cost (issue 46): `Renderer.render` (render, wait, read back, the numpy
array) against the same frame through the Rust library API (`volgraph bench api`), one machine,
one run. Usage: python crates/python/bench_overhead.py [VOLUME] [SIZE]  (needs `volgraph` on PATH
or $VOLGRAPH_BIN)."""

import os
import statistics
import subprocess
import sys
import time

import volgraph

volume = sys.argv[1] if len(sys.argv) > 1 else "engine_vollib"
size = sys.argv[2] if len(sys.argv) > 2 else "512x512"
w, h = map(int, size.split("x"))
frames = 20

r = volgraph.Renderer("modern/fastest", size=(w, h))
r.volume = volgraph.load(volume)
binary = os.environ.get("VOLGRAPH_BIN", "volgraph")


def python_round():
    times, layer = [], []
    for i in range(frames + 1):
        t0 = time.perf_counter()
        r.render(camera=(30, 20, 3.2))
        wall = (time.perf_counter() - t0) * 1e3
        if i:
            times.append(wall)
            # The same frame's own split: wall clock minus the library's time inside it.
            layer.append(wall - r.last_frame_ms)
    python_round.layer.extend(layer)
    return statistics.median(times)


python_round.layer = []


def rust_round():
    out = subprocess.run([binary, "bench", "api", "--volume", volume, "--size", size, "--frames", str(frames)],
                         capture_output=True, text=True, check=True).stdout
    return float(out.split("read back: ")[1].split(" ms")[0])


# Three alternating rounds (the machine's load drifts; one round each would compare two moments).
rounds = [(python_round(), rust_round()) for _ in range(3)]
for k, (p, q) in enumerate(rounds):
    print(f"round {k + 1}: python {p:.2f} ms, rust {q:.2f} ms, ratio {p / q:.3f}")
python_ms = statistics.median(p for p, _ in rounds)
rust_ms = statistics.median(q for _, q in rounds)
print(f"modern/fastest on {volume} at {size}, render + wait + read back, medians of {frames} frames, 3 rounds:")
print(f"python Renderer.render {python_ms:.2f} ms, rust api::Renderer::render {rust_ms:.2f} ms, "
      f"python / rust {python_ms / rust_ms:.3f}")
# Two processes' medians differ by the machine's drift; the per-frame split does not: what the
# Python layer adds (argument conversion, the lock, the GIL's release and return, the numpy array)
# measured around the very frame the library timed.
layer_ms = statistics.median(python_round.layer)
print(f"the Python layer within each frame (wall - library, median of {len(python_round.layer)} frames): "
      f"{layer_ms:.3f} ms = {100 * layer_ms / python_ms:.2f} % of the frame")
