"""Sensor logs and replay outputs as the replay tests write and read them (not a test module)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pytest

from fuzzkit.cli import main
from fuzzkit.studies.replay import ROTATION_COLUMNS

REPO = Path(__file__).parent.parent
SPEC = REPO / "docs" / "examples" / "controller.yaml"
SPEC_PI = REPO / "docs" / "examples" / "controller_pi.yaml"


def run_cli(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    """``fuzzkit ARGV`` in this process: its exit code, stdout and stderr (an option argparse
    refuses: exit 2, as the program's)."""
    try:
        code = main(list(argv))
    except SystemExit as exc:
        code = int(exc.code or 0)
    out, err = capsys.readouterr()
    return code, out, err


def _cell(v: float) -> str:
    return "" if math.isnan(v) else repr(float(v))


def write_log(
    path: Path,
    forces: npt.NDArray[np.float64],
    rotations: npt.NDArray[np.float64] | None,
    *,
    times: bool = True,
    nan_word: bool = False,
) -> None:
    """Write a sensor log as ``fuzzkit replay --forces`` reads it: ``t`` (4 ms periods, unless
    not ``times``), ``fx, fy, fz``, and the rotation columns when ``rotations`` is given; NaN
    as an empty cell, or as the word ``nan`` in the force columns with ``nan_word``."""
    head = (
        (["t"] if times else [])
        + ["fx", "fy", "fz"]
        + (list(ROTATION_COLUMNS) if rotations is not None else [])
    )
    lines = [",".join(head)]
    for k, f in enumerate(forces):
        cells = ([repr(k * 0.004)] if times else []) + [
            ("nan" if nan_word and math.isnan(v) else _cell(v)) for v in f
        ]
        if rotations is not None:
            cells += [_cell(v) for v in rotations[k]]
        lines.append(",".join(cells))
    path.write_text("\n".join(lines) + "\n")


def read_out(path: Path) -> tuple[list[str], npt.NDArray[np.float64]]:
    """A replay's ``--out`` CSV: its header and its rows as floats."""
    lines = path.read_text().splitlines()
    return lines[0].split(","), np.array(
        [[float(c) for c in line.split(",")] for line in lines[1:]]
    )


def _replayed(capsys: pytest.CaptureFixture[str], spec: Path, csv: Path, impl: str) -> str:
    """``fuzzkit replay SPEC --forces CSV --impl IMPL`` of a run's CSV: what it prints (its
    exit code checked against its verdict: 0 when it reproduces the run, else 1)."""
    out = csv.with_name(f"u_{impl}.csv")
    code = main(["replay", str(spec), "--forces", str(csv), "--out", str(out), "--impl", impl])
    printed = capsys.readouterr().out
    assert code == (0 if "replay: reproduces the run" in printed else 1), printed
    return printed


def replayed_difference(
    capsys: pytest.CaptureFixture[str], spec: Path, csv: Path, impl: str
) -> float:
    """The largest difference the replay of a run's CSV prints between the replayed and the
    run's corrections, in metres."""
    printed = _replayed(capsys, spec, csv, impl)
    found = re.search(r"largest difference from the run's corrections \(u<a>_m\): (\S+) m", printed)
    assert found is not None, printed
    return float(found.group(1))


def reproduces(capsys: pytest.CaptureFixture[str], spec: Path, csv: Path, impl: str) -> bool:
    """The replay of a run's CSV reproduces it: status bits equal in every row, corrections
    within the replay's tolerance (relative to their size), exit 0."""
    printed = _replayed(capsys, spec, csv, impl)
    status_equal = "status bits: equal to the run's in every row" in printed
    return status_equal and "replay: reproduces the run" in printed
