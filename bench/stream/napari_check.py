"""napari reads what `volgraph convert` writes (issue 48 item 2's cross-check, run by hand).

    volgraph convert vessels128 v.ome.zarr --chunk 32
    python -m venv nap && nap/bin/pip install "napari[pyqt5]" napari-ome-zarr
    DISPLAY=:77 QT_QPA_PLATFORM=xcb nap/bin/python napari_check.py v.ome.zarr napari3d.png

Run 2026-12-07 under Xvfb with napari 0.9.2 and napari-ome-zarr: the NGFF 0.5 store opens as
one multiscale layer of both levels (128³ and 64³, uint8, the values volgraph wrote), and the 3D
view (MIP; napari draws 3D from its lowest resolution, napari issue 513) shows the vessel tree:
`napari3d.png` beside this file.
"""

import os
import sys

os.environ.setdefault("QT_QPA_PLATFORM", "xcb")

import imageio.v3 as iio
import napari
import numpy as np
from qtpy.QtWidgets import QApplication

store, out = sys.argv[1], sys.argv[2]
viewer = napari.Viewer(show=True)
layers = viewer.open(store, plugin="napari-ome-zarr")
layer = layers[0]
levels = [tuple(d.shape) for d in layer.data]
level0 = np.asarray(layer.data[0])
print(f"napari {napari.__version__}: {len(layers)} layer(s), multiscale {layer.multiscale}, levels {levels}")
print(f"level 0: {level0.dtype}, max {level0.max()}, mean {level0.mean():.2f}")
viewer.dims.ndisplay = 3
for _ in range(20):
    QApplication.processEvents()
viewer.reset_view()
for _ in range(20):
    QApplication.processEvents()
image = viewer.screenshot(canvas_only=True, flash=False)
iio.imwrite(out, image)
lit = int((image[..., :3] > 40).any(axis=-1).sum())
print(f"3D screenshot {image.shape[1]}x{image.shape[0]}: {lit} lit pixels (data level {layer.data_level})")
assert layer.multiscale and levels[0] == level0.shape and lit > 0
