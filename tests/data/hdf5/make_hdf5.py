"""Writes the HDF5 fixtures with h5py (the reference Python binding of libhdf5), run once
offline: `python3 make_hdf5.py` in this folder (pip install h5py numpy). Every voxel is a known
function of its index, so the tests check values without a second copy: value(x, y, z) =
x + 10*y + 100*z (+ 1000*t for a 4-D dataset), stored in C order as h5py writes it, the array
indexed [z, y, x] (the last index fastest). h5py is BSD-licensed; the files are this project's.
`reference.json` beside them freezes h5py's own reading: each dataset's shape, dtype, chunks,
filters, and the sum and first and last values of its voxels (and, for 32- and 64-bit integers,
of numpy's nearest f32 of each, with how many an f32 does not hold exactly)."""

import json
from pathlib import Path

import h5py
import numpy as np

HERE = Path(__file__).resolve().parent
NX, NY, NZ = 6, 5, 4


def ramp(dtype, nt=0):
    if nt:
        t, z, y, x = np.meshgrid(
            np.arange(nt), np.arange(NZ), np.arange(NY), np.arange(NX), indexing="ij"
        )
        return (x + 10 * y + 100 * z + 1000 * t).astype(dtype)
    z, y, x = np.meshgrid(np.arange(NZ), np.arange(NY), np.arange(NX), indexing="ij")
    return (x + 10 * y + 100 * z).astype(dtype)


def new(name, libver=None):
    return h5py.File(HERE / name, "w", libver=libver) if libver else h5py.File(HERE / name, "w")


# Contiguous, the only dataset, in a group; spacing in an `element_size_um` attribute (z, y, x).
with new("ramp_u16_contiguous.h5") as f:
    d = f.create_dataset("volume/ramp", data=ramp(np.uint16))
    d.attrs["element_size_um"] = np.array([2.5, 2.0, 1.5])
# Chunked with gzip and shuffle, chunks that do not divide the shape (edge chunks), f32.
with new("ramp_f32_gzip_shuffle.h5") as f:
    f.create_dataset(
        "data", data=ramp(np.float32), chunks=(3, 2, 4), compression="gzip", shuffle=True
    )
# Chunked with gzip alone, i16, newest file format (superblock v3, object headers v2, chunk
# indexes other than the v1 B-tree).
with new("ramp_i16_gzip_latest.h5", libver="latest") as f:
    f.create_dataset("data", data=ramp(np.int16), chunks=(2, 5, 3), compression="gzip")
# Big-endian f64, contiguous.
with new("ramp_f64_be.h5") as f:
    f.create_dataset("data", data=ramp(">f8"))
# DXchange: a reconstruction at /exchange/data beside a 2-D dataset; u8 chunked uncompressed.
with new("dxchange_recon.h5") as f:
    f.create_dataset("exchange/data", data=ramp(np.uint8), chunks=(1, 5, 6))
    f.create_dataset("exchange/mask2d", data=np.ones((5, 6), np.uint8))
# DXchange's voxel size: the objective's effective pixel size (`resolution`, in microns), or the
# detector's pixel size (`pixel_size_x`, in µm) over the objective's magnification.
with new("dxchange_resolution.h5") as f:
    f.create_dataset("exchange/data", data=ramp(np.uint16))
    r = f.create_dataset("measurement/instrument/detection_system/objective/resolution", data=[0.65])
    r.attrs["units"] = "microns"
with new("dxchange_pixel_size.h5") as f:
    f.create_dataset("exchange/data", data=ramp(np.uint16))
    p = f.create_dataset("measurement/instrument/detector/pixel_size_x", data=[6.5])
    p.attrs["units"] = "um"
    f.create_dataset("measurement/instrument/detection_system/objective/magnification", data=[10.0])
# Two 3-D datasets: one must be named.
with new("two_volumes.h5") as f:
    f.create_dataset("a", data=ramp(np.int32))
    f.create_dataset("b/c", data=ramp(np.uint32) + 1, compression="gzip", shuffle=True)
# A 4-D time series (t, z, y, x), two volumes.
with new("ramp_4d_i8.h5") as f:
    f.create_dataset("series", data=(ramp(np.int16, nt=2) % 128).astype(np.int8), chunks=True)
# Raw projections: DXchange before reconstruction.
with new("projections.h5") as f:
    f.create_dataset("exchange/data", data=ramp(np.uint16))
    f.create_dataset("exchange/data_white", data=np.ones((2, NY, NX), np.uint16))
    f.create_dataset("exchange/data_dark", data=np.zeros((2, NY, NX), np.uint16))
    f.create_dataset("exchange/theta", data=np.linspace(0, 180, NZ))

# 64-bit integers, held as f32: a big-endian i64 ramp, chunked with gzip, and u64 values an f32
# does not hold exactly (the ramp plus 2^40, the last voxel 2^64 - 1).
with new("wide_ints.h5") as f:
    f.create_dataset("ramp", data=ramp(">i8"), chunks=(2, 5, 6), compression="gzip")
    beyond = ramp(np.uint64) + np.uint64(1 << 40)
    beyond[-1, -1, -1] = np.iinfo(np.uint64).max
    f.create_dataset("beyond", data=beyond)

# 32-bit integers an f32 does not hold exactly: the i32 ramp + 2^24 (its odd values rounded).
with new("beyond_i32.h5") as f:
    f.create_dataset("data", data=ramp(np.int32) + np.int32(1 << 24))

# NeXus: the signal of an NXdata group, its axes named by an array of names (h5py's
# variable-length strings, of which rust-hdf5 reads the first) and `*_indices`, each axis dataset
# the voxels' coordinates along it with its `units`: z every 2.5 µm, y every 2 µm, x every
# 1500 nm (x as bin edges: one more than the voxels).
with new("nexus.h5") as f:
    entry = f.create_group("entry")
    entry.attrs["NX_class"] = "NXentry"
    g = entry.create_group("data")
    g.attrs["NX_class"] = "NXdata"
    g.attrs["signal"] = "data"
    g.attrs["axes"] = ["z", "y", "x"]
    for i, a in enumerate("zyx"):
        g.attrs[f"{a}_indices"] = i
    g.create_dataset("data", data=ramp(np.uint16))
    for a, n, step, units in [("z", NZ, 2.5, "um"), ("y", NY, 2.0, "um"), ("x", NX + 1, 1500.0, "nm")]:
        d = g.create_dataset(a, data=10.0 + step * np.arange(n))
        d.attrs["units"] = units
# A cube: every axis of the same length, told apart by their names (z every 3 mm, y 2, x 1).
with new("nexus_cube.h5") as f:
    g = f.create_group("entry/data")
    g.attrs["NX_class"] = "NXdata"
    g.attrs["signal"] = "data"
    g.attrs["axes"] = ["z", "y", "x"]
    g.create_dataset("data", data=np.arange(64, dtype=np.uint8).reshape(4, 4, 4))
    for a, step in [("x", 1.0), ("y", 2.0), ("z", 3.0)]:
        g.create_dataset(a, data=step * np.arange(4)).attrs["units"] = "mm"


def imaris_text(value):
    """Imaris's attributes: text as an array of one-byte strings."""
    return np.array(list(str(value)), dtype="S1")


# Imaris 5.5 (.ims): two resolution levels, two time points, two channels; each Data padded to
# whole chunks (here 8x8x8 for level 0, 4x4x4 for level 1) beyond ImageSizeX/Y/Z; channel c at
# time t holds the ramp + 1000*t + 2000*c (u16); the extents 0..9, 0..10, 0..10 µm make voxels
# of 1.5, 2.0 and 2.5 µm.
with new("imaris.ims") as f:
    info = f.create_group("DataSetInfo/Image")
    for key, value in [("X", NX), ("Y", NY), ("Z", NZ), ("Unit", "um"), ("ExtMin0", 0),
                       ("ExtMin1", 0), ("ExtMin2", 0), ("ExtMax0", 1.5 * NX),
                       ("ExtMax1", 2.0 * NY), ("ExtMax2", 2.5 * NZ)]:
        info.attrs[key] = imaris_text(value)
    for t in range(2):
        for c in range(2):
            for level, (pad, size) in enumerate([((8, 8, 8), (NZ, NY, NX)), ((4, 4, 4), (2, 3, 3))]):
                g = f.create_group(f"DataSet/ResolutionLevel {level}/TimePoint {t}/Channel {c}")
                data = np.zeros(pad, np.uint16)
                if level == 0:
                    data[:NZ, :NY, :NX] = ramp(np.uint16) + 1000 * t + 2000 * c
                else:
                    data[:2, :3, :3] = 7
                g.create_dataset("Data", data=data, chunks=pad, compression="gzip")
                g.create_dataset("Histogram", data=np.zeros(256, np.uint64))
                for axis, n in zip("ZYX", size):
                    g.attrs[f"ImageSize{axis}"] = imaris_text(n)

reference = {}
for path in sorted([*HERE.glob("*.h5"), *HERE.glob("*.ims")]):
    entries = {}

    def visit(name, obj, entries=entries):
        if isinstance(obj, h5py.Dataset):
            a = obj[()]
            entries["/" + name] = {
                "shape": list(obj.shape),
                "dtype": obj.dtype.str,
                "chunks": list(obj.chunks) if obj.chunks else None,
                "filters": [k for k in ("compression", "shuffle") if getattr(obj, k)],
                "sum": float(np.sum(a, dtype=np.float64)),
                "first": float(a.flat[0]) if a.size else None,
                "last": float(a.flat[-1]) if a.size else None,
            }
            if a.dtype.kind in "iu" and a.dtype.itemsize >= 4 and a.ndim == 3:
                # Held as f32: numpy's nearest f32 of each value, and how many are not exact.
                f32 = a.astype(np.float32)
                entries["/" + name]["f32"] = {
                    "sum": float(np.sum(f32, dtype=np.float64)),
                    "first": float(f32.flat[0]),
                    "last": float(f32.flat[-1]),
                    "rounded": int(sum(int(v) != int(w) for v, w in zip(a.flat, f32.flat))),
                }

    with h5py.File(path, "r") as f:
        f.visititems(visit)
    reference[path.name] = entries
(HERE / "reference.json").write_text(json.dumps(reference, indent=1, sort_keys=True) + "\n")
