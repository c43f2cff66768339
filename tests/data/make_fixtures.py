"""Writes the format fixtures in this folder with other programs' writers.

Run from this folder:  pip install numpy nibabel pynrrd SimpleITK tifffile && python3 make_fixtures.py

Every fixture holds the same 5x4x3 "ramp" (x fastest): v = x + 10*y + 100*z, shifted or scaled
per type as noted, so tests/formats.rs can check every voxel.
"""
import gzip
import os

import nibabel as nib
import nrrd
import numpy as np
import SimpleITK as sitk
import tifffile

NX, NY, NZ = 5, 4, 3


def ramp(dtype, offset=0.0, scale=1.0):
    z, y, x = np.meshgrid(np.arange(NZ), np.arange(NY), np.arange(NX), indexing="ij")
    return ((x + 10 * y + 100 * z) * scale + offset).astype(dtype)  # shape (z, y, x)


def xyz(a):
    """(z, y, x) C-order array to (x, y, z) for writers that take x first."""
    return np.ascontiguousarray(a.transpose(2, 1, 0))


# NIfTI (nibabel): every type; scaling; big-endian; gzip; 4D; two gzip members.
for dtype, name, offset, scale in [
    (np.uint8, "u8", 0, 1), (np.int8, "i8", -100, 0.5), (np.uint16, "u16", 1000, 1),
    (np.int16, "i16", -100, 1), (np.uint32, "u32", 70000, 1), (np.int32, "i32", -70000, 1),
    (np.float32, "f32", 0.25, 0.5), (np.float64, "f64", -0.5, 0.25),
]:
    img = nib.Nifti1Image(xyz(ramp(dtype, offset, scale)), np.diag([0.5, 0.75, 2.0, 1.0]))
    img.header.set_xyzt_units("mm")
    nib.save(img, f"ramp_{name}.nii")

img = nib.Nifti1Image(xyz(ramp(np.int16)), np.diag([1.0, 1.0, 1.0, 1.0]))
img.header.set_slope_inter(2.0, -10.0)  # stored v, read as 2v - 10
nib.save(img, "ramp_i16_scaled.nii.gz")

be = xyz(ramp(np.dtype(">f4"), 0.25, 0.5))
img = nib.Nifti1Image(be, np.eye(4))
img.header.set_data_dtype(np.dtype(">f4"))
nib.save(img, "ramp_f32_be.nii")

vol4 = np.stack([xyz(ramp(np.uint16)), xyz(ramp(np.uint16, 500))], axis=-1)
img = nib.Nifti1Image(vol4, np.eye(4))
img.header.set_xyzt_units("micron")  # spacing 1 micron = 0.001 mm
nib.save(img, "ramp_4d_um.nii.gz")

raw = open("ramp_u8.nii", "rb").read()
with open("ramp_u8_two_members.nii.gz", "wb") as f:
    f.write(gzip.compress(raw[:200]) + gzip.compress(raw[200:]))

# NRRD (pynrrd): raw big-endian, gzip, detached, space directions, ascii.
nrrd.write("ramp_u16_be.nrrd", xyz(ramp(np.uint16, 1000)), {"encoding": "raw", "endian": "big", "spacings": [0.5, 0.75, 2.0]}, index_order="F")
nrrd.write("ramp_f32_gzip.nrrd", xyz(ramp(np.float32, 0.25, 0.5)), {"encoding": "gzip", "space directions": np.diag([0.5, 0.75, 2.0]), "space": "left-posterior-superior"}, index_order="F")
nrrd.write("ramp_i16_detached.nhdr", xyz(ramp(np.int16, -100)), {"encoding": "raw", "spacings": [1, 1, 1]}, detached_header=True, index_order="F")
nrrd.write("ramp_u8_ascii.nrrd", xyz(ramp(np.uint8)), {"encoding": "ascii"}, index_order="F")

# MetaImage (SimpleITK): attached, compressed, detached.
def sitk_image(a, spacing):
    im = sitk.GetImageFromArray(a)  # numpy (z, y, x) -> image (x, y, z)
    im.SetSpacing(spacing)
    return im

sitk.WriteImage(sitk_image(ramp(np.int16, -100), (0.5, 0.75, 2.0)), "ramp_i16.mha")
sitk.WriteImage(sitk_image(ramp(np.float32, 0.25, 0.5), (1.0, 1.0, 1.0)), "ramp_f32_zlib.mha", useCompression=True)
sitk.WriteImage(sitk_image(ramp(np.uint8), (1.0, 1.0, 1.0)), "ramp_u8.mhd")

# TIFF (tifffile): a u16 ImageJ stack with spacing, an f32 stack, and a folder of numbered slices.
tifffile.imwrite("ramp_u16_stack.tif", ramp(np.uint16, 1000), imagej=True, resolution=(1 / 0.5, 1 / 0.75), metadata={"spacing": 2.0, "unit": "mm", "axes": "ZYX"})
tifffile.imwrite("ramp_f32_stack.tif", ramp(np.float32, 0.25, 0.5), photometric="minisblack")
os.makedirs("ramp_slices", exist_ok=True)
for z, name in enumerate(["slice_1.tif", "slice_2.tif", "slice_10.tif"]):
    tifffile.imwrite(os.path.join("ramp_slices", name), ramp(np.uint8)[z])
