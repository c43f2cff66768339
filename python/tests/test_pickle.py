"""Pickling and copies of every result type: a volume read from a file pickles as its path and
`load` keywords (or, `carrying_voxels()`, its voxels), one made from an array as its voxels; an
analysis as its volume, keywords and report, its partition analysed again when first needed; a
picture as its pixels; a triage run as the rows not yet taken."""

from __future__ import annotations

import copy
import pickle
import shutil

import numpy as np
import pytest

import slabscope

from conftest import DATA


def again(thing):
    return pickle.loads(pickle.dumps(thing))


def same_volume(a, b):
    assert (a.shape, a.spacing, a.dtype, a.orientation, a.format, a.notes) == (
        b.shape,
        b.spacing,
        b.dtype,
        b.orientation,
        b.format,
        b.notes,
    )
    assert np.array_equal(a.affine, b.affine) and np.array_equal(a.array, b.array, equal_nan=True)
    assert repr(a) == repr(b)


def test_a_volume_from_a_file_pickles_as_its_path_and_keywords(tmp_path, monkeypatch):
    shutil.copy(DATA / "ramp_u16_be.nrrd", tmp_path / "ramp.nrrd")
    monkeypatch.chdir(tmp_path)
    volume = slabscope.load("ramp.nrrd", max_memory="1G")
    data = pickle.dumps(volume)
    assert len(data) < 1000 and tmp_path.name.encode() in data and b"1G" in data
    monkeypatch.chdir("/")  # an absolute path: read again from anywhere
    same_volume(pickle.loads(data), volume)


def test_carrying_voxels_pickles_them_and_keeps_the_geometry(tmp_path):
    shutil.copy(DATA / "ramp_i16.nii", tmp_path / "ramp.nii")
    volume = slabscope.load(tmp_path / "ramp.nii")
    carried = volume.carrying_voxels()
    data = pickle.dumps(carried)
    (tmp_path / "ramp.nii").unlink()  # no file needed where it is unpickled
    back = pickle.loads(data)
    same_volume(back, volume)
    assert back.dtype == "int16" and back.orientation == "RAS"
    with pytest.raises(OSError, match="ramp.nii"):
        pickle.loads(pickle.dumps(volume))


@pytest.mark.parametrize("dtype", ["uint8", "int16", "float32", "float64"])
def test_a_volume_from_an_array_carries_its_voxels(dtype):
    rng = np.random.default_rng(7)
    array = (rng.random((6, 7, 8)) * 100).astype(dtype)
    affine = np.diag([-0.5, 0.5, 2.0, 1.0])
    volume = slabscope.Volume.from_array(array, affine=affine)
    back = again(volume)
    same_volume(back, volume)
    assert back.dtype == dtype and back.orientation == "LAS"
    unknown = again(slabscope.Volume.from_array(array, spacing=(1, 2, 3)))
    assert unknown.orientation is None and unknown.spacing == (1, 2, 3)


def test_a_deep_copy_of_a_volume_lent_an_array_owns_its_voxels():
    array = np.asfortranarray(np.arange(6 * 7 * 8, dtype=np.float32).reshape(6, 7, 8))
    volume = slabscope.Volume.from_array(array)
    assert not volume.copied
    deep = copy.deepcopy(volume)
    array[0, 0, 0] = 1000
    assert deep.array[0, 0, 0] == 0 and volume.array[0, 0, 0] == 1000 and deep.copied
    read = slabscope.load(DATA / "ramp_u8.nii")
    assert copy.deepcopy(read) is read and copy.copy(read) is read  # it never changes


def test_an_analysis_comes_back_whole_with_its_volume(cli_json):
    path = str(DATA / "ramp_i16.nii")
    volume = slabscope.load(path)
    analysis = slabscope.analyze(volume, slabs=2, method="bottomup")
    volume2, analysis2 = again((volume, analysis))
    assert analysis2.volume is volume2
    assert analysis2.to_dict() == cli_json("analyze", path, "--json", "--slabs", "2", "--method", "bottomup")
    assert analysis2.to_json() == analysis.to_json() and repr(analysis2) == repr(analysis)
    assert (analysis2.best_axis, analysis2.slabs, analysis2.information) == (
        analysis.best_axis,
        analysis.slabs,
        analysis.information,
    )
    assert np.array_equal(analysis2.labels(), analysis.labels())
    size = {"size": (64, 48)}
    assert slabscope.render(volume2, analysis2, **size).png() == slabscope.render(volume, analysis, **size).png()
    # Pickled apart from its volume, it still draws that volume (the same voxels and geometry).
    alone = again(analysis)
    assert slabscope.render(volume, alone, **size).png() == slabscope.render(volume, analysis, **size).png()
    assert slabscope.slice(volume, alone).png() == slabscope.slice(volume, analysis).png()
    other = slabscope.load(DATA / "ramp_u8.nii")
    with pytest.raises(ValueError, match="another volume"):
        slabscope.render(other, alone)


def test_an_analysis_whose_file_changed_says_so(tmp_path):
    shutil.copy(DATA / "ramp_i16.nii", tmp_path / "scan.nii")
    analysis = slabscope.analyze(slabscope.load(tmp_path / "scan.nii"), slabs=2)
    data = pickle.dumps(analysis)
    shutil.copy(DATA / "nilearn_image_10426.nii.gz", tmp_path / "scan.nii.gz")
    (tmp_path / "scan.nii").write_bytes((tmp_path / "scan.nii.gz").read_bytes())
    back = pickle.loads(data)
    assert back.slabs == analysis.slabs  # the report needs no analysis
    with pytest.raises((ValueError, OSError)) as raised:
        back.labels()
    assert "\n" not in str(raised.value)


def test_deep_copies_of_an_analysis():
    volume = slabscope.load(DATA / "ramp_u8.nii")
    analysis = slabscope.analyze(volume, slabs=2)
    assert copy.deepcopy(analysis) is analysis and copy.copy(analysis) is analysis
    lent = slabscope.Volume.from_array(np.asfortranarray(np.arange(512, dtype=np.uint8).reshape(8, 8, 8)))
    of_lent = slabscope.analyze(lent, slabs=2)
    deep = copy.deepcopy(of_lent)
    assert deep is not of_lent and deep.volume is not lent and deep.to_json() == of_lent.to_json()
    assert np.array_equal(deep.labels(), of_lent.labels())
    both = copy.deepcopy((lent, of_lent))
    assert both[1].volume is both[0]


def test_pictures_pickle_and_copy():
    volume = slabscope.load(DATA / "ramp_u8.nii")
    picture = slabscope.render(volume, size=(40, 30))
    back = again(picture)
    assert back.png() == picture.png() and back.size == (40, 30)
    assert np.array_equal(back.array, picture.array)
    assert copy.deepcopy(picture) is picture


def test_a_triage_run_pickles_as_the_rows_not_yet_taken(tmp_path):
    for name in ["ramp_u8.nii", "ramp_i16.mha", "ramp_u16_be.nrrd"]:
        shutil.copy(DATA / name, tmp_path / name)
    expected = list(slabscope.triage(tmp_path, slabs=2))
    run = slabscope.triage(tmp_path, slabs=2)
    first = next(run)
    copied = copy.deepcopy(run)
    back = again(run)
    assert len(back) == len(run) == 3
    assert [first] + list(back) == expected
    assert [first] + list(copied) == expected
    assert [first] + list(run) == expected
    assert list(again(run)) == []


def test_an_analysis_draws_only_a_volume_of_its_own_voxels():
    array = np.asfortranarray(np.arange(8 * 8 * 8, dtype=np.float32).reshape(8, 8, 8))
    volume = slabscope.Volume.from_array(array)
    analysis = slabscope.analyze(volume, slabs=2)
    twin = slabscope.Volume.from_array(array.copy(order="F"))
    assert slabscope.render(twin, again(analysis), size=(32, 24)).size == (32, 24)
    # The same shape, spacing, type and statistics, other voxels: another volume.
    mirrored = slabscope.Volume.from_array(np.asfortranarray(array[::-1]))
    assert mirrored.range == volume.range and mirrored.shape == volume.shape
    for drawn in (analysis, again(analysis)):
        with pytest.raises(ValueError, match="another volume"):
            slabscope.render(mirrored, drawn)
        with pytest.raises(ValueError, match="another volume"):
            slabscope.slice(mirrored, drawn)
