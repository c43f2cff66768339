"""Triage from Python: the rows of `triage --json`, in its order, from a walk, a manifest or
entries; early stops; pandas."""

from __future__ import annotations

import json
import shutil

import pytest

import slabscope

from conftest import BAD, DATA


@pytest.fixture()
def archive(tmp_path, phantoms):
    for name in ["ramp_u8.nii", "ramp_i16.mha", "ramp_u16_be.nrrd", "nilearn_image_10426.nii.gz"]:
        shutil.copy(DATA / name, tmp_path / name)
    (tmp_path / "deeper").mkdir()
    shutil.copy(phantoms["body"], tmp_path / "deeper" / "body.nii")
    shutil.copy(BAD / "truncated.nrrd", tmp_path / "deeper" / "truncated.nrrd")
    return tmp_path


def lines(text):
    return [json.loads(line) for line in text.splitlines()]


def test_rows_are_triage_json_rows(archive, cli):
    expected = lines(cli("triage", str(archive), "--json"))
    rows = slabscope.triage(str(archive))
    assert len(rows) == len(expected) == 6
    assert list(rows) == expected
    assert sum(r["error"] is not None for r in expected) == 1


def test_shards_entries_and_manifests_select_what_the_cli_selects(archive, cli, tmp_path_factory):
    listed = cli("triage", str(archive), "--list").splitlines()
    entries = slabscope.list_volumes(str(archive))
    assert entries == listed[1:]
    manifest = tmp_path_factory.mktemp("m") / "volumes.txt"
    manifest.write_text("\n".join(listed) + "\n")
    whole = list(slabscope.triage(manifest=str(manifest), slabs=2))
    parts = [row for k in (1, 2, 3) for row in slabscope.triage(str(archive), shard=(k, 3), slabs=2)]
    one_by_one = [row for e in entries for row in slabscope.triage(entries=[e], slabs=2)]
    assert whole == parts == one_by_one
    assert whole == lines(cli("triage", str(archive), "--json", "--slabs", "2"))


def test_selection_errors_name_the_keyword(archive, tmp_path):
    with pytest.raises(ValueError, match=r"shard=\(4, 3\)"):
        slabscope.triage(str(archive), shard=(4, 3))
    with pytest.raises(ValueError, match="one of paths, manifest= or entries="):
        slabscope.triage(str(archive), entries=["a.nii"])
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(FileNotFoundError, match="no volumes found under"):
        slabscope.triage(str(empty))


def test_paths_none_of_which_exist_are_file_not_found(archive, tmp_path):
    nowhere = str(tmp_path / "nowhere")
    with pytest.raises(FileNotFoundError, match=r"^no volumes found under .*nowhere: no such file"):
        slabscope.triage(nowhere)
    with pytest.raises(FileNotFoundError, match="no such file or folder"):
        slabscope.list_volumes([nowhere, str(tmp_path / "nor_here")])
    # Beside a path that exists, a missing one is a row of its own, as on the CLI.
    rows = list(slabscope.triage([nowhere, str(archive / "ramp_u8.nii")], slabs=2))
    assert [row["error"] is None for row in rows] == [False, True], rows


def test_a_run_closed_early_stops(archive):
    rows = slabscope.triage(str(archive))
    first = next(rows)
    assert first["path"].endswith("body.nii")
    rows.close()
    assert list(rows) == []


def test_a_frame_of_rows():
    pandas = pytest.importorskip("pandas")
    frame = slabscope.triage_frame([str(DATA / "ramp_u8.nii"), str(DATA / "ramp_i16.nii")], slabs=2)
    assert isinstance(frame, pandas.DataFrame)
    assert list(frame["format"]) == ["nifti", "nifti"]
