"""Writes the bad-input corpus: each file is broken in one way that tests/it/bad_input.rs names.

Run from this folder: python3 make_corpus.py (standard library only).
"""
import gzip
import os
import struct
import zlib

def nrrd(name, fields, data=b""):
    with open(name, "wb") as f:
        f.write(b"NRRD0004\n" + "".join(f"{k}: {v}\n" for k, v in fields).encode() + b"\n" + data)

base = [("type", "uint8"), ("dimension", "3"), ("sizes", "4 4 4"), ("encoding", "raw")]
nrrd("truncated.nrrd", base, bytes(40))                                  # 64 expected
nrrd("too_long.nrrd", base, bytes(100))                                  # header and size disagree
nrrd("absurd_dims.nrrd", [("type", "float"), ("dimension", "3"), ("sizes", "100000 100000 100000"), ("endian", "little"), ("encoding", "raw")], bytes(16))
nrrd("overflow_dims.nrrd", [("type", "float"), ("dimension", "3"), ("sizes", "18446744073709551615 2 2"), ("endian", "little"), ("encoding", "raw")], bytes(16))
nrrd("zero_dim.nrrd", [("type", "uint8"), ("dimension", "3"), ("sizes", "4 0 4"), ("encoding", "raw")])
nrrd("int64.nrrd", [("type", "int64"), ("dimension", "3"), ("sizes", "2 2 2"), ("encoding", "raw")], bytes(64))
nrrd("bzip2.nrrd", [("type", "uint8"), ("dimension", "3"), ("sizes", "2 2 2"), ("encoding", "bzip2")], bytes(8))
nrrd("no_sizes.nrrd", [("type", "uint8"), ("dimension", "3"), ("encoding", "raw")], bytes(8))
nrrd("nan_voxels.nrrd", [("type", "float"), ("dimension", "3"), ("sizes", "2 2 2"), ("endian", "little"), ("encoding", "raw")],
     struct.pack("<8f", 1, 2, float("nan"), 4, float("inf"), 6, 7, 8))
nrrd("all_nan.nrrd", [("type", "float"), ("dimension", "3"), ("sizes", "2 1 1"), ("endian", "little"), ("encoding", "raw")],
     struct.pack("<2f", float("nan"), float("nan")))
nrrd("constant.nrrd", [("type", "uint8"), ("dimension", "3"), ("sizes", "2 2 2"), ("encoding", "raw")], bytes([7] * 8))
nrrd("truncated_gzip.nrrd", [("type", "uint16"), ("dimension", "3"), ("sizes", "16 16 16"), ("endian", "little"), ("encoding", "gzip")],
     gzip.compress(bytes(range(256)) * 32)[:-40])
nrrd("corrupt_gzip.nrrd", [("type", "uint8"), ("dimension", "3"), ("sizes", "4 4 4"), ("encoding", "gzip")], b"\x1f\x8b\x08\x00garbage-not-deflate")
nrrd("missing_data_file.nhdr", [("type", "uint8"), ("dimension", "3"), ("sizes", "2 2 2"), ("encoding", "raw"), ("data file", "nowhere.raw")])
nrrd("vector.nrrd", [("type", "uint8"), ("dimension", "4"), ("sizes", "3 2 2 2"), ("kinds", "RGB-color domain domain domain"), ("encoding", "raw")], bytes(24))

with open("mha_missing_datafile.mha", "w") as f:
    f.write("ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\nElementType = MET_UCHAR\n")
with open("mha_truncated_zlib.mha", "wb") as f:
    f.write(b"ObjectType = Image\nNDims = 3\nDimSize = 8 8 8\nElementType = MET_SHORT\nCompressedData = True\nElementDataFile = LOCAL\n")
    f.write(zlib.compress(bytes(1024))[:-6])
with open("mha_bad_type.mha", "w") as f:
    f.write("ObjectType = Image\nNDims = 3\nDimSize = 2 2 2\nElementType = MET_FLOAT_MATRIX\nElementDataFile = LOCAL\n")

def nifti_header(dims, datatype, bitpix, vox_offset=352.0):
    h = bytearray(348)
    struct.pack_into("<i", h, 0, 348)
    dim = [len(dims)] + list(dims) + [1] * (7 - len(dims))
    struct.pack_into("<8h", h, 40, *dim)
    struct.pack_into("<hh", h, 70, datatype, bitpix)
    struct.pack_into("<8f", h, 76, 1, 1, 1, 1, 1, 1, 1, 1)
    struct.pack_into("<f", h, 108, vox_offset)
    struct.pack_into("<f", h, 112, 1.0)
    h[344:348] = b"n+1\0"
    return bytes(h) + bytes(4)

with open("nifti_truncated.nii", "wb") as f:
    f.write(nifti_header((8, 8, 8), 4, 16) + bytes(100))
with open("nifti_complex.nii", "wb") as f:
    f.write(nifti_header((2, 2, 2), 32, 64) + bytes(64))
with open("nifti_absurd.nii", "wb") as f:
    f.write(nifti_header((32767, 32767, 32767), 16, 32) + bytes(64))
with open("nifti_bad_offset.nii", "wb") as f:
    f.write(nifti_header((2, 2, 2), 2, 8, vox_offset=100.0) + bytes(8))
with open("nifti_header_only.nii", "wb") as f:
    f.write(nifti_header((2, 2, 2), 2, 8)[:200])

with open("volumeshop_wrong_size.dat", "wb") as f:
    f.write(struct.pack("<3H", 10, 10, 10) + bytes(100))
with open("empty.nrrd", "wb") as f:
    pass
with open("not_a_volume.txt", "w") as f:
    f.write("Dear diary, today I scanned nothing.\n")
with open("pixel.png", "wb") as f:
    f.write(b"\x89PNG\r\n\x1a\n" + bytes(50))
with open("tiff_garbage.tif", "wb") as f:
    f.write(b"II*\0" + struct.pack("<I", 99999) + bytes(20))
os.makedirs("empty_folder", exist_ok=True)
open(os.path.join("empty_folder", "README"), "w").write("a folder with no TIFF slices\n")
