"""Writes the OME-TIFF fixtures with tifffile (pip install numpy tifffile; python3 make.py).

Each holds the ramp v = x + 10 y + 100 z + 1000 c + 3000 t (uint16), so that a test can tell
every voxel's x, y, z, channel and time point from its value:

- zct.ome.tif: 5x4x3 voxels, 2 channels, 2 time points (axes TCZYX), PhysicalSize 0.5 x 0.25 x
  2 µm;
- ztc_nm.ome.tif: the same voxels stored ZTCYX (pages z fastest, then t, then c), sizes in nm;
- plain_z.ome.tif: one channel and time point, sizes in mm.

Also writes expected.json: each file's sizes, DimensionOrder and physical sizes as tifffile's OME
reader reports them.
"""

import json

import numpy as np
import tifffile

X, Y, Z, C, T = 5, 4, 3, 2, 2
t, c, z, y, x = np.meshgrid(np.arange(T), np.arange(C), np.arange(Z), np.arange(Y), np.arange(X), indexing="ij")
ramp = (x + 10 * y + 100 * z + 1000 * c + 3000 * t).astype(np.uint16)  # TCZYX

tifffile.imwrite(
    "zct.ome.tif",
    ramp,
    ome=True,
    metadata={"axes": "TCZYX", "PhysicalSizeX": 0.5, "PhysicalSizeY": 0.25, "PhysicalSizeZ": 2.0},
)
tifffile.imwrite(
    "ztc_nm.ome.tif",
    np.transpose(ramp, (1, 0, 2, 3, 4)),  # CTZYX: pages z, then t, then c
    ome=True,
    metadata={
        "axes": "CTZYX",
        "PhysicalSizeX": 500.0,
        "PhysicalSizeXUnit": "nm",
        "PhysicalSizeY": 250.0,
        "PhysicalSizeYUnit": "nm",
        "PhysicalSizeZ": 2000.0,
        "PhysicalSizeZUnit": "nm",
    },
)
tifffile.imwrite(
    "plain_z.ome.tif",
    ramp[0, 0],
    ome=True,
    metadata={
        "axes": "ZYX",
        "PhysicalSizeX": 0.5,
        "PhysicalSizeXUnit": "mm",
        "PhysicalSizeY": 0.5,
        "PhysicalSizeYUnit": "mm",
        "PhysicalSizeZ": 1.5,
        "PhysicalSizeZUnit": "mm",
    },
)

expected = {}
for name in ["zct.ome.tif", "ztc_nm.ome.tif", "plain_z.ome.tif"]:
    with tifffile.TiffFile(name) as f:
        xml = tifffile.xml2dict(f.ome_metadata)
        pixels = xml["OME"]["Image"]["Pixels"]
        expected[name] = {
            k: pixels.get(k)
            for k in ["DimensionOrder", "SizeX", "SizeY", "SizeZ", "SizeC", "SizeT", "PhysicalSizeX", "PhysicalSizeXUnit", "PhysicalSizeY", "PhysicalSizeYUnit", "PhysicalSizeZ", "PhysicalSizeZUnit"]
        }
        expected[name]["pages"] = len(f.pages)
with open("expected.json", "w") as out:
    json.dump(expected, out, indent=1, ensure_ascii=False)
    out.write("\n")
