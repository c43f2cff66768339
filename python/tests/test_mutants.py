"""Hostile files never crash the interpreter, on the mutation corpus too: the seed files of every
reader that `tests/slow/mutants.rs` mutates, mutated as it does (the same xorshift64* generator
seeded the same way and the same mutations: bytes flipped, header numbers made extreme, binary
header fields overwritten, header lines repeated or dropped, files cut short or lengthened, so the
same mutants for the same count), each loaded by `slabscope.load(path, max_memory="64M")` in a
child interpreter. A mutant that crashes or aborts the child, hangs it for 10 s, or raises
anything but the package's documented exceptions for a file (`slabscope.VolumeError`, `OSError`,
`ValueError`) with a one-line message naming the file fails the test.

`SLABSCOPE_MUTANTS=N` sets the mutants per reader (default 30)."""

from __future__ import annotations

import json
import os
import queue
import shutil
import subprocess
import sys
import threading
from pathlib import Path

from conftest import DATA

# Seeds, per reader: a file of tests/data (empty: VolumeShop's, made below) and the name a mutant
# takes; as in tests/slow/mutants.rs, whose order the mutants' seeds depend on.
READERS = [
    ("nifti", [
        ("ramp_u8.nii", "m.nii"),
        ("ramp_f32_be.nii", "m.nii"),
        ("ramp_i16_scaled.nii.gz", "m.nii.gz"),
        ("ramp_4d_um.nii.gz", "m.nii.gz"),
    ]),
    ("nifti2", [
        ("nifti2/ramp_i16_oblique.nii", "m.nii"),
        ("nifti2/ramp_f32_be.nii.gz", "m.nii.gz"),
        ("nifti2/ramp_4d_um.nii", "m.nii"),
    ]),
    ("nrrd", [
        ("ramp_u16_be.nrrd", "m.nrrd"),
        ("ramp_f32_gzip.nrrd", "m.nrrd"),
        ("ramp_u8_ascii.nrrd", "m.nrrd"),
        ("ramp_i16_detached.nhdr", "m.nhdr"),
    ]),
    ("metaimage", [
        ("ramp_i16.mha", "m.mha"),
        ("ramp_f32_zlib.mha", "m.mha"),
        ("ramp_u8.mhd", "m.mhd"),
    ]),
    ("tiff", [
        ("ramp_u16_stack.tif", "m.tif"),
        ("ramp_f32_stack.tif", "m.tif"),
        ("ome/zct.ome.tif", "m.ome.tif"),
    ]),
    ("volumeshop", [("", "m.dat")]),
    ("dicom", [
        ("dicom/enhanced.dcm", "m.dcm"),
        ("dicom/jpegll/j1.dcm", "m.dcm"),
        ("dicom/gap/slice00.dcm", "m.dcm"),
        ("dicom/deflated.dcm", "m.dcm"),
        ("dicom/j2k-lossy/s0.dcm", "m.dcm"),
        ("dicom/jxl-lossy/s0.dcm", "m.dcm"),
    ]),
    # Siemens mosaics: their CSA image headers among the header bytes mutated.
    ("mosaic", [
        ("dicom/mosaic/asc/t0.dcm", "m.dcm"),
        ("dicom/mosaic/desc/t0.dcm", "m.dcm"),
    ]),
    ("raw", [("ramp_u8.raw", "m_5x4x3_uint8.raw")]),
    # A folder format: the store is copied whole and one of its files (after `//`) mutated.
    ("zarr", [
        ("zarr/v04_blosc.ome.zarr//.zattrs", "m.ome.zarr"),
        ("zarr/v04_blosc.ome.zarr//s0/.zarray", "m.ome.zarr"),
        ("zarr/v04_blosc.ome.zarr//s0/1/1/1", "m.ome.zarr"),
        ("zarr/v05_sharded.ome.zarr//zarr.json", "m.ome.zarr"),
        ("zarr/v05_sharded.ome.zarr//s0/zarr.json", "m.ome.zarr"),
        ("zarr/v05_sharded.ome.zarr//s0/c/1/1/1", "m.ome.zarr"),
        ("zarr/v05_tczyx.ome.zarr//s0/zarr.json", "m.ome.zarr"),
        ("zarr/v05_tczyx.ome.zarr//s0/c/1/2/1/1/1", "m.ome.zarr"),
    ]),
    # Readers added later come last, as in the Rust harness: each mutant's random stream follows
    # its place in the list.
    ("mrc", [
        ("mrc/ramp_i16.mrc", "m.mrc"),
        ("mrc/ramp_f16.mrc", "m.mrc"),
        ("mrc/ramp_zyx.mrc", "m.mrc"),
        ("mrc/ramp_ext.mrc", "m.rec"),
    ]),
    ("vtk", [
        ("vtk/ramp_i16.vtk", "m.vtk"),
        ("vtk/ramp_u8_ascii.vtk", "m.vtk"),
        ("vtk/ramp_f64_cells.vtk", "m.vtk"),
    ]),
    ("vti", [
        ("vti/ramp_i16_ascii.vti", "m.vti"),
        ("vti/ramp_f32_binary.vti", "m.vti"),
        ("vti/ramp_u8_raw.vti", "m.vti"),
        ("vti/ramp_u16_zlib.vti", "m.vti"),
        ("vti/ramp_i32_zlib_binary.vti", "m.vti"),
        ("vti/ramp_f64_base64.vti", "m.vti"),
    ]),
    # Issue #47's hostile stores: a codec chain (gzip inside gzip), a shard inside a shard, and
    # 4096 chunks of 4³ (a header number made extreme makes a flood of them).
    ("zarr-hostile", [
        ("zarr/hostile/gzip_gzip.zarr//zarr.json", "m.zarr"),
        ("zarr/hostile/gzip_gzip.zarr//c/0/0/0", "m.zarr"),
        ("zarr/hostile/nested_shard.zarr//zarr.json", "m.zarr"),
        ("zarr/hostile/nested_shard.zarr//c/0/0/0", "m.zarr"),
        ("zarr/hostile/small_chunks.zarr//zarr.json", "m.zarr"),
    ]),
    ("hdf5", [
        ("hdf5/ramp_u16_contiguous.h5", "m.h5"),
        ("hdf5/ramp_f32_gzip_shuffle.h5", "m.h5"),
        ("hdf5/ramp_i16_gzip_latest.h5", "m.h5"),
        ("hdf5/ramp_4d_i8.h5", "m.h5"),
        ("hdf5/imaris.ims", "m.ims"),
    ]),
]

# Seeds refused by design (in one line naming the file), whose mutants are still run: a shard
# inside a shard, whose chunks' decoded sizes cannot be weighed.
REFUSED_SEEDS = ("zarr/hostile/nested_shard.zarr//",)

# The data files of the detached seeds, beside every mutant.
DETACHED = ["ramp_i16_detached.raw", "ramp_u8.raw"]

# Numbers a header should never be trusted with.
EXTREMES = [
    "0", "-1", "1", "2147483647", "2147483648", "4294967296", "18446744073709551617",
    "99999999999999999999999", "1e308", "-1e308", "1e-300", "nan", "inf", "65535", "-32768",
    "3.5",
]

# Values an aligned binary header field is overwritten with.
FIELDS = [
    b"\xff\xff", b"\xff\x7f", b"\x00\x80", b"\x00\x00", b"\xff\xff\xff\x7f", b"\x00\x00\xc0\x7f",
    b"\x00\x00\x80\x7f", b"\x01\x00\x00\x00",
]

MASK = (1 << 64) - 1

# Seconds one mutant may take.
TIMEOUT = 10

# The budget every mutant is loaded under, and the address space the child may add to what it
# holds once it has imported the package (the Rust harness's limit for the binary).
BUDGET = 64 << 20
SPACE = 4 * BUDGET + (768 << 20)


class Rng:
    """xorshift64*: the mutants of a seed are the same on every run."""

    def __init__(self, state: int):
        self.state = state

    def next(self) -> int:
        x = self.state
        x ^= x >> 12
        x ^= (x << 25) & MASK
        x ^= x >> 27
        self.state = x
        return (x * 0x2545F4914F6CDD1D) & MASK

    def below(self, n: int) -> int:
        return self.next() % max(n, 1)


def header_len(b: bytes) -> int:
    """The header's length: DICOM's elements before the pixel data, the text before NRRD's blank
    line or up to the end of MetaImage's `ElementDataFile` line, all of JSON (Zarr's metadata) and
    of HDF5 (its metadata spread through the file), else NIfTI's 352 bytes."""
    if b[:1] == b"{" or b[:4] == b"\x89HDF":
        return len(b)
    if b[128:132] == b"DICM":
        at = b.find(b"\xe0\x7f\x10\x00")
        return at if at >= 0 else len(b)
    text = b[:4096]
    at = text.find(b"\n\n")
    if at >= 0:
        return at + 2
    at = text.find(b"ElementDataFile")
    if at >= 0:
        end = text.find(b"\n", at)
        return end + 1 if end >= 0 else len(text)
    return min(len(b), 352)


def extreme_number(b: bytearray, head: int, rng: Rng) -> None:
    text = bytes(b[: min(head, len(b))])
    numbers = []
    for i, c in enumerate(text):
        if 48 <= c <= 57 and (i == 0 or not text[i - 1 : i].isalnum()):
            n = 0
            while i + n < len(text) and (text[i + n : i + n + 1].isdigit() or text[i + n] in b".e"):
                n += 1
            numbers.append((i, n))
    if numbers:
        at, n = numbers[rng.below(len(numbers))]
        b[at : at + n] = EXTREMES[rng.below(len(EXTREMES))].encode()


def extreme_field(b: bytearray, head: int, rng: Rng) -> None:
    at = rng.below(min(head, len(b)) // 2) * 2
    for k, x in enumerate(FIELDS[rng.below(len(FIELDS))]):
        if at + k < len(b):
            b[at + k] = x


def repeat_line(b: bytearray, head: int, rng: Rng) -> None:
    text = bytes(b[: min(head, len(b))])
    starts = [0] + [i + 1 for i, c in enumerate(text) if c == 10]
    starts = [s for s in starts if s < len(text)]
    if starts:
        s = starts[rng.below(len(starts))]
        end = text.find(b"\n", s)
        e = end + 1 if end >= 0 else len(text)
        b[e:e] = b[s:e]


def drop_line(b: bytearray, head: int) -> None:
    text = bytes(b[: min(head, len(b))])
    first = text.find(b"\n")
    if first >= 0:
        end = text.find(b"\n", first + 1)
        if end >= 0:
            del b[first + 1 : end + 1]


def mutate(seed: bytes, rng: Rng) -> bytes:
    """One mutant of `seed`: one to three mutations."""
    b = bytearray(seed)
    head = max(header_len(seed), 1)
    for _ in range(rng.below(3) + 1):
        kind = rng.below(7)
        if kind == 0:  # flip bytes, mostly in the header
            for _ in range(rng.below(8) + 1):
                at = rng.below(head) if rng.below(4) > 0 else rng.below(len(b))
                if at < len(b):
                    b[at] ^= 1 << rng.below(8)
        elif kind == 1:
            extreme_number(b, head, rng)
        elif kind == 2:
            extreme_field(b, head, rng)
        elif kind == 3:  # cut short
            del b[rng.below(len(b) + 1) :]
        elif kind == 4:  # lengthen with zeros or noise
            n = 1 + rng.below(4096)
            noise = rng.below(2) == 0
            b.extend((rng.next() & 0xFF) if noise else 0 for _ in range(n))
        elif kind == 5:
            repeat_line(b, head, rng)
        else:
            drop_line(b, head)
    return bytes(b)


def volumeshop_seed() -> bytes:
    """A valid VolumeShop `.dat`: three u16 dims, then u16 voxels."""
    dims = b"".join(d.to_bytes(2, "little") for d in (5, 4, 3))
    return dims + b"".join((i * 7).to_bytes(2, "little") for i in range(60))


def seed_bytes(seed: str) -> bytes:
    """The bytes of `seed`: a file of tests/data, a member of a store (`STORE//MEMBER`), or
    (empty) the VolumeShop seed."""
    if not seed:
        return volumeshop_seed()
    store, _, member = seed.partition("//")
    return (DATA / store / member).read_bytes() if member else (DATA / seed).read_bytes()


def place(folder: Path, seed: str, name: str, data: bytes) -> str:
    """Writes `data` as `name` in `folder` (for a store's member, a copy of the store with that
    member replaced), with the detached seeds' data files beside it; its path."""
    folder.mkdir()
    store, _, member = seed.partition("//")
    if member:
        shutil.copytree(DATA / store, folder / name)
        (folder / name / member).write_bytes(data)
    else:
        (folder / name).write_bytes(data)
    for f in DETACHED:
        shutil.copy(DATA / f, folder / f)
    return str(folder / name)


def mutants(per_reader: int):
    """(reader, index, seed file, name, bytes) of every mutant, in the Rust harness's order."""
    j = 0
    for reader, seeds in READERS:
        for i in range(per_reader):
            seed, name = seeds[i % len(seeds)]
            data = seed_bytes(seed)
            rng = Rng(0x9E3779B97F4A7C15 ^ (((j + 1) * 0xD1B54A32D192ED03) & MASK))
            yield reader, i, seed, name, mutate(data, rng)
            j += 1


# The child: loads every path of the list file it is given, saying when it starts one and how it
# ended; any other exception than the documented ones ends it with a traceback.
CHILD = r"""
import json, os, sys
import numpy as np
import slabscope

try:
    import resource
    with open("/proc/self/status") as status:
        held = next(int(l.split()[1]) * 1024 for l in status if l.startswith("VmSize:"))
    resource.setrlimit(resource.RLIMIT_AS, (held + int(sys.argv[2]), resource.RLIM_INFINITY))
except (ImportError, OSError, StopIteration, ValueError):
    pass
with open(sys.argv[1]) as listed:
    paths = listed.read().splitlines()
for path in paths:
    print(json.dumps({"start": path}), flush=True)
    try:
        volume = slabscope.load(path, max_memory="64M")
        # Every voxel read back through the NumPy view of the library's memory.
        total = float(np.asarray(volume.array).sum(dtype=np.float64))
        row = {"path": path, "loaded": list(volume.shape), "sum": total}
    except (slabscope.VolumeError, OSError, ValueError) as e:
        row = {"path": path, "error": type(e).__name__, "message": str(e)}
    print(json.dumps(row), flush=True)
"""


def run_children(paths: list[str], folder: Path) -> tuple[dict, dict]:
    """Every path loaded by child interpreters, a new one after each that died: the rows of the
    paths that ended, and what went wrong with the others."""
    rows: dict = {}
    failures: dict = {}
    remaining = list(paths)
    while remaining:
        listed = folder / "paths.txt"
        listed.write_text("".join(p + "\n" for p in remaining))
        errors = folder / "stderr.txt"
        with open(errors, "w") as stderr:
            child = subprocess.Popen(
                [sys.executable, "-c", CHILD, str(listed), str(SPACE)],
                stdout=subprocess.PIPE, stderr=stderr, text=True, cwd=folder,
            )
        lines: queue.Queue = queue.Queue()

        def read(out=child.stdout):
            for line in out:
                lines.put(line)
            lines.put(None)

        reader = threading.Thread(target=read, daemon=True)
        reader.start()
        started = None
        hung = False
        while True:
            try:
                line = lines.get(timeout=TIMEOUT + (5 if started is None and not rows else 0))
            except queue.Empty:
                hung = True
                child.kill()
                break
            if line is None:
                break
            message = json.loads(line)
            if "start" in message:
                started = message["start"]
            else:
                rows[message["path"]] = message
                started = None
        code = child.wait()
        reader.join()
        told = errors.read_text().strip().splitlines()
        if started is None:
            # Between two mutants: the import, or the end.
            assert not hung and code == 0, (code, "\n".join(told))
        else:
            why = f"hung ({TIMEOUT} s)" if hung else (
                f"killed by signal {-code}" if code < 0 else f"exit {code}"
            )
            failures[started] = f"{why}: {told[-1] if told else 'nothing on stderr'}"
        remaining = [p for p in remaining if p not in rows and p not in failures]
    return rows, failures


def test_mutants_of_every_reader_never_crash_the_interpreter(tmp_path):
    per_reader = int(os.environ.get("SLABSCOPE_MUTANTS", "30"))
    paths, seeds, refused = [], [], []
    # The seeds themselves first: each must load (but those refused by design), or the mutants
    # test nothing.
    for reader, listed in READERS:
        for seed, name in listed:
            folder = tmp_path / f"{reader}-seed-{len(seeds) + len(refused)}"
            placed = place(folder, seed, name, seed_bytes(seed))
            (refused if seed.startswith(REFUSED_SEEDS) else seeds).append(placed)
    for reader, i, seed, name, data in mutants(per_reader):
        paths.append(place(tmp_path / f"{reader}-{i}", seed, name, data))
    rows, failures = run_children(seeds + refused + paths, tmp_path)
    assert not failures, "\n".join(f"{p}: {why}" for p, why in failures.items())
    unread = [p for p in seeds if "loaded" not in rows[p]]
    assert not unread, [rows[p] for p in unread]
    unread = [
        p for p in refused if "loaded" in rows[p] or os.path.basename(p) not in rows[p]["message"]
    ]
    assert not unread, [rows[p] for p in unread]
    loaded = [p for p in paths if "loaded" in rows[p]]
    worded = [
        rows[p]
        for p in paths
        if p not in loaded
        and not (rows[p]["message"] and "\n" not in rows[p]["message"] and os.path.basename(p) in rows[p]["message"])
    ]
    assert not worded, "\n".join(f"{r['path']}: {r['error']}: {r['message']!r}" for r in worded)
    # Many mutants are still volumes (a lengthened file, a flipped voxel) and many are not.
    assert 0 < len(loaded) < len(paths), (len(loaded), len(paths))
