"""The stubs as a typed program sees them: `mypy --strict` on typed_examples.py (every call of the
package, its keywords and results), `stubtest` on the extension module (the stubs say what the
module has) and `mypy --strict` on `slabscope.dask`. mypy is optional: without it the test is
skipped, except under `CI=true`, where that is a failure."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from conftest import run_mypy

if os.environ.get("CI") == "true":
    import mypy  # noqa: F401  (a failure, not a skip, in CI)
else:
    pytest.importorskip("mypy", reason="the typing checks need mypy: pip install mypy")

EXAMPLES = Path(__file__).resolve().parent / "typed_examples.py"


def test_mypy_strict_accepts_every_call(tmp_path):
    out = run_mypy(tmp_path, "mypy", "--strict", str(EXAMPLES))
    assert "Success" in out


def test_stubtest_finds_the_stubs_true(tmp_path):
    out = run_mypy(tmp_path, "mypy.stubtest", "slabscope._slabscope")
    assert "Success" in out


def test_mypy_strict_accepts_the_dask_module(tmp_path):
    pytest.importorskip("distributed", reason="slabscope.dask's types need dask: pip install 'slabscope[dask]'")
    out = run_mypy(tmp_path, "mypy", "--strict", "-m", "slabscope.dask")
    assert "Success" in out
