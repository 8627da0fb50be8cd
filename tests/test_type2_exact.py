"""``fuzzkit compile --method exact`` of interval type-2 rule bases (issue 43 item 2): the
constant-time exact IT2 emitter (``codegen/exact_type2.py``) for C float, C double and Python.

Checked against the exact engine (``--verify``, and :func:`verify_exact_python` on fewer
points: the generated Python takes milliseconds a point), against the independent brute force
(``tests/_type2_reference.py``, on a fine grid), and for what the method must not do: the
sanitized runs are in ``tests/test_codegen_exact.py`` (``SANITIZED``).
"""

from __future__ import annotations

import ctypes
import re
from pathlib import Path

import numpy as np
import pytest
from _codegen_util import needs_cc
from _replay_logs import run_cli
from _type2_reference import centroid_interval

from fuzzkit.codegen.exact import emit_exact, unsupported_reason
from fuzzkit.codegen.exact_type2 import ROOT_STEPS
from fuzzkit.codegen.method import compile_rulebase
from fuzzkit.codegen.toolchain import CompiledTable
from fuzzkit.codegen.verify import load_module, verify_exact_python
from fuzzkit.errors import CodegenError
from fuzzkit.formats.registry import load, loads
from fuzzkit.fuzzy.type2_model import Type2RuleBase

NAME = "macvicar_whelan_it2"


@needs_cc
@pytest.mark.parametrize("number_type", ["double", "float"])
def test_compile_exact_verifies_against_the_engine_in_c(
    number_type: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "gen"
    code, printed, err = run_cli(
        capsys, "compile", NAME, "--target", "c", "--type", number_type, "--method", "exact",
        "--verify", "--out", str(out),
    )  # fmt: skip
    assert code == 0, err
    assert re.search(r"verify c exact \(" + number_type + r"\): ok on 10\d{4} points", printed)
    header = (out / f"{NAME}.h").read_text(encoding="utf-8")
    source = (out / f"{NAME}.c").read_text(encoding="utf-8")
    # the header states the bound and how the root is found, in a fixed number of steps
    flat = " ".join(line.lstrip(" *") for line in header.splitlines())
    assert "continuous Karnik-Mendel" in flat and "rounding" in flat
    assert f"{ROOT_STEPS[number_type]} bisection steps" in flat
    assert "malloc" not in source and "while" not in source  # no heap, no open-ended loop


def test_the_generated_python_agrees_with_the_engine() -> None:
    rb = load(NAME)
    result = verify_exact_python(rb, emit_exact(rb, "python"), n=200)
    assert result.ok, result.describe()


@needs_cc
def test_c_double_agrees_with_the_brute_force(tmp_path: Path) -> None:
    # the brute force samples both sets on 20001 points and tries every switch point: its
    # quadrature error is below 1e-7 on this rule base (tests/test_type2_inference.py)
    rb = load(NAME)
    assert isinstance(rb, Type2RuleBase)
    with CompiledTable(emit_exact(rb, "c", "double"), NAME, "double", 2, 1, fpi=True) as lib:
        rng = np.random.default_rng(5)
        points = np.vstack([rng.uniform(-1, 1, (12, 2)), [[0.0, 0.0], [1.0, -1.0], [-0.5, -0.56]]])
        got = lib.eval_batch(points)[:, 0]
    for (e, de), value in zip(points, got, strict=True):
        y_l, y_r = centroid_interval(rb, {"e": e, "de": de}, 20001)
        assert abs(value - 0.5 * (y_l + y_r)) < 1e-7, (e, de)


@needs_cc
def test_auto_prefers_exact_for_it2_and_says_why() -> None:
    compiled = compile_rulebase(load(NAME), "c", "float")
    assert compiled.method == "exact" and "interval type-2" in compiled.reason


SOURCE = Path(__file__).resolve().parent.parent / "rulebases" / f"{NAME}.yaml"


@pytest.mark.parametrize(
    ("change", "why"),
    [
        ("type_reduction: nie-tan", "type reduction nie-tan is generated as a table"),
        (
            "type_reduction: karnik-mendel\nresolution: 101",
            "resolution: N (discrete type reduction) is generated as a table",
        ),
    ],
)
def test_what_the_exact_emitter_does_not_cover_is_refused_with_the_reason(
    change: str, why: str
) -> None:
    text = SOURCE.read_text(encoding="utf-8")
    assert "type_reduction: karnik-mendel\n" in text
    rb = loads(text.replace("type_reduction: karnik-mendel", change))
    assert why in (unsupported_reason(rb) or "")
    with pytest.raises(CodegenError, match=re.escape(why)):
        emit_exact(rb, "c")


def test_a_nan_input_gives_nan_and_no_rule_fires_gives_the_default() -> None:
    module = load_module(emit_exact(load(NAME), "python"), NAME)
    assert np.isnan(module.eval((float("nan"), 0.0))[0])
    assert module.eval((0.0, 0.0))[0] == pytest.approx(0.0, abs=1e-15)  # odd symmetry
    assert isinstance(ctypes.c_double(module.eval((1.0, 1.0))[0]).value, float)
