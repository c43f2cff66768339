"""A store at a URL whose pyramid holds coarser datasets: `load` reads its metadata and coarsest
dataset, level 0 when first needed, and `analyze(volume, resolution=...)` the coarsest dataset
that serves the level, never a chunk of level 0, as `slabscope analyze URL --resolution auto`
does; the labels of such an analysis are level 0's. A server on 127.0.0.1 counts the
requests."""

from __future__ import annotations

import functools
import http.server
import json
import pickle
import shutil
import threading
from pathlib import Path
from typing import Iterator

import numpy as np
import pytest

import slabscope


def _zattrs(scales: list[float]) -> str:
    datasets = [
        {
            "path": str(i),
            "coordinateTransformations": [
                {"type": "scale", "scale": [s, s, s]},
                {"type": "translation", "translation": [(s - 1) / 2] * 3},
            ],
        }
        for i, s in enumerate(scales)
    ]
    axes = [{"name": a, "type": "space", "unit": "micrometer"} for a in "zyx"]
    return json.dumps({"multiscales": [{"version": "0.4", "axes": axes, "datasets": datasets}]})


def _array(folder: Path, n: int, voxels: np.ndarray | None) -> None:
    """An uncompressed uint8 array of n³ voxels in chunks of 64³, indexed [z, y, x]; its
    chunks written only when `voxels` is given (else each is absent: a request the server
    logs and answers 404)."""
    folder.mkdir(parents=True)
    meta = {
        "zarr_format": 2,
        "shape": [n, n, n],
        "chunks": [64, 64, 64],
        "dtype": "|u1",
        "compressor": None,
        "fill_value": 0,
        "order": "C",
        "filters": None,
    }
    (folder / ".zarray").write_text(json.dumps(meta))
    if voxels is None:
        return
    c = n // 64
    for z in range(c):
        for y in range(c):
            for x in range(c):
                block = voxels[z * 64 : z * 64 + 64, y * 64 : y * 64 + 64, x * 64 : x * 64 + 64]
                (folder / f"{z}.{y}.{x}").write_bytes(np.ascontiguousarray(block).tobytes())


def _disc(n: int) -> np.ndarray:
    """The pixels of an n×n plane, [y, x], inside the disc of radius 7n/16 at its centre."""
    y, x = np.indices((n, n))
    c = (n - 1) / 2
    return (x - c) ** 2 + (y - c) ** 2 < (7 * n / 16) ** 2


@pytest.fixture(scope="module")
def stores(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """`pyramid.ome.zarr`: a 256³ level 0 whose chunks are absent over a 128³ level 1;
    `alone.ome.zarr`, that level 1 as an image of its own on the same grid (the Rust suite's
    tests/it/remote_levels.rs, the same voxels); and `full.ome.zarr`, that level 1 + 1 inside a
    cylinder along z (0 outside) over a level 0 whose every 2³ block is level 1's voxel (so
    level 1 is level 0's average)."""
    root = tmp_path_factory.mktemp("levels")
    z, y, x = np.indices((128, 128, 128))
    level1 = ((z // 24) * 40 + (x * y + z) % 9).astype(np.uint8)
    pyramid = root / "pyramid.ome.zarr"
    pyramid.mkdir()
    (pyramid / ".zgroup").write_text('{"zarr_format": 2}')
    (pyramid / ".zattrs").write_text(_zattrs([1.0, 2.0]))
    _array(pyramid / "0", 256, None)
    _array(pyramid / "1", 128, level1)
    alone = root / "alone.ome.zarr"
    alone.mkdir()
    (alone / ".zgroup").write_text('{"zarr_format": 2}')
    (alone / ".zattrs").write_text(_zattrs([2.0]))
    shutil.copytree(pyramid / "1", alone / "0")
    full = root / "full.ome.zarr"
    full.mkdir()
    (full / ".zgroup").write_text('{"zarr_format": 2}')
    (full / ".zattrs").write_text(_zattrs([1.0, 2.0]))
    body = np.where(_disc(128)[None], level1 + 1, 0).astype(np.uint8)
    _array(full / "0", 256, body.repeat(2, 0).repeat(2, 1).repeat(2, 2))
    _array(full / "1", 128, body)
    return root


class _Logged(http.server.SimpleHTTPRequestHandler):
    asked: list[str]

    def do_GET(self) -> None:
        self.asked.append(self.path)
        super().do_GET()

    def do_HEAD(self) -> None:
        self.asked.append(self.path)
        super().do_HEAD()

    def log_message(self, format: str, *args: object) -> None:
        pass


@pytest.fixture
def served(stores: Path) -> Iterator[tuple[str, list[str]]]:
    """The stores' URL on 127.0.0.1 and the paths asked of it, in order."""
    asked: list[str] = []
    handler = type("Handler", (_Logged,), {"asked": asked})
    server = http.server.ThreadingHTTPServer(
        ("127.0.0.1", 0), functools.partial(handler, directory=str(stores))
    )
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}", asked
    finally:
        server.shutdown()


def _level_0_chunks(asked: list[str], store: str = "pyramid.ome.zarr") -> list[str]:
    return [
        p
        for p in asked
        if p.startswith(f"/{store}/0/")
        and not p.endswith((".zarray", ".zattrs", "zarr.json"))
    ]


def test_a_coarser_level_is_analysed_without_a_chunk_of_level_0(served, stores):
    base, asked = served
    url = f"{base}/pyramid.ome.zarr"
    volume = slabscope.load(url)
    # Level 0's grid, from the metadata; the coarsest dataset read, level 0 not.
    assert volume.shape == (256, 256, 256)
    assert volume.spacing == (0.001, 0.001, 0.001)
    assert volume.dtype == "uint8"
    assert volume.format == "ome-zarr"
    assert "256x256x256 uint8" in repr(volume)
    assert "/pyramid.ome.zarr/1/0.0.0" in asked
    assert _level_0_chunks(asked) == []

    auto = slabscope.analyze(volume, resolution="auto", slabs=3).to_dict()
    one = slabscope.analyze(volume, resolution=1, slabs=3).to_dict()
    assert _level_0_chunks(asked) == []
    assert auto["dims"] == [256, 256, 256]
    assert auto["resolution"]["pyramid_level"] == 1
    assert auto["resolution"]["dims"] == [128, 128, 128]
    # The note the CLI prints of the dataset read, on the volume.
    (served,) = [n for n in volume.notes if n.startswith("pyramid level 1 from the store's")]
    assert "level 0 not read: quantized with that dataset's own value range" in served
    # Level 1 analysed as a volume of its own gives the same analysis, its range level 1's.
    own = slabscope.analyze(slabscope.load(stores / "alone.ome.zarr"), slabs=3).to_dict()
    for key in ["range", "views", "best_axis", "partition", "params"]:
        assert auto[key] == own[key], key
    assert one["partition"] == own["partition"]

    # Level 0 is read when its voxels are asked for (its chunks absent: the fill value).
    assert volume.range == (0.0, 0.0)
    assert len(_level_0_chunks(asked)) == 64
    # The analysis at a coarser level is the same once level 0 is held.
    again = slabscope.analyze(volume, resolution="auto", slabs=3).to_dict()
    assert again["partition"] == auto["partition"]


def test_a_store_at_a_url_pickles_as_its_url(served):
    base, asked = served
    volume = slabscope.load(f"{base}/pyramid.ome.zarr")
    copy = pickle.loads(pickle.dumps(volume))
    assert copy.shape == (256, 256, 256)
    assert copy.affine.tolist() == volume.affine.tolist()
    assert _level_0_chunks(asked) == []


def test_labels_of_an_analysis_at_a_served_level_are_at_level_0s_shape(served, stores):
    base, asked = served
    url = f"{base}/full.ome.zarr"
    # Along z, the axis of the layers, so that each label can be told from its slice.
    kw = {"resolution": "auto", "slabs": 3, "axis": "z"}
    remote = slabscope.analyze(slabscope.load(url), **kw)
    local = slabscope.analyze(slabscope.load(stores / "full.ome.zarr"), **kw)
    d = remote.to_dict()
    assert d["resolution"]["pyramid_level"] == 1
    assert local.to_dict()["resolution"] == d["resolution"]
    assert remote.slabs == local.slabs
    assert _level_0_chunks(asked, "full.ome.zarr") == []

    labels = remote.labels()
    # Level 0 read for them (its 64 chunks, once), the labels at its shape, [x, y, z].
    assert len(set(_level_0_chunks(asked, "full.ome.zarr"))) == 64
    assert labels.shape == (256, 256, 256)
    assert labels.dtype == np.uint8
    assert np.array_equal(labels, local.labels())
    # A labelled voxel at z lies in level 1's slice z // 2.
    assert d["partition"]["axis"] == [0.0, 0.0, 1.0]
    slab_of = np.zeros(128, dtype=np.uint8)
    for i, (first, end) in enumerate(remote.slabs):
        slab_of[first:end] = i + 1
    expected = np.broadcast_to(slab_of.repeat(2)[None, None, :], labels.shape)
    # The background found on level 0: the voxels outside the cylinder, and only those.
    inside = _disc(128).repeat(2, 0).repeat(2, 1).T[:, :, None]
    assert np.array_equal(labels, np.where(inside, expected, 0))
