"""Writes the VTK XML image data fixtures with VTK's own writer (vtkXMLImageDataWriter), run once
offline: `python tests/data/vti/make_vti.py` (pip install vtk numpy). Each holds the 6x5x4 ramp
value(x, y, z) = x + 10*y + 100*z (x fastest) of the legacy fixtures (tests/data/vtk), spacing
(1.5, 2.0, 2.5), origin (-3, 4, 10), in one of the writer's encodings; `rotated_*` add a
Direction (x along world y, y along world -x, z along z)."""

import json
import tempfile
from pathlib import Path

import numpy as np
import vtk
from vtk.util import numpy_support

HERE = Path(__file__).resolve().parent
NX, NY, NZ = 6, 5, 4
ROTATED = (0, -1, 0, 1, 0, 0, 0, 0, 1)  # row-major: columns are the axes' directions


def ramp(dtype, components=1):
    z, y, x = np.meshgrid(np.arange(NZ), np.arange(NY), np.arange(NX), indexing="ij")
    values = (x + 10 * y + 100 * z).astype(dtype).ravel()  # x fastest
    if components > 1:
        values = np.stack([values] * components, axis=1)
    return values


def image(dtype, cells=False, direction=None, extra=False):
    dims = (NX + 1, NY + 1, NZ + 1) if cells else (NX, NY, NZ)
    img = vtk.vtkImageData()
    img.SetDimensions(*dims)
    img.SetSpacing(1.5, 2.0, 2.5)
    img.SetOrigin(-3.0, 4.0, 10.0)
    if direction is not None:
        img.SetDirectionMatrix(*direction)
    data = img.GetCellData() if cells else img.GetPointData()
    if extra:
        # Arrays before the scalars: a vector field and another one-component array.
        flow = numpy_support.numpy_to_vtk(ramp(np.float32, 3), deep=True)
        flow.SetName("flow")
        data.AddArray(flow)
        mask = numpy_support.numpy_to_vtk(np.zeros(NX * NY * NZ, np.uint8), deep=True)
        mask.SetName("mask")
        data.AddArray(mask)
    array = numpy_support.numpy_to_vtk(ramp(dtype), deep=True)
    array.SetName("density")
    data.SetScalars(array)
    return img


def write(name, img, mode, compress=False, base64=False, big=False, header64=False, pieces=1):
    w = vtk.vtkXMLImageDataWriter()
    w.SetFileName(str(HERE / name))
    if pieces > 1:
        # Streamed by VTK's reader of the image written whole, which reads each piece's extent
        # alone as the writer asks for the pieces (an image given straight is every piece whole).
        # The pieces of point data share their boundary points, as VTK splits them.
        whole = tempfile.NamedTemporaryFile(suffix=".vti", delete=False).name
        write(whole, img, "appended")
        reader = vtk.vtkXMLImageDataReader()
        reader.SetFileName(whole)
        w.SetInputConnection(reader.GetOutputPort())
        w.SetNumberOfPieces(pieces)
    else:
        w.SetInputData(img)
    {"ascii": w.SetDataModeToAscii, "binary": w.SetDataModeToBinary,
     "appended": w.SetDataModeToAppended}[mode]()
    w.SetEncodeAppendedData(base64)
    if compress:
        if compress == "lz4":
            w.SetCompressorTypeToLZ4()
        else:
            w.SetCompressorTypeToZLib()
        w.SetBlockSize(64)  # several blocks, the last one short
    else:
        w.SetCompressorTypeToNone()
    if big:
        w.SetByteOrderToBigEndian()
    if header64:
        w.SetHeaderTypeToUInt64()
    else:
        w.SetHeaderTypeToUInt32()
    assert w.Write() == 1, name


write("ramp_i16_ascii.vti", image(np.int16), "ascii")
write("ramp_f32_binary.vti", image(np.float32), "binary")
write("ramp_u8_raw.vti", image(np.uint8), "appended", header64=True)  # values wrap to u8
write("ramp_f64_base64.vti", image(np.float64), "appended", base64=True)
write("ramp_u16_zlib.vti", image(np.uint16, extra=True), "appended", compress=True)
write("ramp_i32_zlib_binary.vti", image(np.int32), "binary", compress=True, header64=True)
write("ramp_i8_be.vti", image(np.int8), "appended", big=True)  # values wrap to i8
write("ramp_u32_be_zlib.vti", image(np.uint32), "appended", compress=True, big=True)
write("rotated_f64_cells.vti", image(np.float64, cells=True, direction=ROTATED), "appended")
write("rotated_i16_ascii.vti", image(np.int16, direction=ROTATED), "ascii")
write("ramp_i64_raw.vti", image(np.int64), "appended")
write("ramp_u64_ascii.vti", image(np.uint64), "ascii")
write("ramp_f32_lz4.vti", image(np.float32), "appended", compress="lz4")
write("ramp_i64_lz4_binary.vti", image(np.int64), "binary", compress="lz4", big=True)
write("ramp_u16_pieces.vti", image(np.uint16), "appended", pieces=3)
write("ramp_i16_pieces_ascii.vti", image(np.int16), "ascii", pieces=2)


def beyond_f32():
    """The ramp plus 2^40 (and a first voxel of -2^62 - 1): 64-bit integers an f32 does not hold
    exactly, with VTK's own reading of them and numpy's nearest f32 frozen beside them."""
    values = ramp(np.int64) + (1 << 40)
    values[0] = -(1 << 62) - 1
    img = vtk.vtkImageData()
    img.SetDimensions(NX, NY, NZ)
    array = numpy_support.numpy_to_vtk(values, deep=True)
    array.SetName("ids")
    img.GetPointData().SetScalars(array)
    write("beyond_f32_i64.vti", img, "appended", compress="zlib")
    r = vtk.vtkXMLImageDataReader()
    r.SetFileName(str(HERE / "beyond_f32_i64.vti"))
    r.Update()
    read = numpy_support.vtk_to_numpy(r.GetOutput().GetPointData().GetScalars())
    assert (read == values).all()
    reference = {
        "values": [int(v) for v in read],
        "f32": [float(np.float32(v)) for v in read],
        "rounded": int(sum(int(np.float32(v)) != int(v) for v in read)),
    }
    (HERE / "beyond_f32_i64.json").write_text(json.dumps(reference) + "\n")


beyond_f32()
