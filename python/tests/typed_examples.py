"""Every call of slabscope as a typed program uses it: `mypy --strict` checks this file against the
package's stubs (test_typing.py runs it, and `stubtest` on the extension module). Never run: it
names files that do not exist."""

from __future__ import annotations

import copy
import pickle
from pathlib import Path
from typing import Any, Optional

import numpy as np
import numpy.typing as npt

import slabscope
import slabscope.dask
from slabscope import Analysis, Image, Triage, Volume, VolumeError


def progress(phase: str, done: float) -> None:
    print(phase, done)


def volumes() -> list[Volume]:
    loaded = slabscope.load("head.nii.gz")
    raw = slabscope.load(
        Path("scan.raw"),
        dims=(64, 64, 32),
        dtype="uint16",
        spacing=(1.0, 1.0, 2.0),
        endian="big",
        offset=0,
        max_memory="2G",
        scratch=None,
        threads=2,
        volume=0,
        channel=0,
        array=None,
        series=None,
        include_localizers=False,
        resample=False,
        show_phi=False,
        label_image=None,
    )
    array: npt.NDArray[np.float32] = np.zeros((8, 8, 8), dtype=np.float32, order="F")
    made = Volume.from_array(array, spacing=(1.0, 1.0, 1.0))
    placed = Volume.from_array(array, affine=np.eye(4))
    # nibabel's argument order, and other libraries' images (untyped: Any).
    ordered = Volume.from_array(array, np.eye(4))
    image: Any = None
    foreign = [Volume.from_nibabel(image), Volume.from_sitk(image)] if image is not None else []
    carried = loaded.carrying_voxels()
    return [loaded, raw, made, placed, ordered, carried, *foreign]


def describe(volume: Volume) -> str:
    voxels: np.ndarray = volume.array
    as_numpy = np.asarray(volume)
    as_float = np.asarray(volume, dtype=np.float64)
    nx, ny, nz = volume.shape
    sx, sy, sz = volume.spacing
    low, high = volume.range
    orientation: Optional[str] = volume.orientation
    notes: list[str] = volume.notes
    parts = [
        volume.format,
        volume.dtype,
        str(volume.copied),
        str(volume.affine.shape),
        str(volume.missing),
        str(voxels.shape),
        str(as_numpy.shape),
        str(as_float.dtype),
    ]
    return " ".join(parts + notes) + f"{nx}{ny}{nz}{sx}{sy}{sz}{low}{high}{orientation}"


def analyse(volume: Volume) -> Analysis:
    analysis = slabscope.analyze(
        volume,
        progress,
        bins=32,
        block=3,
        level=1,
        ray_spacing=None,
        sample_spacing=None,
        phases=8,
        phase_subset=12,
        refine=False,
        axis="best",
        axis_by="entropy",
        gain=False,
        method="topdown",
        slabs=4,
        threshold=None,
        background="auto",
        views=True,
        explain="all",
        resolution="full",
        max_memory=1 << 30,
    )
    named = slabscope.analyze(volume, axis=(0.0, 0.0, 1.0), background=0.5, resolution=1, explain=8)
    numbered = slabscope.analyze(volume, axis=2, progress=True)
    bounded = slabscope.analyze(np.random.default_rng(0).random((8, 8, 8), dtype=np.float32), threads=1)
    views: list[dict[str, Any]] = analysis.views
    x, y, z = analysis.best_axis
    uncertain: bool = analysis.uncertain
    contenders: list[dict[str, Any]] = analysis.contenders
    slabs: list[tuple[int, int]] = analysis.slabs
    steps: list[dict[str, Any]] = analysis.steps
    information: float = analysis.information
    partition: dict[str, Any] = analysis.partition
    notes: list[str] = analysis.notes
    report: dict[str, Any] = analysis.to_dict()
    text: str = analysis.to_json()
    labels: np.ndarray = analysis.labels()
    analysis.write_labels("labels.nii.gz", force=True, progress=True)
    print(views, x, y, z, uncertain, contenders, slabs, steps, information, partition, notes)
    print(report, text, labels.shape, named, numbered)
    return analysis


def pictures(volume: Volume, analysis: Analysis) -> list[Image]:
    exploded = slabscope.render(
        volume,
        analysis,
        progress,
        size=(640, 480),
        mode="dvr",
        tf="ct-bone",
        colormap="bone",
        window=(0.0, 100.0),
        azimuth=30.0,
        elevation=20.0,
        zoom=1.0,
        perspective=False,
        gap="uniform",
        spread=0.5,
        highlight=1,
        solo=False,
        step=1.0,
        no_shading=False,
        no_outlines=False,
        no_labels=False,
        faces=False,
    )
    faces = slabscope.render(volume, faces=True)
    one = slabscope.slice(
        volume,
        analysis,
        3,
        progress,
        size=(256, 256),
        no_letters=True,
        tf="mri",
        colormap="hot",
        window=None,
        axis="best",
    )
    across = slabscope.slice(volume, index=2, axis=(1.0, 0.0, 0.0), bins=16, slabs=3)
    last = slabscope.slice(volume, index=-1, axis=2, progress=False)
    for image in (exploded, faces, one, across, last):
        pixels: np.ndarray = image.array
        rgba = np.asarray(image)
        width, height = image.size
        png: bytes = image.png()
        shown: bytes = image._repr_png_()
        image.save("out.png", force=True)
        print(pixels.shape, rgba.shape, width, height, len(png), len(shown))
    return [exploded, faces, one, across]


def rows() -> list[dict[str, Any]]:
    run: Triage = slabscope.triage(["a", Path("b")], shard=(1, 2), full=False, timeout=30.0, slabs=3)
    print(len(run))
    taken = [row for row in run]
    more = slabscope.triage(manifest="manifest.tsv")
    first: dict[str, Any] = next(more)
    more.close()
    lines: list[str] = slabscope.list_volumes(".", shard=(1, 4), series="largest")
    from_lines = slabscope.triage(entries=lines)
    frame = slabscope.triage_frame(".", slabs=2)
    print(frame, list(from_lines))
    return taken + [first]


def on_a_cluster(client: Any) -> None:
    triaged: list[Any] = slabscope.dask.triage(client, ".", slabs=2)
    analysed: list[Any] = slabscope.dask.analyze(client, ["a.nii"], slabs=2)
    print(triaged, analysed, slabscope.dask.LOAD_KEYWORDS)
    one = slabscope.dask.analyze_array(client, "a.ome.zarr", slabs=2)
    affine = [[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 2.0, 0], [0, 0, 0, 1.0]]
    other = slabscope.dask.analyze_array(client, "b.zarr", axes="zyx", affine=affine, progress=print)
    print(one, other)


def copies(volume: Volume, analysis: Analysis, image: Image) -> None:
    again: Volume = pickle.loads(pickle.dumps(volume))
    deep: Analysis = copy.deepcopy(analysis)
    same: Image = copy.copy(image)
    of: Volume = analysis.volume
    print(again, deep, same, of)


def main() -> None:
    try:
        for volume in volumes():
            print(describe(volume))
            analysis = analyse(volume)
            images = pictures(volume, analysis)
            copies(volume, analysis, images[0])
    except VolumeError as e:
        print(e)
    print(rows(), slabscope.__version__, slabscope.SCHEMA_VERSION)
