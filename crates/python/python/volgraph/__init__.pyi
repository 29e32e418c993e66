"""Type stubs of volgraph (the extension module volgraph._volgraph)."""

from os import PathLike
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

OneLight = Literal["headlight"] | str | tuple[float, float] | tuple[Literal["point"], float, float, float]
Light = OneLight | list[OneLight]
Crop = tuple[float, float, float, float, float, float]
Clip = tuple[float, float, float, float] | list[tuple[float, float, float, float]]
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

class TransferFunction:
    """A piecewise-linear transfer function: control points (value, (r, g, b), alpha)."""
    @staticmethod
    def from_points(
        points: list[tuple[float, tuple[float, float, float], float] | tuple[float, float, float, float, float]],
        domain: tuple[float, float] | None = None,
    ) -> TransferFunction:
        """Points sorted by data value; colour linear RGB in 0..1, alpha the opacity per voxel."""
    @staticmethod
    def load(path: str | PathLike[str]) -> TransferFunction:
        """A TF file: RON, or a ParaView colour map .json."""
    @property
    def points(self) -> list[tuple[float, tuple[float, float, float], float]]: ...
    @property
    def domain(self) -> tuple[float, float]: ...
    def hidden_below(self, value: float) -> TransferFunction:
        """Transparent below `value` (a step there), unchanged above."""
    def __call__(self, value: float) -> tuple[float, float, float, float]: ...
    def to_ron(self) -> str:
        """The text of a TF file (`volgraph render --tf FILE`)."""

class Volume:
    """A volume: voxels, spacing and what the file says of them."""
    @property
    def array(self) -> npt.NDArray[Any]:
        """The voxels indexed [z, y, x]: a read-only view of the loaded buffer (no copy)."""
    @property
    def world_from_volume(self) -> npt.NDArray[np.float64]:
        """4×4: voxel index (x, y, z, 1) to the world (LPS mm in the patient frame)."""
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
    """A graph kept on the GPU: set a volume, a transfer function, parameters, effects, cuts
    and the light; render. Made and used in one thread."""
    def __init__(
        self,
        graph: str | PathLike[str] | None = None,
        size: tuple[int, int] | None = None,
        *,
        scene: str | PathLike[str] | None = None,
    ) -> None:
        """A graph's name or file, and/or a scene file (its graph, size, volume, TF, camera,
        effects, cuts and light where nothing else gives them); size default 512×512."""
    volume: Any
    """Write-only: a Volume, a [z, y, x] array (spacing 1, 1, 1; set_volume takes another) or a
    path read as --volume reads it (an OME-Zarr store, or a file over 512 MiB, is streamed by a
    streaming graph)."""
    time_budget_ms: float | None
    """Write-only: how long a render of a streaming graph refines; None: until complete."""
    def stream(self, path: str | PathLike[str], *, frame: int | None = None, memory_mb: int | None = None) -> None:
        """Streams an OME-Zarr store brick by brick (graph streaming/ray_guided): frame picks
        N = t·C + c, memory_mb bounds the decoded chunks held (default 512). A raw, NRRD or
        MetaImage file larger than memory_mb streams from the file itself; a smaller one is read
        in core."""
    @property
    def tf(self) -> TransferFunction:
        """The TF the next frame classifies with (fitted to the volume unless one was set)."""
    @tf.setter
    def tf(self, tf: str | PathLike[str] | TransferFunction | None) -> None: ...
    effects: list[str] | str | None
    """Write-only: effects on besides the scene's (as --features): ["shading", "jitter"]."""
    light: Light
    """Write-only: "headlight", (azimuth, elevation) or ("point", x, y, z) (as --light); a list
    of up to three for several (as --light repeated)."""
    @property
    def value_range(self) -> tuple[float, float] | None: ...
    @property
    def default_camera(self) -> tuple[float, float, float]: ...
    @property
    def size(self) -> tuple[int, int]: ...
    @property
    def last_frame_ms(self) -> float:
        """The library's time of the last render, without the Python layer."""
    @property
    def notes(self) -> list[str]:
        """Notes of the last compile (what the CLI prints on stderr)."""
    def set_cuts(self, crop: Crop | None = None, clip: Clip | None = None) -> None:
        """Crop box and clip planes in volume fractions (as --crop, --clip); none: no cuts."""
    def reference(self, camera: Camera = None, step_voxels: float = 0.1) -> npt.NDArray[np.float64]:
        """The converged f64 image of the graph's raycast model: compare with render(output="image")."""
    def widget(self, camera: tuple[float, float, float] | None = None, threshold: bool = True) -> Any:
        """An interactive view in Jupyter (jupyter_rfb): drag rotates, wheel zooms, a slider thresholds."""
    def set_volume(
        self,
        volume: Any,
        spacing: tuple[float, float, float] | None = None,
        axes: Literal["zyx", "xyz"] = "zyx",
        name: str | None = None,
    ) -> None:
        """A Volume or array; `name` binds another volume input of the graph ("pet"), as --volume NAME=…."""
    def set_named_tf(self, name: str, tf: str | PathLike[str]) -> None:
        """Binds a TF or label-table input by name ("pet_tf"), as --tf NAME=…."""
    def set(self, key: str, value: bool | int | float | str) -> None:
        """Sets "PASS.PARAM" or "input.NAME"; checked (range, name) at the next render."""
    def render(self, camera: Camera = None, output: str | None = None) -> npt.NDArray[Any]:
        """(H, W, 4) uint8 sRGB of `display`, or float32 linear of another output ("image")."""
    def _repr_png_(self) -> bytes: ...

def load(path: str | PathLike[str], *, series: str | None = None, frame: int | None = None) -> Volume:
    """A file, a DICOM folder, a dataset of the data folder by name, or a generated volume (ml64);
    `series` picks a DICOM series of a folder, `frame` a volume of a 4D NIfTI."""

def render(
    graph: str | PathLike[str] | None = None,
    volume: Any = None,
    *,
    scene: str | PathLike[str] | None = None,
    spacing: tuple[float, float, float] | None = None,
    axes: Literal["zyx", "xyz"] = "zyx",
    tf: str | PathLike[str] | TransferFunction | None = None,
    size: tuple[int, int] | None = None,
    camera: Camera = None,
    output: str | None = None,
    effects: list[str] | str | None = None,
    crop: Crop | None = None,
    clip: Clip | None = None,
    light: Light | None = None,
    volumes: dict[str, Any] | None = None,
    tfs: dict[str, str | PathLike[str]] | None = None,
    params: dict[str, bool | int | float | str] | None = None,
) -> npt.NDArray[Any]:
    """Renders once: (H, W, 4) uint8 sRGB, or float32 linear for output="image"."""

def graphs() -> list[dict[str, str]]:
    """The built-in graphs: name, paper, description."""

def plan(graph: str | PathLike[str], size: tuple[int, int] = (1920, 1080)) -> dict[str, Any]:
    """What a graph compiles to (no GPU): name, viewport, features, inputs, steps, culled, outputs."""
