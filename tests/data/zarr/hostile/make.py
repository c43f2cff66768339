"""The hostile stores' seeds of the mutation harness (tests/slow/mutants.rs), issue #47: a codec
chain (gzip inside gzip), a shard inside a shard, and a store of many small chunks. Standard
library only: `python3 make.py` in this folder rewrites them exactly."""

import gzip
import json
import os
import shutil
import struct

BYTES = {"name": "bytes", "configuration": {"endian": "little"}}
GZIP = {"name": "gzip", "configuration": {"level": 5}}
BY_INDEX = [BYTES]


def ramp(n):
    return bytes((x + 2 * y + 3 * z) % 256 for z in range(n) for y in range(n) for x in range(n))


def block(data, n, at, size):
    """The size³ block at `at` (z, y, x) of an n³ volume, x fastest."""
    z0, y0, x0 = at
    return b"".join(
        data[((z0 + z) * n + y0 + y) * n + x0 : ((z0 + z) * n + y0 + y) * n + x0 + size]
        for z in range(size)
        for y in range(size)
    )


def gz(b):
    return gzip.compress(b, mtime=0)


def shard(chunks):
    """A shard of `chunks` (in C order) with its index at the end, without a checksum."""
    body, index = b"", b""
    for c in chunks:
        index += struct.pack("<QQ", len(body), len(c))
        body += c
    return body + index


def array(path, shape, chunk, codecs, files):
    if os.path.exists(path):
        shutil.rmtree(path)
    os.makedirs(path)
    meta = {
        "zarr_format": 3,
        "node_type": "array",
        "shape": [shape] * 3,
        "data_type": "uint8",
        "fill_value": 0,
        "chunk_grid": {"name": "regular", "configuration": {"chunk_shape": [chunk] * 3}},
        "chunk_key_encoding": {"name": "default", "configuration": {"separator": "/"}},
        "codecs": codecs,
    }
    with open(os.path.join(path, "zarr.json"), "w") as f:
        json.dump(meta, f, indent=1)
    for key, data in files.items():
        os.makedirs(os.path.join(path, os.path.dirname(key)), exist_ok=True)
        with open(os.path.join(path, key), "wb") as f:
            f.write(data)


def corners(size, step):
    return [(z, y, x) for z in range(0, size, step) for y in range(0, size, step) for x in range(0, size, step)]


data = ramp(16)
array("gzip_gzip.zarr", 16, 16, [BYTES, GZIP, GZIP], {"c/0/0/0": gz(gz(data))})

inner = {"name": "sharding_indexed", "configuration": {"chunk_shape": [4, 4, 4], "codecs": [BYTES, GZIP], "index_codecs": BY_INDEX}}
outer = {"name": "sharding_indexed", "configuration": {"chunk_shape": [8, 8, 8], "codecs": [inner], "index_codecs": BY_INDEX}}
eighths = []
for at in corners(16, 8):
    part = block(data, 16, at, 8)
    eighths.append(shard([gz(block(part, 8, c, 4)) for c in corners(8, 4)]))
array("nested_shard.zarr", 16, 16, [outer], {"c/0/0/0": shard(eighths)})

array("small_chunks.zarr", 64, 4, [BYTES], {"c/0/0/0": block(ramp(64), 64, (0, 0, 0), 4)})
