"""Writes the NIfTI-2 fixtures in this folder with nibabel, and expected.json: the affine nibabel
reads back from each, frozen so that `cargo test` needs no Python.

Run from this folder:  pip install numpy nibabel && python3 make.py

Each volume is the 5x4x3 ramp of ../make_fixtures.py (v = x + 10*y + 100*z, x fastest), shifted or
scaled per file as noted.
"""
import json

import nibabel as nib
import numpy as np

NX, NY, NZ = 5, 4, 3


def ramp(dtype, offset=0.0, scale=1.0):
    z, y, x = np.meshgrid(np.arange(NZ), np.arange(NY), np.arange(NX), indexing="ij")
    return ((x + 10 * y + 100 * z) * scale + offset).astype(dtype).transpose(2, 1, 0)


def rotated(zooms, shift):
    """A rotation of 30 degrees about z and 20 about x, with `zooms` and an origin `shift`."""
    a, b = np.radians(30), np.radians(20)
    rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    rx = np.array([[1, 0, 0], [0, np.cos(b), -np.sin(b)], [0, np.sin(b), np.cos(b)]])
    m = np.eye(4)
    m[:3, :3] = rz @ rx @ np.diag(zooms)
    m[:3, 3] = shift
    return m


expected = {}


def save(img, name):
    nib.save(img, name)
    back = nib.load(name)
    assert back.header["sizeof_hdr"] == 540, name
    expected[name] = {"affine": back.affine.tolist(), "zooms": [float(z) for z in back.header.get_zooms()]}


# Oblique sform and qform (nibabel writes both), i16 scaled by slope and intercept, mm.
img = nib.Nifti2Image(ramp(np.int16), rotated([0.5, 0.75, 2.0], [-12.5, 30.25, 7.0]))
img.header.set_slope_inter(2.0, -10.0)  # stored v, read as 2v - 10
img.header.set_xyzt_units("mm")
save(img, "ramp_i16_oblique.nii")

# Big-endian f32, gzipped, a qform alone (sform code 0).
be = ramp(np.dtype(">f4"), 0.25, 0.5)
img = nib.Nifti2Image(be, None)
img.header.set_data_dtype(np.dtype(">f4"))
img.header.set_qform(rotated([1.5, 1.5, 3.0], [1.0, 2.0, 3.0]), code=1)
img.header.set_sform(None, code=0)
save(img, "ramp_f32_be.nii.gz")

# A header and image pair (ni2), u16.
img = nib.Nifti2Pair(ramp(np.uint16, 1000), np.diag([0.5, 0.75, 2.0, 1.0]))
save(img, "ramp_u16_pair.hdr")

# 4D: two volumes, micron units.
vol4 = np.stack([ramp(np.uint16), ramp(np.uint16, 500)], axis=-1)
img = nib.Nifti2Image(vol4, np.eye(4))
img.header.set_xyzt_units("micron")
save(img, "ramp_4d_um.nii")

# A CIFTI-2 dense scalar file's NIfTI-2 shape: dims 1x1x1x1x3x4 and intent code 3006.
img = nib.Nifti2Image(np.zeros((1, 1, 1, 1, 3, 4), np.float32), np.eye(4))
img.header.set_intent(3006)
nib.save(img, "cifti2_dscalar.nii")

with open("expected.json", "w") as f:
    lines = [f"{json.dumps(k)}: {json.dumps(v)}" for k, v in sorted(expected.items())]
    f.write("{\n" + ",\n".join(lines) + "\n}\n")
