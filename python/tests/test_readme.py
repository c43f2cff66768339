"""The walk-through of python/README.md runs as written, block after block, in a folder holding
the brain it names (the repository's nilearn image)."""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

import pytest

from conftest import DATA

README = Path(__file__).resolve().parents[1] / "README.md"


def test_the_walk_through_runs(tmp_path, monkeypatch):
    pytest.importorskip("nibabel")
    pytest.importorskip("distributed")
    shutil.copy(DATA / "nilearn_image_10426.nii.gz", tmp_path / "brain.nii.gz")
    monkeypatch.chdir(tmp_path)
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    assert len(blocks) >= 5
    scope: dict = {}
    for block in blocks:
        exec(compile(block, str(README), "exec"), scope)
    assert (tmp_path / "exploded.png").is_file()
    assert len(scope["rows"]) == 1 and scope["rows"][0]["error"] is None
    assert scope["analysis"].partition["anatomy"] == "P→A, coronal"
    assert os.path.basename(scope["rows"][0]["path"]) == "brain.nii.gz"
