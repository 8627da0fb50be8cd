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
#: How far the generated Python may be from the C controller a run deployed: double rounding
#: of one arithmetic evaluated in two languages, never a different controller (those differ
#: by more than 1e-7 m).
PYTHON_TOLERANCE_M = 1e-12


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


def replayed_difference(
    capsys: pytest.CaptureFixture[str], spec: Path, csv: Path, impl: str
) -> float:
    """``fuzzkit replay SPEC --forces CSV --impl IMPL`` of a run's CSV: the largest difference
    it prints between the replayed and the run's corrections, in metres."""
    out = csv.with_name(f"u_{impl}.csv")
    assert main(["replay", str(spec), "--forces", str(csv), "--out", str(out), "--impl", impl]) == 0
    printed = capsys.readouterr().out
    found = re.search(r"largest difference from the run's corrections \(u<a>_m\): (\S+) m", printed)
    assert found is not None, printed
    return float(found.group(1))
