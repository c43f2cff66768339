"""The CLI and the package take their parameters from one table in the library: every keyword of
a call has the default its flag shows in the CLI's help, and both refuse the same values."""

from __future__ import annotations

import inspect
import re
import subprocess

import numpy as np
import pytest

import slabscope

# Each call beside the command whose flags it shares.
COMMANDS = {"load": "info", "analyze": "analyze", "render": "render", "slice": "slice", "triage": "triage"}


def cli_defaults(binary: str, command: str) -> dict[str, str | None]:
    """Every flag of `command`'s help with the default it shows (None: none shown)."""
    text = subprocess.run(
        [binary, command, "--help"], capture_output=True, text=True, check=True
    ).stdout
    blocks = re.split(r"\n(?=\s{2,}(?:-\w, )?--[\w-]+)", text)
    shown: dict[str, str | None] = {}
    for block in blocks:
        flag = re.match(r"\s*(?:-\w, )?(--[\w-]+)", block)
        if flag:
            default = re.search(r"\[default: ([^\]]*)\]", block)
            shown[flag.group(1)] = default.group(1) if default else None
    return shown


def as_cli_text(value: object) -> str | None:
    """A Python default as the CLI's help writes it."""
    if value is None or value is False:
        return None
    if isinstance(value, tuple):
        return "x".join(str(v) for v in value)
    if isinstance(value, float):
        return f"{value:g}"
    return str(value)


@pytest.mark.parametrize("call", sorted(COMMANDS))
def test_every_keyword_has_its_flags_default(cli, call):
    shown = cli_defaults(cli.binary, COMMANDS[call])
    signature = inspect.signature(getattr(slabscope, call))
    entries = slabscope.parameters(call)
    assert entries, call
    for entry in entries:
        keyword, flag = entry["keyword"], entry["flag"]
        assert flag in shown, f"{call}: {flag} is not a flag of slabscope {COMMANDS[call]}"
        default = signature.parameters[keyword].default
        assert default == entry["default"] or (default is None and entry["default"] is None)
        if entry["conflicts"]:
            # A default that holds only when no rival is given is not shown by the CLI.
            assert shown[flag] is None, flag
        else:
            assert shown[flag] == as_cli_text(default), f"{call}: {keyword}={default!r} vs {flag}"


def out_of_range(entry: dict) -> list[float]:
    values = []
    if entry.get("max") is not None:
        values.append(entry["max"] + 1)
    if entry["kind"] == "number" or entry["min"] > 0:
        values.append(entry["min"] - 1)
    return values


def test_both_refuse_the_same_values(cli):
    volume = slabscope.Volume.from_array(np.arange(6**3, dtype=np.float32).reshape(6, 6, 6))
    analysis = slabscope.analyze(volume, axis="z", slabs=2, phases=0)
    calls = {
        "analyze": lambda **kw: slabscope.analyze(volume, **kw),
        "render": lambda **kw: slabscope.render(volume, analysis, **kw),
        # Refused before any path is looked at: triage's own (`timeout`), the loader's, the
        # analysis'.
        "triage": lambda **kw: slabscope.triage("nowhere.nii", **kw),
    }
    checked = 0
    for call, run in calls.items():
        for entry in slabscope.parameters(call):
            if entry["kind"] not in ("count", "number"):
                continue
            for value in out_of_range(entry):
                value = int(value) if entry["kind"] == "count" else value
                text = str(int(value)) if float(value).is_integer() else repr(value)
                with pytest.raises(ValueError, match=rf"^{entry['keyword']}={text}: expected"):
                    run(**{entry["keyword"]: value})
                output = ["-o", "x.png"] if call == "render" else []
                done = subprocess.run(
                    [cli.binary, COMMANDS[call], "nowhere.nii", *output, f"{entry['flag']}={text}"],
                    capture_output=True,
                    text=True,
                    check=False,
                )
                assert done.returncode == 2 and entry["flag"] in done.stderr, done.stderr
                checked += 1
    assert checked >= 20


def as_given(entry: dict, value: float) -> int | float:
    return int(value) if entry["kind"] == "count" else value


def as_flag_text(value: float) -> str:
    return str(int(value)) if float(value).is_integer() else repr(value)


OUTPUT = {"render": ["-o", "x.png"], "slice": ["-o", "x.png"]}


def test_both_take_the_ends_of_every_range(cli, tmp_path):
    """Each end of every range is a value both take: beside the refusals just outside them, the
    CLI's range and the package's are the same, the table's (`min`, `max`)."""
    volume = slabscope.Volume.from_array(np.arange(6**3, dtype=np.float32).reshape(6, 6, 6))
    analysis = slabscope.analyze(volume, axis="z", slabs=2, phases=0)
    calls = {
        "analyze": lambda **kw: slabscope.analyze(volume, axis="z", **kw),
        "render": lambda **kw: slabscope.render(volume, analysis, size=(32, 24), **kw),
    }
    checked = 0
    for call, command in COMMANDS.items():
        for entry in slabscope.parameters(call):
            if entry["kind"] not in ("count", "number"):
                continue
            for end in (entry["min"], entry["max"]):
                if end is None:
                    continue
                text = as_flag_text(end)
                done = subprocess.run(
                    [cli.binary, command, "nowhere.nii", *OUTPUT.get(call, []), f"{entry['flag']}={text}"],
                    capture_output=True,
                    text=True,
                    check=False,
                    cwd=tmp_path,
                )
                # Taken: the run goes on to find no file (a usage error is 2; triage's row says so).
                said = done.stderr + done.stdout
                assert done.returncode == 1 and "nowhere.nii" in said, (entry["flag"], text, said)
                # Python's whole numbers are i64: a range with no top (u64::MAX) is not given there.
                if call in calls and end < 2**63:
                    try:
                        calls[call](**{entry["keyword"]: as_given(entry, end)})
                    except ValueError as e:
                        # Taken by the table; the volume may refuse it (slabs=0 of 6 slices).
                        refused = f"{entry['keyword']}={text}: expected {entry['expected']}"
                        assert str(e) != refused, refused
                checked += 1
    assert checked >= 30
