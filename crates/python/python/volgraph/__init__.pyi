"""Type stubs of volgraph (the extension module volgraph._volgraph)."""

from os import PathLike
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

Camera = tuple[float, float, float] | Literal["anterior", "posterior", "left", "right", "superior", "inferior"] | None
VolumeLike = "Volume | npt.NDArray[np.uint8] | npt.NDArray[np.uint16] | npt.NDArray[np.int16] | npt.NDArray[np.float32]"

class GraphError(Exception):
    """A graph file's problems, located; the message is the command line's, with the fixes."""
    path: str
    line: int | None
    column: int | None

class VolumeError(Exception):
    """A volume that cannot be read, with the reason and the fix."""

class GpuError(Exception):
    """No GPU adapter, or the GPU refused the work."""

class Volume:
    """A volume: voxels, spacing and what the file says of them."""
    @property
    def array(self) -> npt.NDArray[Any]:
        """The voxels indexed [z, y, x] (a copy)."""
    @property
    def spacing(self) -> tuple[float, float, float]:
        """Voxel spacing (x, y, z)."""
    @property
    def dims(self) -> tuple[int, int, int]:
        """Voxels per axis (x, y, z)."""
    @property
    def value_range(self) -> tuple[float, float]:
        """The data values that map to 0 and 1 on the GPU."""
    @property
    def meta(self) -> dict[str, Any]:
        """modality, units, window (center, width), frame, origin (LPS mm), description."""

class Renderer:
    """A graph kept on the GPU: set a volume, a transfer function and parameters; render."""
    def __init__(self, graph: str | PathLike[str], size: tuple[int, int] = (512, 512)) -> None: ...
    # Write-only attributes (setters): `r.volume = v` and `r.tf = "ct-bone"`.
    volume: Any
    """Write-only: a Volume or a [z, y, x] array (spacing 1, 1, 1; set_volume takes another)."""
    tf: str | PathLike[str] | None
    """Write-only: a preset ("ct-bone"), a TF file, a data-folder TF's name, or None (fitted)."""
    def set_volume(
        self, volume: Any, spacing: tuple[float, float, float] | None = None, axes: Literal["zyx", "xyz"] = "zyx"
    ) -> None: ...
    def set(self, key: str, value: bool | int | float | str) -> None:
        """Sets "PASS.PARAM" or "input.NAME"; checked (range, name) at the next render."""
    def render(self, camera: Camera = None, output: str | None = None) -> npt.NDArray[Any]:
        """(H, W, 4) uint8 sRGB of `display`, or float32 linear of another output ("image")."""
    def _repr_png_(self) -> bytes: ...

def load(path: str | PathLike[str]) -> Volume:
    """A file, a DICOM folder, a dataset of the data folder by name, or a generated volume (ml64)."""

def render(
    graph: str | PathLike[str],
    volume: Any,
    *,
    spacing: tuple[float, float, float] | None = None,
    axes: Literal["zyx", "xyz"] = "zyx",
    tf: str | PathLike[str] | None = None,
    size: tuple[int, int] = (512, 512),
    camera: Camera = None,
    output: str | None = None,
    params: dict[str, bool | int | float | str] | None = None,
) -> npt.NDArray[Any]:
    """Renders once: (H, W, 4) uint8 sRGB, or float32 linear for output="image"."""

def graphs() -> list[dict[str, str]]:
    """The built-in graphs: name, paper, description."""

def plan(graph: str | PathLike[str], size: tuple[int, int] = (1920, 1080)) -> dict[str, Any]:
    """What a graph compiles to (no GPU): name, viewport, features, inputs, steps, culled, outputs."""
