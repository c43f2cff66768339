"""Makes the OME-Zarr fixtures of tests/data/zarr with the reference libraries (zarr-python 3,
ome-zarr-py 0.18, numcodecs), and expected.json with what zarr-python reads back from each.

    python3 -m venv v && v/bin/pip install zarr ome-zarr numcodecs && v/bin/python make.py

Every voxel follows a formula (`value` below) that the Rust tests recompute; expected.json holds
zarr-python's own reading of each level (sum, weighted sum, a few voxels), the axes, scales and
translations as written, so the tests need none of these libraries.
"""

import json
import shutil
from pathlib import Path

import numpy as np
import zarr
from numcodecs import Blosc, GZip
from ome_zarr.format import FormatV04, FormatV05
from ome_zarr.writer import write_labels, write_multiscale
from zarr.codecs import GzipCodec, ZstdCodec

HERE = Path(__file__).parent


def value(shape, dtype, labels=False):
    """The voxels of a t/c/z/y/x prefix of `shape` (any trailing subset), by formula."""
    idx = np.indices(shape)
    weights = [211, 101, 29, 13, 7][-len(shape):]
    v = sum(w * i for w, i in zip(weights, idx))
    if labels:
        return (v // 40 % 5).astype(dtype)
    if np.dtype(dtype).kind == "f":
        return (v % 997).astype(dtype) * np.float32(0.25) - np.float32(50)
    return (v % 997).astype(dtype) - (300 if np.dtype(dtype).kind == "i" else 0)


def halve(a, spatial):
    """The next level of slabscope's pyramid: 2x2x2 block means over the last `spatial` axes,
    sizes rounded up (a block cut by the far edge averages the voxels it has)."""
    out = a.astype(np.float64)
    for ax in range(a.ndim - spatial, a.ndim):
        n = out.shape[ax]
        if n == 1:
            continue
        pad = n % 2
        if pad:
            edge = np.take(out, [n - 1], axis=ax)
            out = np.concatenate([out, np.full_like(edge, np.nan)], axis=ax)
        shape = out.shape[:ax] + (out.shape[ax] // 2, 2) + out.shape[ax + 1:]
        out = np.nanmean(out.reshape(shape), axis=ax + 1)
    return out.astype(a.dtype) if a.dtype.kind == "f" else np.round(out).astype(a.dtype)


def fresh(name):
    path = HERE / name
    shutil.rmtree(path, ignore_errors=True)
    return path


def read_back(path):
    """What zarr-python reads of every array in the store, by its path."""
    root = zarr.open_group(str(path), mode="r")
    out = {}

    def visit(group, prefix):
        for name, node in group.members():
            key = f"{prefix}{name}"
            if isinstance(node, zarr.Array):
                a = node[...].astype(np.float64)
                flat = a.reshape(-1)
                out[key] = {
                    "shape": list(node.shape),
                    "dtype": str(node.dtype),
                    "sum": float(flat.sum()),
                    "weighted": float((flat * (np.arange(flat.size) % 101)).sum()),
                    "first": float(flat[0]),
                    "last": float(flat[-1]),
                }
            else:
                visit(node, key + "/")

    visit(root, "")
    return out


def transforms(scale, translation, levels, spatial):
    out = []
    for k in range(levels):
        f = 2 ** k
        s = [v * (f if i >= len(scale) - spatial else 1) for i, v in enumerate(scale)]
        t = [
            v + (scale[i] * (f - 1) / 2 if i >= len(scale) - spatial else 0)
            for i, v in enumerate(translation)
        ]
        out.append([{"type": "scale", "scale": s}, {"type": "translation", "translation": t}])
    return out


def pyramid(a, levels, spatial):
    out = [a]
    for _ in range(levels - 1):
        out.append(halve(out[-1], spatial))
    return out


def store_v04_blosc():
    """NGFF 0.4 (Zarr v2), z/y/x u16, Blosc-LZ4 chunks 4x5x6 with edge chunks, three levels of
    slabscope's own pyramid, micrometres, a translation."""
    path = fresh("v04_blosc.ome.zarr")
    a = value((10, 12, 14), np.uint16)
    group = zarr.open_group(str(path), mode="w", zarr_format=2)
    axes = [{"name": n, "type": "space", "unit": "micrometer"} for n in "zyx"]
    write_multiscale(
        pyramid(a, 3, 3),
        group,
        fmt=FormatV04(),
        axes=axes,
        coordinate_transformations=transforms([2.0, 0.5, 0.25], [10.0, 20.0, 30.0], 3, 3),
        storage_options={"chunks": (4, 5, 6), "compressor": Blosc(cname="lz4", clevel=5)},
    )


def store_v05_tczyx():
    """NGFF 0.5 (Zarr v3), t/c/z/y/x i16 (2 time points, 3 channels), zstd, nanometres."""
    path = fresh("v05_tczyx.ome.zarr")
    a = value((2, 3, 6, 7, 8), np.int16)
    group = zarr.open_group(str(path), mode="w", zarr_format=3)
    axes = [
        {"name": "t", "type": "time", "unit": "second"},
        {"name": "c", "type": "channel"},
    ] + [{"name": n, "type": "space", "unit": "nanometer"} for n in "zyx"]
    write_multiscale(
        pyramid(a, 2, 3),
        group,
        fmt=FormatV05(),
        axes=axes,
        coordinate_transformations=transforms(
            [1.0, 1.0, 500000.0, 250000.0, 250000.0], [0.0, 0.0, 0.0, 0.0, 0.0], 2, 3
        ),
        storage_options={"chunks": (1, 1, 3, 4, 5), "compressors": [ZstdCodec(level=3)]},
    )


def store_v05_sharded():
    """NGFF 0.5 (Zarr v3), z/y/x f32 in shards of 8x8x8 holding 4x4x4 gzip chunks; a region of
    the fill value (0) whose chunks are not written; millimetres; a labels image `cells`."""
    path = fresh("v05_sharded.ome.zarr")
    a = value((9, 10, 11), np.float32)
    a[:4, :4, :4] = 0.0  # one inner chunk of the fill value: not stored
    group = zarr.open_group(str(path), mode="w", zarr_format=3)
    axes = [{"name": n, "type": "space", "unit": "millimeter"} for n in "zyx"]
    write_multiscale(
        [a],
        group,
        fmt=FormatV05(),
        axes=axes,
        coordinate_transformations=transforms([1.5, 1.0, 1.0], [0.0, 0.0, 0.0], 1, 3),
        storage_options={
            "chunks": (4, 4, 4),
            "shards": (8, 8, 8),
            "compressors": [GzipCodec(level=5)],
        },
    )
    labels = value((9, 10, 11), np.uint8, labels=True)
    write_labels(
        labels,
        group,
        name="cells",
        fmt=FormatV05(),
        axes=axes,
        scale_factors=[],
        coordinate_transformations=transforms([1.5, 1.0, 1.0], [0.0, 0.0, 0.0], 1, 3),
    )


def store_v04_yx():
    """NGFF 0.4 (Zarr v2), a single y/x plane of u8, gzip, axes without units."""
    path = fresh("v04_yx.ome.zarr")
    a = value((12, 9), np.uint8)
    group = zarr.open_group(str(path), mode="w", zarr_format=2)
    write_multiscale(
        [a],
        group,
        fmt=FormatV04(),
        axes=[{"name": "y", "type": "space"}, {"name": "x", "type": "space"}],
        coordinate_transformations=[[{"type": "scale", "scale": [0.5, 0.5]}]],
        storage_options={"chunks": (5, 4), "compressor": GZip(level=5)},
    )


def main():
    store_v04_blosc()
    store_v05_tczyx()
    store_v05_sharded()
    store_v04_yx()
    expected = {
        p.name: read_back(p) for p in sorted(HERE.glob("*.ome.zarr"))
    }
    (HERE / "expected.json").write_text(json.dumps(expected, indent=1, sort_keys=True) + "\n")


if __name__ == "__main__":
    main()
