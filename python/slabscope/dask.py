"""slabscope on a Dask cluster: triage or analysis of many volumes, one task per volume.

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

from typing import Any, Optional, Sequence

import slabscope

__all__ = ["triage", "analyze", "LOAD_KEYWORDS"]

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
