"""OME-Zarr against ome-zarr-py, the library users' stores come from (issue 48): a store that
`volgraph convert` wrote reads in ome-zarr-py with the same levels, scales and voxels, and a store
ome-zarr-py wrote renders in volgraph like the array it was written from; its channels are its
volumes, bound one per input."""

import numpy as np
import pytest
from helpers import ball_nifti, cli, ramp_volume, read_png

import volgraph

# ome-zarr-py 0.18's own writer builds a deprecated Scaler by default: its warning, not ours.
pytestmark = pytest.mark.filterwarnings("ignore:Call to deprecated class Scaler:DeprecationWarning")


def test_a_converted_store_reads_in_ome_zarr_py(tmp_path):
    from ome_zarr.io import parse_url
    from ome_zarr.reader import Reader

    a = ramp_volume()  # [z, y, x] uint16, 24×20×16
    raw = tmp_path / "ball_24x20x16_uint16.raw"
    a.tofile(raw)
    out = tmp_path / "ball.ome.zarr"
    cli("convert", raw, out, "--chunk", "8", "--spacing", "0.8,0.8,1.5", cwd=tmp_path)
    node = list(Reader(parse_url(str(out)))())[0]
    levels = [np.asarray(level) for level in node.data]
    assert [level.shape for level in levels] == [(16, 20, 24)]  # 24 ≤ 64: one level
    assert np.array_equal(levels[0], a)
    axes = node.metadata["axes"]
    assert [x["name"] for x in axes] == ["z", "y", "x"]
    scale = node.metadata["coordinateTransformations"][0][0]["scale"]
    assert scale == [1.5, 0.8, 0.8]


def test_a_store_from_ome_zarr_py_renders_like_its_array(tmp_path):
    import zarr
    from ome_zarr.io import parse_url
    from ome_zarr.writer import write_image

    a = ramp_volume()
    path = tmp_path / "from_py.ome.zarr"
    root = zarr.group(store=parse_url(str(path), mode="w").store)
    write_image(a, root, axes="zyx", scale={"z": 1.5, "y": 0.8, "x": 0.8})  # levels halving y and x
    v = volgraph.load(path)
    assert v.dims == (24, 20, 16) and v.spacing == (0.8, 0.8, 1.5)
    assert np.array_equal(v.array, a)
    assert np.array_equal(volgraph.render("basic/fragment_raycast", v, size=(48, 40)),
                          volgraph.render("basic/fragment_raycast", a, spacing=(0.8, 0.8, 1.5), size=(48, 40)))


def test_a_store_from_ome_zarr_py_streams_like_its_array(tmp_path):
    """A third-party store (ome-zarr-py's levels: halving y and x only, dims rounded down, no chunk
    ranges) streamed brick by brick renders, fully loaded at level 0, as its array does (held in
    memory as a pyramid): within 1/255, bricks of 8 so the rays cross many."""
    import zarr
    from ome_zarr.io import parse_url
    from ome_zarr.writer import write_image

    a = ramp_volume()
    path = tmp_path / "from_py.ome.zarr"
    root = zarr.group(store=parse_url(str(path), mode="w").store)
    write_image(a, root, axes="zyx", scale={"z": 1.5, "y": 0.8, "x": 0.8})
    images = []
    for volume in (path, a):
        r = volgraph.Renderer("streaming/ray_guided", size=(48, 40))
        r.set("input.brick_cells", 8)
        r.set("march.lod", 0.5)
        if volume is path:
            r.stream(path)
        else:
            r.set_volume(a, spacing=(0.8, 0.8, 1.5))
        images.append(r.render(camera=(30, 20, 2.4), output="image"))
        assert images[-1][..., 3].max() > 0.1
    assert np.abs(images[0] - images[1]).max() <= 1.5 / 255


def test_an_ngff_0_4_store_on_zarr_v2_reads(tmp_path):
    import zarr
    from ome_zarr.format import FormatV04
    from ome_zarr.io import parse_url
    from ome_zarr.writer import write_image

    a = ramp_volume()
    path = tmp_path / "v04.ome.zarr"
    root = zarr.group(store=parse_url(str(path), mode="w", fmt=FormatV04()).store, zarr_format=2)
    write_image(a, root, axes="zyx", fmt=FormatV04(), scale={"z": 2.0, "y": 0.5, "x": 0.5})
    assert (path / ".zattrs").is_file() and not (path / "zarr.json").exists()
    v = volgraph.load(path)
    assert v.spacing == (0.5, 0.5, 2.0) and np.array_equal(v.array, a)
    assert "uint16" in repr(v.array.dtype) and "U16" in repr(v)
    info = cli("info", path, cwd=tmp_path).stdout
    assert "OME-Zarr (NGFF 0.4)" in info and "5 levels" in info


def test_a_nifti_converted_renders_like_the_nifti(tmp_path):
    nifti = tmp_path / "ball.nii.gz"
    ball_nifti(nifti)
    out = tmp_path / "ball.ome.zarr"
    cli("convert", nifti, out, "--chunk", "8", cwd=tmp_path)
    store, original = volgraph.load(out), volgraph.load(nifti)
    assert np.array_equal(store.array, original.array) and store.spacing == original.spacing
    assert store.meta["frame"] == original.meta["frame"] and store.meta["origin"] == original.meta["origin"]
    # The patient frame kept: the default camera is the anterior view of both.
    assert np.array_equal(volgraph.render("basic/fragment_raycast", store, size=(48, 40)),
                          volgraph.render("basic/fragment_raycast", original, size=(48, 40)))


def test_the_channels_of_a_store_are_its_volumes(tmp_path):
    import zarr
    from ome_zarr.io import parse_url
    from ome_zarr.writer import write_image

    a = ramp_volume()
    b = np.ascontiguousarray((a // 2)[::-1])
    path = tmp_path / "two.ome.zarr"
    root = zarr.group(store=parse_url(str(path), mode="w").store)
    write_image(np.stack([a, b]), root, axes="czyx", scale={"c": 1.0, "z": 1.5, "y": 0.8, "x": 0.8})
    assert np.array_equal(volgraph.load(path).array, a)
    assert np.array_equal(volgraph.load(path, frame=1).array, b)
    with pytest.raises(volgraph.VolumeError, match="holds 2"):
        volgraph.load(path, frame=2)
    # Bound one channel per input, as a 4D NIfTI's volumes are (`#N`).
    png = tmp_path / "cli.png"
    cli("render", "multi/pet_ct", "--volume", f"volume={path}#0", "--volume", f"pet={path}#1", "--size", "48x40",
        "-o", png, cwd=tmp_path)
    ours = volgraph.render("multi/pet_ct", volgraph.load(path), volumes={"pet": volgraph.load(path, frame=1)},
                           size=(48, 40))
    assert np.array_equal(ours[..., :3], read_png(png)[..., :3])


def test_a_store_streams_brick_by_brick_as_the_cli_streams_it(tmp_path):
    """Issue 48: `Renderer.stream` (and a store path given as the volume of a streaming graph)
    reads the store brick by brick as `volgraph render streaming/ray_guided` does: the same image
    within 1/255 in linear colour (bricks land in whichever atlas slot is free, and lavapipe's
    fixed-point filter weights follow the atlas position; 2 levels of the sRGB PNG); a graph that
    reads its volume whole says to load the store instead."""
    store = tmp_path / "v.ome.zarr"
    cli("convert", "vessels128", store, "--chunk", "32", cwd=tmp_path)
    png = tmp_path / "cli.png"
    cli("render", "streaming/ray_guided", "--volume", store, "--size", "64x64", "--camera", "30,20,1.8",
        "-o", png, cwd=tmp_path)
    r = volgraph.Renderer("streaming/ray_guided", size=(64, 64))
    r.stream(store)
    assert any("streamed brick by brick from 2 levels" in n for n in r.notes)
    streamed = r.render(camera=(30, 20, 1.8), output="image")
    by_path = volgraph.Renderer("streaming/ray_guided", size=(64, 64))
    by_path.volume = str(store)
    assert np.abs(streamed - by_path.render(camera=(30, 20, 1.8), output="image")).max() <= 1.5 / 255
    display = r.render(camera=(30, 20, 1.8)).astype(int)
    assert np.abs(display - read_png(png).astype(int)).max() <= 2
    # No time to refine: the coarse first frame.
    r2 = volgraph.Renderer("streaming/ray_guided", size=(64, 64))
    r2.stream(store)
    r2.time_budget_ms = 0
    assert np.abs(r2.render(camera=(30, 20, 1.8), output="image") - streamed).max() > 8 / 255
    with pytest.raises(ValueError, match="streamed brick by brick by streaming/ray_guided"):
        volgraph.Renderer("modern/fastest", size=(32, 32)).stream(store)
    for bad in (float("nan"), -1, 1e39):
        with pytest.raises(ValueError, match="time_budget_ms"):
            r2.time_budget_ms = bad
    with pytest.raises(ValueError, match="not an OME-Zarr store"):
        r2.stream(tmp_path)
    with pytest.raises(ValueError, match="memory_mb 0"):
        r2.stream(store, memory_mb=0)


def test_a_raw_file_over_memory_mb_streams_from_the_file(tmp_path):
    """Issue 48 item 4 from Python: `Renderer.stream` of a raw file larger than memory_mb
    streams it from the file (no store), and the image equals the file read in core: within
    1.5/255 linear, the bound of the store test above — a brick lands in whichever atlas slot is
    free when its read finishes, and lavapipe's fixed-point filter weights follow the atlas
    position (0 measured in three runs here; a brick of the wrong level or place is far over)."""
    z, y, x = np.mgrid[0:256, 0:256, 0:288].astype(np.float32)
    shell = np.abs(np.sqrt((x - 140) ** 2 + (y - 128) ** 2 + (z - 120) ** 2) - 80)
    voxels = (255 * np.clip(1 - shell / 6, 0, None)).astype(np.uint8)
    path = tmp_path / "shell_288x256x256_uint8.raw"
    voxels.tofile(path)  # 18 MiB: over memory_mb=16
    streamed = volgraph.Renderer("streaming/ray_guided", size=(64, 64))
    streamed.stream(path, memory_mb=16)
    assert any("streamed brick by brick from the file" in n for n in streamed.notes), streamed.notes
    in_core = volgraph.Renderer("streaming/ray_guided", size=(64, 64))
    in_core.stream(path, memory_mb=64)
    assert any("fits in memory_mb: read in core" in n for n in in_core.notes), in_core.notes
    a = streamed.render(camera=(30, 20, 2.5), output="image")
    b = in_core.render(camera=(30, 20, 2.5), output="image")
    assert a[..., 3].max() > 0.5, "the shell is drawn"
    assert np.abs(a - b).max() <= 1.5 / 255
