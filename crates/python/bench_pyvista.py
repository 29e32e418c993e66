"""Issue 46's comparison: volgraph.render vs PyVista's plot(volume=True) off screen on the same 256³ array, same size and
a similar TF (linear opacity ramp), one machine, medians of 5 after a warm-up.
Needs `pip install pyvista`; run off screen with a display (`xvfb-run -a python crates/python/bench_pyvista.py`);
it prints which VTK mapper ran (SmartVolumeMapper picks its OpenGL ray caster where GL works, Mesa
llvmpipe here)."""
import statistics, time, os
import numpy as np
import volgraph
import pyvista as pv

pv.OFF_SCREEN = True
a = volgraph.load("engine_vollib").array  # [z, y, x] uint8, 256³
size = (512, 512)

def timed(f, n=5):
    f()
    ts = []
    for _ in range(n):
        t = time.perf_counter(); f(); ts.append((time.perf_counter() - t) * 1e3)
    return statistics.median(ts)

vg = timed(lambda: volgraph.render("modern/fastest", a, size=size, camera=(30, 20, 3.2)))
r = volgraph.Renderer("modern/fastest", size=size); r.volume = a
vg_kept = timed(lambda: r.render(camera=(30, 20, 3.2)))

grid = pv.wrap(np.ascontiguousarray(a.transpose(2, 1, 0)))  # pyvista indexes [x, y, z]
def pyvista_once():
    p = pv.Plotter(off_screen=True, window_size=size)
    p.add_volume(grid, cmap="bone", opacity="linear")
    img = p.screenshot(return_img=True)
    p.close()
    return img
pv_ms = timed(pyvista_once)
p = pv.Plotter(off_screen=True, window_size=size)
vol = p.add_volume(grid, cmap="bone", opacity="linear")
p.show(auto_close=False)
def pyvista_frame():
    p.camera.azimuth += 1
    p.render()
    return p.screenshot(return_img=True)
pv_kept = timed(pyvista_frame)
mapper = type(vol.mapper).__name__
info = p.render_window.ReportCapabilities().splitlines()[:3] if hasattr(p.render_window, "ReportCapabilities") else []
print(f"volgraph.render (new renderer each call): {vg:.1f} ms; Renderer.render (GPU state kept): {vg_kept:.1f} ms")
print(f"pyvista plot(volume=True) off screen (new plotter each call): {pv_ms:.1f} ms; frame of a kept plotter: {pv_kept:.1f} ms")
print(f"pyvista mapper: {mapper}; {' | '.join(info)}")
