"""slabscope on a Dask cluster: triage or analysis of many volumes, one task per volume, and
the view search of one volume split into tasks over its chunks (:func:`analyze_array`).

Dask is optional (``pip install 'slabscope[dask]'``). Each task runs on a worker of an existing
``distributed.Client`` and gets, as its memory budget, half of that worker's Dask memory limit
(the budget slabscope's ``max_memory`` bounds, the other half left to Dask); a worker without a
limit uses slabscope's default, half the machine's memory. Results come back as rows, in the
order of the volumes: exactly the rows ``slabscope triage --json`` prints.

>>> from distributed import Client                        # doctest: +SKIP
>>> import slabscope.dask
>>> rows = slabscope.dask.triage(Client(), "/archive")   # doctest: +SKIP
"""

from __future__ import annotations

import os
from typing import Any, Optional, Sequence

import numpy as np

import slabscope

__all__ = ["triage", "analyze", "analyze_array", "LOAD_KEYWORDS"]

#: The keywords of :func:`slabscope.load`, which also choose the volumes a run takes.
LOAD_KEYWORDS = (
    "dims",
    "dtype",
    "spacing",
    "endian",
    "offset",
    "max_memory",
    "scratch",
    "volume",
    "channel",
    "array",
    "series",
    "include_localizers",
    "resample",
    "show_phi",
    "label_image",
    "endpoint",
    "missing_as_fill",
)


def _budget() -> Optional[int]:
    """Half the Dask memory limit of the worker running this task, bytes (None: no limit)."""
    from distributed import get_worker

    worker = get_worker()
    manager = getattr(worker, "memory_manager", None)
    limit = getattr(manager, "memory_limit", None) or getattr(worker, "memory_limit", None)
    return int(limit) // 2 if limit else None


def _with_budget(options: dict) -> dict:
    if options.get("max_memory") is None:
        budget = _budget()
        if budget is not None:
            return {**options, "max_memory": budget}
    return options


def _triage_one(entry: str, options: dict) -> dict:
    rows = list(slabscope.triage(entries=[entry], **_with_budget(options)))
    return rows[0]


def _analyze_one(path: str, load: dict, params: dict) -> dict:
    load = _with_budget(load)
    try:
        volume = slabscope.load(path, **load)
        return slabscope.analyze(volume, max_memory=load.get("max_memory"), **params).to_dict()
    except (slabscope.VolumeError, OSError, ValueError) as e:
        return {"file": path, "error": str(e)}


def triage(
    client: Any,
    paths: Any = None,
    *,
    manifest: Any = None,
    entries: Optional[Sequence[str]] = None,
    shard: Optional[tuple] = None,
    **options: Any,
) -> list:
    """The rows of ``slabscope.triage(paths, ...)`` (the same keywords), one Dask task per
    volume on ``client``'s workers, gathered in order."""
    load = {k: v for k, v in options.items() if k in LOAD_KEYWORDS}
    lines = slabscope.list_volumes(paths, manifest=manifest, entries=entries, shard=shard, **load)
    futures = client.map(_triage_one, lines, options=options, pure=False)
    return client.gather(futures)


def analyze(client: Any, paths: Sequence[Any], **options: Any) -> list:
    """``slabscope.analyze(slabscope.load(path), ...).to_dict()`` for every path, one Dask task
    each, in order; a volume that cannot be read or analysed gives ``{"file", "error"}``."""
    load = {k: v for k, v in options.items() if k in LOAD_KEYWORDS}
    params = {k: v for k, v in options.items() if k not in LOAD_KEYWORDS}
    futures = client.map(_analyze_one, [str(p) for p in paths], load=load, params=params, pure=False)
    return client.gather(futures)


#: The NumPy types a volume holds as they are; any other is held as float32.
_HELD = ("uint8", "int8", "uint16", "int16", "float32")


def _as_xyz(source: Any, axes: Optional[str]) -> Any:
    """``source`` (a Zarr path or URL, or a dask array whose axis order ``axes`` names) as a
    dask array indexed ``[z, y, x]`` in the type the volume holds."""
    import dask.array as da

    if isinstance(source, (str, os.PathLike)):
        array = da.from_zarr(str(source))
        axes = axes or "zyx"
    else:
        array = source
    if axes is None:
        raise ValueError("analyze_array: axes= names the array's axis order (\"zyx\" for what dask.array.from_zarr gives); it is never assumed")
    if sorted(axes) != ["x", "y", "z"] or array.ndim != 3:
        raise ValueError(f"analyze_array: axes={axes!r} for an array of {array.ndim} dimensions: a permutation of \"xyz\" for 3")
    array = array.transpose([axes.index(a) for a in "zyx"])
    held = array.dtype.name if array.dtype.name in _HELD else "float32"
    return array.astype(held), held


def _range(array: Any) -> tuple:
    """The finite voxels' min, max and count (one round of reductions on the cluster)."""
    import dask.array as da

    finite = da.isfinite(array)
    low = da.where(finite, array, np.inf).min()
    high = da.where(finite, array, -np.inf).max()
    return low, high, finite.sum()


def _count(block: Any, first: int, planes: tuple, grid: tuple, samples: Any, params: dict) -> Any:
    """One task: the part of the slab ``planes`` from its voxel planes ``block`` ([z, y, x])."""
    return slabscope._slabscope._count_view_slab(block.T, first, planes, *grid, samples=samples, **params)


def _round(client: Any, array: Any, slabs: list, grid: tuple, samples: Any, params: dict, report: Any) -> Any:
    """A round of tasks, one a slab, added up on the client as they come."""
    import dask
    from distributed import as_completed

    tasks = []
    for planes in slabs:
        first, end, _ = slabscope._slabscope._slab_planes(planes, *grid, **params)
        block = array[first:end]
        tasks.append(dask.delayed(_count)(block, first, planes, grid, samples, params))
    total = None
    for future in as_completed(client.compute(tasks)):
        part = future.result()
        total = part if total is None else total + part
        report()
    return total


def analyze_array(
    client: Any,
    source: Any,
    *,
    axes: Optional[str] = None,
    spacing: Any = None,
    progress: Any = None,
    **params: Any,
) -> Any:
    """``slabscope.analyze`` of one volume held as a Zarr store (a path or URL) or a dask
    array (``axes`` naming its axis order, ``"zyx"`` for what ``dask.array.from_zarr`` gives;
    never assumed), its view search counted by tasks on ``client``'s workers, a task a slab of
    the array's chunks along z (with the planes around it that its samples read), the parts
    added on the client: the same ``Analysis`` as one process gives, ``to_dict()`` equal.

    Rounds: the range (min/max reductions), the paper's lattices, the shifted lattices (with
    phases), then the partition and the background in one task over the whole array (not
    split yet: docs/design.md). ``progress(phase, fraction)`` hears the tasks done of all.
    The refinement (``refine=True``) is refused: it is not split yet."""

    array, held = _as_xyz(source, axes)
    nz, ny, nx = array.shape
    spacing = (1.0, 1.0, 1.0) if spacing is None else tuple(float(s) for s in spacing)
    low, high, finite = client.compute(list(_range(array)), sync=True)
    grid = ([nx, ny, nz], list(spacing), held, (float(low), float(high), int(finite)))
    cells = max(nz - 1, 1)
    cuts = [int(c) for c in np.cumsum((0,) + array.chunks[0])]
    cuts = sorted({min(c, cells) for c in cuts} | {0, cells})
    slabs = [(a, b) for a, b in zip(cuts, cuts[1:]) if b > a]
    _, _, shifted = slabscope._slabscope._slab_planes(slabs[0], *grid, **params)
    total = len(slabs) * (2 if shifted else 1) + 1
    done = [0]

    def report() -> None:
        done[0] += 1
        if progress is not None:
            progress("view search in parts", done[0] / total)

    paper = _round(client, array, slabs, grid, None, params, report)
    more = None
    if shifted:
        samples = slabscope._slabscope._paper_samples(paper, *grid, **params)
        more = _round(client, array, slabs, grid, samples, params, report)
    import dask

    whole = client.compute(dask.delayed(_finish)(array, spacing, paper, more, params)).result()
    report()
    return whole


def _finish(array: Any, spacing: tuple, paper: Any, shifted: Any, params: dict) -> Any:
    """The last task: the analysis of the whole array from the view search's parts."""
    volume = slabscope.Volume.from_array(np.asarray(array).T, spacing=spacing)
    return slabscope._slabscope._analyze_with_parts(volume, paper, shifted, **params)
