"""Type stubs of slabscope's extension module: every call, its keywords and their defaults."""

from __future__ import annotations

import os
from typing import Any, Callable, Iterator, Literal, Optional, Sequence, Tuple, Union, final

import numpy as np
import numpy.typing as npt
from typing_extensions import TypeAlias

__all__ = [
    "SCHEMA_VERSION",
    "Analysis",
    "Image",
    "Triage",
    "Volume",
    "VolumeError",
    "__version__",
    "analyze",
    "list_volumes",
    "load",
    "parameters",
    "render",
    "slice",
    "triage",
    "_volume_from_file",
    "_volume_from_voxels",
    "_analysis_of",
    "_image_of",
    "_triage_of",
    "ViewPart",
    "_view_part_of",
    "_count_view_slab",
    "_slab_planes",
    "_view_slabs",
    "_shifted_samples",
    "_refine_in_parts",
    "_analyze_with_parts",
    "_volume_of_grid",
    "PartitionPart",
    "PartitionSplit",
    "_partition_part_of",
    "_count_strip",
    "_count_strip_keeping",
    "StripRuns",
    "_strip_joints",
    "_strip_runs_of",
    "_layer_border",
    "_background_threshold",
    "_layer_summary",
    "_background_answers",
    "_layer_mask",
    "_layer_below",
    "_runs_search",
]

__version__: str
SCHEMA_VERSION: int

# Private: the stubs' own names, absent at runtime.
_PathLike: TypeAlias = Union[str, "os.PathLike[str]"]
_Progress: TypeAlias = Union[Callable[[str, float], Any], bool]
_Axis: TypeAlias = Union[str, int, Tuple[float, float, float]]

class VolumeError(Exception):
    """A file slabscope cannot read as a volume, or a volume it cannot analyse."""

@final
class Volume:
    """A volume: voxels indexed [x, y, z], spacing in mm, a voxel-to-world affine."""

    copied: bool
    format: str
    notes: list[str]
    @staticmethod
    def from_array(
        array: npt.ArrayLike,
        spacing: Optional[Union[Tuple[float, float, float], npt.ArrayLike]] = None,
        affine: Optional[npt.ArrayLike] = None,
    ) -> Volume:
        """A volume of a NumPy array indexed [x, y, z]: read in place when Fortran-ordered
        uint8, int8, uint16, int16 or float32 in native byte order, else copied once. A
        nibabel or SimpleITK image is taken as from_nibabel and from_sitk take it, and
        nibabel's argument order, from_array(array, image.affine), is understood."""
    @staticmethod
    def from_nibabel(image: Any) -> Volume:
        """A volume of a nibabel image: its voxels as nibabel gives them and its affine."""
    @staticmethod
    def from_sitk(image: Any) -> Volume:
        """A volume of a SimpleITK image: its voxels, spacing, origin and direction (LPS to RAS+)."""
    @property
    def array(self) -> np.ndarray: ...
    @property
    def shape(self) -> Tuple[int, int, int]: ...
    @property
    def spacing(self) -> Tuple[float, float, float]: ...
    @property
    def affine(self) -> np.ndarray: ...
    @property
    def orientation(self) -> Optional[str]: ...
    @property
    def dtype(self) -> str: ...
    @property
    def range(self) -> Tuple[float, float]: ...
    @property
    def missing(self) -> int: ...
    def __array__(self, dtype: Any = None, copy: Optional[bool] = None) -> np.ndarray:
        """The voxels for NumPy: `np.asarray(volume)` is `array`; `copy=False` never copies."""
    def carrying_voxels(self) -> Volume:
        """This volume, pickled with its voxels (a file's volume otherwise pickles as its path
        and `load` keywords)."""
    def __reduce__(self) -> Tuple[Any, ...]: ...
    def __copy__(self) -> Volume: ...
    def __deepcopy__(self, memo: Any, /) -> Volume: ...

def load(
    path: _PathLike,
    *,
    dims: Optional[Tuple[int, int, int]] = None,
    dtype: Any = None,
    spacing: Optional[Tuple[float, float, float]] = None,
    endian: Optional[Literal["little", "big"]] = None,
    offset: Optional[int] = None,
    max_memory: Union[int, str, None] = None,
    scratch: Optional[str] = None,
    threads: Optional[int] = None,
    volume: int = 0,
    channel: int = 0,
    array: Optional[str] = None,
    series: Union[int, str, None] = None,
    include_localizers: bool = False,
    resample: bool = False,
    show_phi: bool = False,
    label_image: Optional[str] = None,
    endpoint: Optional[str] = None,
    missing_as_fill: bool = False,
    cache: Optional[str] = None,
) -> Volume:
    """Reads a volume: NIfTI, NRRD, MetaImage, TIFF, DICOM (file or folder), OME-Zarr,
    MRC, VTK, HDF5, VolumeShop, raw."""

@final
class Analysis:
    """The views with their scores, the best axis and the slabs along it."""

    @property
    def views(self) -> list[dict[str, Any]]: ...
    @property
    def best_axis(self) -> Tuple[float, float, float]: ...
    @property
    def uncertain(self) -> bool: ...
    @property
    def contenders(self) -> list[dict[str, Any]]: ...
    @property
    def slabs(self) -> list[Tuple[int, int]]: ...
    @property
    def steps(self) -> list[dict[str, Any]]: ...
    @property
    def information(self) -> float: ...
    @property
    def partition(self) -> dict[str, Any]: ...
    @property
    def notes(self) -> list[str]: ...
    def to_dict(self) -> dict[str, Any]:
        """The object `slabscope analyze --json` prints."""
    def to_json(self) -> str: ...
    def labels(self) -> np.ndarray:
        """Every voxel's slab index + 1 (0 for background), [x, y, z] at the volume's shape,
        uint8 (uint16 beyond 255 slabs); refused beyond max_memory= (see write_labels)."""
    def write_labels(
        self, path: _PathLike, force: bool = False, progress: Optional[_Progress] = None
    ) -> None:
        """labels() written to a .nrrd, .nii or .nii.gz a few planes at a time, never held
        whole, as `analyze --export-labels` writes them."""
    @property
    def volume(self) -> Volume: ...
    def __reduce__(self) -> Tuple[Any, ...]: ...
    def __copy__(self) -> Analysis: ...
    def __deepcopy__(self, memo: Any, /) -> Analysis: ...

def analyze(
    volume: Union[Volume, npt.ArrayLike],
    progress: Optional[_Progress] = None,
    *,
    bins: int = 32,
    block: int = 3,
    level: int = 1,
    ray_spacing: Optional[float] = None,
    sample_spacing: Optional[float] = None,
    phases: int = 8,
    phase_subset: int = 12,
    refine: bool = False,
    axis: _Axis = "best",
    axis_by: Literal["entropy", "gain"] = "entropy",
    gain: bool = False,
    method: Literal["topdown", "bottomup", "optimal"] = "topdown",
    slabs: Optional[int] = None,
    threshold: Optional[float] = None,
    background: Union[Literal["auto", "none"], float] = "auto",
    views: bool = False,
    explain: Union[bool, Literal["all"], int, None] = None,
    resolution: Union[Literal["full", "auto"], int] = "full",
    max_memory: Union[int, str, None] = None,
    threads: Optional[int] = None,
) -> Analysis:
    """The most structured view and the slabs along it, as `slabscope analyze` finds them."""

@final
class Image:
    """A picture; a notebook shows it."""

    @property
    def array(self) -> np.ndarray:
        """(height, width, 4) uint8 RGBA."""
    @property
    def size(self) -> Tuple[int, int]: ...
    def png(self) -> bytes: ...
    def __array__(self, dtype: Any = None, copy: Optional[bool] = None) -> np.ndarray:
        """The pixels for NumPy: `np.asarray(image)`, (height, width, 4) uint8 RGBA."""
    def _repr_png_(self) -> bytes: ...
    def save(self, path: _PathLike, force: bool = False) -> None: ...
    def __reduce__(self) -> Tuple[Any, ...]: ...
    def __copy__(self) -> Image: ...
    def __deepcopy__(self, memo: Any, /) -> Image: ...

def render(
    volume: Volume,
    analysis: Optional[Analysis] = None,
    progress: Optional[_Progress] = None,
    *,
    size: Tuple[int, int] = (640, 480),
    threads: Optional[int] = None,
    mode: Literal["cut", "dvr", "mip"] = "cut",
    tf: Literal["auto", "ct-bone", "ct-soft", "mri"] = "auto",
    colormap: Literal["grey", "bone", "hot", "viridis"] = "grey",
    window: Optional[Tuple[float, float]] = None,
    azimuth: float = 30.0,
    elevation: float = 20.0,
    zoom: float = 1.0,
    perspective: bool = False,
    gap: Literal["uniform", "similarity"] = "similarity",
    spread: float = 0.5,
    highlight: Optional[int] = None,
    solo: bool = False,
    step: float = 1.0,
    no_shading: bool = False,
    no_outlines: bool = False,
    no_labels: bool = False,
    faces: bool = False,
) -> Image:
    """The exploded view of the slabs, as `slabscope render` draws it; with `faces=True` the
    strip of every slab's faces, as `render --faces` (only `size` and the look apply)."""

def slice(
    volume: Volume,
    analysis: Optional[Analysis] = None,
    index: Optional[int] = None,
    progress: Optional[_Progress] = None,
    *,
    size: Tuple[int, int] = (512, 512),
    threads: Optional[int] = None,
    no_letters: bool = False,
    tf: Literal["auto", "ct-bone", "ct-soft", "mri"] = "auto",
    colormap: Literal["grey", "bone", "hot", "viridis"] = "grey",
    window: Optional[Tuple[float, float]] = None,
    axis: _Axis = "best",
    **params: Any,
) -> Image:
    """One slice across the slab axis, oriented as radiologists read it."""

@final
class Triage(Iterator[dict[str, Any]]):
    """The rows of a triage run, in order."""

    def __iter__(self) -> Triage: ...
    def __next__(self) -> dict[str, Any]: ...
    def __len__(self) -> int: ...
    def close(self) -> None: ...
    def __reduce__(self) -> Tuple[Any, ...]: ...

def triage(
    paths: Union[_PathLike, Sequence[_PathLike], None] = None,
    *,
    manifest: Optional[_PathLike] = None,
    entries: Optional[Sequence[str]] = None,
    shard: Optional[Tuple[int, int]] = None,
    full: bool = False,
    timeout: float = 60.0,
    **options: Any,
) -> Triage:
    """Every volume, one row each, as `slabscope triage --json` prints them."""

def list_volumes(
    paths: Union[_PathLike, Sequence[_PathLike], None] = None,
    *,
    manifest: Optional[_PathLike] = None,
    entries: Optional[Sequence[str]] = None,
    shard: Optional[Tuple[int, int]] = None,
    **load_options: Any,
) -> list[str]:
    """The volumes triage would take, as the lines `triage --list` prints."""

def parameters(call: str) -> list[dict[str, Any]]:
    """The keywords `call` takes from the library's table of parameters: `keyword`, `flag`,
    `default`, `kind`, `min`, `max`, `words`, `expected`, `help`, `conflicts`."""
    ...

# What pickles unpickle with (private).
def _volume_from_file(path: _PathLike, options: dict[str, Any], name: str) -> Volume: ...
def _volume_from_voxels(array: np.ndarray, state: dict[str, Any]) -> Volume: ...
def _analysis_of(volume: Volume, params: dict[str, Any], json: str) -> Analysis: ...
def _image_of(width: int, height: int, pixels: bytes) -> Image: ...
def _triage_of(rows: Sequence[str], count: int) -> Triage: ...

@final
class ViewPart:
    """The view search's counts of one round over some slabs of a volume (issue #44): adds
    with ``+`` (any grouping and order), or in place with ``+=``, and pickles as bytes."""

    @property
    def round(self) -> int: ...
    @property
    def complete(self) -> bool: ...
    def __add__(self, other: ViewPart, /) -> ViewPart: ...
    def __radd__(self, other: ViewPart, /) -> ViewPart: ...
    def __iadd__(self, other: ViewPart, /) -> ViewPart: ...
    def __reduce__(self) -> Tuple[Any, ...]: ...

def _view_part_of(round: int, counts: Sequence[bytes]) -> ViewPart: ...
def _count_view_slab(
    voxels: np.ndarray,
    first: int,
    planes: Tuple[int, int],
    dims: Sequence[int],
    spacing: Sequence[float],
    dtype: str,
    range: Tuple[float, float, int],
    samples: Optional[Sequence[int]] = None,
    axes: Optional[Sequence[Tuple[float, float, float]]] = None,
    **params: Any,
) -> ViewPart: ...
def _slab_planes(
    planes: Sequence[Tuple[int, int]],
    dims: Sequence[int],
    spacing: Sequence[float],
    dtype: str,
    range: Tuple[float, float, int],
    **params: Any,
) -> Tuple[list[Tuple[int, int]], bool]: ...
def _view_slabs(
    layers: Sequence[Tuple[int, int]],
    tasks: int,
    counting_threads: int,
    dims: Sequence[int],
    spacing: Sequence[float],
    dtype: str,
    range: Tuple[float, float, int],
    samples: Optional[Sequence[int]] = None,
    axes: Optional[Sequence[Tuple[float, float, float]]] = None,
    **params: Any,
) -> list[Tuple[int, int]]: ...
def _shifted_samples(
    paper: ViewPart,
    dims: Sequence[int],
    spacing: Sequence[float],
    dtype: str,
    range: Tuple[float, float, int],
    **params: Any,
) -> Optional[list[int]]: ...
def _refine_in_parts(
    paper: ViewPart,
    dims: Sequence[int],
    spacing: Sequence[float],
    dtype: str,
    range: Tuple[float, float, int],
    count: Callable[[list[Tuple[float, float, float]], Optional[list[int]]], ViewPart],
    shifted: Optional[ViewPart] = None,
    **params: Any,
) -> None: ...
def _analyze_with_parts(
    volume: Volume,
    paper: ViewPart,
    shifted: Optional[ViewPart] = None,
    refined: Optional[
        Sequence[Tuple[Sequence[Tuple[float, float, float]], Optional[Sequence[int]], ViewPart]]
    ] = None,
    **params: Any,
) -> Analysis: ...
def _volume_of_grid(
    grid: Tuple[Sequence[int], Sequence[float], Sequence[Sequence[float]], bool], dtype: str, name: str
) -> Volume: ...

@final
class PartitionPart:
    """The partition's counts of one pass over some strips of the slice stack's rows (issue
    #44): adds with ``+`` (any grouping and order), or in place with ``+=``, and pickles as
    bytes."""

    @property
    def round(self) -> int: ...
    def __add__(self, other: PartitionPart, /) -> PartitionPart: ...
    def __radd__(self, other: PartitionPart, /) -> PartitionPart: ...
    def __iadd__(self, other: PartitionPart, /) -> PartitionPart: ...
    def __reduce__(self) -> Tuple[Any, ...]: ...

@final
class PartitionSplit:
    """The client's side of the partition in parts: the view search finished from its parts,
    the axis, the strips, the slabs, the analysis."""

    def __new__(
        cls,
        probe: Volume,
        dims: Sequence[int],
        dtype: str,
        range: Tuple[float, float, int],
        paper: Optional[ViewPart] = None,
        shifted: Optional[ViewPart] = None,
        refined: Optional[
            Sequence[Tuple[Sequence[Tuple[float, float, float]], Optional[Sequence[int]], ViewPart]]
        ] = None,
        /,
        **params: Any,
    ) -> PartitionSplit: ...
    @property
    def axis(self) -> Tuple[float, float, float]: ...
    def strips(
        self, count: int, planes: Sequence[Tuple[int, int]]
    ) -> list[Tuple[Tuple[int, int], list[Tuple[int, list[int], list[int]]]]]: ...
    def slabs(
        self, counts: PartitionPart, background: Tuple[Optional[float], int]
    ) -> list[Tuple[int, int]]: ...
    def analysis(self, joints: Optional[PartitionPart], name: str, /, **params: Any) -> Analysis: ...

def _partition_part_of(bytes: bytes) -> PartitionPart: ...
def _count_strip(
    voxels: np.ndarray,
    boxes: Sequence[Tuple[Tuple[int, int], Sequence[int], Sequence[int]]],
    rows: Tuple[int, int],
    axis: Sequence[float],
    dims: Sequence[int],
    spacing: Sequence[float],
    dtype: str,
    range: Tuple[float, float, int],
    background: Tuple[Optional[float], Sequence[bytes]],
    slabs: Optional[Sequence[Tuple[int, int]]] = None,
    /,
    **params: Any,
) -> PartitionPart: ...
def _count_strip_keeping(
    voxels: np.ndarray,
    boxes: Sequence[Tuple[Tuple[int, int], Sequence[int], Sequence[int]]],
    rows: Tuple[int, int],
    axis: Sequence[float],
    dims: Sequence[int],
    spacing: Sequence[float],
    dtype: str,
    range: Tuple[float, float, int],
    background: Tuple[Optional[float], Sequence[bytes]],
    /,
    **params: Any,
) -> Tuple[PartitionPart, Optional[StripRuns]]: ...

@final
class StripRuns:
    """A strip of the slice stack as its columns' runs, kept on the worker that cut it between
    the partition's passes (issue #44): pickles as bytes; ``sys.getsizeof`` gives the memory it
    holds."""

    @property
    def rows(self) -> Tuple[int, int]: ...
    def __sizeof__(self) -> int: ...
    def __reduce__(self) -> Tuple[Any, ...]: ...

def _strip_joints(runs: StripRuns, slabs: Sequence[Tuple[int, int]], /, **params: Any) -> PartitionPart: ...
def _strip_runs_of(bytes: bytes) -> StripRuns: ...
def _layer_border(layer: np.ndarray, z0: int, dims: Sequence[int], dtype: str) -> bytes: ...
def _background_threshold(
    borders: Sequence[bytes], dims: Sequence[int], range: Tuple[float, float]
) -> Optional[float]: ...
def _layer_summary(
    layer: np.ndarray,
    z0: int,
    dims: Sequence[int],
    dtype: str,
    threshold: float,
    max_memory: Any = None,
) -> bytes: ...
def _background_answers(summaries: Sequence[bytes], dims: Sequence[int]) -> list[Tuple[int, bytes]]: ...
def _layer_mask(
    layer: np.ndarray,
    z0: int,
    dims: Sequence[int],
    dtype: str,
    threshold: float,
    answer: bytes,
    max_memory: Any = None,
) -> Tuple[bytes, int]: ...
def _layer_below(layer: np.ndarray, dtype: str, **params: Any) -> int: ...
def _runs_search(**params: Any) -> bool: ...
