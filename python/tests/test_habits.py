"""What Python users reach for first (#46): NumPy's axis numbers, negative indices, a progress bar
with `progress=True`, and errors that name the keyword given."""

from __future__ import annotations

import re
import sys

import numpy as np
import pytest

import slabscope

from conftest import DATA


@pytest.fixture(scope="module")
def volume():
    rng = np.random.default_rng(0)
    return slabscope.Volume.from_array(rng.random((12, 10, 8), dtype=np.float32))


@pytest.mark.parametrize(("number", "word"), [(0, "x"), (1, "y"), (2, "z")])
def test_axis_numbers_are_x_y_z(volume, number, word):
    by_number = slabscope.analyze(volume, axis=number, slabs=2, phases=0)
    by_word = slabscope.analyze(volume, axis=word, slabs=2, phases=0)
    assert by_number.to_dict() == by_word.to_dict()
    assert slabscope.analyze(volume, axis=np.int64(number), slabs=2, phases=0).slabs == by_word.slabs


@pytest.mark.parametrize("number", [3, -1])
def test_other_axis_numbers_are_value_errors_naming_axis(volume, number):
    with pytest.raises(ValueError, match=rf"^axis={number}: expected 0, 1 or 2 \(x, y, z\)"):
        slabscope.analyze(volume, axis=number)


def test_a_negative_index_counts_from_the_end(volume):
    analysis = slabscope.analyze(volume, axis="z", slabs=2, phases=0)
    last = slabscope.slice(volume, analysis, index=-1)
    assert np.array_equal(np.asarray(last), np.asarray(slabscope.slice(volume, analysis, index=7)))
    first = slabscope.slice(volume, index=-8, axis=2)
    assert np.array_equal(np.asarray(first), np.asarray(slabscope.slice(volume, analysis, index=0)))
    with pytest.raises(ValueError, match=r"^index=-9: expected a slice from 0 to 7, or from -8 to -1"):
        slabscope.slice(volume, analysis, index=-9)
    with pytest.raises(ValueError, match=r"^index=8: expected a slice from 0 to 7"):
        slabscope.slice(volume, analysis, index=8)


def test_progress_true_draws_a_tqdm_bar(volume, capsys):
    pytest.importorskip("tqdm")
    slabscope.analyze(volume, slabs=2, progress=True)
    err = capsys.readouterr().err
    # A bar a phase, named: which phases show depends on the build's speed (the progress is read
    # every 50 ms, and a fast release build finishes the view search of this volume between two
    # reads), so only that some phase's bar ran to its end is held.
    assert re.search(r"[a-z ]+: 100%\|", err), err


def test_progress_true_without_tqdm_writes_a_line(volume, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "tqdm", None)
    slabscope.render(volume, slabscope.analyze(volume, slabs=2), size=(64, 48), progress=True)
    err = capsys.readouterr().err
    assert err.startswith("\r") and err.endswith("100%\n") and "|" not in err, err


def test_progress_false_is_silent(volume, capsys):
    slabscope.analyze(volume, slabs=2, progress=False)
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize("call", ["analyze", "render", "slice"])
def test_a_progress_that_is_not_a_function_is_a_type_error(volume, call):
    with pytest.raises(TypeError, match=rf"^{call}\(\): progress=5: expected a function"):
        getattr(slabscope, call)(volume, progress=5)


@pytest.mark.parametrize("spacing", [(1, 1), 2.0, (1, -1, 1), "a", (1, 1, float("nan"))])
def test_a_spacing_that_is_not_three_positive_numbers_names_spacing(spacing):
    array = np.zeros((4, 4, 4), np.float32)
    with pytest.raises(ValueError, match=rf"^spacing={re.escape(repr(spacing))}: expected three positive numbers"):
        slabscope.Volume.from_array(array, spacing=spacing)
    assert slabscope.Volume.from_array(array, spacing=[1, 2, 3]).spacing == (1.0, 2.0, 3.0)
    assert slabscope.Volume.from_array(array, spacing=np.array([1.0, 2, 3])).spacing == (1.0, 2.0, 3.0)


def test_a_negative_slab_count_names_slabs(volume):
    with pytest.raises(ValueError, match=r"^slabs=-1: expected a whole number from 0"):
        slabscope.analyze(volume, slabs=-1)


def test_a_budget_too_small_for_the_slabs_is_blamed_on_max_memory():
    volume = slabscope.load(DATA / "ramp_f32_be.nii")
    assert slabscope.analyze(volume).slabs, "without a budget the default slabs fit"
    for given in ({}, {"slabs": 4}):
        with pytest.raises(ValueError, match=r"slabs.*, because level 0 needs") as raised:
            slabscope.analyze(volume, max_memory="4K", **given)
        assert "computed on pyramid level 1" in str(raised.value)
        assert str(raised.value).endswith("(raise it with max_memory=)")
    with pytest.raises(ValueError, match=r"^max_memory=1\.0 KiB: expected room for the analysis"):
        slabscope.analyze(volume, max_memory="1K")


def test_values_given_as_tuples_or_numbers_are_shown_as_python_shows_them(volume, tmp_path):
    raw = tmp_path / "data.raw"
    raw.write_bytes(bytes(64))
    with pytest.raises(ValueError, match=r"^spacing=\(1, 1\): expected three positive numbers"):
        slabscope.load(raw, dims=(4, 4, 4), dtype=np.uint8, spacing=(1, 1))
    with pytest.raises(ValueError, match=r"^dims=\(4, 4\): expected"):
        slabscope.load(raw, dims=(4, 4), dtype=np.uint8)
    with pytest.raises(ValueError, match=r"^window=\(3, 1\): expected LO,HI with LO below HI"):
        slabscope.render(volume, window=(3, 1))
    with pytest.raises(ValueError, match=r"^axis=\(0, 0, 0\): expected"):
        slabscope.analyze(volume, axis=(0, 0, 0))
    with pytest.raises(ValueError, match=r"^max_memory=-5: expected a size"):
        slabscope.analyze(volume, max_memory=-5)


def test_a_level_asked_for_that_cannot_be_read_is_an_error(tmp_path):
    import shutil
    import struct

    store = tmp_path / "v04_blosc.ome.zarr"
    shutil.copytree(DATA / "zarr" / "v04_blosc.ome.zarr", store)
    # Level 1's chunk: a Blosc header that claims a million bytes.
    (store / "s1" / "0" / "0" / "0").write_bytes(bytes([2, 1, 1, 2]) + struct.pack("<I", 1_000_000) + bytes(8))
    volume = slabscope.load(store, max_memory="64M")
    with pytest.raises(slabscope.VolumeError, match=r"s1/0/0/0.*says it decodes to more"):
        slabscope.analyze(volume, resolution=1)
    assert slabscope.analyze(volume, slabs=2).slabs, "level 0 is read; the broken level is never needed"


def test_an_index_beyond_64_bits_is_a_value_error_naming_index(volume):
    analysis = slabscope.analyze(volume, axis="z", slabs=2, phases=0)
    for huge in (2**70, -(2**70)):
        with pytest.raises(ValueError, match=rf"^index={huge}: expected a slice from 0 to 7"):
            slabscope.slice(volume, analysis, index=huge)
    with pytest.raises(TypeError, match=r"^index='2': expected an int"):
        slabscope.slice(volume, analysis, index="2")


def test_threads_bound_the_work_and_change_no_answer(volume, tmp_path):
    alone = slabscope.analyze(volume, slabs=2, threads=1)
    assert alone.to_dict() == slabscope.analyze(volume, slabs=2).to_dict()
    picture = slabscope.render(volume, alone, size=(64, 48), threads=1)
    assert np.array_equal(np.asarray(picture), np.asarray(slabscope.render(volume, alone, size=(64, 48))))
    assert np.array_equal(
        np.asarray(slabscope.slice(volume, alone, threads=1)), np.asarray(slabscope.slice(volume, alone))
    )
    path = tmp_path / "v.nii"
    path.write_bytes(b"")
    with pytest.raises(ValueError, match=r"^threads=0: expected "):
        slabscope.analyze(volume, threads=0)
    with pytest.raises(ValueError, match=r"^threads=0: expected "):
        slabscope.load(path, threads=0)
    assert "threads" in str(inspect_signature(slabscope.analyze))


def inspect_signature(call):
    import inspect

    return inspect.signature(call)


def test_a_file_cut_short_under_its_map_raises_instead_of_ending_python(tmp_path):
    # A raw i16 file read in place (mapped): cut short while the volume lives, the next call
    # finds pages gone; the interpreter lives on and the call raises naming the file.
    path = tmp_path / "scan_64x64x64_i16.raw"
    rng = np.random.default_rng(1)
    rng.integers(0, 1000, 64**3, dtype=np.int16).tofile(path)
    volume = slabscope.load(path)
    with open(path, "r+b") as f:
        f.truncate(4096)
    with pytest.raises(slabscope.VolumeError, match=r"scan_64x64x64_i16\.raw: the file was cut short"):
        slabscope.analyze(volume, slabs=2)
    with pytest.raises(slabscope.VolumeError, match="load it again"):
        volume.array


def test_small_voxels_are_shown_in_their_own_unit():
    # An electron microscopy map (MRC): its voxels are ångströms, as `info` says them.
    volume = slabscope.load(DATA / "mrc" / "ramp_i16.mrc")
    assert volume.format == "mrc"
    assert "6x5x4 int16 spacing (1.5, 2, 2.5) Å>" in repr(volume)
    assert volume.spacing == pytest.approx((1.5e-7, 2e-7, 2.5e-7))
