#!/usr/bin/env python3
"""The peer of `volgraph bench graphs --preset peer`: VTK's CPU raycaster
(vtkFixedPointVolumeRayCastMapper) on the same volumes, transfer functions, viewport, step and
views, timed the same way (median wall ms per frame after one warm-up frame).

    python3 bench/peer/vtk_cpu_raycast.py --data ../shared/data \
        --cases engine_vollib:engine_opaque,hydrogen_atom:hydrogen --size 512x512 --frames 12 --step 0.5

Prints one JSON object on stdout: {"vtk": version, "mapper": ..., "rows": [{dataset, tf, dims,
viewport, frames_ms, median_ms}]}. Settings as the issue's measurement: offscreen render
window, the renderer's reset camera (the volume framed as `--camera AZ,0,3.2` frames it in
volgraph), the camera turned 360/frames degrees about the view-up axis per frame, sample
distance `--step` voxels (spacing 1), no automatic sample-distance adjustment, one image sample
per pixel, opacity per unit distance of one voxel (the TFs' convention), the mapper's own early
ray termination. Needs `pip install vtk==9.7.2` (and numpy, which it brings).
"""

import argparse
import json
import re
import statistics
import sys
import time
from pathlib import Path


def parse_tf(path):
    """(value, (r, g, b), alpha) points of a volgraph RON transfer function."""
    text = path.read_text(encoding="utf-8-sig")
    points = []
    pattern = r"value:\s*([-\d.eE+]+)\s*,\s*color:\s*\(\s*([-\d.eE+]+)\s*,\s*([-\d.eE+]+)\s*,\s*([-\d.eE+]+)\s*\)\s*,\s*alpha:\s*([-\d.eE+]+)"
    for m in re.finditer(pattern, text):
        v, r, g, b, a = (float(x) for x in m.groups())
        points.append((v, (r, g, b), a))
    if not points:
        raise SystemExit(f"{path}: no control points found")
    return points


def find_volume(data, name):
    matches = sorted((data / "volumes").glob(f"{name}_*x*x*_uint8.raw"))
    if not matches:
        raise SystemExit(f"{data / 'volumes'}: no {name}_XxYxZ_uint8.raw")
    path = matches[0]
    dims = tuple(int(x) for x in re.search(r"_(\d+)x(\d+)x(\d+)_uint8\.raw$", path.name).groups())
    return path, dims


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, required=True)
    ap.add_argument("--cases", required=True, help="dataset:tf pairs, comma separated")
    ap.add_argument("--size", default="512x512")
    ap.add_argument("--frames", type=int, default=12)
    ap.add_argument("--step", type=float, default=0.5)
    args = ap.parse_args()

    import numpy as np
    import vtk
    from vtk.util import numpy_support

    width, height = (int(x) for x in args.size.lower().split("x"))
    rows = []
    for case in args.cases.split(","):
        dataset, tf_name = case.split(":")
        path, dims = find_volume(args.data, dataset)
        voxels = np.fromfile(path, dtype=np.uint8)
        image = vtk.vtkImageData()
        image.SetDimensions(*dims)
        image.SetSpacing(1.0, 1.0, 1.0)
        array = numpy_support.numpy_to_vtk(voxels, deep=True, array_type=vtk.VTK_UNSIGNED_CHAR)
        image.GetPointData().SetScalars(array)

        color = vtk.vtkColorTransferFunction()
        opacity = vtk.vtkPiecewiseFunction()
        for value, rgb, alpha in parse_tf(args.data / "tf" / f"{tf_name}.ron"):
            color.AddRGBPoint(value, *rgb)
            opacity.AddPoint(value, alpha)
        prop = vtk.vtkVolumeProperty()
        prop.SetColor(color)
        prop.SetScalarOpacity(opacity)
        prop.SetScalarOpacityUnitDistance(1.0)
        prop.SetInterpolationTypeToLinear()
        prop.ShadeOff()

        mapper = vtk.vtkFixedPointVolumeRayCastMapper()
        mapper.SetInputData(image)
        mapper.AutoAdjustSampleDistancesOff()
        mapper.SetSampleDistance(args.step)
        mapper.SetImageSampleDistance(1.0)
        volume = vtk.vtkVolume()
        volume.SetMapper(mapper)
        volume.SetProperty(prop)

        window = vtk.vtkRenderWindow()
        window.SetOffScreenRendering(1)
        window.SetSize(width, height)
        renderer = vtk.vtkRenderer()
        renderer.SetBackground(0, 0, 0)
        window.AddRenderer(renderer)
        renderer.AddVolume(volume)
        renderer.ResetCamera()
        window.Render()  # warm-up
        frames = []
        for _ in range(args.frames):
            renderer.GetActiveCamera().Azimuth(360.0 / args.frames)
            t0 = time.perf_counter()
            window.Render()
            frames.append((time.perf_counter() - t0) * 1e3)
        rows.append(
            {
                "dataset": dataset,
                "tf": tf_name,
                "dims": list(dims),
                "viewport": [width, height],
                "frames_ms": frames,
                "median_ms": statistics.median(frames),
            }
        )
    json.dump(
        {"vtk": vtk.vtkVersion.GetVTKVersion(), "mapper": "vtkFixedPointVolumeRayCastMapper", "rows": rows},
        sys.stdout,
    )
    print()


if __name__ == "__main__":
    main()
