"""Writes the legacy VTK fixtures with VTK's own writer (vtkStructuredPointsWriter), run once
offline: `python tests/data/vtk/make_vtk.py` (pip install vtk numpy). Each holds the 6x5x4 ramp
value(x, y, z) = x + 10*y + 100*z (x fastest), spacing (1.5, 2.0, 2.5), origin (-3, 4, 10)."""

from pathlib import Path

import numpy as np
import vtk
from vtk.util import numpy_support

HERE = Path(__file__).resolve().parent
NX, NY, NZ = 6, 5, 4


def image(dtype, cells=False):
    dims = (NX + 1, NY + 1, NZ + 1) if cells else (NX, NY, NZ)
    z, y, x = np.meshgrid(np.arange(NZ), np.arange(NY), np.arange(NX), indexing="ij")
    values = (x + 10 * y + 100 * z).astype(dtype).ravel()  # x fastest
    img = vtk.vtkImageData()
    img.SetDimensions(*dims)
    img.SetSpacing(1.5, 2.0, 2.5)
    img.SetOrigin(-3.0, 4.0, 10.0)
    array = numpy_support.numpy_to_vtk(values, deep=True)
    array.SetName("density")
    data = img.GetCellData() if cells else img.GetPointData()
    data.SetScalars(array)
    return img


def write(name, img, binary):
    w = vtk.vtkStructuredPointsWriter()
    w.SetFileName(str(HERE / name))
    w.SetInputData(img)
    if binary:
        w.SetFileTypeToBinary()
    else:
        w.SetFileTypeToASCII()
    w.Write()


write("ramp_i16.vtk", image(np.int16), binary=True)
write("ramp_f32.vtk", image(np.float32), binary=True)
write("ramp_u8_ascii.vtk", image(np.uint8), binary=False)  # values up to 345 wrap to u8
write("ramp_f64_cells.vtk", image(np.float64, cells=True), binary=True)
# 64-bit integers (held as f32): VTK names an int64 array `vtktypeint64`, a uint64 one
# `vtktypeuint64`.
write("ramp_i64.vtk", image(np.int64), binary=True)
write("ramp_u64_ascii.vtk", image(np.uint64), binary=False)
