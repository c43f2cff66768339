"""The package gives the CLI's numbers: the same report for the same file and keywords, the
same analysis for the same voxels however they arrive (slabscope's reader, nibabel, an array)."""

from __future__ import annotations

import numpy as np
import pytest

import slabscope

from conftest import DATA


@pytest.mark.parametrize(
    "keywords,flags",
    [
        ({}, []),
        ({"slabs": 3, "method": "bottomup"}, ["--slabs", "3", "--method", "bottomup"]),
        ({"axis": "z", "views": True}, ["--axis", "z", "--views"]),
        ({"threshold": 0.01, "background": "none"}, ["--threshold", "0.01", "--background", "none"]),
        ({"gain": True, "phases": 0}, ["--gain", "--phases", "0"]),
        ({"explain": True}, ["--explain"]),
        ({"explain": "all", "method": "bottomup"}, ["--explain", "all", "--method", "bottomup"]),
        ({"explain": 2, "method": "optimal"}, ["--explain", "2", "--method", "optimal"]),
    ],
)
def test_the_report_is_analyze_json(phantoms, cli_json, keywords, flags):
    path = str(phantoms["body"])
    ours = slabscope.analyze(slabscope.load(path), **keywords).to_dict()
    assert ours == cli_json("analyze", path, "--json", *flags)


@pytest.mark.parametrize("name", ["ramp_i16.nii", "ramp_f64.nii", "ramp_u16_be.nrrd", "nilearn_image_10426.nii.gz"])
def test_every_format_and_type_gives_the_cli_report(cli_json, name):
    path = str(DATA / name)
    ours = slabscope.analyze(slabscope.load(path), slabs=2).to_dict()
    assert ours == cli_json("analyze", path, "--json", "--slabs", "2")


def test_explain_carries_the_numbers_behind_the_axis(phantoms):
    analysis = slabscope.analyze(slabscope.load(str(phantoms["body"])), explain=True)
    report = analysis.to_dict()
    chosen, worst = report["explain"]["axes"]
    assert (chosen["role"], worst["role"]) == ("chosen", "worst")
    assert chosen["entropy_rate"] == report["views"][0]["entropy_rate"]
    assert worst["entropy_rate"] == report["views"][-1]["entropy_rate"]
    assert len(report["explain"]["splits"]) == len(report["partition"]["steps"])
    assert "explain" not in slabscope.analyze(slabscope.load(str(phantoms["body"]))).to_dict()
    with pytest.raises(ValueError, match="explain="):
        slabscope.analyze(slabscope.load(str(phantoms["body"])), explain="some")


def test_the_analysis_reads_as_its_report(phantoms):
    analysis = slabscope.analyze(slabscope.load(str(phantoms["body"])))
    report = analysis.to_dict()
    assert list(analysis.best_axis) == report["best_axis"]
    assert [list(s) for s in analysis.slabs] == report["partition"]["slabs"]
    assert analysis.steps == report["partition"]["steps"]
    assert analysis.information == report["partition"]["information"]
    assert analysis.uncertain is report["uncertain"]
    assert analysis.views == report["views"]
    assert report["schema_version"] == slabscope.SCHEMA_VERSION
    assert analysis.to_dict() is not analysis.to_dict(), "a new dict each call"


def test_labels_number_every_voxel_by_its_slab_plus_one(phantoms):
    volume = slabscope.load(str(phantoms["body"]))
    analysis = slabscope.analyze(volume, axis="z")
    labels = analysis.labels()
    assert labels.shape == volume.shape and labels.dtype == np.uint8
    for i, (first, end) in enumerate(analysis.slabs):
        # The slab's index + 1, and 0 for the air around the body (the background).
        assert set(np.unique(labels[:, :, first:end])) == {0, i + 1}
    assert (labels[0, 0, :] == 0).all(), "the corner is air"


def test_labels_of_a_coarser_level_have_the_volumes_shape(phantoms):
    volume = slabscope.load(str(phantoms["body"]))
    analysis = slabscope.analyze(volume, axis="z", resolution=1, slabs=2)
    labels = analysis.labels()
    assert labels.shape == volume.shape
    assert set(np.unique(labels)) == {0, 1, 2}


def test_nibabel_arrays_give_slabscopes_own_analysis(phantoms):
    nibabel = pytest.importorskip("nibabel")
    path = str(phantoms["body"])
    image = nibabel.load(path)
    array = np.asanyarray(image.dataobj)
    assert array.dtype == np.int16 and array.flags.f_contiguous
    from_nibabel = slabscope.Volume.from_array(array, affine=image.affine)
    assert not from_nibabel.copied, "an unscaled integer NIfTI is read in place"
    ours = slabscope.load(path)
    np.testing.assert_allclose(from_nibabel.affine, ours.affine, atol=1e-6)
    a = slabscope.analyze(from_nibabel).to_dict()
    b = slabscope.analyze(ours).to_dict()
    a.pop("file"), b.pop("file")
    assert a == b


def test_parameters_are_checked_and_named_as_keywords(phantoms):
    volume = slabscope.load(str(phantoms["body"]))
    with pytest.raises(ValueError, match=r"^bins=1: expected 2 to 255$"):
        slabscope.analyze(volume, bins=1)
    with pytest.raises(ValueError, match=r"^block=5: expected 2 to 4$"):
        slabscope.analyze(volume, block=5)
    with pytest.raises(ValueError, match=r"method=.*expected one of topdown, bottomup, optimal"):
        slabscope.analyze(volume, method="sideways")
    with pytest.raises(ValueError, match="slabs= and threshold= cannot both be given"):
        slabscope.analyze(volume, slabs=3, threshold=0.1)
    with pytest.raises(TypeError, match="unexpected keyword argument 'bin'"):
        slabscope.analyze(volume, bin=3)
    with pytest.raises(TypeError, match="slabs='four'"):
        slabscope.analyze(volume, slabs="four")


def test_the_default_slab_count_is_not_blamed_on_slabs(cli):
    thin = slabscope.Volume.from_array(np.arange(2 * 2 * 3, dtype=np.uint8).reshape((2, 2, 3), order="F"))
    with pytest.raises(ValueError, match=r"the default of 4 slabs does not fit: .*\(slabs=K asks for another\)"):
        slabscope.analyze(thin, axis="z", background="none")


def test_write_labels_streams_what_labels_holds_as_the_cli_writes_it(phantoms, cli, tmp_path):
    path = str(phantoms["body"])
    volume = slabscope.load(path)
    analysis = slabscope.analyze(volume, axis="z", resolution=1, slabs=3)
    labels = analysis.labels()
    for name in ("l.nrrd", "l.nii", "l.nii.gz"):
        out = tmp_path / name
        analysis.write_labels(out)
        written = slabscope.load(str(out))
        assert written.array.dtype == np.uint8 and written.shape == volume.shape, name
        assert np.array_equal(written.array, labels), name
        np.testing.assert_allclose(written.affine, volume.affine, atol=1e-5)
    # The CLI's export of the same analysis is the same file, byte for byte.
    ours = tmp_path / "cli.nrrd"
    cli("analyze", path, "--axis", "z", "--resolution", "1", "--slabs", "3", "--export-labels", str(ours))
    assert ours.read_bytes() == (tmp_path / "l.nrrd").read_bytes()
    with pytest.raises(FileExistsError, match="l.nrrd"):
        analysis.write_labels(tmp_path / "l.nrrd")
    analysis.write_labels(str(tmp_path / "l.nrrd"), force=True, progress=lambda phase, f: None)
    with pytest.raises(ValueError, match="never writes over its input"):
        analysis.write_labels(path, force=True)
    with pytest.raises(ValueError, match=r"\.nrrd, \.nii or \.nii\.gz"):
        analysis.write_labels(tmp_path / "l.png")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["cli.nrrd", "l.nii", "l.nii.gz", "l.nrrd"]


def test_labels_beyond_the_budget_are_refused_as_an_array_and_written_to_a_file(phantoms, tmp_path):
    # The 96×96×128 body (2.3 MiB of int16), analysed on level 2: its labels (1.1 MiB of uint8)
    # do not fit beside it in 3 MiB, the background's mask and a chunk of planes do.
    volume = slabscope.load(str(phantoms["big"]))
    analysis = slabscope.analyze(volume, axis="z", resolution=2, slabs=3, max_memory="3M")
    with pytest.raises(slabscope.VolumeError, match=r"max_memory=.*write_labels\(path\)") as refused:
        analysis.labels()
    assert "\n" not in str(refused.value)
    out = tmp_path / "labels.nii.gz"
    analysis.write_labels(out)
    roomy = slabscope.analyze(volume, axis="z", resolution=2, slabs=3)
    assert roomy.slabs == analysis.slabs
    assert np.array_equal(slabscope.load(str(out)).array, roomy.labels())


def test_labels_under_a_budget_below_the_background_mask_are_written_all_the_same(phantoms, tmp_path):
    # The 96×96×128 body (2.25 MiB of int16 held) analysed on level 2 (72 KiB of float32) in
    # 2450 KiB: its found background's mask (144 KiB, a bit a voxel) and a plane of labels do not
    # fit beside them, so the mask is held in an unnamed scratch file and the labels written.
    volume = slabscope.load(str(phantoms["big"]))
    analysis = slabscope.analyze(volume, axis="z", resolution=2, slabs=3, max_memory="2450K")
    assert analysis.to_dict()["resolution"]["pyramid_level"] == 2
    out = tmp_path / "labels.nrrd"
    analysis.write_labels(out)
    roomy = slabscope.analyze(volume, axis="z", resolution=2, slabs=3)
    assert roomy.slabs == analysis.slabs
    roomy.write_labels(tmp_path / "roomy.nrrd")
    assert out.read_bytes() == (tmp_path / "roomy.nrrd").read_bytes()
    assert (slabscope.load(str(out)).array == 0).any(), "the air left out by the mask"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["labels.nrrd", "roomy.nrrd"]
