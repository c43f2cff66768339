"""The walk-through of python/README.md runs as written, block after block, in a folder holding
the brain it names (the repository's nilearn image): in this interpreter, and as a notebook of one
cell a block in a real Jupyter kernel, where the picture the README says is shown inline is; and
its Dask block runs as a script, as `python script.py` runs it (worker processes import it
again)."""

from __future__ import annotations

import base64
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import DATA

README = Path(__file__).resolve().parents[1] / "README.md"


def walk_through() -> list[str]:
    """The README's Python blocks, in order."""
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    assert len(blocks) >= 5
    return blocks


def test_the_walk_through_runs(tmp_path, monkeypatch):
    pytest.importorskip("nibabel")
    pytest.importorskip("distributed")
    shutil.copy(DATA / "nilearn_image_10426.nii.gz", tmp_path / "brain.nii.gz")
    monkeypatch.chdir(tmp_path)
    scope: dict = {"__name__": "__main__"}  # as a script's or a notebook's
    for block in walk_through():
        exec(compile(block, str(README), "exec"), scope)
    assert (tmp_path / "exploded.png").is_file()
    assert len(scope["rows"]) == 1 and scope["rows"][0]["error"] is None
    assert scope["analysis"].partition["anatomy"] == "P→A, coronal"
    assert os.path.basename(scope["rows"][0]["path"]) == "brain.nii.gz"


def test_the_walk_through_runs_in_a_jupyter_kernel(tmp_path, monkeypatch):
    why = "the notebook test needs nbclient, nbformat and ipykernel: pip install './python[test]'"
    nbclient = pytest.importorskip("nbclient", reason=why)
    nbformat = pytest.importorskip("nbformat", reason=why)
    pytest.importorskip("ipykernel", reason=why)
    pytest.importorskip("nibabel")
    pytest.importorskip("distributed")
    # The kernel is this interpreter (its packages, the slabscope under test), whatever kernels
    # the machine has installed.
    spec = tmp_path / "jupyter" / "kernels" / "slabscope-test"
    spec.mkdir(parents=True)
    argv = [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"]
    (spec / "kernel.json").write_text(json.dumps({"argv": argv, "display_name": "slabscope", "language": "python"}))
    monkeypatch.setenv("JUPYTER_PATH", str(tmp_path / "jupyter"))
    monkeypatch.setenv("JUPYTER_RUNTIME_DIR", str(tmp_path / "runtime"))
    work = tmp_path / "work"
    work.mkdir()
    shutil.copy(DATA / "nilearn_image_10426.nii.gz", work / "brain.nii.gz")
    blocks = walk_through()
    notebook = nbformat.v4.new_notebook(cells=[nbformat.v4.new_code_cell(b) for b in blocks])
    client = nbclient.NotebookClient(
        notebook, kernel_name="slabscope-test", timeout=300, resources={"metadata": {"path": str(work)}}
    )
    client.execute()  # a cell's error raises CellExecutionError, with its traceback
    errors = [o for cell in notebook.cells for o in cell.outputs if o.output_type == "error"]
    assert not errors, errors
    shown = [
        (i, o)
        for i, cell in enumerate(notebook.cells)
        for o in cell.outputs
        if "image/png" in o.get("data", {})
    ]
    drawn = [i for i, b in enumerate(blocks) if "picture = slabscope.render(" in b]
    assert [i for i, _ in shown] == drawn and len(drawn) == 1, [(i, o.output_type) for i, o in shown]
    (_, output), = shown
    assert output.output_type == "execute_result", "the cell's value, as Jupyter shows one"
    # The picture shown is the Image's PNG: the one the same cell saved.
    assert base64.b64decode(output["data"]["image/png"]) == (work / "exploded.png").read_bytes()


def test_the_dask_block_runs_as_a_script(tmp_path):
    pytest.importorskip("distributed")
    (block,) = [b for b in walk_through() if "LocalCluster" in b]
    assert 'if __name__ == "__main__":' in block
    script = tmp_path / "cluster.py"
    check = '\nif __name__ == "__main__":\n    print("rows:", len(rows), rows[0]["error"], rows[0]["format"])\n'
    script.write_text(block + check)
    shutil.copy(DATA / "nilearn_image_10426.nii.gz", tmp_path / "brain.nii.gz")
    done = subprocess.run(
        [sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=300, check=False
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip().splitlines()[-1] == "rows: 1 None nifti", done.stdout
