#!/usr/bin/env python3
"""Writes the Siemens mosaic fixtures of tests/it/mosaic.rs (pydicom 3, numpy), and with
--freeze runs dcm2niix on them and keeps what it makes of each series in <series>.json, so that
the tests need neither tool.

Each file is one mosaic: NumberOfImagesInMosaic = 7 tiles of 6x5 pixels (columns x rows) in a
3x3 grid (18x15 pixels), the last two tiles empty, with a CSA2 ("SV10") image header written
byte by byte below. Tile k of time point t holds

    stored(i, j, k, t) = 3*i + 5*j + 11*k + 100*t + 1      (i column, j row in the tile)

so a test checks each slice of each volume voxel by voxel.

  asc/   three time points at one position (a 4D series); SliceNormalVector along the cross
         product of the orientation; SpacingBetweenSlices 3.3 mm (SliceThickness 3 mm); the
         CSA block is the usual (0029,10xx).
  desc/  one time point; SliceNormalVector against the cross product (slices descending);
         no SpacingBetweenSlices (SliceThickness 4 mm); the CSA block is reserved at (0029,0011),
         after another creator's, so its header is (0029,1110).

Both carry NumberOfImagesInMosaic in (0019,100A) too, as Siemens writes it.

Run from the repository root:  python3 tests/data/dicom/mosaic/make.py [--freeze]
"""

import hashlib
import json
import math
import os
import shutil
import struct
import subprocess
import sys
import tempfile

import numpy as np
import pydicom
from pydicom.dataset import Dataset, FileMetaDataset
from pydicom.uid import ExplicitVRLittleEndian

OUT = os.path.dirname(os.path.abspath(__file__))
TILE_COLS, TILE_ROWS, TILES, PER_ROW, TIMES = 6, 5, 7, 3, 3
ROOT = "1.2.826.0.1.3680043.8.498."


def uid(name):
    """A stable UID for a name (fixtures stay byte-identical between runs)."""
    return ROOT + str(int(hashlib.sha1(name.encode()).hexdigest()[:24], 16))


def stored(i, j, k, t):
    return 3 * i + 5 * j + 11 * k + 100 * t + 1


def mosaic(t):
    """The 15x18 mosaic of time point t, tiles row by row."""
    m = np.zeros((TILE_ROWS * PER_ROW, TILE_COLS * PER_ROW), dtype=np.uint16)
    j, i = np.mgrid[0:TILE_ROWS, 0:TILE_COLS]
    for k in range(TILES):
        r0, c0 = (k // PER_ROW) * TILE_ROWS, (k % PER_ROW) * TILE_COLS
        m[r0:r0 + TILE_ROWS, c0:c0 + TILE_COLS] = stored(i, j, k, t)
    return m


def rotation(degrees_z, degrees_x):
    """Rz @ Rx: an oblique frame."""
    a, b = math.radians(degrees_z), math.radians(degrees_x)
    rz = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    rx = np.array([[1, 0, 0], [0, math.cos(b), -math.sin(b)], [0, math.sin(b), math.cos(b)]])
    return rz @ rx


def csa2(tags):
    """A CSA2 header: "SV10", 4 unused bytes, the tag count, 77; each tag a 64-byte name, VM,
    VR, syngo data type, item count and 77 (or 205); each item four words (length, length, 77,
    length) then its bytes padded to 4."""
    out = bytearray(b"SV10\x04\x03\x02\x01")
    out += struct.pack("<2I", len(tags), 77)
    for name, vr, vm, items in tags:
        out += name.encode().ljust(64, b"\0")
        out += struct.pack("<i4s3i", vm, vr.encode().ljust(4, b"\0"), 3, len(items), 77 if items else 205)
        for item in items:
            value = item.encode()
            out += struct.pack("<4i", len(value), len(value), 77, len(value))
            out += value + b"\0" * (-len(value) % 4)
    return bytes(out)


def csa_tags(normal):
    # Values as Siemens writes them: NUL-terminated text, vm 1 padded with empty items.
    vec = [f"{v:.8f}\0" for v in normal]
    return [
        ("EchoLinePosition", "IS", 1, ["32\0", "", "", "", "", ""]),
        ("NumberOfImagesInMosaic", "US", 1, [f"{TILES}\0\0\0", "", "", "", "", ""]),
        ("SliceNormalVector", "FD", 3, vec),
        ("ImaRelTablePosition", "IS", 3, ["0\0", "0\0", "0\0"]),
    ]


def write(path, name, t, frame, normal, spacing_between, thickness, csa_block):
    ds = Dataset()
    ds.SOPClassUID = "1.2.840.10008.5.1.4.1.1.4"
    ds.SOPInstanceUID = uid(f"{name}-{t}")
    ds.StudyInstanceUID = uid("study")
    ds.SeriesInstanceUID = uid(name)
    ds.FrameOfReferenceUID = uid("frame")
    ds.Modality = "MR"
    ds.Manufacturer = "SIEMENS"
    ds.ImageType = ["ORIGINAL", "PRIMARY", "M", "ND", "MOSAIC"]
    ds.SeriesNumber = 5 if name == "asc" else 6
    ds.SeriesDescription = f"ep2d mosaic {name}"
    ds.InstanceNumber = t + 1
    ds.AcquisitionNumber = t + 1
    ds.AcquisitionTime = f"1200{t:02d}.000000"
    ds.ImageOrientationPatient = [f"{v:.8f}" for v in list(frame[:, 0]) + list(frame[:, 1])]
    ds.ImagePositionPatient = ["-61.5", "-49.25", "12.75"]
    ds.PixelSpacing = ["2.5", "2"]  # between rows, between columns
    ds.SliceThickness = str(thickness)
    if spacing_between:
        ds.SpacingBetweenSlices = str(spacing_between)
    ds.add_new((0x0019, 0x0010), "LO", "SIEMENS MR HEADER")
    ds.add_new((0x0019, 0x100A), "US", TILES)
    if csa_block != 0x10:
        ds.add_new((0x0029, 0x0010), "LO", "SIEMENS MEDCOM HEADER2")
        ds.add_new((0x0029, 0x1010), "OB", b"not a CSA header")
    ds.add_new((0x0029, csa_block), "LO", "SIEMENS CSA HEADER")
    ds.add_new((0x0029, (csa_block << 8) | 0x08), "CS", "IMAGE NUM 4")
    ds.add_new((0x0029, (csa_block << 8) | 0x10), "OB", csa2(csa_tags(normal)))
    pixels = mosaic(t)
    ds.Rows, ds.Columns = pixels.shape
    ds.SamplesPerPixel = 1
    ds.PhotometricInterpretation = "MONOCHROME2"
    ds.BitsAllocated, ds.BitsStored, ds.HighBit = 16, 12, 11
    ds.PixelRepresentation = 0
    ds.PixelData = pixels.tobytes()
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = ds.SOPClassUID
    meta.MediaStorageSOPInstanceUID = ds.SOPInstanceUID
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds.file_meta = meta
    ds.preamble = b"\0" * 128
    ds.save_as(path, enforce_file_format=True)


SERIES = {
    # name: (time points, rotation, SliceNormalVector sign, SpacingBetweenSlices, thickness, block)
    "asc": (TIMES, rotation(20, 15), 1, 3.3, 3.0, 0x10),
    "desc": (1, rotation(-10, 25), -1, None, 4.0, 0x11),
}


def make():
    for name, (times, frame, sign, between, thick, block) in SERIES.items():
        d = os.path.join(OUT, name)
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)
        normal = sign * np.cross(frame[:, 0], frame[:, 1])
        for t in range(times):
            write(os.path.join(d, f"t{t}.dcm"), name, t, frame, normal, between, thick, block)


def nifti(path):
    """dims, the sform's rows and the voxels (x fastest) of an uncompressed NIfTI-1 file."""
    raw = open(path, "rb").read()
    dim = struct.unpack_from("<8h", raw, 40)
    datatype, _bitpix = struct.unpack_from("<2h", raw, 70)
    offset = int(struct.unpack_from("<f", raw, 108)[0])
    sform_code = struct.unpack_from("<h", raw, 254)[0]
    srow = [list(struct.unpack_from("<4f", raw, 280 + 16 * r)) for r in range(3)]
    dtype = {4: "<i2", 512: "<u2", 2: "u1"}[datatype]
    n = int(np.prod(dim[1:dim[0] + 1]))
    values = np.frombuffer(raw, dtype=dtype, count=n, offset=offset)
    return list(dim[1:dim[0] + 1]), sform_code, srow, values.tolist()


def freeze():
    version = subprocess.run(["dcm2niix", "--version"], capture_output=True, text=True).stdout
    for name in SERIES:
        with tempfile.TemporaryDirectory() as tmp:
            subprocess.run(["dcm2niix", "-z", "n", "-b", "n", "-f", "out", "-o", tmp,
                            os.path.join(OUT, name)], check=True, capture_output=True)
            dims, code, srow, values = nifti(os.path.join(tmp, "out.nii"))
        expected = {
            "made_by": version.strip().splitlines()[-1] if version.strip() else "dcm2niix",
            "dims": dims,
            "sform_code": code,
            "sform": srow,
            "values": values,
        }
        lines = [f' "{k}": {json.dumps(v)}' for k, v in expected.items()]
        with open(os.path.join(OUT, f"{name}.json"), "w") as f:
            f.write("{\n" + ",\n".join(lines) + "\n}\n")


if __name__ == "__main__":
    make()
    if "--freeze" in sys.argv[1:]:
        freeze()
