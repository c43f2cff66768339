"""slabscope: similarity-based exploded views of 3D volumes (Ruiz et al., 2008).

Find a volume's most structured view (the axis of lowest entropy rate), cut it into slabs across
that axis, and draw the slabs pulled apart. The calls mirror the ``slabscope`` command line: its
flags are keyword arguments with the same names and defaults (``--slabs 4`` is ``slabs=4``,
``--no-shading`` is ``no_shading=True``; ``--type`` is ``dtype``).

>>> import slabscope
>>> volume = slabscope.load("head.nii.gz")               # doctest: +SKIP
>>> analysis = slabscope.analyze(volume, slabs=5)        # doctest: +SKIP
>>> slabscope.render(volume, analysis)                   # doctest: +SKIP
"""

from __future__ import annotations

from typing import Any, Iterable

from ._slabscope import (
    SCHEMA_VERSION,
    Analysis,
    Image,
    Triage,
    Volume,
    VolumeError,
    __version__,
    analyze,
    list_volumes,
    load,
    render,
    slice,
    triage,
)

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
    "render",
    "slice",
    "triage",
    "triage_frame",
]


def triage_frame(paths: Any = None, **options: Any):
    """The rows of :func:`triage` as a pandas DataFrame, one row a volume (pandas needed)."""
    try:
        import pandas
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("triage_frame needs pandas: pip install pandas") from e
    rows: Iterable[dict] = triage(paths, **options)
    return pandas.DataFrame(list(rows))
