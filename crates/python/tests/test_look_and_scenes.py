"""Effects, crop and clip, the light, scene files and transfer functions made in Python: each
equals the command line's image of the same flags bit for bit (issue 46)."""

from pathlib import Path

import numpy as np
import pytest
from helpers import cli, ramp_volume, read_png

import volgraph

REPO = Path(__file__).resolve().parents[3]


def test_effects_cuts_and_light_equal_the_cli_flags(tmp_path):
    a = ramp_volume()
    raw = tmp_path / "ball_24x20x16_uint16.raw"
    a.tofile(raw)
    png = tmp_path / "cli.png"
    cli("render", "modern/fastest", "--volume", raw, "--size", "64x56", "--features", "shading,jitter",
        "--crop", "0,0,0.2,1,0.9,1", "--clip", "1,1,0,0.6", "--clip", "0,0,-1,-0.95", "--light", "40,30",
        "-o", png, cwd=tmp_path)
    ours = volgraph.render("modern/fastest", a, size=(64, 56), effects=["shading", "jitter"],
                           crop=(0, 0, 0.2, 1, 0.9, 1), clip=[(1, 1, 0, 0.6), (0, 0, -1, -0.95)], light=(40, 30))
    assert np.array_equal(ours[..., :3], read_png(png)[..., :3])
    plain = volgraph.render("modern/fastest", a, size=(64, 56))
    assert not np.array_equal(ours, plain), "the effects, cuts and light change the image"
    # The same through a kept renderer, one setting at a time: cuts moved, then turned off.
    r = volgraph.Renderer("modern/fastest", size=(64, 56))
    r.volume = a
    r.effects = "shading,jitter"
    r.light = "40,30"
    r.set_cuts(crop=(0, 0, 0.2, 1, 0.9, 1), clip=[(1, 1, 0, 0.6), (0, 0, -1, -0.95)])
    assert np.array_equal(r.render(), ours)
    r.set_cuts()
    r.effects = None
    r.light = "headlight"
    assert np.array_equal(r.render(), plain)


def test_several_lights_equal_the_repeated_flag(tmp_path):
    a = ramp_volume()
    raw = tmp_path / "ball_24x20x16_uint16.raw"
    a.tofile(raw)
    png = tmp_path / "cli.png"
    cli("render", "modern/fastest", "--volume", raw, "--size", "48x40", "--features", "shading,shadows",
        "--light", "40,30", "--light", "point:0,1.5,1", "-o", png, cwd=tmp_path)
    ours = volgraph.render("modern/fastest", a, size=(48, 40), effects=["shading", "shadows"],
                           light=[(40, 30), ("point", 0, 1.5, 1)])
    assert np.array_equal(ours[..., :3], read_png(png)[..., :3])
    key_only = volgraph.render("modern/fastest", a, size=(48, 40), effects=["shading", "shadows"], light=(40, 30))
    assert not np.array_equal(ours, key_only), "the second light changes the image"
    with pytest.raises(ValueError, match="4 lights"):
        volgraph.render("modern/fastest", a, size=(16, 16), light=["headlight"] * 4)


def test_bad_effects_cuts_and_lights_are_value_errors():
    a = ramp_volume()
    with pytest.raises(ValueError, match="shadding"):  # the typo named, with the graph's effects
        volgraph.render("modern/fastest", a, size=(16, 16), effects=["shadding"])
    with pytest.raises(ValueError, match="crop"):
        volgraph.render("modern/fastest", a, size=(16, 16), crop=(0.5, 0, 0, 0.2, 1, 1))
    with pytest.raises(ValueError, match="crop"):
        volgraph.render("modern/fastest", a, size=(16, 16), crop=(0, 0, 0))
    with pytest.raises(ValueError, match="clip"):
        volgraph.render("modern/fastest", a, size=(16, 16), clip=[(0, 0, 0, 0.5)])
    with pytest.raises(ValueError, match="clip"):
        volgraph.render("modern/fastest", a, size=(16, 16), clip=[(1, 0, 0, 0.5)] * 7)
    with pytest.raises(ValueError, match="light"):
        volgraph.render("modern/fastest", a, size=(16, 16), light=(10, 120))
    with pytest.raises(ValueError, match="light"):
        volgraph.render("modern/fastest", a, size=(16, 16), light=[1, 2, 3, 4, 5])


def test_a_scene_renders_as_the_cli_renders_it(tmp_path):
    scene = REPO / "scenes" / "engine_cut_open.ron"
    png = tmp_path / "cli.png"
    cli("render", "--scene", scene, "--size", "64x64", "-o", png, cwd=tmp_path)
    ours = volgraph.render(scene=scene, size=(64, 64))
    assert np.array_equal(ours[..., :3], read_png(png)[..., :3])
    # A renderer of the scene: its camera by default; another graph keeps the scene's look.
    r = volgraph.Renderer(scene=scene, size=(64, 64))
    assert r.default_camera == (35.0, 25.0, 3.0)
    assert np.array_equal(r.render(), ours)
    # The scene's volume and TF give way to the caller's.
    r.volume = ramp_volume()
    assert not np.array_equal(r.render(), ours)
    with pytest.raises(ValueError, match="no graph|scene="):
        volgraph.Renderer()


def test_a_transfer_function_made_in_python_equals_its_file(tmp_path):
    a = ramp_volume()
    tf = volgraph.TransferFunction.from_points(
        [(0, (0, 0, 0), 0), (20000, (0.9, 0.3, 0.1), 0.0), (40000, (1, 0.9, 0.5), 0.4), (65535, (1, 1, 1), 0.9)]
    )
    assert tf.domain == (0, 65535) and len(tf.points) == 4 and tf(40000) == (1, 0.9, 0.5, 0.4)
    (tmp_path / "tf.ron").write_text(tf.to_ron())
    raw = tmp_path / "ball_24x20x16_uint16.raw"
    a.tofile(raw)
    png = tmp_path / "cli.png"
    cli("render", "basic/fragment_raycast", "--volume", raw, "--tf", "tf.ron", "--size", "48x48", "-o", png,
        cwd=tmp_path)
    ours = volgraph.render("basic/fragment_raycast", a, tf=tf, size=(48, 48))
    assert np.array_equal(ours[..., :3], read_png(png)[..., :3])
    assert volgraph.TransferFunction.load(tmp_path / "tf.ron") == tf
    # The renderer's TF is the one it classifies with: the fitted one until another is set.
    r = volgraph.Renderer("basic/fragment_raycast", size=(48, 48))
    r.volume = a
    fitted = r.tf
    assert fitted.domain[1] > fitted.domain[0]
    r.tf = tf
    assert r.tf == tf and np.array_equal(r.render(), ours)
    hidden = tf.hidden_below(41000)
    assert hidden(40000)[3] == 0 and hidden(50000)[3] > 0
    with pytest.raises(ValueError, match=r"points\[1\]\.color\.r = 2 is outside \[0, 1\]"):
        volgraph.TransferFunction.from_points([(0, (0, 0, 0), 0), (10, (2, 0, 0), 0.5)])
    with pytest.raises(ValueError, match=r"points\[1\]: \(value, \(r, g, b\), alpha\)"):
        volgraph.TransferFunction.from_points([(0, (0, 0, 0), 0), "red"])
    with pytest.raises(ValueError):
        volgraph.TransferFunction.from_points([])
    with pytest.raises(ValueError, match=r"points\[0\]\.value = NaN"):
        volgraph.TransferFunction.from_points([(float("nan"), (1, 1, 1), 0.5)])


def test_the_reference_converges_and_the_gpu_follows_it():
    """Accuracy against time from a script: the error of the `image` output against the converged
    f64 reference falls as the step shrinks."""
    r = volgraph.Renderer("modern/fastest", size=(48, 40))
    r.volume = ramp_volume()
    camera = (30, 20, 3.2)
    reference = r.reference(camera=camera, step_voxels=0.1)
    assert reference.shape == (40, 48, 4) and reference.dtype == np.float64 and reference[..., 3].max() > 0.1
    errors = []
    for step in [2.0, 0.5, 0.125]:
        r.set("march.step_voxels", step)
        image = r.render(camera=camera, output="image")
        errors.append(np.abs(image.astype(np.float64) - reference).max())
    assert errors[0] > errors[1] > errors[2], errors
    # At an eighth of a voxel the GPU's float32 march on a 16-bit texture stays within 2/255 of
    # the f64 integral: the remaining step error (0.125 vs 0.1) plus the texture's 16-bit
    # quantization and float32 accumulation, each well under 1/255 on this smooth ball.
    assert errors[2] < 2 / 255, errors
    with pytest.raises(ValueError, match="step_voxels"):
        r.reference(step_voxels=0)
    slices = volgraph.Renderer("clinical/slices", size=(32, 32))
    slices.volume = ramp_volume()
    with pytest.raises(ValueError, match="no raycast step"):
        slices.reference()


def test_several_volumes_bind_by_name_as_the_cli_binds_them(tmp_path):
    ct = ramp_volume()
    z, y, x = np.mgrid[0:16, 0:20, 0:24]
    pet = (np.exp(-((x - 15) ** 2 + (y - 8) ** 2 + (z - 9) ** 2) / 18.0) * 1000).astype(np.float32)
    ct.tofile(tmp_path / "ct_24x20x16_uint16.raw")
    pet.tofile(tmp_path / "pet_24x20x16_float32.raw")
    png = tmp_path / "cli.png"
    cli("render", "multi/pet_ct", "--volume", "volume=ct_24x20x16_uint16.raw", "--volume",
        "pet=pet_24x20x16_float32.raw", "--spacing", "0.8,0.8,1.5", "--size", "56x48", "-o", png, cwd=tmp_path)
    ours = volgraph.render("multi/pet_ct", ct, spacing=(0.8, 0.8, 1.5), volumes={"pet": (pet, (0.8, 0.8, 1.5))},
                           size=(56, 48))
    assert np.array_equal(ours[..., :3], read_png(png)[..., :3])
    alone = volgraph.render("multi/pet_ct", ct, spacing=(0.8, 0.8, 1.5), size=(56, 48))
    assert not np.array_equal(ours, alone), "the PET shows"
    r = volgraph.Renderer("multi/pet_ct", size=(56, 48))
    r.set_volume(ct, spacing=(0.8, 0.8, 1.5))
    r.render()
    assert any("pet" in note for note in r.notes), "one volume for two inputs is said"
    r.set_volume(pet, spacing=(0.8, 0.8, 1.5), name="pet")
    assert np.array_equal(r.render(), ours) and not any("pet" in n for n in r.notes)
    with pytest.raises(ValueError, match="petscan"):
        volgraph.render("multi/pet_ct", ct, volumes={"petscan": pet}, size=(16, 16))


def test_four_channels_bind_by_name_as_the_cli_binds_them(tmp_path):
    """Four volumes in one march (multi/channels4), from arrays and from files, alike."""
    z, y, x = np.mgrid[0:16, 0:20, 0:24]
    first = ramp_volume()
    blobs = [(np.exp(-((x - cx) ** 2 + (y - cy) ** 2 + (z - cz) ** 2) / 12.0) * 1000).astype(np.float32)
             for cx, cy, cz in [(6, 6, 5), (17, 12, 8), (12, 15, 11)]]
    first.tofile(tmp_path / "c1_24x20x16_uint16.raw")
    for k, blob in enumerate(blobs):
        blob.tofile(tmp_path / f"c{k + 2}_24x20x16_float32.raw")
    png = tmp_path / "cli.png"
    cli("render", "multi/channels4", "--volume", "volume=c1_24x20x16_uint16.raw",
        "--volume", "channel2=c2_24x20x16_float32.raw", "--volume", "channel3=c3_24x20x16_float32.raw",
        "--volume", "channel4=c4_24x20x16_float32.raw", "--size", "56x48", "-o", png, cwd=tmp_path)
    named = {f"channel{k + 2}": blob for k, blob in enumerate(blobs)}
    ours = volgraph.render("multi/channels4", first, volumes=named, size=(56, 48))
    assert np.array_equal(ours[..., :3], read_png(png)[..., :3])
    three = dict(named)
    three["channel4"] = np.zeros_like(blobs[2])
    assert not np.array_equal(ours, volgraph.render("multi/channels4", first, volumes=three, size=(56, 48))), \
        "the fourth channel shows"
