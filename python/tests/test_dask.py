"""slabscope.dask on a real distributed.LocalCluster of two worker processes: its rows are the
CLI's `triage --json` rows. Dask is optional: without it the test is skipped, except under
`CI=true`, where that is a failure."""

from __future__ import annotations

import json
import os
import shutil

import pytest

from conftest import BAD, DATA

if os.environ.get("CI") == "true":
    import distributed  # noqa: F401  (a failure, not a skip, in CI)
else:
    pytest.importorskip("distributed")

import slabscope
import slabscope.dask


def test_a_cluster_gives_the_cli_rows(client, cli, tmp_path):
    for name in ["ramp_u8.nii", "ramp_i16.mha", "ramp_u16_be.nrrd", "nilearn_image_10426.nii.gz"]:
        shutil.copy(DATA / name, tmp_path / name)
    shutil.copy(BAD / "truncated.nrrd", tmp_path / "truncated.nrrd")
    rows = slabscope.dask.triage(client, str(tmp_path), slabs=2)
    expected = [json.loads(line) for line in cli("triage", str(tmp_path), "--json", "--slabs", "2").splitlines()]
    assert rows == expected
    assert len(rows) == 5 and sum(r["error"] is not None for r in rows) == 1
    workers = client.run(lambda: os.getpid())
    assert len(set(workers.values())) == 2, "two worker processes"


def test_each_task_gets_half_its_workers_memory_limit(client):
    workers = list(client.scheduler_info()["workers"])
    budgets = client.gather([client.submit(slabscope.dask._budget, workers=[w], pure=False) for w in workers])
    assert budgets == [1 << 30, 1 << 30]


def test_analyses_on_a_cluster_are_the_reports(client, cli):
    paths = [str(DATA / "ramp_i16.nii"), str(DATA / "ramp_u8.nii"), str(BAD / "truncated.nrrd")]
    reports = slabscope.dask.analyze(client, paths, slabs=2)
    assert reports[0] == json.loads(cli("analyze", paths[0], "--json", "--slabs", "2"))
    assert reports[1] == json.loads(cli("analyze", paths[1], "--json", "--slabs", "2"))
    assert reports[2]["file"] == paths[2] and "truncated voxel data" in reports[2]["error"]


def test_volumes_and_analyses_travel_to_and_from_worker_processes(client, cli_json):
    import numpy as np

    path = str(DATA / "ramp_i16.nii")
    # A volume a worker read comes back (as its path, read again here).
    volume = client.submit(slabscope.load, path, pure=False).result()
    assert isinstance(volume, slabscope.Volume) and volume.shape == (5, 4, 3) and volume.orientation == "RAS"
    # An analysis made on a worker comes back whole: its report, its labels, drawn with the volume
    # read here.
    analysis = client.submit(lambda p: slabscope.analyze(slabscope.load(p), slabs=2), path, pure=False).result()
    assert analysis.to_dict() == cli_json("analyze", path, "--json", "--slabs", "2")
    local = slabscope.analyze(volume, slabs=2)
    assert np.array_equal(analysis.labels(), local.labels())
    size = {"size": (48, 32)}
    assert slabscope.render(volume, analysis, **size).png() == slabscope.render(volume, local, **size).png()
    # A volume sent to a worker: read from its path there, or carried with its voxels.
    array = np.asfortranarray(np.arange(8 * 9 * 10, dtype=np.float32).reshape(8, 9, 10))
    sent = [volume, volume.carrying_voxels(), slabscope.Volume.from_array(array)]
    shapes = client.gather([client.submit(lambda v: (v.shape, float(v.array.sum())), v, pure=False) for v in sent])
    assert shapes == [((5, 4, 3), float(volume.array.sum()))] * 2 + [((8, 9, 10), float(array.sum()))]
