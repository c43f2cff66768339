"""Volumes from NumPy arrays: read in place where promised, copied once otherwise, refused with a
clear error when they are not volumes."""

from __future__ import annotations

import numpy as np
import pytest

import slabscope


def ramp(dtype, order="F"):
    x, y, z = np.meshgrid(np.arange(6), np.arange(5), np.arange(7), indexing="ij")
    return np.asarray(x + 10 * y + 100 * z, dtype=dtype, order=order)


@pytest.mark.parametrize("dtype", [np.uint8, np.int8, np.uint16, np.int16, np.float32])
def test_fortran_arrays_of_held_types_are_read_in_place(dtype):
    array = ramp(dtype)
    volume = slabscope.Volume.from_array(array, spacing=(1.0, 2.0, 3.0))
    assert not volume.copied
    assert np.shares_memory(volume.array, array)
    assert volume.shape == (6, 5, 7) and volume.spacing == (1.0, 2.0, 3.0)
    assert volume.dtype == np.dtype(dtype).name
    assert volume.range == (float(array.min()), float(array.max()))


@pytest.mark.parametrize(
    "array,held",
    [
        (ramp(np.int16, order="C"), "int16"),
        (ramp(np.float64), "float32"),
        (ramp(np.int64), "float32"),
        (ramp(np.uint32), "float32"),
        (ramp(np.int16).astype(">i2"), "int16"),
        (ramp(np.float32)[::2, :, :], "float32"),
    ],
    ids=["c-order", "float64", "int64", "uint32", "big-endian", "strided"],
)
def test_other_arrays_are_copied_once_with_the_same_values(array, held):
    volume = slabscope.Volume.from_array(array)
    assert volume.copied
    assert not np.shares_memory(volume.array, array)
    assert volume.array.dtype == np.dtype(held)
    np.testing.assert_array_equal(volume.array, array.astype(held))


def test_the_same_voxels_give_the_same_analysis_in_place_or_copied():
    f = ramp(np.int16)
    c = np.ascontiguousarray(f)
    a = slabscope.analyze(slabscope.Volume.from_array(f), slabs=2).to_dict()
    b = slabscope.analyze(slabscope.Volume.from_array(c), slabs=2).to_dict()
    assert a == b


def test_infinities_are_missing_and_the_array_is_left_alone():
    array = ramp(np.float32)
    array[0, 0, 0] = np.inf
    volume = slabscope.Volume.from_array(array)
    assert volume.copied, "lent memory cannot be changed, so an infinity means a copy"
    assert volume.missing == 1 and np.isnan(volume.array[0, 0, 0])
    assert np.isinf(array[0, 0, 0])


def test_the_volumes_array_is_a_read_only_view():
    volume = slabscope.Volume.from_array(ramp(np.uint16))
    with pytest.raises(ValueError):
        volume.array[0, 0, 0] = 1


@pytest.mark.parametrize("dtype,what", [(bool, "bool"), (np.complex64, "complex64"), (object, "object")])
def test_arrays_that_are_not_numbers_are_a_type_error(dtype, what):
    with pytest.raises(TypeError, match=what):
        slabscope.Volume.from_array(np.zeros((2, 2, 2), dtype=dtype))


def test_shapes_and_geometry_are_checked():
    with pytest.raises(ValueError, match="3 dimensions"):
        slabscope.Volume.from_array(np.zeros((4, 4), np.uint8))
    with pytest.raises(ValueError, match="at least one voxel"):
        slabscope.Volume.from_array(np.zeros((4, 0, 4), np.uint8))
    affine = np.diag([2.0, 2.0, 3.0, 1.0])
    with pytest.raises(ValueError, match="disagrees with the affine"):
        slabscope.Volume.from_array(ramp(np.uint8), spacing=(1.0, 1.0, 1.0), affine=affine)
    volume = slabscope.Volume.from_array(ramp(np.uint8), spacing=(2.0, 2.0, 3.0), affine=affine)
    assert volume.spacing == (2.0, 2.0, 3.0) and volume.orientation == "RAS"
    with pytest.raises(ValueError, match="singular"):
        slabscope.Volume.from_array(ramp(np.uint8), affine=np.diag([1.0, 0.0, 1.0, 1.0]))
    with pytest.raises(ValueError, match="spacing"):
        slabscope.Volume.from_array(ramp(np.uint8), spacing=(1.0, -1.0, 1.0))


def test_an_array_outlives_its_name():
    volume = slabscope.Volume.from_array(ramp(np.uint16))
    import gc

    gc.collect()
    assert volume.array[5, 4, 6] == 5 + 40 + 600
    assert slabscope.analyze(volume, slabs=2).slabs


def test_numpy_takes_a_volume_as_its_voxels():
    from conftest import DATA

    array = ramp(np.int16)
    volume = slabscope.Volume.from_array(array)
    view = np.asarray(volume)
    assert view.dtype == np.int16 and view.shape == (6, 5, 7) and np.array_equal(view, array)
    assert np.shares_memory(view, array) and not view.flags.writeable
    assert np.asarray(volume, copy=False) is not None and np.shares_memory(np.asarray(volume, copy=False), array)
    owned = np.array(volume, copy=True)
    assert not np.shares_memory(owned, array) and owned.flags.writeable and np.array_equal(owned, array)
    as_float = np.asarray(volume, dtype=np.float64)
    assert as_float.dtype == np.float64 and np.array_equal(as_float, array)
    assert np.asarray(volume, dtype="int16").dtype == np.int16
    with pytest.raises(ValueError, match=r"Volume.__array__: dtype=.*float64.*copy=False"):
        np.asarray(volume, dtype=np.float64, copy=False)
    read = slabscope.load(DATA / "ramp_i16.nii")
    assert np.array_equal(np.asarray(read), read.array) and np.shares_memory(np.asarray(read), read.array)
    assert float(np.mean(read)) == float(read.array.mean())  # NumPy functions take a volume


def test_numpy_takes_a_picture_as_its_rgba_pixels():
    volume = slabscope.Volume.from_array(ramp(np.uint8))
    picture = slabscope.render(volume, size=(40, 30))
    pixels = np.asarray(picture)
    assert pixels.shape == (30, 40, 4) and pixels.dtype == np.uint8 and not pixels.flags.writeable
    assert np.array_equal(pixels, picture.array)
    assert np.shares_memory(np.asarray(picture, copy=False), pixels)  # the picture's own memory
    copied = np.array(picture, copy=True)
    assert copied.flags.writeable and not np.shares_memory(copied, pixels)
    assert np.asarray(picture, dtype=np.float32).dtype == np.float32
    with pytest.raises(ValueError, match="Image.__array__"):
        np.asarray(picture, dtype=np.float32, copy=False)
    del picture
    assert pixels.sum() > 0  # the array keeps the picture alive
