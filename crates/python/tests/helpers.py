"""What the tests share: the command line to compare with, a PNG reader of the standard library
alone, and a small volume."""

import os
from pathlib import Path

import numpy as np

BIN = os.environ.get("VOLGRAPH_BIN", "volgraph")


def cli_run(*args, cwd):
    """Runs the command line; returns the finished process (any exit status)."""
    import subprocess

    return subprocess.run([BIN, *map(str, args)], cwd=cwd, capture_output=True, text=True)


def cli(*args, cwd):
    out = cli_run(*args, cwd=cwd)
    assert out.returncode == 0, out.stderr
    return out


def read_png(path):
    """A PNG's pixels as (H, W, 4) uint8, with a PNG decoder of the standard library alone."""
    import struct
    import zlib

    data = Path(path).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, chunks, width, height = 8, [], 0, 0
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8]
        body = data[pos + 8 : pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour = struct.unpack(">IIBB", body[:10])
            assert (depth, colour) == (8, 6), "8-bit RGBA"
        elif kind == b"IDAT":
            chunks.append(body)
        pos += 12 + length
    raw = zlib.decompress(b"".join(chunks))
    stride = width * 4
    out = np.zeros((height, stride), np.int32)
    prev = np.zeros(stride, np.int32)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = np.frombuffer(raw, np.uint8, stride, y * (stride + 1) + 1).astype(np.int32)
        cur = np.zeros(stride, np.int32)
        for x in range(stride):
            a = cur[x - 4] if x >= 4 else 0
            b = prev[x]
            c = prev[x - 4] if x >= 4 else 0
            if f == 0:
                p = 0
            elif f == 1:
                p = a
            elif f == 2:
                p = b
            elif f == 3:
                p = (a + b) // 2
            else:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                p = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
            cur[x] = (line[x] + p) & 0xFF
        out[y] = cur
        prev = cur
    return out.reshape(height, width, 4).astype(np.uint8)


def ramp_volume():
    """A 24×20×16 uint16 volume, [z, y, x]: a ball of rising values in a noisy floor."""
    z, y, x = np.mgrid[0:16, 0:20, 0:24]
    r = np.sqrt(((x - 11.5) / 12) ** 2 + ((y - 9.5) / 10) ** 2 + ((z - 7.5) / 8) ** 2)
    rng = np.random.default_rng(7)
    return (np.clip(1.0 - r, 0, 1) * 60000 + rng.integers(0, 400, r.shape)).astype(np.uint16)




def ball_nifti(path):
    """`ramp_volume` as int16 written by nibabel at `path` (RAS, 0.8 × 0.9 × 1.5 mm, origin
    (-10, 20, 5)); returns nibabel's [x, y, z] array."""
    import nibabel as nib

    data = ramp_volume().astype(np.int16).transpose(2, 1, 0)
    affine = np.diag([0.8, 0.9, 1.5, 1.0])
    affine[:3, 3] = (-10.0, 20.0, 5.0)
    nib.save(nib.Nifti1Image(data, affine), path)
    return data
