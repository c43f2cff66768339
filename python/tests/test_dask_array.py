"""slabscope.dask.analyze_array on a real distributed.LocalCluster of two worker processes: one
volume's view search counted by tasks over its chunks, its parts added on the client, gives the
analysis one process gives, `to_dict()` equal. Skipped without Dask, except under `CI=true`."""

from __future__ import annotations

import os
import pickle

import numpy as np
import pytest

if os.environ.get("CI") == "true":
    import distributed  # noqa: F401  (a failure, not a skip, in CI)
else:
    pytest.importorskip("distributed")

import dask.array as da

import slabscope
import slabscope.dask


def voxels() -> np.ndarray:
    """A 30×26×37 volume indexed [z, y, x] of layers along a tilted axis, with noise and a
    border of air, so that the automatic background finds something."""
    z, y, x = np.meshgrid(np.arange(37), np.arange(26), np.arange(30), indexing="ij")
    rng = np.random.default_rng(44)
    values = ((x * 3 + y * 2 + z * 5) // 23 % 5) * 40.0 + rng.integers(0, 9, size=x.shape)
    values[:, :2] = 0
    values[:, :, -2:] = 0
    return values.astype(np.uint8)


@pytest.mark.parametrize("params", [{"phases": 0, "background": "none"}, {}])
def test_one_volume_across_the_cluster_is_the_single_process_analysis(client, params):
    zyx = voxels()
    spacing = (1.0, 0.9, 1.3)
    heard = []
    got = slabscope.dask.analyze_array(
        client,
        da.from_array(zyx, chunks=(8, 13, 30)),
        axes="zyx",
        spacing=spacing,
        progress=lambda phase, fraction: heard.append(fraction),
        slabs=3,
        **params,
    )
    one = slabscope.analyze(slabscope.Volume.from_array(zyx.T, spacing=spacing), slabs=3, **params)
    assert got.to_dict() == one.to_dict()
    slabs = 5  # chunks of 8 planes along z over 36 planes of cells
    assert heard[-1] == 1.0 and len(heard) == slabs * (2 if not params else 1) + 1
    assert heard == sorted(heard)


def test_axes_in_another_order_and_a_zarr_store(client, tmp_path):
    zarr = pytest.importorskip("zarr")
    zyx = voxels()
    store = str(tmp_path / "v.zarr")
    stored = zarr.open_array(store, mode="w", shape=zyx.shape, chunks=(10, 26, 30), dtype=zyx.dtype)
    stored[:] = zyx
    one = slabscope.analyze(slabscope.Volume.from_array(zyx.T), phases=0, background="none").to_dict()
    from_store = slabscope.dask.analyze_array(client, store, phases=0, background="none")
    assert from_store.to_dict() == one
    xyz = da.from_array(np.ascontiguousarray(zyx.T), chunks=(30, 26, 9))
    assert slabscope.dask.analyze_array(client, xyz.transpose(2, 1, 0), axes="zyx", phases=0, background="none").to_dict() == one
    assert slabscope.dask.analyze_array(client, da.from_array(zyx.transpose(1, 0, 2)), axes="yzx", phases=0, background="none").to_dict() == one


def test_axes_are_never_assumed_and_the_refinement_is_refused(client):
    array = da.from_array(voxels())
    with pytest.raises(ValueError, match="never assumed"):
        slabscope.dask.analyze_array(client, array)
    with pytest.raises(ValueError, match="refine"):
        slabscope.dask.analyze_array(client, array, axes="zyx", refine=True)


def test_view_parts_add_and_pickle():
    zyx = voxels()
    nz, ny, nx = zyx.shape
    grid = ([nx, ny, nz], [1.0, 1.0, 1.0], "uint8", (float(zyx.min()), float(zyx.max()), zyx.size))
    parts = []
    for planes in [(0, 20), (20, 36)]:
        first, end, _ = slabscope._slabscope._slab_planes(planes, *grid, phases=0)
        parts.append(slabscope._slabscope._count_view_slab(zyx[first:end].T, first, planes, *grid, phases=0))
    assert not parts[0].complete and not parts[1].complete
    back = pickle.loads(pickle.dumps(parts[1]))
    total = parts[0] + back
    assert total.complete and total.round == 0
    volume = slabscope.Volume.from_array(zyx.T)
    got = slabscope._slabscope._analyze_with_parts(volume, total, None, phases=0, background="none")
    assert got.to_dict() == slabscope.analyze(volume, phases=0, background="none").to_dict()
