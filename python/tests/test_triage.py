"""Triage from Python: the rows of `triage --json`, in its order, from a walk, a manifest or
entries; early stops; pandas; the manifest the TUI writes from marks."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import time

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


class Tmux:
    """A tmux server of the test's own (never the user's sessions), running one command."""

    def __init__(self, command: str, cwd) -> None:
        self.socket = f"slabscope-py-{os.getpid()}"
        self.run("new-session", "-d", "-s", "t", "-x", "120", "-y", "32", "-c", str(cwd), command)

    def run(self, *args: str) -> str:
        done = subprocess.run(["tmux", "-L", self.socket, *args], capture_output=True, text=True, check=False)
        return done.stdout

    def wait_for(self, text: str, secs: float = 60) -> str:
        end = time.monotonic() + secs
        while True:
            screen = self.run("capture-pane", "-p", "-t", "t")
            if text in screen:
                return screen
            assert time.monotonic() < end, f"waited {secs} s for {text!r}; the screen shows:\n{screen}"
            time.sleep(0.1)

    def keys(self, *keys: str) -> None:
        for key in keys:
            self.run("send-keys", "-t", "t", key)

    def close(self) -> None:
        self.run("kill-server")


def test_marks_the_tui_writes_as_a_manifest_read_back_to_the_same_rows(archive, cli, tmp_path_factory):
    """`slabscope FOLDER` in tmux: two volumes marked (Space) and written (M) as a manifest, which
    Python's triage(manifest=...) reads to the rows `triage --manifest` gives, of those two."""
    if shutil.which("tmux") is None:
        pytest.skip("tmux is not installed (apt-get install tmux)")
    where = tmp_path_factory.mktemp("tui")
    tmux = Tmux(f"{cli.binary} {archive} --protocol blocks --slabs 2; echo EXITED $?; sleep 60", where)
    try:
        tmux.wait_for("6 volumes in")
        # The first row is marked and the cursor steps to the second; the third is marked.
        tmux.keys("Space", "Down", "Space")
        tmux.wait_for("2 marked")
        tmux.keys("M")
        tmux.wait_for("manifest to> slabscope-marked.txt")
        tmux.keys("Enter")
        tmux.wait_for("wrote 2 volume(s) to slabscope-marked.txt")
        tmux.keys("q")
        tmux.wait_for("EXITED 0")
    finally:
        tmux.close()
    manifest = where / "slabscope-marked.txt"
    rows = list(slabscope.triage(manifest=str(manifest), slabs=2))
    assert rows == lines(cli("triage", "--manifest", str(manifest), "--json", "--slabs", "2"))
    # The pane lists the folder sorted: deeper/body.nii, deeper/truncated.nrrd, the brain, ...
    marked = [archive / "deeper" / "body.nii", archive / "nilearn_image_10426.nii.gz"]
    assert rows == lines(cli("triage", *map(str, marked), "--json", "--slabs", "2"))
    assert [r["error"] is None for r in rows] == [True, True]
