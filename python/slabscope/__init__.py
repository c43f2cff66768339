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

import functools
import inspect
from typing import TYPE_CHECKING, Any, Callable, Iterable

from ._slabscope import (
    SCHEMA_VERSION,
    Analysis,
    Image,
    Triage,
    ViewPart,
    Volume,
    VolumeError,
    __version__,
    analyze,
    list_volumes,
    load,
    parameters,
    render,
    triage,
)
from ._slabscope import slice as slice  # exported, though not by `import *` (see __all__)

# `slice` is left out: `from slabscope import *` would shadow the builtin. `slabscope.slice` and
# `from slabscope import slice` work.
__all__ = [
    "SCHEMA_VERSION",
    "Analysis",
    "Image",
    "Triage",
    "ViewPart",
    "Volume",
    "VolumeError",
    "__version__",
    "analyze",
    "list_volumes",
    "load",
    "parameters",
    "render",
    "triage",
    "triage_frame",
]


def triage_frame(paths: Any = None, **options: Any) -> Any:
    """The rows of :func:`triage` as a pandas DataFrame, one row a volume (pandas needed)."""
    try:
        import pandas
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("triage_frame needs pandas: pip install pandas") from e
    rows: Iterable[dict] = triage(paths, **options)
    return pandas.DataFrame(list(rows))


def _signed(call: Callable[..., Any], *positional: tuple[str, Any]) -> Callable[..., Any]:
    """`call` with a signature that lists its keywords and their defaults, from the library's
    table of parameters (the CLI's flags are made from the same table), so that ``help()``,
    Jupyter and IDEs show them. The package's own keywords (``explain``, ``manifest``,
    ``entries``) stay in ``**options``, as the call's docstring says."""
    kind = inspect.Parameter
    params = [kind(name, kind.POSITIONAL_OR_KEYWORD, default=d) for name, d in positional]
    params += [
        kind(p["keyword"], kind.KEYWORD_ONLY, default=p["default"])
        for p in parameters(call.__name__)
    ]
    params.append(kind("options", kind.VAR_KEYWORD))

    @functools.wraps(call)
    def signed(*args: Any, **kwargs: Any) -> Any:
        return call(*args, **kwargs)

    signed.__signature__ = inspect.Signature(params)  # type: ignore[attr-defined]
    signed.__module__ = __name__
    return signed


if not TYPE_CHECKING:
    _REQUIRED = inspect.Parameter.empty
    load = _signed(load, ("path", _REQUIRED))
    analyze = _signed(analyze, ("volume", _REQUIRED), ("progress", None))
    render = _signed(render, ("volume", _REQUIRED), ("analysis", None), ("progress", None))
    slice = _signed(
        slice, ("volume", _REQUIRED), ("analysis", None), ("index", None), ("progress", None)
    )
    triage = _signed(triage, ("paths", None))
    list_volumes = _signed(list_volumes, ("paths", None))
