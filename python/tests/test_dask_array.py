"""slabscope.dask.analyze_array on a real distributed.LocalCluster of two worker processes: one
volume's view search counted by tasks over its chunks, its parts added on the client, gives the
analysis one process gives, `to_dict()` equal. Skipped without Dask, except under `CI=true`."""

from __future__ import annotations

import os
import pickle
import re
import time
from typing import Any

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
        progress=lambda phase, fraction: heard.append((phase, fraction)),
        slabs=3,
        **params,
    )
    one = slabscope.analyze(slabscope.Volume.from_array(zyx.T, spacing=spacing), slabs=3, **params)
    assert got.to_dict() == one.to_dict()
    # Chunks of 8 planes along z: 5 layers, joined into 2 slabs of cells for the view search
    # (the cluster's two threads). The view search's rounds (two with phases), the found
    # background's three rounds of a task a layer, the partition's two passes of a task a strip
    # (5 strips), and the end.
    views, background = (2, 0) if params else (4, 15)
    assert [p for p, _ in heard] == ["view search in parts"] * views + ["background in parts"] * background + ["partition in parts"] * 11
    fractions = [f for _, f in heard]
    assert fractions[-1] == 1.0 and fractions.count(1.0) == 1 and fractions == sorted(fractions)


@pytest.mark.parametrize("holed, rounds", [(0, 1), (15, 2)], ids=["guessed", "guessed-wrong"])
def test_the_phases_counted_in_the_paper_round_on_the_cluster(client, holed, rounds):
    # With 4 bins the volume's box holds enough samples for the shifted lattices' largest
    # subset: they are counted in the paper's round, and no second round is needed, unless
    # missing voxels (planes of NaN) bring an axis's paper samples under it.
    zyx = voxels().astype(np.float32)
    zyx[:holed] = np.nan
    spacing = (1.0, 0.9, 1.3)
    heard = []
    params = {"bins": 4, "background": "none", "slabs": 2}
    got = slabscope.dask.analyze_array(
        client,
        da.from_array(zyx, chunks=(8, 13, 30)),
        axes="zyx",
        spacing=spacing,
        progress=lambda phase, fraction: heard.append((phase, fraction)),
        **params,
    )
    one = slabscope.analyze(slabscope.Volume.from_array(zyx.T, spacing=spacing), **params)
    assert got.to_dict() == one.to_dict()
    # A round is 2 slabs (5 layers joined for the cluster's two threads).
    assert [p for p, _ in heard].count("view search in parts") == 2 * rounds
    fractions = [f for _, f in heard]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0


def test_axes_in_another_order_and_a_zarr_store(client, tmp_path):
    zarr = pytest.importorskip("zarr")
    zyx = voxels()
    store = str(tmp_path / "v.zarr")
    stored = zarr.open_array(store, mode="w", shape=zyx.shape, chunks=(10, 26, 30), dtype=zyx.dtype)
    stored[:] = zyx
    one = slabscope.analyze(slabscope.Volume.from_array(zyx.T), phases=0, background="none").to_dict()
    with pytest.raises(ValueError, match="v.zarr: not an OME-Zarr group .* needs its axis order given with axes="):
        slabscope.dask.analyze_array(client, store, phases=0, background="none")
    with pytest.raises(ValueError, match="nowhere.zarr"):
        slabscope.dask.analyze_array(client, tmp_path / "nowhere.zarr")
    from_store = slabscope.dask.analyze_array(client, store, axes="zyx", phases=0, background="none")
    assert from_store.to_dict() == one
    xyz = da.from_array(np.ascontiguousarray(zyx.T), chunks=(30, 26, 9))
    assert slabscope.dask.analyze_array(client, xyz.transpose(2, 1, 0), axes="zyx", phases=0, background="none").to_dict() == one
    assert slabscope.dask.analyze_array(client, da.from_array(zyx.transpose(1, 0, 2)), axes="yzx", phases=0, background="none").to_dict() == one


def test_axes_are_never_assumed(client):
    array = da.from_array(voxels())
    with pytest.raises(ValueError, match="never assumed"):
        slabscope.dask.analyze_array(client, array)


@pytest.mark.parametrize("params", [{"phases": 0, "background": "none"}, {}], ids=["paper", "defaults"])
def test_the_refinement_as_rounds_of_tasks_is_the_single_process_analysis(client, params):
    zyx = voxels()
    heard = []
    got = slabscope.dask.analyze_array(
        client,
        da.from_array(zyx, chunks=(8, 13, 30)),
        axes="zyx",
        spacing=(1.0, 0.9, 1.3),
        refine=True,
        progress=lambda phase, fraction: heard.append((phase, fraction)),
        **params,
    )
    one = slabscope.analyze(slabscope.Volume.from_array(zyx.T, spacing=(1.0, 0.9, 1.3)), refine=True, **params)
    assert got.to_dict() == one.to_dict()
    assert got.to_dict()["refined"] is not None
    # The sphere's rounds, then at least two steps of the refinement, a round each of the
    # paper's lattices (and of the shifted ones with phases), 2 slabs a round (5 layers joined
    # for the cluster's two threads).
    rounds = 1 if params else 2
    phases = [p for p, _ in heard]
    assert phases[: 2 * rounds] == ["view search in parts"] * (2 * rounds)
    refining = phases.count("refining in parts")
    assert refining >= 2 * 2 * rounds and refining % (2 * rounds) == 0
    fractions = [f for _, f in heard]
    assert fractions == sorted(fractions) and fractions[-1] == 1.0 and fractions.count(1.0) == 1


def test_refined_rounds_out_of_order_are_refused(client):
    zyx = voxels()
    nz, ny, nx = zyx.shape
    grid = ([nx, ny, nz], [1.0, 1.0, 1.0], "uint8", (float(zyx.min()), float(zyx.max()), zyx.size))
    params = {"phases": 0, "refine": True}
    (held,), _ = slabscope._slabscope._slab_planes([(0, nz - 1)], *grid, **params)
    count = lambda samples, axes: slabscope._slabscope._count_view_slab(zyx[held[0] : held[1]].T, held[0], (0, nz - 1), *grid, samples=samples, axes=axes, **params)  # noqa: E731
    paper = count(None, None)
    asked = []

    def counted(axes, samples):
        part = count(samples, axes)
        asked.append((axes, samples, part))
        return part

    slabscope._slabscope._refine_in_parts(paper, *grid, counted, **params)
    assert len(asked) >= 2 and all(s is None and len(a) in (8, 16, 24) for a, s, _ in asked)
    assert {p.round for _, _, p in asked} == {2}
    volume = slabscope.Volume.from_array(zyx.T)
    got = slabscope._slabscope._analyze_with_parts(volume, paper, refined=asked, **params)
    assert got.to_dict() == slabscope.analyze(volume, **params).to_dict()
    with pytest.raises(ValueError, match="refined"):
        slabscope._slabscope._analyze_with_parts(volume, paper, refined=asked[::-1], **params)
    with pytest.raises(ValueError, match="refined"):
        slabscope._slabscope._analyze_with_parts(volume, paper, refined=asked[:-1], **params)
    with pytest.raises(ValueError, match="refine=True"):
        slabscope._slabscope._analyze_with_parts(volume, paper, refined=asked, phases=0)
    # A count that gives a part of the wrong round, or raises, stops the refinement with it.
    with pytest.raises(ValueError, match="round 0, not 2"):
        slabscope._slabscope._refine_in_parts(paper, *grid, lambda axes, samples: paper, **params)
    with pytest.raises(ZeroDivisionError):
        slabscope._slabscope._refine_in_parts(paper, *grid, lambda axes, samples: 1 / 0, **params)


def test_view_slabs_join_layers_for_the_threads_within_the_budget():
    """The view search's slabs: the chunk layers joined into as few slabs as the cluster's
    threads take, evenly, each within the task budget; thinner where they do not fit; the
    layers' own where none joined fits (each task then refuses, naming its slab)."""
    zyx = voxels()
    nz, ny, nx = zyx.shape
    grid = ([nx, ny, nz], [1.0, 1.0, 1.0], "uint8", (float(zyx.min()), float(zyx.max()), zyx.size))
    layers = [(0, 8), (8, 16), (16, 24), (24, 32), (32, 39)]
    view_slabs = slabscope._slabscope._view_slabs
    assert view_slabs(layers, 2, 1, *grid, phases=0) == [(0, 16), (16, 39)]
    assert view_slabs(layers, 1, 1, *grid, phases=0) == [(0, 39)]
    assert view_slabs(layers, 3, 1, *grid, phases=0) == [(0, 8), (8, 24), (24, 39)]
    assert view_slabs(layers, 8, 1, *grid, phases=0) == layers
    assert view_slabs([], 2, 1, *grid, phases=0) == []
    # What one task of each plan weighs (on one thread, as the plans are made for), from the
    # task's own refusal at a budget of a byte.
    def weighs(planes):
        (first, end), = slabscope._slabscope._slab_planes([planes], *grid, phases=0)[0]
        with pytest.raises(ValueError, match="beyond the task's budget") as refused:
            slabscope._slabscope._count_view_slab(zyx[first:end].T, first, planes, *grid, phases=0, threads=1, max_memory=1)
        return int(re.search(r"holds (\d+) bytes", str(refused.value)).group(1))

    whole, half, layer = weighs((0, 39)), weighs((16, 39)), weighs((32, 39))
    assert layer < half < whole
    # A budget the whole volume's slab exceeds and a half's meets: two slabs even for one thread.
    assert view_slabs(layers, 1, 1, *grid, phases=0, max_memory=whole - 1) == [(0, 16), (16, 39)]
    assert view_slabs(layers, 2, 1, *grid, phases=0, max_memory=layer) == layers
    assert view_slabs(layers, 2, 1, *grid, phases=0, max_memory=1) == layers


def test_view_parts_add_and_pickle():
    zyx = voxels()
    nz, ny, nx = zyx.shape
    grid = ([nx, ny, nz], [1.0, 1.0, 1.0], "uint8", (float(zyx.min()), float(zyx.max()), zyx.size))
    parts = []
    slabs = [(0, 20), (20, 36)]
    held, shifted = slabscope._slabscope._slab_planes(slabs, *grid, phases=0)
    assert held == [(0, 22), (19, 37)] and not shifted
    for planes, (first, end) in zip(slabs, held):
        parts.append(slabscope._slabscope._count_view_slab(zyx[first:end].T, first, planes, *grid, phases=0))
    assert not parts[0].complete and not parts[1].complete
    back = pickle.loads(pickle.dumps(parts[1]))
    total = parts[0] + back
    assert total.complete and total.round == 0
    # In place (`+=`, as the client adds a round's parts): the same sum, the part added left
    # as it was; parts of another version of slabscope are refused by name.
    inplace = pickle.loads(pickle.dumps(parts[0]))
    same = inplace
    inplace += back
    assert inplace is same and inplace.complete and not back.complete
    assert pickle.dumps(inplace) == pickle.dumps(total)
    with pytest.raises(ValueError, match="version 2 where this slabscope reads version 3"):
        slabscope._slabscope._view_part_of(0, [b"SLABPC\x00\x02" + bytes(8)])
    volume = slabscope.Volume.from_array(zyx.T)
    got = slabscope._slabscope._analyze_with_parts(volume, total, None, phases=0, background="none")
    assert got.to_dict() == slabscope.analyze(volume, phases=0, background="none").to_dict()


def ome_zarr(path, zyx: np.ndarray, axes: list, scale: list, version: str) -> None:
    """An OME-Zarr group at ``path`` (0.4 in Zarr format 2, or 0.5 in format 3) of one
    dataset: ``zyx``, given leading axes of length 1 where ``axes`` names more than it has."""
    zarr = pytest.importorskip("zarr")
    data = zyx.reshape((1,) * (len(axes) - zyx.ndim) + zyx.shape)
    group = zarr.open_group(str(path), mode="w", zarr_format=2 if version == "0.4" else 3)
    stored = group.create_array("0", shape=data.shape, chunks=(1,) * (data.ndim - 3) + (9, 26, 30), dtype=data.dtype)
    stored[:] = data
    multiscales = [{"version": version, "axes": axes, "datasets": [{"path": "0", "coordinateTransformations": [{"type": "scale", "scale": scale}]}]}]
    if version == "0.4":
        group.attrs["multiscales"] = multiscales
    else:
        group.attrs["ome"] = {"version": version, "multiscales": multiscales}


def test_an_ome_zarr_group_gives_its_axes_and_spacing(client, tmp_path):
    zyx = voxels()
    params = {"phases": 0, "background": "none"}
    space = lambda name, unit: {"name": name, "type": "space", "unit": unit}  # noqa: E731
    # Spacing (x, y, z) = (1.0, 0.9, 1.3) mm, in micrometres with a channel axis, and in mm.
    one = slabscope.analyze(slabscope.Volume.from_array(zyx.T, spacing=(1.0, 0.9, 1.3)), **params).to_dict()
    channel = [{"name": "c", "type": "channel"}] + [space(a, "micrometer") for a in "zyx"]
    ome_zarr(tmp_path / "a.zarr", zyx, channel, [1.0, 1300.0, 900.0, 1000.0], "0.4")
    # The spacing and the analysis are those of slabscope.load of the same store.
    loaded = slabscope.load(str(tmp_path / "a.zarr"))
    assert loaded.spacing == (1000.0 * 1e-3, 900.0 * 1e-3, 1300.0 * 1e-3)
    got = slabscope.dask.analyze_array(client, str(tmp_path / "a.zarr"), **params).to_dict()
    assert got == slabscope.analyze(slabscope.Volume.from_array(zyx.T, spacing=loaded.spacing), **params).to_dict()
    # Named "array", as every volume made from an array is; all else is load's.
    assert got == {**slabscope.analyze(loaded, **params).to_dict(), "file": "array"}
    ome_zarr(tmp_path / "b.zarr", zyx, [space(a, "millimeter") for a in "zyx"], [1.3, 0.9, 1.0], "0.5")
    assert slabscope.dask.analyze_array(client, tmp_path / "b.zarr", **params).to_dict() == one
    # Axes stored in another order: the metadata's order is read, not assumed.
    yzx = np.ascontiguousarray(zyx.transpose(1, 0, 2))
    ome_zarr(tmp_path / "c.zarr", yzx, [space(a, None) for a in "yzx"], [0.9, 1.3, 1.0], "0.4")
    assert slabscope.dask.analyze_array(client, str(tmp_path / "c.zarr"), **params).to_dict() == one
    # spacing= overrides the store's.
    ones = slabscope.analyze(slabscope.Volume.from_array(zyx.T), **params).to_dict()
    assert slabscope.dask.analyze_array(client, str(tmp_path / "a.zarr"), spacing=(1, 1, 1), **params).to_dict() == ones
    # A time axis of more than one volume, and a unit that is no length, are refused.
    ome_zarr(tmp_path / "t.zarr", np.stack([zyx, zyx]), [{"name": "t", "type": "time"}] + [space(a, None) for a in "zyx"], [1.0] * 4, "0.4")
    with pytest.raises(ValueError, match="'t' axis holds 2"):
        slabscope.dask.analyze_array(client, str(tmp_path / "t.zarr"), **params)
    ome_zarr(tmp_path / "u.zarr", zyx, [space(a, "furlong") for a in "zyx"], [1.0] * 3, "0.4")
    with pytest.raises(ValueError, match="furlong"):
        slabscope.dask.analyze_array(client, str(tmp_path / "u.zarr"), **params)


def test_an_affine_as_nibabel_gives_it(client):
    zyx = voxels()
    params = {"phases": 0, "background": "none"}
    c, s = np.cos(0.3), np.sin(0.3)
    affine = np.array([[c, -s, 0, 4.0], [s, c, 0, -2.0], [0, 0, 1, 7.0], [0, 0, 0, 1]]) @ np.diag([1.0, 0.9, 1.3, 1.0])
    one = slabscope.analyze(slabscope.Volume.from_array(zyx.T, affine=affine), **params).to_dict()
    got = slabscope.dask.analyze_array(client, da.from_array(zyx, chunks=(9, 26, 30)), axes="zyx", affine=affine, **params)
    assert got.to_dict() == one
    with pytest.raises(ValueError, match="spacing"):
        slabscope.dask.analyze_array(client, da.from_array(zyx), axes="zyx", affine=affine, spacing=(2, 2, 2), **params)


def test_no_task_holds_the_whole_array(client):
    """The background and the partition run in parts too: the analysis is assembled on the
    client, of a volume holding no voxel (its grid alone), which says so when its voxels are
    asked for; it pickles as its grid. A task's budget bounds what each task holds: a slab's
    view counts, a layer's labelling, a strip."""
    zyx = voxels()
    array = da.from_array(zyx, chunks=(8, 26, 30))
    one = slabscope.analyze(slabscope.Volume.from_array(zyx.T), slabs=3)
    got = slabscope.dask.analyze_array(client, array, axes="zyx", max_memory="64M", slabs=3)
    assert got.to_dict() == one.to_dict()
    assert got.slabs == one.slabs and got.best_axis == one.best_axis
    volume = got.volume
    assert volume.shape == (30, 26, 37) and volume.dtype == np.dtype("uint8")
    with pytest.raises(ValueError, match="counted in parts across a cluster .* held nowhere here"):
        volume.array
    with pytest.raises(ValueError, match="held nowhere here"):
        got.labels()
    back = pickle.loads(pickle.dumps(got))
    assert back.to_dict() == one.to_dict() and back.volume.shape == (30, 26, 37)
    # A view task weighs its voxels and its round's counts: a block table of 32³ codes a
    # lattice (266 KiB with its ends), 147 of them in the shifted round, and the pieces of
    # rays open at its faces.
    with pytest.raises(ValueError, match=r"the slab of cell planes \d+\.\.\d+ holds \d+ bytes \(its voxel planes .* beyond the task's budget of 4194304 \(chunks of fewer planes"):
        slabscope.dask.analyze_array(client, array, axes="zyx", max_memory="4M")
    # With an axis given no view task runs. Labelling a layer of 8 planes of 30×26 voxels
    # holds up to 12 bytes a voxel.
    with pytest.raises(ValueError, match=r"labelling the background of planes 0..8 takes up to 63640 bytes, beyond the task's budget of 10240"):
        slabscope.dask.analyze_array(client, array, axes="zyx", axis=(0, 0, 1), max_memory="10K")
    # So does what a strip's task holds: its boxes' voxels, given and copied, and masks.
    with pytest.raises(ValueError, match=r"the strip of rows \d+\.\.\d+ holds \d+ bytes \(its voxels in \d+ boxes .* beyond the task's budget of 4096"):
        slabscope.dask.analyze_array(client, array, axes="zyx", axis=(0, 0, 1), max_memory="4K", background="none")
    # What reads the voxels where they are does not run in parts.
    with pytest.raises(ValueError, match="explain"):
        slabscope.dask.analyze_array(client, array, axes="zyx", explain=True)
    with pytest.raises(ValueError, match="resolution"):
        slabscope.dask.analyze_array(client, array, axes="zyx", resolution=1)
    with pytest.raises(TypeError, match="unexpected keyword argument 'slab'"):
        slabscope.dask.analyze_array(client, array, axes="zyx", slab=3)
    # Each task counts in a pool of threads=, kept by its worker process for the next tasks.
    assert slabscope.dask.analyze_array(client, array, axes="zyx", threads=1, slabs=3).to_dict() == one.to_dict()
    with pytest.raises(ValueError, match="threads"):
        slabscope.dask.analyze_array(client, array, axes="zyx", threads=0)


@pytest.mark.parametrize("params", [{"background": 60}, {"axis": "x", "slabs": 3}, {"method": "optimal", "slabs": 2}], ids=["threshold", "axis", "optimal"])
def test_the_partition_in_parts_follows_every_rule(client, params):
    """A threshold's background (no rounds of its own), an axis given (no view search; the
    stack's rows then lie along z, so every strip's box crosses every layer), the optimal
    partition: `analyze`'s, to the key."""
    zyx = voxels()
    array = da.from_array(zyx, chunks=(7, 26, 30))
    one = slabscope.analyze(slabscope.Volume.from_array(zyx.T, spacing=(1.0, 0.9, 1.3)), **params)
    got = slabscope.dask.analyze_array(client, array, axes="zyx", spacing=(1.0, 0.9, 1.3), **params)
    assert got.to_dict() == one.to_dict()


def test_partition_parts_add_and_pickle():
    """A strip's part pickles as bytes and adds in any order; the two passes do not mix."""
    zyx = voxels()
    nz, ny, nx = zyx.shape
    grid = ([nx, ny, nz], [1.0, 1.0, 1.0], "uint8", (float(zyx.min()), float(zyx.max()), zyx.size))
    probe = slabscope.Volume.from_array(np.zeros((1, 1, 1), np.uint8))
    split = slabscope._slabscope.PartitionSplit(probe, grid[0], "uint8", grid[3], axis="z", background="none")
    assert split.axis == (0.0, 0.0, 1.0)
    # One layer of every plane: a box a strip.
    strips = split.strips(3, [(0, nz)])
    assert [rows for rows, _ in strips] == [(0, 8), (8, 17), (17, 26)]

    def count(strip: Any, slabs: Any = None, short: int = 0) -> Any:
        rows, [(k, (x0, y0, z0), (sx, sy, sz))] = strip
        box = zyx[z0 : z0 + sz, y0 + short : y0 + sy, x0 : x0 + sx]
        held = [((0, nz), (x0, y0 + short, z0), (sx, sy - short, sz))]
        return slabscope._slabscope._count_strip(box, held, rows, split.axis, *grid, (None, []), slabs, axis="z", background="none")

    parts = [count(strip) for strip in strips]
    total = pickle.loads(pickle.dumps(parts[2])) + parts[0]
    total += parts[1]
    slabs = split.slabs(total, (None, 0))
    assert len(slabs) == 4
    joints = [count(strip, slabs) for strip in strips]
    with pytest.raises(ValueError, match="first pass"):
        split.slabs(joints[0], (None, 0))
    with pytest.raises(ValueError, match="two passes"):
        total + joints[0]
    both = joints[0] + pickle.loads(pickle.dumps(joints[2])) + joints[1]
    assert both.round == 1 and total.round == 0
    got = split.analysis(both, "array", axis="z", background="none")
    one = slabscope.analyze(slabscope.Volume.from_array(zyx.T), axis="z", background="none")
    assert got.to_dict() == one.to_dict()
    # A box one voxel short of what the rows read is refused, not counted as zeros; so is a
    # plane the rows read in no layer given.
    with pytest.raises(ValueError, match="not all in the"):
        count(strips[1], short=1)
    rows, [(_, (x0, y0, _), (sx, sy, _))] = strips[1]
    top = zyx[:20, y0 : y0 + sy, x0 : x0 + sx]
    with pytest.raises(ValueError, match="read plane 20, in none of the layers given"):
        slabscope._slabscope._count_strip(top, [((0, 20), (x0, y0, 0), (sx, sy, 20))], rows, split.axis, *grid, (None, []), axis="z", background="none")


def smooth() -> np.ndarray:
    """A 30×26×37 volume indexed [z, y, x] of thick tilted layers held as i16: a strip's
    columns hold a few runs each, which take less memory than its voxels."""
    z, y, x = np.meshgrid(np.arange(37), np.arange(26), np.arange(30), indexing="ij")
    values = ((x + y + 4 * z) // 60 % 4) * 300 - 200
    values[:, :2] = 0
    return values.astype(np.int16)


def ran(stream: Any) -> Any:
    """How many tasks of each function a task stream holds (a task's key is the function's
    name, a dash and a token)."""
    from collections import Counter

    return Counter(str(t["key"]).split("-", 1)[0] for t in stream.data)


@pytest.mark.parametrize("kind", ["kept", "cut again"])
def test_the_second_pass_reads_the_runs_the_first_kept(client, kind):
    """The partition's first pass keeps each strip's runs on its worker where they take no
    more memory than its voxels, and the second pass reads them there: no box of voxels is
    cut for it. A strip whose runs would take more (the noisy volume's, u8) is cut from its
    voxels again. The answer is one process's either way."""
    from distributed import get_task_stream

    # Along z a strip's columns are its voxels' columns; along the oblique axis the columns at
    # a strip's corners hold a sample or two between missing ones, and take more than voxels.
    zyx = smooth() if kind == "kept" else voxels()
    array = da.from_array(zyx, chunks=(8, 26, 30))
    axis = (0.0, 0.0, 1.0) if kind == "kept" else (0.3, 0.5, 0.8)
    params = {"axis": axis, "slabs": 3, "background": "none"}
    with get_task_stream(client) as stream:
        got = slabscope.dask.analyze_array(client, array, axes="zyx", **params)
    assert got.to_dict() == slabscope.analyze(slabscope.Volume.from_array(zyx.T), **params).to_dict()
    tasks = ran(stream)
    # A strip a layer, each given a box from every layer its rows read.
    nz, ny, nx = zyx.shape
    grid = ([nx, ny, nz], "uint8", (0.0, 1.0, 1))
    probe = slabscope.Volume.from_array(np.zeros((1, 1, 1), np.uint8))
    split = slabscope._slabscope.PartitionSplit(probe, *grid, axis=axis, background="none")
    boxes = sum(len(b) for _, b in split.strips(5, [(0, 8), (8, 16), (16, 24), (24, 32), (32, 37)]))
    assert tasks["_strip_keeping"] == 5
    if kind == "kept":
        assert (tasks["_joints_of"], tasks["_strip"], tasks["_box_of"]) == (5, 0, boxes)
    else:
        assert (tasks["_joints_of"], tasks["_strip"], tasks["_box_of"]) == (0, 5, 2 * boxes)


def test_strip_runs_pickle_and_give_the_second_pass():
    """A strip's runs pickle as bytes (should Dask move them) and give the second pass's
    counts the strip's voxels give; bytes of anything else are refused."""
    zyx = smooth()
    nz, ny, nx = zyx.shape
    grid = ([nx, ny, nz], [1.0, 1.0, 1.0], "int16", (float(zyx.min()), float(zyx.max()), zyx.size))
    probe = slabscope.Volume.from_array(np.zeros((1, 1, 1), np.uint8))
    split = slabscope._slabscope.PartitionSplit(probe, grid[0], "int16", grid[3], axis="z", background="none")
    ext = slabscope._slabscope
    parts, kept, boxes = [], [], []
    for rows, [(_, (x0, y0, z0), (sx, sy, sz))] in split.strips(3, [(0, nz)]):
        box = zyx[z0 : z0 + sz, y0 : y0 + sy, x0 : x0 + sx]
        held = [((0, nz), (x0, y0, z0), (sx, sy, sz))]
        part, runs = ext._count_strip_keeping(box, held, rows, split.axis, *grid, (None, []), axis="z", background="none")
        assert runs is not None and runs.rows == rows and 0 < runs.__sizeof__() < box.nbytes
        parts.append(part)
        kept.append(pickle.loads(pickle.dumps(runs)))
        boxes.append((box, held, rows))
    slabs = split.slabs(parts[0] + parts[1] + parts[2], (None, 0))
    for runs, (box, held, rows) in zip(kept, boxes):
        again = ext._count_strip(box, held, rows, split.axis, *grid, (None, []), slabs, axis="z", background="none")
        assert pickle.dumps(ext._strip_joints(runs, slabs)) == pickle.dumps(again)
    with pytest.raises(ValueError, match="tile the stack"):
        ext._strip_joints(kept[0], [(0, 3)])
    with pytest.raises(ValueError, match="not slabscope's strip's runs"):
        ext._strip_runs_of(b"junk")


def test_a_worker_killed_mid_run_costs_only_its_tasks(client):
    """A worker process killed (SIGKILL) while the view search's tasks run: its nanny starts
    another, the scheduler runs its tasks again elsewhere (and reads again the chunk layers the
    dead process held), and the answer is unchanged."""
    import signal

    zyx = voxels()
    before = set(client.run(os.getpid).values())
    victim = sorted(before)[0]
    heard = []

    def progress(phase: str, fraction: float) -> None:
        # The first part of the paper's round is in: the other tasks of the round are queued
        # or running, and each worker holds chunk layers.
        if not heard:
            os.kill(victim, signal.SIGKILL)
        heard.append(fraction)

    array = da.from_array(zyx, chunks=(8, 26, 30))
    got = slabscope.dask.analyze_array(client, array, axes="zyx", slabs=3, progress=progress)
    client.wait_for_workers(2, timeout=60)  # the nanny's new process, perhaps still starting
    after = set(client.run(os.getpid).values())
    assert len(after) == 2 and victim not in after and len(before & after) == 1  # one replaced
    one = slabscope.analyze(slabscope.Volume.from_array(zyx.T), slabs=3)
    assert got.to_dict() == one.to_dict()
    # Every task reported once, however many times it ran: the view search's two rounds (2
    # slabs each), the background's three and the partition's two (5 layers, 5 strips), and
    # the end.
    assert len(heard) == 2 * 2 + 5 * 3 + 5 * 2 + 1 and heard[-1] == 1.0


def marking(marks: str) -> Any:
    """A ``map_blocks`` function leaving a mark in the folder ``marks`` for each chunk it reads
    (a file a chunk, a byte a read), the chunk as it is."""

    def chunk(block: np.ndarray, block_info: Any = None) -> np.ndarray:
        k, j, i = block_info[0]["chunk-location"]
        with open(os.path.join(marks, f"read-{k}-{j}-{i}"), "a") as f:
            f.write("x")
        return block

    return chunk


def nothing_held(client: Any) -> bool:
    """Whether the workers hold nothing, waiting up to 30 s for the scheduler to hear of what
    a call released as it returned."""
    held = lambda: sum(client.run(lambda dask_worker: len(dask_worker.data)).values())  # noqa: E731
    deadline = time.monotonic() + 30
    while held() and time.monotonic() < deadline:
        time.sleep(0.05)
    return held() == 0


def test_each_chunk_is_read_once_in_a_call(client, tmp_path):
    """Every chunk of the array is read (computed) once in a whole call, whatever the rounds:
    the range, the paper's and the shifted lattices, the refinement's, the background's and
    the partition's all read the chunk layers held on the workers (before, each round read
    every chunk again, and neighbouring slabs' tasks each read the chunks they share: 22 to 32
    times a chunk here)."""
    zyx = voxels()
    chunk = marking(str(tmp_path))

    array = da.from_array(zyx, chunks=(8, 13, 15)).map_blocks(chunk, dtype=zyx.dtype)
    got = slabscope.dask.analyze_array(client, array, axes="zyx", refine=True)
    assert got.to_dict() == slabscope.analyze(slabscope.Volume.from_array(zyx.T), refine=True).to_dict()
    reads = {name: len(open(os.path.join(tmp_path, name)).read()) for name in os.listdir(tmp_path)}
    assert len(reads) == 5 * 2 * 2  # chunks of 8 planes, 13 rows, 15 columns
    assert set(reads.values()) == {1}
    # Nothing of the call is left on the workers (released as the call returns; the
    # scheduler hears of it a moment later).
    assert nothing_held(client)


def test_an_array_beyond_the_workers_memory_is_read_once_a_round(client, tmp_path, monkeypatch):
    """Where the array does not fit within the share of the workers' memory limits it may
    take, its layers are not kept between rounds: each round reads the chunks it needs again
    (at most once: the range, the view search's two rounds, the background's three, the
    partition's two; Dask computes a chunk once for two rounds when the first's is still in
    memory as the second asks for it) and releases them, and the answer is the same."""
    zyx = voxels()
    chunk = marking(str(tmp_path))

    monkeypatch.setattr(slabscope.dask, "_KEEP_SHARE", 0.0)
    array = da.from_array(zyx, chunks=(8, 13, 15)).map_blocks(chunk, dtype=zyx.dtype)
    got = slabscope.dask.analyze_array(client, array, axes="zyx", slabs=3)
    assert got.to_dict() == slabscope.analyze(slabscope.Volume.from_array(zyx.T), slabs=3).to_dict()
    reads = {name: len(open(os.path.join(tmp_path, name)).read()) for name in os.listdir(tmp_path)}
    assert len(reads) == 5 * 2 * 2 and max(reads.values()) <= 1 + 2 + 3 + 2
    assert sum(reads.values()) > 2 * len(reads), "read again in later rounds"
    # From a store, a task a layer each round.
    zarr = pytest.importorskip("zarr")
    store = str(tmp_path / "v.zarr")
    stored = zarr.open_array(store, mode="w", shape=zyx.shape, chunks=(10, 26, 30), dtype=zyx.dtype)
    stored[:] = zyx
    assert slabscope.dask.analyze_array(client, store, axes="zyx", slabs=3).to_dict() == got.to_dict()
    assert nothing_held(client)
