"""Coverage gaps: an error by default for YAML, a located warning under coverage: allow_gaps."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import pytest

from fuzzkit.cli import main
from fuzzkit.errors import RuleBaseError
from fuzzkit.formats.registry import load_with_warnings, loads
from fuzzkit.formats.yaml_reader import loads_rulebase_with_warnings
from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.validation import check, diagnose, ensure_valid

# MATLAB's tipper has this shape: 'food' is rancid below 3 and delicious above 7, nothing between.
TIPPER = """\
name: tipper
$coverage
inputs:
  food: {range: [0, 10], terms: {rancid: {shape: trapezoid, points: [0, 0, 1, 3]},
                                 delicious: {shape: trapezoid, points: [7, 9, 10, 10]}}}
outputs:
  tip:
    range: [0, 30]
    $default
    terms: {cheap: {shape: triangle, points: [0, 5, 10]},
            generous: {shape: triangle, points: [20, 25, 30]}}
rules:
  - {if: {food: rancid}, then: {tip: cheap}}
  - {if: {food: delicious}, then: {tip: generous}}
"""
GAP = "input 'food' is not covered on [3.0, 7.0]"


def tipper(coverage: str = "", default: str = "") -> str:
    return TIPPER.replace("$coverage", coverage).replace("$default", default)


def test_yaml_keeps_gaps_as_errors_by_default_and_says_how_to_allow_them() -> None:
    with pytest.raises(RuleBaseError) as info:
        loads(tipper(), source="tip.yaml")
    (problem,) = info.value.problems
    assert str(problem).startswith(f"tip.yaml:4:33: {GAP}")
    assert "set coverage: allow_gaps to make this a warning" in problem.message


def test_allow_gaps_loads_and_returns_the_gap_as_a_located_warning() -> None:
    rb, warnings = loads_rulebase_with_warnings(tipper("coverage: allow_gaps"), "tip.yaml")
    (w,) = warnings
    assert w.severity == "warning" and (w.location.line, w.location.col) == (4, 33)
    assert str(w).startswith(f"tip.yaml:4:33: warning: {GAP}")
    assert check(rb) == []  # follows rb.coverage
    assert [m for _, m in check(rb, allow_gaps=False)] == [
        m + " (set coverage: allow_gaps to make this a warning)" for _, m in diagnose(rb).warnings
    ]
    found = diagnose(rb, allow_gaps=True)
    assert found.errors == [] and [p for p, _ in found.warnings] == [("inputs", "food", "terms")]
    with pytest.raises(RuleBaseError, match=r"inputs\.food\.terms: input 'food' is not covered"):
        ensure_valid(replace(rb, coverage="strict"))


@pytest.mark.parametrize(("default", "want"), [("", math.nan), ("default: 15", 15.0)])
def test_in_a_gap_the_output_is_its_default_or_nan(default: str, want: float) -> None:
    rb = loads(tipper("coverage: allow_gaps", default))
    got = Engine(rb).evaluate({"food": [5.0, 3.0, 7.0, 1.0]})["tip"]
    assert got[0] == pytest.approx(want, nan_ok=True)
    assert got[1] == pytest.approx(want, nan_ok=True) and got[2] == pytest.approx(want, nan_ok=True)
    assert got[3] == pytest.approx(5.0)  # rancid fully: the centroid of cheap


def test_registry_returns_no_warnings_for_a_covered_rule_base() -> None:
    rb, warnings = load_with_warnings("macvicar_whelan")
    assert warnings == [] and rb.coverage == "strict"


def test_validate_prints_warnings_and_strict_makes_them_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "tip.yaml"
    path.write_text(tipper("coverage: allow_gaps"))
    assert main(["validate", str(path)]) == 0
    out, err = capsys.readouterr()
    assert f"{path}: ok (rule base tipper: 1 input, 1 output, 2 rules, 1 warning)" in out
    assert f"{path}:4:33: warning: {GAP}" in err
    assert main(["validate", "--strict", str(path)]) == 2
    out, err = capsys.readouterr()
    assert "ok" not in out
    assert f"{path}:4:33: {GAP}" in err and "(an error under --strict)" in err
    assert "1 of 1 file invalid" in err
