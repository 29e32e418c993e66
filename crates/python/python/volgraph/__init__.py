"""volgraph from Python: numpy in, images out.

GPU volume rendering assembled from a declarative render graph (https://github.com/ — see the
repository's README). The same graphs, transfer functions, cameras and checks as the
``volgraph`` command line, so an image here equals ``volgraph render``'s of the same voxels.

    import volgraph, numpy as np
    v = volgraph.load("ct_series/")               # a file, a DICOM folder or a dataset's name
    img = volgraph.render("modern/fastest", v, tf="ct-bone", size=(512, 512))   # (H, W, 4) uint8
    a = np.fromfile("vol_64x64x64_uint8.raw", np.uint8).reshape(64, 64, 64)      # [z, y, x]
    img = volgraph.render("basic/fragment_raycast", a, spacing=(1, 1, 1), camera=(30, 20, 3.2))
    r = volgraph.Renderer("kruger_westermann_2003/rc_b", size=(512, 512))       # GPU state kept
    r.volume = v; r.tf = "ct-bone"; r.set("march.step_voxels", 0.25)
    r.effects = ["shading"]; r.set_cuts(crop=(0, 0, 0, 1, 1, 0.5)); r.light = (30, 45)
    frame = r.render(camera=(40, 20, 3.2)); hdr = r.render(output="image")    # float32 linear
    ref = r.reference(camera=(40, 20, 3.2))       # the converged f64 image: hdr's error is |hdr - ref|
    r.tf = volgraph.TransferFunction.from_points([(0, (1, 1, 1), 0), (255, (1, 0.8, 0.6), 0.5)])
    r.widget()                                     # in Jupyter: drag rotates, wheel zooms (jupyter_rfb)

Arrays are indexed [z, y, x] (napari, scikit-image, SimpleITK, OME-Zarr; a C-order array has x
varying fastest, like a .raw file); pass ``axes="xyz"`` for nibabel's [x, y, z]. ``spacing`` is
(x, y, z) like the CLI's ``--spacing``. uint8, uint16, int16 and float32 are taken in any order
and strides; the voxels are copied once, into the volume the GPU upload reads (``Volume.array``
of a loaded volume is a read-only view of the loader's buffer: no copy).
"""

from . import _volgraph
from ._volgraph import (
    GpuError,
    GraphError,
    TransferFunction,
    Volume,
    VolumeError,
    graphs,
    load,
    plan,
    render,
)


class Renderer(_volgraph.Renderer):
    __doc__ = _volgraph.Renderer.__doc__

    def widget(self, camera=None, threshold=True):
        """An interactive view in Jupyter, rendered on the kernel side (jupyter_rfb): drag
        rotates, the wheel zooms, and with ``threshold`` a slider hides the transfer function
        below a data value. ``camera``: where it starts (default: ``self.default_camera``)."""
        from .widget import volume_widget

        return volume_widget(self, camera=camera, threshold=threshold)


__all__ = [
    "GpuError",
    "GraphError",
    "Renderer",
    "TransferFunction",
    "Volume",
    "VolumeError",
    "graphs",
    "load",
    "plan",
    "render",
]
