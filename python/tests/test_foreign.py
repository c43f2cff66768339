"""Images of nibabel and SimpleITK as they come (issue #46): the same volume, geometry and
analysis as slabscope's own reader gives for the same file."""

from __future__ import annotations

import numpy as np
import pytest

import slabscope


def _same_analysis(a: slabscope.Volume, b: slabscope.Volume) -> None:
    x, y = slabscope.analyze(a).to_dict(), slabscope.analyze(b).to_dict()
    x.pop("file"), y.pop("file")
    assert x == y


def test_a_nibabel_image_is_a_volume_in_every_way_it_is_given(phantoms):
    nibabel = pytest.importorskip("nibabel")
    path = str(phantoms["body"])
    image = nibabel.load(path)
    ours = slabscope.load(path)
    for volume in (
        slabscope.Volume.from_nibabel(image),
        slabscope.Volume.from_array(image),
        # nibabel's own argument order: the affine where the spacing goes.
        slabscope.Volume.from_array(np.asanyarray(image.dataobj), image.affine),
    ):
        assert volume.shape == ours.shape
        np.testing.assert_allclose(volume.affine, ours.affine, atol=1e-6)
        assert np.array_equal(volume.array, ours.array)
    from_nibabel = slabscope.Volume.from_nibabel(image)
    assert not from_nibabel.copied, "an unscaled integer image is read in place"
    assert slabscope.analyze(from_nibabel).to_dict()["file"] == path, "named by its file"
    _same_analysis(from_nibabel, ours)
    with pytest.raises(ValueError, match="carries its own"):
        slabscope.Volume.from_array(image, spacing=(1, 1, 1))
    with pytest.raises(TypeError, match="expected a SimpleITK image"):
        slabscope.Volume.from_sitk(image)


def test_a_4d_nibabel_image_of_one_volume_is_that_volume(tmp_path):
    nibabel = pytest.importorskip("nibabel")
    data = np.arange(4 * 5 * 6, dtype=np.int16).reshape(4, 5, 6, 1, order="F")
    affine = np.diag([2.0, 3.0, 4.0, 1.0])
    one = slabscope.Volume.from_nibabel(nibabel.Nifti1Image(data, affine))
    assert one.shape == (4, 5, 6)
    assert one.spacing == (2.0, 3.0, 4.0)
    many = nibabel.Nifti1Image(np.zeros((4, 5, 6, 3), np.int16), affine)
    with pytest.raises(ValueError, match=r"dataobj\[\.\.\., t\]"):
        slabscope.Volume.from_nibabel(many)


def test_a_simpleitk_image_keeps_its_anatomy(phantoms):
    sitk = pytest.importorskip("SimpleITK")
    path = str(phantoms["body"])
    image = sitk.ReadImage(path)
    ours = slabscope.load(path)
    for volume in (slabscope.Volume.from_sitk(image), slabscope.Volume.from_array(image)):
        # SimpleITK indexes [z, y, x]: taken as [x, y, z], with LPS turned to RAS+.
        assert volume.shape == ours.shape
        np.testing.assert_allclose(volume.affine, ours.affine, atol=1e-5)
        assert np.array_equal(volume.array, ours.array)
        assert volume.orientation == ours.orientation
    _same_analysis(slabscope.Volume.from_sitk(image), ours)
    with pytest.raises(TypeError, match="expected a nibabel image"):
        slabscope.Volume.from_nibabel(image)
    vectors = sitk.Image([4, 5, 6], sitk.sitkVectorFloat32, 3)
    with pytest.raises(ValueError, match="3 components a pixel"):
        slabscope.Volume.from_sitk(vectors)


def test_a_simpleitk_direction_is_taken(tmp_path):
    sitk = pytest.importorskip("SimpleITK")
    image = sitk.GetImageFromArray(np.arange(6 * 5 * 4, dtype=np.float32).reshape(6, 5, 4))
    image.SetSpacing((0.5, 0.7, 2.0))
    image.SetOrigin((10.0, 20.0, 30.0))
    # Index x runs along LPS y, index y along LPS x.
    image.SetDirection((0, 1, 0, 1, 0, 0, 0, 0, 1))
    volume = slabscope.Volume.from_sitk(image)
    assert volume.shape == (4, 5, 6)
    expected = np.array(
        [[0.0, -0.7, 0.0, -10.0], [-0.5, 0.0, 0.0, -20.0], [0.0, 0.0, 2.0, 30.0], [0, 0, 0, 1]]
    )
    np.testing.assert_allclose(volume.affine, expected)
    # Voxel [x, y, z] is SimpleITK's pixel (x, y, z).
    assert volume.array[3, 1, 2] == image.GetPixel(3, 1, 2)


def test_analyze_takes_an_array_directly():
    rng = np.random.default_rng(3)
    array = np.asfortranarray(rng.integers(0, 200, (20, 22, 24), dtype=np.uint8))
    assert slabscope.analyze(array).to_dict() == slabscope.analyze(
        slabscope.Volume.from_array(array)
    ).to_dict()
