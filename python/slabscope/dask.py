"""slabscope on a Dask cluster: triage or analysis of many volumes, one task per volume, and
the analysis of one volume split into tasks over its chunks (:func:`analyze_array`).

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
from contextlib import contextmanager
from typing import Any, Callable, Dict, Iterator, List, Optional, Sequence, Tuple

import numpy as np

import slabscope

__all__ = ["triage", "analyze", "analyze_array", "LOAD_KEYWORDS"]

#: Keyword arguments passed on (to ``slabscope.load``, ``slabscope.analyze`` or a task).
Options = Dict[str, Any]

#: What every task of :func:`analyze_array` is told of the whole grid: its dims (x, y, z),
#: spacing (mm), held type, and the finite voxels' min, max and count.
Grid = Tuple[List[int], List[float], str, Tuple[float, float, int]]

#: A round of the view search: the paper samples of a shifted round and a refinement step's
#: axes (None for the paper round and the sphere's axes).
Round = Tuple[Optional[List[int]], Optional[List[Tuple[float, float, float]]]]

#: A range of planes or cell planes along z, ``(start, end)``.
Planes = Tuple[int, int]

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
    "cache",
)


def _budget() -> Optional[int]:
    """Half the Dask memory limit of the worker running this task, bytes (None: no limit)."""
    from distributed import get_worker

    return _worker_budget(get_worker())


def _worker_limit(dask_worker: Any) -> Optional[int]:
    """``dask_worker``'s Dask memory limit, bytes (None: no limit)."""
    manager = getattr(dask_worker, "memory_manager", None)
    limit = getattr(manager, "memory_limit", None) or getattr(dask_worker, "memory_limit", None)
    return int(limit) if limit else None


def _worker_budget(dask_worker: Any) -> Optional[int]:
    """Half ``dask_worker``'s Dask memory limit, bytes (None: no limit): a task's budget there."""
    limit = _worker_limit(dask_worker)
    return limit // 2 if limit else None


def _threads() -> int:
    """The threads a task's counts run on by default here (the processors this process may use)."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


def _with_budget(options: Options) -> Options:
    if options.get("max_memory") is None:
        budget = _budget()
        if budget is not None:
            return {**options, "max_memory": budget}
    return options


def _triage_one(entry: str, options: Options) -> Options:
    rows: List[Options] = list(slabscope.triage(entries=[entry], **_with_budget(options)))
    return rows[0]


def _analyze_one(path: str, load: Options, params: Options) -> Options:
    load = _with_budget(load)
    try:
        volume = slabscope.load(path, **load)
        result: Options = slabscope.analyze(volume, max_memory=load.get("max_memory"), **params).to_dict()
        return result
    except (slabscope.VolumeError, OSError, ValueError) as e:
        return {"file": path, "error": str(e)}


def triage(
    client: Any,
    paths: Any = None,
    *,
    manifest: Any = None,
    entries: Optional[Sequence[str]] = None,
    shard: Any = None,
    **options: Any,
) -> List[Options]:
    """The rows of ``slabscope.triage(paths, ...)`` (the same keywords), one Dask task per
    volume on ``client``'s workers, gathered in order."""
    load = {k: v for k, v in options.items() if k in LOAD_KEYWORDS}
    lines = slabscope.list_volumes(paths, manifest=manifest, entries=entries, shard=shard, **load)
    futures = client.map(_triage_one, lines, options=options, pure=False)
    rows: List[Options] = client.gather(futures)
    return rows


def analyze(client: Any, paths: Sequence[Any], **options: Any) -> List[Options]:
    """``slabscope.analyze(slabscope.load(path), ...).to_dict()`` for every path, one Dask task
    each, in order; a volume that cannot be read or analysed gives ``{"file", "error"}``."""
    load = {k: v for k, v in options.items() if k in LOAD_KEYWORDS}
    params = {k: v for k, v in options.items() if k not in LOAD_KEYWORDS}
    futures = client.map(_analyze_one, [str(p) for p in paths], load=load, params=params, pure=False)
    rows: List[Options] = client.gather(futures)
    return rows


#: The NumPy types a volume holds as they are; any other is held as float32.
_HELD = ("uint8", "int8", "uint16", "int16", "float32")

#: Millimetres in a length unit of OME-Zarr's (UDUNITS-2 names): the table the Rust reader
#: of OME-Zarr stores uses (src/formats/zarr/meta.rs), so that the spacing is `load`'s.
_MM = {
    "angstrom": 1e-7,
    "attometer": 1e-15,
    "centimeter": 10.0,
    "decimeter": 100.0,
    "exameter": 1e21,
    "femtometer": 1e-12,
    "foot": 304.8,
    "gigameter": 1e12,
    "hectometer": 1e5,
    "inch": 25.4,
    "kilometer": 1e6,
    "megameter": 1e9,
    "meter": 1e3,
    "micrometer": 1e-3,
    "mile": 1_609_344.0,
    "millimeter": 1.0,
    "nanometer": 1e-6,
    "parsec": 3.085_677_581_491_367e19,
    "petameter": 1e18,
    "picometer": 1e-9,
    "terameter": 1e15,
    "yard": 914.4,
    "yoctometer": 1e-21,
    "yottameter": 1e27,
    "zeptometer": 1e-18,
    "zettameter": 1e24,
}


def _scales(transforms: Any, n: int) -> List[float]:
    """The product of the ``scale`` transformations of an OME-Zarr ``coordinateTransformations``
    list, one factor an axis (its translations move no voxel nearer another: not read)."""
    scale = [1.0] * n
    for t in transforms or []:
        if t.get("type") == "scale":
            given = [float(f) for f in t["scale"]]
            if len(given) != n:
                raise ValueError(f"a scale of {len(given)} factors for {n} axes")
            scale = [a * b for a, b in zip(scale, given)]
    return scale


def _ome_zarr(path: str) -> Tuple[Any, str, Tuple[float, ...], Tuple[Any, List[Optional[str]]]]:
    """An OME-Zarr group's full-resolution array (its first dataset) as a dask array, its axes'
    names, their spacing, mm (scales in the axes' units; without a unit, taken as mm), and the
    stored array with the name of each of its axes (None for one dropped). Axes other than
    x, y and z (time, channel) must be one long: they are dropped."""
    import dask.array as da
    import zarr

    try:
        group = zarr.open_group(path, mode="r")
    except Exception as e:  # zarr raises its own errors for a store that is not a group
        raise ValueError(f"{path}: not an OME-Zarr group ({e}): a plain Zarr array needs its axis order given with axes= (\"zyx\" for most; never assumed)") from None
    attrs = dict(group.attrs)
    meta = attrs.get("ome", attrs)  # OME-Zarr 0.5 keeps its metadata under "ome"
    multiscales = meta.get("multiscales") if isinstance(meta, dict) else None
    if not multiscales:
        raise ValueError(f"{path}: a Zarr group without OME-Zarr multiscales metadata: name the array inside it")
    ms = multiscales[0]
    try:
        axes = [a["name"] if isinstance(a, dict) else str(a) for a in ms["axes"]]
        units = [a.get("unit") if isinstance(a, dict) else None for a in ms["axes"]]
        dataset = ms["datasets"][0]
        scale = _scales(dataset.get("coordinateTransformations"), len(axes))
        scale = [a * b for a, b in zip(scale, _scales(ms.get("coordinateTransformations"), len(axes)))]
    except (AttributeError, KeyError, IndexError, TypeError, ValueError) as e:
        raise ValueError(f"{path}: OME-Zarr multiscales metadata without axes, datasets or a valid scale ({e})") from None
    stored = zarr.open_array(store=path, path=dataset["path"], mode="r")
    array = da.from_zarr(stored)  # type: ignore[no-untyped-call]
    if array.ndim != len(axes):
        raise ValueError(f"{path}: {len(axes)} axes named for an array of {array.ndim} dimensions")
    keep = []
    for i, (name, n) in enumerate(zip(axes, array.shape)):
        if name in ("x", "y", "z"):
            keep.append(i)
        elif n != 1:
            raise ValueError(f"{path}: its {name!r} axis holds {n}: one volume at a time (take one with dask.array indexing and axes=)")
    spacing: Dict[str, float] = {}
    for i in keep:
        unit = units[i]
        if unit is not None and unit not in _MM:
            raise ValueError(f"{path}: the unit {unit!r} of axis {axes[i]!r} is not a length unit OME-Zarr names (UDUNITS-2: micrometer, millimeter, ...)")
        spacing[axes[i]] = scale[i] * (_MM[unit] if unit else 1.0)
    array = array[tuple(slice(None) if i in keep else 0 for i in range(array.ndim))]
    names = "".join(axes[i] for i in keep)
    reader = (stored, [axes[i] if i in keep else None for i in range(len(axes))])
    return array, names, tuple(spacing.get(a, 1.0) for a in "xyz"), reader


def _as_xyz(source: Any, axes: Optional[str]) -> Tuple[Any, str, Optional[Tuple[float, ...]], Optional[Tuple[Any, List[Optional[str]]]]]:
    """``source`` (a Zarr path or URL, or a dask array whose axis order ``axes`` names) as a
    dask array indexed ``[z, y, x]`` in the type the volume holds, that type, the spacing an
    OME-Zarr store gives (else None), and for a store, the stored array and its axes' names
    (what :func:`_read_layer` reads; else None)."""
    import dask.array as da

    spacing: Optional[Tuple[float, ...]] = None
    reader: Optional[Tuple[Any, List[Optional[str]]]] = None
    if isinstance(source, (str, os.PathLike)):
        path = str(source)
        if axes is None:
            array, axes, spacing, reader = _ome_zarr(path)
        else:
            import zarr

            stored = zarr.open_array(store=path, mode="r")
            array = da.from_zarr(stored)  # type: ignore[no-untyped-call]
            reader = (stored, list(axes))
    else:
        array = source
    if axes is None:
        raise ValueError("analyze_array: axes= names the array's axis order (\"zyx\" for what dask.array.from_zarr gives); it is never assumed")
    if sorted(axes) != ["x", "y", "z"] or array.ndim != 3:
        raise ValueError(f"analyze_array: axes={axes!r} for an array of {array.ndim} dimensions: a permutation of \"xyz\" for 3")
    array = array.transpose([axes.index(a) for a in "zyx"])
    held = array.dtype.name if array.dtype.name in _HELD else "float32"
    return array.astype(held), held, spacing, reader


def _geometry(spacing: Any, affine: Any, stored: Optional[Tuple[float, ...]]) -> Any:
    """A volume of one voxel with the whole volume's geometry (its spacing the one the tasks
    count with, its affine the report's): from ``affine`` (4×4, voxel index ``(x, y, z)`` to
    RAS+ mm, as nibabel gives it) and ``spacing`` as ``Volume.from_array`` takes them (so that
    they must agree, and the spacing is the one ``from_array`` finds), else the store's."""
    if affine is None and spacing is None:
        spacing = stored
    given: Options = {}
    if affine is not None:
        given["affine"] = np.asarray(affine, dtype=float)
    if spacing is not None:
        given["spacing"] = tuple(float(s) for s in spacing)
    return slabscope.Volume.from_array(np.zeros((1, 1, 1), np.uint8), **given)


def _layers(client: Any, array: Any, reader: Optional[Tuple[Any, List[Optional[str]]]]) -> List[Any]:
    """The array's chunk layers along z as futures on ``client``'s workers, each a layer's
    voxel planes ([z, y, x], whole planes, in the held type) held there until released. Each
    chunk read once (issue #44): from a store (``reader``), a task a layer reads its chunks in
    one call; from a dask array, one graph for all layers, each chunk computed once and
    gathered into its layer."""
    if reader is not None:
        stored, names = reader
        held = array.dtype.name
        cuts = [int(c) for c in np.cumsum((0,) + array.chunks[0])]
        return [client.submit(_read_layer, stored, names, held, a, b, pure=False) for a, b in zip(cuts, cuts[1:])]
    futures: List[Any] = client.compute(list(array.rechunk({1: -1, 2: -1}).to_delayed().ravel()))
    return futures


def _read_layer(stored: Any, names: List[Optional[str]], held: str, start: int, end: int) -> np.ndarray:
    """Planes ``start..end`` along z of a stored array whose axes ``names`` names (None for
    an axis of one, dropped), indexed [z, y, x], in the held type: what the dask array
    ``_as_xyz`` makes of the store gives for them."""
    index = tuple(slice(start, end) if n == "z" else slice(None) if n else 0 for n in names)
    kept = [n for n in names if n]
    planes = np.asarray(stored[index]).transpose([kept.index(a) for a in "zyx"])
    return np.ascontiguousarray(planes.astype(held, copy=False))


#: The share of the workers' memory limits the array may take to be kept whole between rounds.
_KEEP_SHARE = 0.5


def _fits(client: Any, nbytes: int) -> bool:
    """Whether an array of ``nbytes`` fits within :data:`_KEEP_SHARE` of the workers' Dask
    memory limits added up (a worker without a limit: it fits)."""
    limits = client.run(_worker_limit)
    if not limits or not all(limits.values()):
        return True
    return nbytes <= _KEEP_SHARE * sum(int(v) for v in limits.values())


class _Layers:
    """The array's chunk layers along z on the workers. Kept when the array fits within
    :data:`_KEEP_SHARE` of the workers' memory limits: read once, at the first round, and held
    until :meth:`release`; else read again for each round (each chunk once a round) and
    released as the round ends, so that a volume beyond the cluster's memory is analysed
    from its store rather than from Dask's spill."""

    def __init__(self, client: Any, array: Any, reader: Optional[Tuple[Any, List[Optional[str]]]]) -> None:
        self.client, self.array, self.reader = client, array, reader
        cuts = [int(c) for c in np.cumsum((0,) + array.chunks[0])]
        self.bounds: List[Planes] = list(zip(cuts, cuts[1:]))
        self.keep = _fits(client, int(array.nbytes))
        self._kept: Optional[List[Any]] = None
        self._pieces: Dict[Tuple[Planes, ...], List[List[Any]]] = {}

    def __len__(self) -> int:
        return len(self.bounds)

    @contextmanager
    def round(self) -> Iterator[List[Any]]:
        """The layers' futures for a round: the kept ones, or read for this round alone."""
        if self.keep:
            if self._kept is None:
                self._kept = _layers(self.client, self.array, self.reader)
            yield self._kept
            return
        futures = _layers(self.client, self.array, self.reader)
        try:
            yield futures
        finally:
            for future in futures:
                future.release()

    @contextmanager
    def pieces(self, held: List[Planes]) -> Iterator[List[List[Any]]]:
        """For each slab's held planes, the futures of its planes for a round (:func:`_pieces`):
        cut once for the call from kept layers, else for this round from its own read."""
        if self.keep:
            with self.round() as layers:
                key = tuple(held)
                if key not in self._pieces:
                    self._pieces[key] = _pieces(self.client, layers, self.bounds, held)
                yield self._pieces[key]
            return
        with self.round() as layers:
            pieces = _pieces(self.client, layers, self.bounds, held)
            try:
                yield pieces
            finally:
                for these in pieces:
                    for future in these:
                        future.release()

    def release(self) -> None:
        """Releases what is kept (an error's traceback would keep the futures alive)."""
        pieces = [f for slabs in self._pieces.values() for these in slabs for f in these]
        for future in (self._kept or []) + pieces:
            future.release()


def _range_of(layer: np.ndarray) -> Tuple[float, float, int]:
    """A layer's finite voxels' min, max and count (min above max when it has none)."""
    if layer.dtype.kind in "iu":
        if layer.size == 0:
            return np.inf, -np.inf, 0
        return float(layer.min()), float(layer.max()), int(layer.size)
    finite = np.isfinite(layer)
    count = int(np.count_nonzero(finite))
    if count == 0:
        return np.inf, -np.inf, 0
    values = layer if count == layer.size else layer[finite]
    return float(values.min()), float(values.max()), count


def _range(client: Any, layers: List[Any]) -> Tuple[float, float, int]:
    """The finite voxels' min, max and count: one task a layer, where it is held."""
    ranges = client.gather(client.map(_range_of, layers, pure=False))
    return min(r[0] for r in ranges), max(r[1] for r in ranges), sum(r[2] for r in ranges)


def _planes(layer: np.ndarray, start: int, end: int) -> np.ndarray:
    """Planes ``start..end`` of a layer (a task where the layer is held: the few planes a
    neighbouring slab's task reads travel, not the layer)."""
    return np.ascontiguousarray(layer[start:end])


def _pieces(client: Any, layers: List[Any], bounds: List[Planes], held: List[Planes]) -> List[List[Any]]:
    """For each slab's held planes ``(first, end)``, the futures whose planes, in order, are
    exactly those: the layers held whole, and tasks taking the planes it needs of the others
    (made once for every round)."""
    pieces: List[List[Any]] = []
    for first, end in held:
        these: List[Any] = []
        for layer, (z0, z1) in zip(layers, bounds):
            a, b = max(first, z0), min(end, z1)
            if a >= b:
                continue
            these.append(layer if (a, b) == (z0, z1) else client.submit(_planes, layer, a - z0, b - z0, pure=False))
        pieces.append(these)
    return pieces


def _count(first: int, planes: Planes, grid: Grid, round: Round, params: Options, *pieces: np.ndarray) -> Any:
    """One task: the part of the slab ``planes`` from its voxel planes (``pieces``, [z, y, x],
    in order from plane ``first``) in the round ``(samples, axes)``."""
    samples, axes = round
    block = pieces[0] if len(pieces) == 1 else np.concatenate(pieces, axis=0)
    dims, spacing, held, range_ = grid
    return slabscope._slabscope._count_view_slab(block.T, first, planes, dims, spacing, held, range_, samples=samples, axes=axes, **_with_budget(params))


def _round(
    client: Any,
    layers: _Layers,
    planned: Tuple[List[Planes], List[Planes]],
    grid: Grid,
    round: Round,
    params: Options,
    report: Callable[[], None],
) -> Any:
    """A round of tasks, one a slab (given the futures of its voxel planes from ``layers``,
    from plane ``held``'s first), added up on the client as they come; ``round`` is ``(samples, axes)``:
    the paper samples of a shifted round (else None) and a refinement step's axes (else None,
    the sphere's)."""
    slabs, held = planned
    with layers.pieces(held) as pieces:
        tasks: List[Any] = []
        for planes, (first, _), these in zip(slabs, held, pieces):
            tasks.append(client.submit(_count, first, planes, grid, round, params, *these, pure=False))
        return _sum(tasks, report)


def _sum(tasks: List[Any], report: Callable[[], None]) -> Any:
    """The parts ``tasks`` give, added up on the client as they come (in place: the total is
    never copied, issue #44), ``report`` called for each."""
    from distributed import as_completed

    total = None
    for future in as_completed(tasks):  # type: ignore[no-untyped-call]
        part = future.result()
        if total is None:
            total = part
        else:
            total += part
        report()
    return total


def analyze_array(
    client: Any,
    source: Any,
    *,
    axes: Optional[str] = None,
    spacing: Any = None,
    affine: Any = None,
    progress: Any = None,
    **params: Any,
) -> Any:
    """``slabscope.analyze`` of one volume held as a Zarr store (a path or URL) or a dask
    array, counted by tasks on ``client``'s workers over the array's chunks, no task holding
    the whole array, the parts added on the client: the same ``Analysis`` as one process
    gives, ``to_dict()`` equal, of a volume holding no voxel (its grid alone: what reads
    voxels, ``labels()`` or a picture, raises a ``ValueError`` saying so).

    ``axes`` names the array's axis order (``"zyx"`` for what ``dask.array.from_zarr``
    gives; never assumed). An OME-Zarr group's path needs none: its ``multiscales``
    metadata names the axes and gives the spacing (the scales of its first dataset, in its
    units, as mm); a Zarr array without that metadata needs ``axes``. ``spacing`` (mm, x y z)
    or ``affine`` (4×4, voxel index ``(x, y, z)`` to RAS+ mm, as nibabel gives it) are taken as
    ``Volume.from_array`` takes them, and override the store's.

    The chunks are read into layers of whole planes (a chunk layer along z each): once, held on
    the workers until the call returns, where the array fits within half their Dask memory
    limits; else once a round, released after it. Rounds: the range
    (a task a layer); the view search, a task a slab of whole chunk layers along z (as few
    slabs as keep the cluster's threads at work within a task's budget; with the planes around
    it that its samples read): the paper's lattices, with the shifted lattices (phases) where
    their rays can be guessed before the paper's are counted (a volume whose box holds enough
    samples), then the shifted lattices the first round did not count right (none on most
    volumes), with ``refine=True`` such rounds for each step of the refinement (the axes each
    step asks for, found on the client from the sums); the background (the automatic one in three
    rounds of a task a layer, a threshold's in one); the partition in two rounds of a task a
    strip of the slice stack's rows, each gathering the box of voxels its rows read. Labelling
    a layer's background keeps within half its worker's Dask memory limit unless
    ``max_memory`` is given. ``explain``, the gain ranking and a coarser ``resolution`` read
    voxels where they lie and are refused. ``progress(phase, fraction)`` hears the tasks done
    of all (with the refinement, whose steps are not known ahead, of all foreseen: one more
    step while it goes on), never less than before."""

    array, held_type, stored, reader = _as_xyz(source, axes)
    geometry = _geometry(spacing, affine, stored)
    spacing = tuple(geometry.spacing)
    nz, ny, nx = array.shape
    # Each chunk is read into its layer of whole planes, once in the whole call where the
    # array fits the workers' memory (held until the partition's last round has taken its
    # boxes from them), else once a round (design.md).
    layers = _Layers(client, array, reader)
    bounds = layers.bounds
    try:
        with layers.round() as current:
            low, high, finite = _range(client, current)
        grid: Grid = ([nx, ny, nz], list(spacing), held_type, (float(low), float(high), int(finite)))
        cells = max(nz - 1, 1)
        cuts = sorted({min(b, cells) for _, b in bounds} | {0, cells})
        # The cell planes of each layer, which a round's slabs join (none with an axis given
        # and no view search asked for).
        slabs = [(a, b) for a, b in zip(cuts, cuts[1:]) if b > a] if slabscope._slabscope._runs_search(**params) else []
        return _rounds(client, layers, _Slabs(client, slabs, grid, params), grid, geometry, params, progress)
    finally:
        layers.release()


class _Slabs:
    """The slabs of the view search's rounds: the chunk layers' cell planes joined into as few
    slabs as keep the cluster's threads at work within a task's budget (``_view_slabs``), for
    each round as its counts weigh, with the voxel planes each slab's task holds (a slab's
    planes taken from its layers are cut out once for the call where the layers are kept)."""

    def __init__(self, client: Any, layers: List[Planes], grid: Grid, params: Options) -> None:
        self.layers, self.grid, self.params = layers, grid, params
        self.tasks = max(sum(client.nthreads().values()), 1)
        self.threads = int(params.get("threads") or max(client.run(_threads).values(), default=1))
        # The smallest worker's task budget, unless one is given.
        budgets = [b for b in client.run(_worker_budget).values() if b is not None]
        given = params.get("max_memory") is not None or not budgets
        self.budgeted = params if given else {**params, "max_memory": min(budgets)}
        self.shifted = bool(slabscope._slabscope._slab_planes([], *grid, **params)[1])

    def __bool__(self) -> bool:
        return bool(self.layers)

    def of(self, samples: Optional[List[int]] = None, axes: Optional[List[Any]] = None) -> Tuple[List[Planes], List[Planes]]:
        """The slabs of the round ``(samples, axes)`` and the voxel planes each holds."""
        slabs = slabscope._slabscope._view_slabs(self.layers, self.tasks, self.threads, *self.grid, samples=samples, axes=axes, **self.budgeted)
        held, _ = slabscope._slabscope._slab_planes(slabs, *self.grid, **self.params)
        return slabs, held


def _rounds(
    client: Any,
    layers: "_Layers",
    planned: _Slabs,
    grid: Grid,
    geometry: Any,
    params: Options,
    progress: Any,
) -> Any:
    """The view search's rounds of tasks, then the background's and the partition's, reporting
    to ``progress``."""
    shifted = planned.shifted
    slabs = planned.of() if planned else ([], [])
    step = len(slabs[0]) * (2 if shifted else 1)
    refine = bool(params.get("refine")) and bool(planned)
    # Tasks foreseen and not yet done: the sphere's rounds, the background's three rounds of a
    # task a layer (a found one's), the partition's two of a task a strip (as many as layers),
    # the analysis and, with the refinement, its first step (another foreseen as each step
    # starts, the one never taken dropped at its end).
    after = (_BACKGROUND_ROUNDS[_background_rule(params)] + 2) * len(layers)
    ahead = [step + after + 1 + (step if refine else 0)]
    done = [0]
    heard = [0.0]

    def report(phase: str = "view search in parts") -> None:
        done[0] += 1
        ahead[0] -= 1
        heard[0] = 1.0 if ahead[0] <= 0 else max(heard[0], done[0] / (done[0] + ahead[0]))
        if progress is not None:
            progress(phase, heard[0])

    def end(views: Tuple[Any, Any, List[Tuple[Any, Any, Any]]]) -> Any:
        whole = _after_views(client, layers, grid, geometry, views, params, report)
        ahead[0] = 1
        report("partition in parts")
        return whole

    def planned_for(samples: Optional[List[int]], axes: Optional[List[Any]] = None) -> Tuple[List[Planes], List[Planes]]:
        # A round weighed apart may be split more finely than the paper's: its further tasks
        # foreseen.
        these = planned.of(samples, axes)
        ahead[0] += len(these[0]) - len(slabs[0])
        return these

    if not planned:
        return end((None, None, []))
    paper = _round(client, layers, slabs, grid, (None, None), params, report)
    # The shifted lattices the paper round did not count (guessed wrong, or not guessed: a
    # small volume), a second round where there are any.
    more = None
    samples = slabscope._slabscope._shifted_samples(paper, *grid, **params)
    if samples is not None:
        if not shifted:
            ahead[0] += len(slabs[0])
        more = _round(client, layers, planned_for(samples), grid, (samples, None), params, report)
    elif shifted:
        ahead[0] -= len(slabs[0])
    refined: List[Tuple[Any, Any, Any]] = []
    if refine:

        def count(axes: List[Tuple[float, float, float]], samples: Optional[List[int]]) -> Any:
            if samples is None:
                ahead[0] += step
            elif not shifted:
                ahead[0] += len(slabs[0])
            total = _round(client, layers, planned_for(samples, axes), grid, (samples, axes), params, lambda: report("refining in parts"))
            refined.append((axes, samples, total))
            return total

        dims, spacing, held_type, range_ = grid
        slabscope._slabscope._refine_in_parts(paper, dims, spacing, held_type, range_, count, shifted=more, **params)
        ahead[0] -= step
    return end((paper, more, refined))


def _background_rule(params: Options) -> str:
    """The background rule the analysis keywords name, as the library reads ``background=``:
    ``auto`` (the default: three rounds of a task a layer), ``none``, or ``value`` (a
    threshold: one round, counting the voxels at or below it)."""
    rule = params.get("background")
    word = "auto" if rule is None else str(rule).strip()
    return word if word in ("auto", "none") else "value"


#: The background's rounds of a task a layer, by its rule.
_BACKGROUND_ROUNDS = {"auto": 3, "value": 1, "none": 0}

#: What the background's rounds give: a found background's threshold (None: no background, or
#: another rule), each layer's mask and voxel count (futures where they were made), and how
#: many voxels the background holds in all.
Found = Tuple[Optional[float], List[Any], int]


def _after_views(
    client: Any,
    layers: _Layers,
    grid: Grid,
    geometry: Any,
    views: Tuple[Any, Any, List[Tuple[Any, Any, Any]]],
    params: Options,
    report: Callable[[str], None],
) -> Any:
    """The background's rounds, then the partition's, then the analysis."""
    found = _background(client, layers, grid, params, lambda: report("background in parts"))
    try:
        return _partition(client, layers, grid, geometry, views, found, params, lambda: report("partition in parts"))
    finally:
        for future in found[1]:
            future.release()


def _background(client: Any, layers: _Layers, grid: Grid, params: Options, report: Callable[[], None]) -> Found:
    """The background by the rule the keywords name, in rounds of a task a layer. A found one
    (the default) in three: each layer's border values, the summary of its components at or
    below the threshold they give (the client joining the summaries), its mask. A threshold's
    in one: each layer's voxels at or below it, counted for the fraction."""
    dims, _, _, range_ = grid
    rule = _background_rule(params)
    starts = [a for a, _ in layers.bounds]

    def each(task: Callable[..., Any], *given: Any) -> List[Any]:
        with layers.round() as current:
            futures = [client.submit(task, layer, a, grid, params, *given, pure=False) for layer, a in zip(current, starts)]
            done = []
            for future in futures:
                done.append(future.result())
                report()
            return done

    if rule == "none":
        return None, [], 0
    if rule == "value":
        return None, [], sum(each(_below))
    threshold = slabscope._slabscope._background_threshold(each(_border), dims, (range_[0], range_[1]))
    if threshold is None:
        for _ in range(2 * len(layers)):
            report()
        return None, [], 0
    answers = dict(slabscope._slabscope._background_answers(each(_labelled, threshold), dims))
    with layers.round() as current:
        masks = [client.submit(_labelled, layer, a, grid, params, threshold, answers[a], pure=False) for layer, a in zip(current, starts)]
        count = 0
        for future in masks:
            count += client.submit(_second, future, pure=False).result()  # a refusal raises here
            report()
    return threshold, masks, count


def _second(pair: Tuple[Any, Any]) -> Any:
    """The second of a pair (a task where the pair is held: a mask's count, not its bits)."""
    return pair[1]


def _border(layer: np.ndarray, z0: int, grid: Grid, params: Options) -> bytes:
    """A task: a layer's ([z, y, x], from plane ``z0``) finite values on the volume's faces."""
    dims, _, held_type, _ = grid
    values: bytes = slabscope._slabscope._layer_border(layer.T, z0, dims, held_type)
    return values


def _below(layer: np.ndarray, z0: int, grid: Grid, params: Options) -> int:
    """A task: how many of a layer's voxels are at or below the threshold ``background=``
    gives."""
    count: int = slabscope._slabscope._layer_below(layer.T, grid[2], **params)
    return count


def _labelled(layer: np.ndarray, z0: int, grid: Grid, params: Options, threshold: float, answer: Optional[bytes] = None) -> Any:
    """A task: a layer's summary of its components at or below ``threshold`` (``answer``
    None), or its mask and count given the client's answer; labelling within half its
    worker's Dask memory limit unless ``max_memory`` is given."""
    dims, _, held_type, _ = grid
    budget = _with_budget({"max_memory": params.get("max_memory")})["max_memory"]
    ext = slabscope._slabscope
    if answer is None:
        return ext._layer_summary(layer.T, z0, dims, held_type, threshold, max_memory=budget)
    return ext._layer_mask(layer.T, z0, dims, held_type, threshold, answer, max_memory=budget)


def _partition(
    client: Any,
    layers: _Layers,
    grid: Grid,
    geometry: Any,
    views: Tuple[Any, Any, List[Tuple[Any, Any, Any]]],
    background: Found,
    params: Options,
    report: Callable[[], None],
) -> Any:
    """The partition in two rounds of a task a strip of the slice stack's rows (as many strips
    as layers): the first's tasks gathering the box of voxels their rows read from the layers
    they cross (with their background masks) and keeping their strips' runs, the second's
    reading those runs (:func:`_second_pass`), the client adding the parts as they come; then the
    analysis, on the client, of a volume holding no voxel."""
    dims, _, held_type, range_ = grid
    split = slabscope._slabscope.PartitionSplit(geometry, dims, held_type, range_, *views, **params)
    strips = split.strips(len(layers), layers.bounds)
    near = [[background[1][k] for k, _, _ in boxes] if background[1] else [] for _, boxes in strips]
    told = (split.axis, grid, background[0], params)
    total, kept = _first_pass(client, layers, strips, near, told, report)
    try:
        slabs = split.slabs(total, (background[0], background[2]))
        joints = None
        if len(slabs) > 1:
            joints = _second_pass(client, layers, strips, near, told, slabs, kept, report)
        else:
            for _ in strips:
                report()
    finally:
        for future in kept:
            future.release()
    return split.analysis(joints, "array", **params)


def _box_of(layer: np.ndarray, z: Planes, y: Planes, x: Planes) -> np.ndarray:
    """The voxels of a layer ([z, y, x]) in a box (a task where the layer is held: the box
    travels, not the layer)."""
    return np.ascontiguousarray(layer[z[0] : z[1], y[0] : y[1], x[0] : x[1]])


#: What every strip's task is told: the axis, the grid, the background's threshold and the
#: analysis keywords.
Told = Tuple[Tuple[float, float, float], Grid, Optional[float], Options]


#: A strip as ``PartitionSplit.strips`` names it: its rows, and its boxes of voxels, one a
#: layer it reads (the layer's index, the box's origin and size, x y z).
Strip = Tuple[Planes, List[Tuple[int, List[int], List[int]]]]


@contextmanager
def _boxes(client: Any, layers: _Layers, strips: List[Strip]) -> Iterator[List[List[Any]]]:
    """For each strip, the futures of its boxes cut from the layers it reads (where they lie,
    for this pass: released as it ends, so that the workers hold one pass's boxes at most
    beside the layers)."""
    with layers.round() as current:
        pieces = []
        for _, boxes in strips:
            these = []
            for k, (x0, y0, z0), (sx, sy, sz) in boxes:
                a = layers.bounds[k][0]
                these.append(client.submit(_box_of, current[k], (z0 - a, z0 - a + sz), (y0, y0 + sy), (x0, x0 + sx), pure=False))
            pieces.append(these)
        try:
            yield pieces
        finally:
            for these in pieces:
                for future in these:
                    future.release()


def _held(strip: Strip, layers: _Layers) -> List[Tuple[Planes, List[int], List[int]]]:
    """A strip's boxes as its task is told of them: each with its layer's planes."""
    return [(layers.bounds[k], origin, size) for k, origin, size in strip[1]]


def _first_pass(
    client: Any,
    layers: _Layers,
    strips: List[Strip],
    near: List[List[Any]],
    told: Told,
    report: Callable[[], None],
) -> Tuple[Any, List[Any]]:
    """The partition's first pass: a task a strip, given its boxes and the masks of the layers
    they come from, its counts added on the client as they come. Each task keeps its strip's
    runs where it ran (when they take no more memory than its voxels), so that the second pass
    reads them instead of the voxels: the futures of the tasks' (counts, runs) come back with
    the sum, for the caller to release."""
    with _boxes(client, layers, strips) as pieces:
        kept = []
        for strip, these, masks in zip(strips, pieces, near):
            kept.append(client.submit(_strip_keeping, strip[0], _held(strip, layers), told, masks, *these, pure=False))
        try:
            return _sum([client.submit(_first, pair, pure=False) for pair in kept], report), kept
        except BaseException:
            for future in kept:
                future.release()
            raise


def _second_pass(
    client: Any,
    layers: _Layers,
    strips: List[Strip],
    near: List[List[Any]],
    told: Told,
    slabs: List[Planes],
    kept: List[Any],
    report: Callable[[], None],
) -> Any:
    """The partition's second pass, the joint histograms of consecutive ``slabs``: from each
    strip's runs where its first task kept them, else (they took more memory than its voxels)
    from its boxes cut again; added on the client as they come."""
    has = client.gather([client.submit(_has_runs, pair, pure=False) for pair in kept])
    tasks = [client.submit(_joints_of, pair, slabs, told[3], pure=False) for pair, h in zip(kept, has) if h]
    again = [k for k, h in enumerate(has) if not h]
    if not again:
        return _sum(tasks, report)
    with _boxes(client, layers, [strips[k] for k in again]) as pieces:
        for k, these in zip(again, pieces):
            tasks.append(client.submit(_strip, strips[k][0], _held(strips[k], layers), told, near[k], slabs, *these, pure=False))
        return _sum(tasks, report)


def _first(pair: Tuple[Any, Any]) -> Any:
    """The first of a pair (a task where the pair is held: a strip's counts, not its runs)."""
    return pair[0]


def _has_runs(pair: Tuple[Any, Any]) -> bool:
    """Whether a strip's first task kept its runs."""
    return pair[1] is not None


def _joints_of(pair: Tuple[Any, Any], slabs: List[Planes], params: Options) -> Any:
    """One task, where a strip's runs are held: its second-pass counts from them."""
    return slabscope._slabscope._strip_joints(pair[1], slabs, **_with_budget(params))


def _strip_keeping(rows: Planes, held: List[Tuple[Planes, List[int], List[int]]], told: Told, masks: List[Tuple[bytes, int]], *pieces: np.ndarray) -> Any:
    """One task: a strip's first-pass counts and its runs (or None), as :func:`_strip` is
    given them."""
    return _strip_counted(slabscope._slabscope._count_strip_keeping, rows, held, told, masks, pieces)


def _strip(rows: Planes, held: List[Tuple[Planes, List[int], List[int]]], told: Told, masks: List[Tuple[bytes, int]], slabs: List[Planes], *pieces: np.ndarray) -> Any:
    """One task: a strip's second-pass counts, given ``slabs``, from its boxes of voxels
    (``pieces``, each [z, y, x], a layer's planes, origin and size in ``held``) and the masks of
    the layers it reads, within half its worker's Dask memory limit unless ``max_memory`` is
    given."""
    return _strip_counted(slabscope._slabscope._count_strip, rows, held, told, masks, pieces, slabs)


def _strip_counted(count: Callable[..., Any], rows: Planes, held: List[Tuple[Planes, List[int], List[int]]], told: Told, masks: List[Tuple[bytes, int]], pieces: Tuple[np.ndarray, ...], *more: Any) -> Any:
    """``count`` (the extension's count of a strip) given a strip's boxes' voxels one after
    another, its boxes, rows, axis, grid and background, then ``more``."""
    axis, grid, threshold, params = told
    dims, spacing, held_type, range_ = grid
    voxels = np.concatenate([p.ravel() for p in pieces]) if pieces else np.zeros(0, dtype=held_type)
    bits = [mask for mask, _ in masks]
    return count(voxels, held, rows, axis, dims, spacing, held_type, range_, (threshold, bits), *more, **_with_budget(params))
