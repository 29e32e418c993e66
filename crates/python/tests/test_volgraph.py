"""volgraph from Python against the command line (issue 46). Run by tests/pytest.rs from the
README's test command, or by hand: `pip install ./crates/python pytest && pytest crates/python/tests`.
The `volgraph` binary the comparisons run is $VOLGRAPH_BIN (the test runner gives the workspace's)."""

from pathlib import Path

import numpy as np
import pytest
from helpers import cli, ramp_volume, read_png

import volgraph


def test_a_numpy_render_equals_the_cli_render_of_the_same_raw_file(tmp_path):
    a = ramp_volume()
    raw = tmp_path / "ball_24x20x16_uint16.raw"
    a.tofile(raw)  # C order: x fastest, as a .raw file is
    for graph, camera in [("basic/fragment_raycast", (30, 20, 3.2)), ("modern/fastest", (70, -10, 2.8))]:
        png = tmp_path / "cli.png"
        cli("render", graph, "--volume", raw, "--spacing", "0.8,0.8,1.5", "--size", "80x64",
            "--camera", ",".join(map(str, camera)), "-o", png, cwd=tmp_path)
        ours = volgraph.render(graph, a, spacing=(0.8, 0.8, 1.5), size=(80, 64), camera=camera)
        assert ours.shape == (64, 80, 4) and ours.dtype == np.uint8
        theirs = read_png(png)
        assert np.array_equal(ours[..., :3], theirs[..., :3]), f"{graph}: {np.abs(ours.astype(int) - theirs).max()}"
        assert (ours[..., :3] > 10).any(), "the ball shows"


def test_axes_xyz_and_strided_arrays_are_the_same_voxels():
    a = ramp_volume()
    base = volgraph.render("basic/fragment_raycast", a, size=(48, 48))
    nibabel_like = np.ascontiguousarray(a.transpose(2, 1, 0))  # [x, y, z]
    assert np.array_equal(base, volgraph.render("basic/fragment_raycast", nibabel_like, axes="xyz", size=(48, 48)))
    fortran = np.asfortranarray(a)
    assert np.array_equal(base, volgraph.render("basic/fragment_raycast", fortran, size=(48, 48)))
    padded = np.zeros((16, 20, 48), np.uint16)
    padded[:, :, ::2] = a
    assert np.array_equal(base, volgraph.render("basic/fragment_raycast", padded[:, :, ::2], size=(48, 48)))


def test_load_reads_what_the_cli_reads(tmp_path):
    a = ramp_volume()
    raw = tmp_path / "ball_24x20x16_uint16.raw"
    a.tofile(raw)
    v = volgraph.load(raw)
    assert v.dims == (24, 20, 16) and v.spacing == (1.0, 1.0, 1.0)
    assert np.array_equal(v.array, a)
    # NRRD with a header's spacing: the same voxels and spacing, rendered as the CLI renders it.
    nrrd = tmp_path / "ball.nrrd"
    header = ("NRRD0004\ntype: uint16\ndimension: 3\nsizes: 24 20 16\nspacings: 0.5 0.5 2\n"
              "encoding: raw\nendian: little\n\n")
    nrrd.write_bytes(header.encode() + a.astype("<u2").tobytes())
    n = volgraph.load(nrrd)
    assert n.spacing == (0.5, 0.5, 2.0) and np.array_equal(n.array, a)
    png = tmp_path / "nrrd.png"
    cli("render", "basic/fragment_raycast", "--volume", nrrd, "--size", "48x40", "-o", png, cwd=tmp_path)
    assert np.array_equal(volgraph.render("basic/fragment_raycast", n, size=(48, 40))[..., :3], read_png(png)[..., :3])
    # A generated volume by name gets the CLI's default TF (the band that shows its rings).
    png = tmp_path / "ml.png"
    cli("render", "basic/fragment_raycast", "--volume", "ml32", "--size", "40x40", "-o", png, cwd=tmp_path)
    ml = volgraph.load("ml32")
    assert np.array_equal(volgraph.render("basic/fragment_raycast", ml, size=(40, 40))[..., :3], read_png(png)[..., :3])


def test_graph_errors_carry_the_file_line_and_column(tmp_path):
    bad = tmp_path / "bad.ron"
    bad.write_text('Graph(\n    name: "x",\n    passes: [Pass(id: "a", kind: "raycast_typo")],\n    outputs: {},\n)\n')
    with pytest.raises(volgraph.GraphError) as e:
        volgraph.Renderer(bad)
    assert e.value.path == str(bad)
    assert (e.value.line, e.value.column) == (3, 34), str(e.value)  # the kind's string
    assert "raycast_typo" in str(e.value)
    r = volgraph.Renderer("basic/fragment_raycast", size=(32, 32))
    r.volume = ramp_volume()
    r.set("march.step_voxels", 100.0)
    with pytest.raises(volgraph.GraphError, match="step_voxels"):
        r.render()


def test_bad_arrays_and_arguments_are_value_errors_naming_the_problem():
    cases = [
        (np.zeros((2, 3, 4, 5), np.uint8), "3 axes"),
        (np.zeros((4, 4, 4), bool), "dtype bool"),
        (np.zeros((0, 4, 4), np.uint8), "empty"),
        (np.full((4, 4, 4), np.nan, np.float32), "no finite value"),
        ([[1, 2], [3, 4]], "numpy array"),
    ]
    for array, message in cases:
        with pytest.raises(ValueError, match=message):
            volgraph.render("basic/fragment_raycast", array, size=(16, 16))
    with pytest.raises(ValueError, match="camera"):
        volgraph.render("basic/fragment_raycast", ramp_volume(), size=(16, 16), camera=(0, 0, -1))
    with pytest.raises(ValueError, match="patient frame"):
        volgraph.render("basic/fragment_raycast", ramp_volume(), size=(16, 16), camera="anterior")
    with pytest.raises(volgraph.VolumeError, match="No such file"):
        volgraph.load("/nonexistent/volume.nrrd")
    # A control character in a name comes back escaped, never sent to a terminal raw.
    with pytest.raises(volgraph.VolumeError) as e:
        volgraph.load("bad\x1b[31mname.nrrd")
    assert "\x1b" not in str(e.value) and "\\x1b" in str(e.value)
    with pytest.raises(ValueError, match="1 to 16384 pixels"):
        volgraph.render("basic/fragment_raycast", ramp_volume(), size=(0, 16))
    with pytest.raises(ValueError, match="not a graph file"):
        volgraph.plan(Path("/"))


def test_a_renderer_keeps_its_gpu_state_and_renders_floats_and_png():
    r = volgraph.Renderer("modern/fastest", size=(64, 48))
    r.volume = ramp_volume()
    first = r.render(camera=(40, 20, 3.2))
    assert first.shape == (48, 64, 4) and first.dtype == np.uint8
    hdr = r.render(camera=(40, 20, 3.2), output="image")
    assert hdr.dtype == np.float32 and hdr.shape == (48, 64, 4) and hdr[..., 3].max() > 0.1
    r.tf = "graphs/tf/default.ron"
    assert r._repr_png_()[:8] == b"\x89PNG\r\n\x1a\n"
    names = [g["name"] for g in volgraph.graphs()]
    assert "modern/fastest" in names and "clinical/slices" in names
    p = volgraph.plan("clinical/slices", size=(64, 48))
    assert p["viewport"] == (64, 48) and [s["kind"] for s in p["steps"]] == ["reslice"] * 3
    assert p["outputs"] == ["axial", "coronal", "sagittal"] and p["inputs"] == ["volume"]


def test_renderers_in_threads_render_what_they_render_alone():
    from concurrent.futures import ThreadPoolExecutor

    a = ramp_volume()
    cameras = [(40 * k, 20, 3.2) for k in range(4)]
    alone = [volgraph.render("basic/fragment_raycast", a, size=(40, 40), camera=c) for c in cameras]

    def work(camera):
        # A renderer per thread; the GIL is released while each renders.
        r = volgraph.Renderer("basic/fragment_raycast", size=(40, 40))
        r.volume = a
        return [r.render(camera=camera) for _ in range(3)]

    with ThreadPoolExecutor(4) as pool:
        results = list(pool.map(work, cameras))
    for want, frames in zip(alone, results):
        assert all(np.array_equal(want, got) for got in frames)
    # One renderer shared by four threads: calls take turns, each frame is its camera's.
    shared = volgraph.Renderer("basic/fragment_raycast", size=(40, 40))
    shared.volume = a
    with ThreadPoolExecutor(4) as pool:
        frames = list(pool.map(lambda c: shared.render(camera=c), cameras * 3))
    assert all(np.array_equal(alone[i % 4], got) for i, got in enumerate(frames))


def test_a_thousand_renders_do_not_grow_memory():
    def rss_kib():
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
        return 0

    r = volgraph.Renderer("basic/fragment_raycast", size=(32, 32))
    r.volume = ramp_volume()
    for _ in range(100):  # warm: pipelines, pools, allocator
        r.render()
    before = rss_kib()
    for i in range(1000):
        r.render(camera=(i % 360, 20, 3.2))
    grown = rss_kib() - before
    # 1,000 frames of 32×32: a leak of one image per frame would add ≥ 16 MiB.
    assert grown < 8 * 1024, f"RSS grew {grown} KiB over 1,000 renders"
