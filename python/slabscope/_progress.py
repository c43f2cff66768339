"""``progress=True``: a bar for each phase of a long call, tqdm's when it is installed, else one
line on stderr rewritten in place."""

from __future__ import annotations

import sys
from typing import Any

# Each phase fills the bar once: its percentage and time, no rate (the unit is a percent).
_FORMAT = "{desc}: {percentage:3.0f}%|{bar}| {elapsed}"


class Bar:
    """Called as ``progress(phase, fraction)``; ``close()`` ends the bar (or the line)."""

    def __init__(self) -> None:
        try:
            from tqdm import tqdm
        except ImportError:
            self._tqdm: Any = None
        else:
            self._tqdm = tqdm
        self._bar: Any = None
        self._phase: str | None = None
        self._shown = ""

    def __call__(self, phase: str, fraction: float) -> None:
        percent = max(0, min(100, round(fraction * 100)))
        if self._tqdm is not None:
            if self._bar is None:
                self._bar = self._tqdm(total=100, desc=phase, bar_format=_FORMAT)
            elif phase != self._phase:
                self._bar.set_description_str(phase, refresh=False)
                self._bar.reset(total=100)
            self._bar.update(percent - self._bar.n)
        else:
            line = f"{phase}: {percent:3d}%"
            if line != self._shown:
                sys.stderr.write("\r" + line.ljust(len(self._shown)))
                sys.stderr.flush()
                self._shown = line
        self._phase = phase

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None
        elif self._shown:
            sys.stderr.write("\n")
            sys.stderr.flush()
            self._shown = ""
