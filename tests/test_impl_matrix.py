"""Every command runs the generated controller (issue 37, "done when"): command x plant x
controller kind, each run's implementation read from what the command itself reports
(``bench/impl_matrix.py``, which prints the same matrix as the closing note's table).

``make test`` runs :data:`COVER` (every kind, command and plant at least once; ``report`` is
covered by ``tests/test_report.py``, whose report checks its ``runs.json`` the same way);
``make verify`` the full product, with one report (a quick report costs about 40 CPU-s).
The reference controller must never run unless asked for: a cell
that names it, or the generated Python where a C compiler exists, fails.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path
from typing import Any

import pytest
from _codegen_util import needs_cc
from _pairwise import verify

ROOT = Path(__file__).resolve().parent.parent
_SPEC = importlib.util.spec_from_file_location("impl_matrix", ROOT / "bench" / "impl_matrix.py")
assert _SPEC is not None and _SPEC.loader is not None
M: Any = importlib.util.module_from_spec(_SPEC)
_SPEC.loader.exec_module(M)

#: the kinds by name (their options need a folder for the table spec: see M.kinds)
KIND_NAMES = (
    "PI",
    "fuzzy-PI, exact surface",
    "fuzzy-PI, table surface",
    "Sugeno (sugeno_pi)",
    "Gaussian output (gaussian3x3)",
    "renamed spec (spec_renamed)",
    ".fis (gauss_outputs.fis)",
)

#: ``make test``'s rows: every kind once, every command and plant at least once
COVER = (
    ("simulate", "mujoco", "Sugeno (sugeno_pi)"),
    ("simulate", "mujoco-elastic", "renamed spec (spec_renamed)"),
    ("compare", "arm6", "Gaussian output (gaussian3x3)"),
    ("sweep", "planar", "fuzzy-PI, table surface"),
    ("sweep", "arm6", ".fis (gauss_outputs.fis)"),
    ("tune", "planar", "fuzzy-PI, exact surface"),
    ("simulate", "planar", "PI"),
    ("stability --simulate", "arm6", "renamed spec (spec_renamed)"),
    ("latency sweep", "mujoco", "Sugeno (sugeno_pi)"),
)
#: the report's rows in ``make verify``
REPORT_ROWS = (("report", "arm6", "fuzzy-PI, exact surface"),)


def _cases() -> list[Any]:
    cover = [pytest.param(*row, id="cover-" + "-".join(row)) for row in COVER]
    full = [
        pytest.param(command, plant, kind, marks=verify, id=f"full-{command}-{plant}-{kind}")
        for command in M.COMMANDS
        for plant in M.PLANTS
        for kind in KIND_NAMES
        if (command, kind) not in M.NOT_TAKEN and command != "report"
    ]
    report = [pytest.param(*row, marks=verify, id="-".join(row)) for row in REPORT_ROWS]
    return cover + full + report


def test_the_matrix_names_every_kind(tmp_path: Path) -> None:
    assert tuple(M.kinds(tmp_path)) == KIND_NAMES
    assert set(M.COMMANDS) == {
        "simulate", "compare", "sweep", "tune", "stability --simulate", "latency sweep", "report"
    }  # fmt: skip


@needs_cc
@pytest.mark.parametrize("command, plant, kind", _cases())
def test_every_run_executes_the_generated_c(
    command: str, plant: str, kind: str, tmp_path: Path
) -> None:
    labels = M.implementations(command, plant, kind, tmp_path)
    assert labels  # the command ran and reported its runs
    for label in labels:
        assert M.generated_c(label), label
        assert "reference" not in label
    # compare runs both controllers, sweep every stiffness, a report many runs: each says so
    if command != "report":
        assert len(labels) == {"compare": 2, "sweep": 2}.get(command, 1)
    assert M.cell(labels).startswith("generated C")


def test_a_reference_run_is_no_generated_cell(tmp_path: Path) -> None:
    # the check can fail: the reference, asked for by name, is reported as such
    labels = M._simulate(
        M.scenario(tmp_path), ["--controller", "pi", "--controller-impl", "reference"],
        "planar", tmp_path,
    )  # fmt: skip
    assert not any(M.generated_c(x) for x in labels)
    assert M.cell(labels).startswith("REFERENCE")
