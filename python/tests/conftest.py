"""Fixtures of the Python suite: the repository's test data, the `slabscope` binary whose JSON the
package must reproduce, and volumes the binary writes.

The binary is `$SLABSCOPE_BIN`, else the repository's release or debug build. Without one the
comparisons with the CLI are skipped, except under `CI=true`, where that is a failure."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data"
BAD = ROOT / "tests" / "bad"


def _binary() -> str | None:
    given = os.environ.get("SLABSCOPE_BIN")
    if given:
        return given
    for profile in ("release", "debug"):
        for target in (os.environ.get("CARGO_TARGET_DIR"), ROOT / "target"):
            if target and (Path(target) / profile / "slabscope").is_file():
                return str(Path(target) / profile / "slabscope")
    return shutil.which("slabscope")


@pytest.fixture(scope="session")
def cli():
    """Runs the CLI; returns its standard output (the command must succeed)."""
    binary = _binary()
    if binary is None:
        message = "no slabscope binary: build it (cargo build --release) or set SLABSCOPE_BIN"
        if os.environ.get("CI") == "true":
            pytest.fail(message)
        pytest.skip(message)

    def run(*args: str) -> str:
        done = subprocess.run([binary, *args], capture_output=True, text=True, check=False)
        assert done.returncode in (0, 1), done.stderr
        return done.stdout

    run.binary = binary
    return run


@pytest.fixture(scope="session")
def cli_json(cli):
    """The JSON object a CLI command prints."""
    return lambda *args: json.loads(cli(*args))


@pytest.fixture(scope="session")
def phantoms(cli, tmp_path_factory):
    """Phantoms the CLI writes: a CT-like body (i16 NIfTI) and layers (u8 NRRD)."""
    folder = tmp_path_factory.mktemp("phantoms")
    body = folder / "body.nii"
    layers = folder / "layers.nrrd"
    big = folder / "big.nrrd"
    cli("phantom", "body", "--dims", "40x40x56", "-o", str(body))
    cli("phantom", "layers", "--size", "32", "-o", str(layers))
    cli("phantom", "body", "--dims", "96x96x128", "-o", str(big))
    return {"body": body, "layers": layers, "big": big, "folder": folder}


@pytest.fixture(scope="session")
def client():
    """A distributed.LocalCluster of two worker processes and its client, for the Dask tests
    (which skip themselves without Dask, except under `CI=true`)."""
    from distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, memory_limit="2GiB", dashboard_address=None) as cluster:
        with Client(cluster) as client:
            yield client


def pytest_sessionfinish(session, exitstatus):
    """Under `CI=true` a skipped test fails the run: CI installs everything the suite uses."""
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    skipped = len(reporter.stats.get("skipped", [])) if reporter else 0
    if os.environ.get("CI") == "true" and skipped and exitstatus == 0:
        session.exitstatus = 1
        if reporter:
            reporter.write_line(f"CI=true: {skipped} tests skipped, which fails the run", red=True)


def run_mypy(tmp_path: Path, *args: str) -> str:
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
