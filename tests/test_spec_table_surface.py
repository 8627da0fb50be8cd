"""A spec's ``surface: {method: table, ...}`` end to end (issue 28 item 1): the generated C and
Python controllers, the reference controller, the compiled closed loop and replay all evaluate
the same lookup table, so a run replays to 0 m (``--impl c``) and within 1e-12 m
(``--impl reference``), and the table's corrections are not the exact surface's."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _codegen_util import needs_cc
from _replay_logs import replayed_difference, reproduces

from fuzzkit.cli import main
from fuzzkit.codegen.controller import surface_table
from fuzzkit.control.spec import role_ordered
from fuzzkit.control.spec_reader import load_spec
from fuzzkit.loop.controller_code import spec_surface
from fuzzkit.loop.spec import RunSpec
from fuzzkit.studies.batch import run_spec
from fuzzkit.studies.run_table import run_csv

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "docs" / "examples" / "controller.yaml"

pytestmark = needs_cc


def _spec(tmp_path: Path, surface: str) -> Path:
    text = EXAMPLE.read_text(encoding="utf-8").rstrip("\n") + f"\nsurface: {surface}\n"
    path = tmp_path / "spec.yaml"
    path.write_text(text, encoding="utf-8")
    return path


def test_the_reference_evaluates_the_specs_table(tmp_path: Path) -> None:
    # the reference surface is the 5 x 5 table's interpolation: its stored (fitted) node values
    # at the nodes;
    # the exact engine (an independent computation) is within the table's certified bound
    # everywhere, and a 5 x 5 table is visibly not the exact surface
    spec = load_spec(_spec(tmp_path, "{method: table, resolution: 5}"))
    assert spec.rulebase is not None
    table = surface_table(role_ordered(spec, spec.rulebase), None, 5)
    assert [len(b) for b in table.breakpoints] == [5, 5]
    f = spec_surface(spec)
    exact = spec_surface(load_spec(EXAMPLE))
    bp0, bp1 = table.breakpoints
    stored = np.asarray(table.stored[0], dtype=np.float64).reshape(5, 5)
    for i, e in enumerate(bp0):
        for j, de in enumerate(bp1):
            assert f(float(e), float(de)) == float(stored[i, j])
    grid = np.linspace(-1.0, 1.0, 41)
    off = np.array([[abs(f(e, de) - exact(e, de)) for de in grid] for e in grid])
    assert off.max() <= table.bound[0]
    assert off.max() > 1e-2


@pytest.mark.parametrize(
    "surface", ["{method: table, resolution: 17}", "{method: table, tolerance: 0.01}"]
)
def test_a_table_spec_compiles_verified(
    surface: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # without --type: a table surface's controller is built in double (the C target's
    # default, float, is refused for it), and said so
    spec = _spec(tmp_path, surface)
    for target in ("c", "python"):
        out = tmp_path / target
        argv = ["compile", str(spec), "--target", target, "--out", str(out), "--verify"]
        assert main(argv) == 0
        printed = capsys.readouterr().out
        assert "(double)" in printed.splitlines()[0] and "verify: ok" in printed
    header = (tmp_path / "c" / "e1_fuzzy_surface.h").read_text(encoding="utf-8")
    assert "lookup table" in header.lower() and "bound" in header.lower()
    module = (tmp_path / "python" / "e1_fuzzy_controller.py").read_text(encoding="utf-8")
    assert "by its lookup table" in module


def test_a_table_spec_refuses_a_float_build(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    spec = _spec(tmp_path, "{method: table, resolution: 17}")
    argv = ["compile", str(spec), "--target", "c", "--type", "float", "--out", str(tmp_path / "o")]
    assert main(argv) == 2
    assert "a table surface's controller computes in double" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_a_table_run_replays_and_differs_from_the_exact_one(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    spec = _spec(tmp_path, "{method: table, resolution: 9}")
    runs = {}
    for name, path in (("table", spec), ("exact", EXAMPLE)):
        result = run_spec(
            RunSpec("E1", plant="arm6", controller_spec=str(path), fault="spike",
                    latency=(1, 1), seed=2, duration_s=3.5)
        )  # fmt: skip
        assert result.loop == "compiled" and "generated C controller" in result.controller_impl
        assert not result.tripped and float(np.max(np.abs(result.u))) > 1e-4
        runs[name] = result
    csv = tmp_path / "run.csv"
    csv.write_text(run_csv(runs["table"]), encoding="utf-8")
    assert replayed_difference(capsys, spec, csv, "c") == 0.0
    assert reproduces(capsys, spec, csv, "reference")
    # the exact spec's controller on the table run's samples is another controller
    assert replayed_difference(capsys, EXAMPLE, csv, "c") > 1e-7
    assert float(np.max(np.abs(runs["table"].u - runs["exact"].u))) > 1e-7


def test_the_python_loop_runs_the_specs_table(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # --controller-impl reference (in the Python loop) evaluates the table too
    spec = _spec(tmp_path, "{method: table, resolution: 9}")
    result = run_spec(
        RunSpec("E1", plant="planar", controller_spec=str(spec), controller_impl="reference",
                seed=2, duration_s=2.0)
    )  # fmt: skip
    assert result.loop.startswith("python") and "lookup table" in result.controller_impl
    csv = tmp_path / "run.csv"
    csv.write_text(run_csv(result), encoding="utf-8")
    assert replayed_difference(capsys, spec, csv, "reference") == 0.0
    assert reproduces(capsys, spec, csv, "c")
    assert replayed_difference(capsys, EXAMPLE, csv, "reference") > 1e-7
