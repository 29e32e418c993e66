"""Notebooks (issue 46): a Renderer shows as its image, `Renderer.widget()` rotates, zooms and
thresholds as a user's pointer, wheel and slider drive it (the events jupyter_rfb sends), and the
example notebook runs top to bottom with images for outputs."""

import base64
from pathlib import Path

import numpy as np
from helpers import ramp_volume

import volgraph

REPO = Path(__file__).resolve().parents[3]


def test_the_widget_rotates_zooms_and_thresholds_as_its_events_say():
    r = volgraph.Renderer("modern/fastest", size=(48, 40))
    r.volume = ramp_volume()
    box = r.widget(camera=(30, 20, 3.2))
    view, slider = box.view, box.slider
    first = view.get_frame()
    assert first.shape == (40, 48, 4) and np.array_equal(first, r.render(camera=(30, 20, 3.2)))
    # A drag 20 px right and 10 px down: the orbit turns by 10° and tilts by 5°.
    view.handle_event({"type": "pointer_down", "x": 10, "y": 10, "button": 1, "buttons": [1], "modifiers": []})
    view.handle_event({"type": "pointer_move", "x": 30, "y": 20, "button": 0, "buttons": [1], "modifiers": []})
    view.handle_event({"type": "pointer_up", "x": 30, "y": 20, "button": 1, "buttons": [], "modifiers": []})
    assert view.camera == (20.0, 25.0, 3.2)
    turned = view.get_frame()
    assert np.array_equal(turned, r.render(camera=(20.0, 25.0, 3.2))) and not np.array_equal(turned, first)
    # A move with no button down does nothing; a wheel notch away zooms out by 10 %.
    view.handle_event({"type": "pointer_move", "x": 90, "y": 90, "button": 0, "buttons": [], "modifiers": []})
    view.handle_event({"type": "wheel", "x": 5, "y": 5, "dx": 0, "dy": 100, "buttons": [], "modifiers": []})
    assert view.camera[:2] == (20.0, 25.0) and abs(view.camera[2] - 3.52) < 1e-9
    # The slider hides the transfer function below its value: the ball's rim goes (less opacity
    # in the linear `image`; `display` is composited over the background, opaque).
    zoomed = view.get_frame()
    opacity = r.render(camera=view.camera, output="image")[..., 3].sum()
    lo, hi = r.value_range
    slider.value = lo + 0.6 * (hi - lo)
    thresholded = view.get_frame()
    assert not np.array_equal(thresholded, zoomed)
    assert r.render(camera=view.camera, output="image")[..., 3].sum() < 0.9 * opacity
    slider.value = lo
    assert np.array_equal(view.get_frame(), zoomed)
    assert r._repr_png_()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_example_notebook_runs_and_shows_images(tmp_path):
    import nbclient
    import nbformat

    notebook = nbformat.read(REPO / "examples" / "notebooks" / "tour.ipynb", as_version=4)
    nbclient.NotebookClient(notebook, timeout=900, kernel_name="python3",
                            resources={"metadata": {"path": str(tmp_path)}}).execute()
    outputs = [o for cell in notebook.cells if cell.cell_type == "code" for o in cell.get("outputs", [])]
    assert not [o for o in outputs if o.output_type == "error"]
    pngs = [base64.b64decode(o.data["image/png"]) for o in outputs if "image/png" in o.get("data", {})]
    assert len(pngs) >= 2, "the papers side by side and the accuracy plot"
    assert all(p[:8] == b"\x89PNG\r\n\x1a\n" and len(p) > 5000 for p in pngs)
    widgets = [o for o in outputs if "application/vnd.jupyter.widget-view+json" in o.get("data", {})]
    assert widgets, "the interactive view"
    (tmp_path / "papers.png").write_bytes(pngs[0])
