"""slabscope.dask.analyze_array on dask-jobqueue's SLURMCluster: two Dask workers, each a SLURM
job on the one-node SLURM that `.ci/slurm-cluster` starts (the one the shard recipe's test runs
on), give the single process's analysis of a volume of a few hundred chunks, by the paper's
method and by the defaults.

Skipped without dask-jobqueue or SLURM (slurmctld, munged), except under `CI=true`, where
`.ci/run` installs both and a skip is a failure. A SLURM already reached through `$SLURM_CONF`
is used as it is; otherwise the test starts its own and stops it."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from conftest import ROOT

CI = os.environ.get("CI") == "true"


def _require(found: bool, message: str) -> None:
    if not found:
        if CI:
            pytest.fail(message)
        pytest.skip(message)


@pytest.fixture(scope="module")
def slurm(tmp_path_factory):
    """A SLURM that `sbatch` reaches: `$SLURM_CONF`'s, else one `.ci/slurm-cluster` starts."""
    if os.environ.get("SLURM_CONF"):
        yield os.environ["SLURM_CONF"]
        return
    script = ROOT / ".ci" / "slurm-cluster"
    installed = all(shutil.which(t) or Path("/usr/sbin", t).exists() for t in ("slurmctld", "slurmd", "munged", "sbatch"))
    _require(installed and script.exists(), "no SLURM: slurmctld, slurmd, munged and sbatch (Debian's slurm-wlm and munge; `.ci/slurm-cluster install`) and the repository's .ci/slurm-cluster")
    work = tmp_path_factory.mktemp("slurm")
    path = os.environ["PATH"]
    os.environ["PATH"] = f"{path}:/usr/sbin"
    done = subprocess.run([str(script), "start", str(work)], capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stdout + done.stderr
    os.environ["SLURM_CONF"] = str(work / "slurm.conf")
    try:
        yield os.environ["SLURM_CONF"]
    finally:
        subprocess.run([str(script), "stop", str(work)], check=False)
        del os.environ["SLURM_CONF"]
        os.environ["PATH"] = path


@pytest.fixture(scope="module")
def slurm_client(slurm, tmp_path_factory):
    """A Dask client of two workers, each a SLURM job of one core and 2 GiB (a Dask memory
    limit; the node declares no memory to SLURM, so no --mem is asked)."""
    try:
        import dask_jobqueue
        from distributed import Client
    except ImportError as e:
        _require(False, f"no dask-jobqueue ({e}): pip install dask-jobqueue")
    logs = tmp_path_factory.mktemp("slurm-logs")
    with dask_jobqueue.SLURMCluster(
        cores=1,
        processes=1,
        memory="2GiB",
        walltime="00:20:00",
        python=sys.executable,
        job_directives_skip=["--mem"],
        log_directory=str(logs),
        scheduler_options={"host": "127.0.0.1", "dashboard_address": None},
    ) as cluster:
        cluster.scale(jobs=2)
        with Client(cluster) as client:
            client.wait_for_workers(2, timeout=180)
            yield client


def voxels() -> np.ndarray:
    """A 96×80×72 volume indexed [z, y, x] of tilted layers with noise and a border of air."""
    z, y, x = np.meshgrid(np.arange(96), np.arange(80), np.arange(72), indexing="ij")
    rng = np.random.default_rng(4)
    values = ((x * 3 + y * 2 + z * 5) // 29 % 6) * 35.0 + rng.integers(0, 12, size=x.shape)
    values[:, :3] = 0
    values[:, :, -3:] = 0
    return values.astype(np.uint8)


@pytest.mark.parametrize("params", [{"phases": 0, "background": "none"}, {}], ids=["paper", "defaults"])
def test_one_volume_on_slurm_jobs_is_the_single_process_analysis(slurm_client, params):
    import dask.array as da

    import slabscope
    import slabscope.dask

    zyx = voxels()
    array = da.from_array(zyx, chunks=(8, 16, 18))  # 12 × 5 × 4: 240 chunks, 12 slabs along z
    assert array.npartitions == 240
    # The tasks ran on the SLURM jobs' workers.
    jobs = slurm_client.run(lambda: os.environ.get("SLURM_JOB_ID"))
    assert len(jobs) == 2 and all(jobs.values()) and len(set(jobs.values())) == 2
    got = slabscope.dask.analyze_array(slurm_client, array, axes="zyx", spacing=(1.0, 0.8, 1.2), **params)
    one = slabscope.analyze(slabscope.Volume.from_array(zyx.T, spacing=(1.0, 0.8, 1.2)), **params)
    assert got.to_dict() == one.to_dict()
