"""The stubs as a typed program sees them: `mypy --strict` on typed_examples.py (every call of the
package, its keywords and results) and `stubtest` on the extension module (the stubs say what the
module has). mypy is optional: without it the test is skipped, except under `CI=true`, where that is
a failure."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

if os.environ.get("CI") == "true":
    import mypy  # noqa: F401  (a failure, not a skip, in CI)
else:
    pytest.importorskip("mypy", reason="the typing checks need mypy: pip install mypy")

EXAMPLES = Path(__file__).resolve().parent / "typed_examples.py"


def mypy(tmp_path: Path, *args: str) -> str:
    """Runs a mypy tool in an empty folder (the installed package, not a source folder, is
    checked) with its cache there; returns its output, failing with it unless it succeeded."""
    done = subprocess.run(
        [sys.executable, "-m", *args],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        check=False,
        env={**os.environ, "MYPY_CACHE_DIR": str(tmp_path / "cache")},
    )
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout


def test_mypy_strict_accepts_every_call(tmp_path):
    out = mypy(tmp_path, "mypy", "--strict", str(EXAMPLES))
    assert "Success" in out


def test_stubtest_finds_the_stubs_true(tmp_path):
    out = mypy(tmp_path, "mypy.stubtest", "slabscope._slabscope")
    assert "Success" in out
