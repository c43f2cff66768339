#!/usr/bin/env python3
"""Orientation fixtures for slabscope, written by other programs' writers, and what those programs
read back.

    pip install numpy nibabel pynrrd SimpleITK
    python3 make.py                 # writes the fixtures and expected.json beside this script
    python3 make.py read FILE...    # prints, as JSON, the RAS affine nibabel and SimpleITK read

`expected.json` freezes, per fixture, the voxel-to-world affine (RAS+ mm, rows) as the writer's
own library reads it back and the orientation codes of nibabel's `aff2axcodes`, so that
`cargo test` needs no Python. `read` is what tests/orientation.rs runs, when Python and these
libraries are there, on the label volumes slabscope exports.
"""

import json
import math
import sys
from pathlib import Path

import nibabel as nib
import nrrd
import numpy as np
import SimpleITK as sitk
from nibabel.orientations import aff2axcodes

HERE = Path(__file__).resolve().parent
DIMS = (6, 5, 7)
LPS = np.diag([-1.0, -1.0, 1.0])


def ramp(dtype=np.uint8):
    """v = x + 2y + 3z over DIMS, x fastest on disk (array index order x, y, z)."""
    x, y, z = np.meshgrid(*(np.arange(n) for n in DIMS), indexing="ij")
    return (x + 2 * y + 3 * z).astype(dtype)


def rot(axis, degrees):
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    m = np.eye(3)
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    return m


def affine(linear, origin):
    a = np.eye(4)
    a[:3, :3] = linear
    a[:3, 3] = origin
    return a


def nifti(name, aff, sform_code, qform_code):
    img = nib.Nifti1Image(ramp(), None)
    img.header.set_sform(aff if sform_code else None, code=sform_code)
    img.header.set_qform(aff if qform_code else None, code=qform_code)
    if not (sform_code or qform_code):
        img.header.set_zooms((1.5, 2.0, 2.5))
    path = HERE / name
    nib.save(img, path)
    return path


def read_nifti(path):
    img = nib.load(path)
    h = img.header
    if h["sform_code"] == 0 and h["qform_code"] == 0:
        return None
    return img.affine


def read_nrrd(path):
    _, h = nrrd.read(str(path))
    sign = {"left-posterior-superior": [-1, -1, 1], "right-anterior-superior": [1, 1, 1],
            "left-anterior-superior": [-1, 1, 1]}[h["space"]]
    directions = np.asarray(h["space directions"], dtype=float)  # one row per axis
    return affine(np.diag(sign) @ directions.T, np.asarray(sign) * h["space origin"])


def read_sitk(path):
    img = sitk.ReadImage(str(path))
    direction = np.asarray(img.GetDirection()).reshape(3, 3)
    linear = LPS @ direction @ np.diag(img.GetSpacing())
    return affine(linear, LPS @ np.asarray(img.GetOrigin()))


def make():
    fixtures = {}

    def record(path, aff):
        fixtures[path.name] = {
            "affine": None if aff is None else np.round(aff, 9).tolist(),
            "orientation": None if aff is None else "".join(aff2axcodes(aff)),
        }

    rotated = rot(2, 30) @ rot(0, 20) @ np.diag([1.5, 2.0, 2.5])
    flipped = rot(1, 15) @ np.diag([1.0, 1.2, -3.0])  # left-handed: qfac -1
    lsa = np.array([[-1.0, 0, 0], [0, 0, 1.5], [0, 1.25, 0]])
    sheared = np.array([[1.0, 0, 0], [0, 1.0, 0.4], [0, 0, 1.2]])  # a tilted gantry
    for path in [
        nifti("sform_rotated.nii.gz", affine(rotated, [-40.25, 12.5, -7.75]), 1, 0),
        nifti("qform_only.nii", affine(flipped, [10.0, -20.0, 30.0]), 0, 1),
        nifti("ras.nii.gz", affine(np.eye(3), [-2.0, -3.0, -4.0]), 1, 1),
        nifti("las.nii.gz", affine(np.diag([-2.0, 2.0, 2.0]), [5.0, -5.0, 0.0]), 1, 1),
        nifti("lsa.nii.gz", affine(lsa, [3.0, -60.0, 20.0]), 1, 1),
        nifti("sheared.nii.gz", affine(sheared, [0.0, 0.0, 0.0]), 1, 0),
        nifti("no_orientation.nii", None, 0, 0),
    ]:
        record(path, read_nifti(path))

    directions = (rot(2, -25) @ rot(1, 10) @ np.diag([0.8, 0.9, 2.0])).T  # rows: axes, LPS
    nrrd.write(str(HERE / "lps_oblique.nrrd"), ramp(np.int16), {
        "space": "left-posterior-superior",
        "space directions": directions,
        "space origin": np.array([-12.5, 30.0, 44.0]),
        "kinds": ["domain"] * 3,
        "encoding": "gzip",
    }, index_order="F")
    record(HERE / "lps_oblique.nrrd", read_nrrd(HERE / "lps_oblique.nrrd"))

    img = sitk.GetImageFromArray(ramp(np.uint16).transpose(2, 1, 0).copy())  # z, y, x
    img.SetSpacing((1.25, 0.75, 3.0))
    img.SetOrigin((7.0, -8.0, 9.5))
    img.SetDirection((rot(2, 25) @ rot(0, 10) @ np.diag([1.0, -1.0, -1.0])).flatten().tolist())
    sitk.WriteImage(img, str(HERE / "transform.mha"))
    record(HERE / "transform.mha", read_sitk(HERE / "transform.mha"))

    lines = [f" {json.dumps(k)}: {json.dumps(fixtures[k])}" for k in sorted(fixtures)]
    (HERE / "expected.json").write_text("{\n" + ",\n".join(lines) + "\n}\n")


def read(paths):
    """What nibabel (NIfTI) and SimpleITK (every format) read from each file."""
    out = {}
    for p in map(Path, paths):
        try:
            entry = {"sitk": np.round(read_sitk(p), 9).tolist()}
        except RuntimeError as e:  # ITK refuses sheared transforms
            entry = {"sitk_error": str(e).strip().splitlines()[-1]}
        if p.name.endswith((".nii", ".nii.gz")):
            img = nib.load(p)
            entry["nibabel"] = np.round(img.affine, 9).tolist()
            entry["sform_code"] = int(img.header["sform_code"])
            entry["qform_code"] = int(img.header["qform_code"])
            entry["qform"] = np.round(img.header.get_qform(), 9).tolist()
        if p.name.endswith(".nrrd"):
            entry["pynrrd"] = np.round(read_nrrd(p), 9).tolist()
        out[p.name] = entry
    print(json.dumps(out))


if __name__ == "__main__":
    if sys.argv[1:2] == ["read"]:
        read(sys.argv[2:])
    else:
        make()
