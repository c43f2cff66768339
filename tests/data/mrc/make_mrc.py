"""Writes the MRC fixtures with mrcfile (the CCP-EM reference library), run once offline:
`python tests/data/mrc/make_mrc.py` (pip install mrcfile numpy). Every voxel is a known function
of its index, so the tests check values without a second copy: value(x, y, z) = x + 10*y + 100*z
(scaled where the type needs it). mrcfile is BSD-licensed; the files are this project's."""

from pathlib import Path

import mrcfile
import numpy as np

HERE = Path(__file__).resolve().parent
NX, NY, NZ = 6, 5, 4


def ramp(dtype):
    z, y, x = np.meshgrid(np.arange(NZ), np.arange(NY), np.arange(NX), indexing="ij")
    return (x + 10 * y + 100 * z).astype(dtype)  # mrcfile's arrays are [z, y, x]


def write(name, data, voxel_size=(1.5, 2.0, 2.5), **header):
    with mrcfile.new(HERE / name, overwrite=True) as mrc:
        mrc.set_data(data)
        mrc.voxel_size = voxel_size
        for key, value in header.items():
            setattr(mrc.header, key, value)
        if "ispg" not in header:
            mrc.set_volume()


write("ramp_i16.mrc", ramp(np.int16))
write("ramp_f32.mrc", ramp(np.float32))
write("ramp_u16.mrc", ramp(np.uint16))
write("ramp_i8.mrc", (ramp(np.int16) % 128).astype(np.int8))
write("ramp_f16.mrc", ramp(np.float16))
with mrcfile.new(HERE / "ramp_ext.mrc", overwrite=True) as mrc:
    mrc.set_data(ramp(np.int16))
    mrc.set_extended_header(np.arange(40, dtype=np.int32))  # 160 bytes skipped
    mrc.voxel_size = (1.5, 2.0, 2.5)
    mrc.set_volume()
# Sections along X, rows along Y, columns along Z: stored [x][y][z] with z fastest.
with mrcfile.new(HERE / "ramp_zyx.mrc", overwrite=True) as mrc:
    mrc.set_data(np.ascontiguousarray(np.transpose(ramp(np.int16), (2, 1, 0))))
    mrc.header.mapc, mrc.header.mapr, mrc.header.maps = 3, 2, 1
    # The sampling and the cell run along the map's X, Y, Z (mrcfile's voxel_size would take
    # them along the columns, rows and sections).
    mrc.header.mx, mrc.header.my, mrc.header.mz = NX, NY, NZ
    mrc.header.cella = (1.5 * NX, 2.0 * NY, 2.5 * NZ)
    mrc.set_volume()
# A tilt series: images, not a volume.
with mrcfile.new(HERE / "tilts.st", overwrite=True) as mrc:
    mrc.set_data(ramp(np.int16))
    mrc.set_image_stack()
