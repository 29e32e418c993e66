"""An interactive view of a Renderer in Jupyter (``Renderer.widget()``), rendered on the kernel
side: a drag rotates the orbit camera, the wheel zooms, and a slider
hides the transfer function below a data value — the viewer's threshold. Frames are rendered by
the kernel's GPU (lavapipe where there is none) and sent as images through jupyter_rfb, which
also throttles them to what the connection carries."""

from __future__ import annotations

import math

try:
    import ipywidgets
    from jupyter_rfb import RemoteFrameBuffer
except ImportError as e:  # pragma: no cover - the message is the point
    raise ImportError(
        "Renderer.widget() needs jupyter_rfb and ipywidgets: pip install jupyter_rfb ipywidgets"
    ) from e


class VolumeView(RemoteFrameBuffer):
    """The frame buffer: a Renderer's ``display`` at the orbit camera the pointer moves.

    ``camera`` is (azimuth, elevation, distance), degrees and world units; events arrive as
    jupyter_rfb dicts (``pointer_down``, ``pointer_move``, ``wheel``, ``resize``…)."""

    #: Degrees of rotation per pixel dragged.
    DEGREES_PER_PIXEL = 0.5
    #: Zoom factor per wheel notch (100 units of dy).
    ZOOM_PER_NOTCH = 1.1

    def __init__(self, renderer, camera=None, **kwargs):
        super().__init__(**kwargs)
        self.renderer = renderer
        self.camera = tuple(camera) if camera is not None else renderer.default_camera
        self._last = None
        self.frames = 0
        width, height = renderer.size
        self.css_width, self.css_height = f"{width}px", f"{height}px"
        self.resizable = False

    def handle_event(self, event):
        kind = event.get("type") or event.get("event_type")
        if kind == "pointer_down":
            self._last = (event["x"], event["y"])
        elif kind == "pointer_up":
            self._last = None
        elif kind == "pointer_move" and self._last is not None and event.get("buttons"):
            dx, dy = event["x"] - self._last[0], event["y"] - self._last[1]
            self._last = (event["x"], event["y"])
            self.rotate(dx, dy)
        elif kind == "wheel":
            self.zoom(event.get("dy", 0.0) / 100.0)

    def rotate(self, dx, dy):
        """Turns the orbit by a drag of (dx, dy) pixels: right turns the volume right, down tilts it."""
        azimuth, elevation, distance = self.camera
        azimuth = (azimuth - dx * self.DEGREES_PER_PIXEL) % 360.0
        elevation = max(-89.0, min(89.0, elevation + dy * self.DEGREES_PER_PIXEL))
        self.camera = (azimuth, elevation, distance)
        self.request_draw()

    def zoom(self, notches):
        """Moves the camera out by ZOOM_PER_NOTCH per notch (in for negative notches)."""
        azimuth, elevation, distance = self.camera
        distance = max(0.5, min(50.0, distance * math.pow(self.ZOOM_PER_NOTCH, notches)))
        self.camera = (azimuth, elevation, distance)
        self.request_draw()

    def get_frame(self):
        self.frames += 1
        return self.renderer.render(camera=self.camera)


def volume_widget(renderer, camera=None, threshold=True):
    """The view and, with ``threshold``, a slider over the volume's values that hides the
    transfer function below the value chosen. Returns an ``ipywidgets.VBox`` whose ``.view`` is
    the VolumeView and ``.slider`` the slider (None without one)."""
    view = VolumeView(renderer, camera=camera)
    children = [view]
    slider = None
    if threshold:
        base = renderer.tf
        lo, hi = renderer.value_range
        slider = ipywidgets.FloatSlider(
            value=lo, min=lo, max=hi, step=(hi - lo) / 255.0, description="hide below", continuous_update=True
        )

        def on_change(change):
            renderer.tf = base.hidden_below(change["new"]) if change["new"] > lo else base
            view.request_draw()

        slider.observe(on_change, names="value")
        children.append(slider)
    box = ipywidgets.VBox(children)
    box.view, box.slider = view, slider
    return box
