"""Interval type-2 rule bases in YAML: reading, located errors, writing, schema, info, refusals."""

from __future__ import annotations

import re
import subprocess
import sys

import jsonschema
import pytest
import yaml

from fuzzkit.errors import RuleBaseError
from fuzzkit.formats.foreign_common import ExportError
from fuzzkit.formats.registry import dumps, load, loads
from fuzzkit.formats.schema import json_schema
from fuzzkit.formats.yaml_writer import dump
from fuzzkit.fuzzy.type2_model import Type2RuleBase, footprint_of
from fuzzkit.fuzzy.type2_validation import lower_excess

DOC = """name: it2
inputs:
  e:
    range: [-1, 1]
    terms:
      N:
        upper: {shape: left_shoulder, points: [-1, 0.2]}
        lower: {shape: left_shoulder, points: [-1, -0.2], scale: 0.8}
      P:
        upper: {shape: right_shoulder, points: [-0.2, 1]}
        lower: {shape: right_shoulder, points: [0.2, 1], scale: 0.8}
outputs:
  u:
    range: [-1, 1]
    terms:
      N: {shape: triangle, points: [-2, -1, 0]}
      P:
        upper: {shape: triangle, points: [-0.2, 1, 2]}
        lower: {shape: triangle, points: [0.2, 1, 1.8], scale: 0.5}
rules:
  - {if: {e: N}, then: {u: N}}
  - {if: {e: P}, then: {u: P}}
"""


def test_reads_upper_lower_and_scale() -> None:
    rb = loads(DOC)
    assert isinstance(rb, Type2RuleBase)
    fp = rb.footprint
    assert fp.type_reduction == "karnik-mendel" and fp.resolution is None
    assert rb.input("e").term("N").params == (-1.0, 0.2)  # the terms are the upper ones
    low = fp.lower("e", "N")
    assert low is not None and low.shape.params == (-1.0, -0.2) and low.scale == 0.8
    assert fp.lower("u", "N") is None  # a type-1 term inside an IT2 rule base
    assert footprint_of(load("macvicar_whelan")) is None


@pytest.mark.parametrize(
    ("old", "new", "where", "message"),
    [
        (
            "scale: 0.8}\n      P",
            "scale: 0}\n      P",
            (8, 66),
            r"scale must be in \(0, 1\], got 0",
        ),
        ("scale: 0.8}\n      P", "scale: 1.2}\n      P", (8, 66), r"got 1\.2"),
        ("scale: 0.5", "scale: .nan", (19, 64), r"scale must be in \(0, 1\], got nan"),
        (
            "[0.2, 1, 1.8], scale: 0.5",
            "[-0.5, 1, 1.8], scale: 0.5",
            (17, 7),
            r"rises above the upper one at u = -0\.2 \(by 0\.1\)",
        ),
        (
            "[0.2, 1, 1.8], scale: 0.5",
            "[0.2, 1, 1.8], scale: 0.5, colour: red",
            (19, 69),
            r"unknown key 'colour'",
        ),
        (
            "        lower: {shape: triangle, points: [0.2, 1, 1.8], scale: 0.5}\n",
            "",
            (18, 9),
            r"missing required key 'lower' in interval type-2 term 'P'",
        ),
        (
            "lower: {shape: left_shoulder, points: [-1, -0.2]",
            "lower: {shape: left_shoulder, points: [-1]",
            (8, 47),
            r"left_shoulder needs 2 points",
        ),
        (
            "rules:",
            "type_reduction: karnik\nrules:",
            (20, 17),
            r"unknown type reduction 'karnik' \(did you mean 'karnik-mendel'\?\)",
        ),
        ("rules:", "resolution: 1\nrules:", (20, 13), r"expected an integer >= 2"),
        ("rules:", "defuzzifier: bisector\nrules:", (20, 14), r"defuzzifier must be centroid"),
        (
            "rules:",
            "operators: {aggregation: bounded_sum}\nrules:",
            (20, 26),
            r"aggregates with max",
        ),
        ("{if: {e: N}", "{if: {e: {not: N}}", (21, 11), r"'not' is not supported"),
    ],
)
def test_bad_documents_are_located(
    old: str, new: str, where: tuple[int, int], message: str
) -> None:
    assert old in DOC
    with pytest.raises(RuleBaseError) as err:
        loads(DOC.replace(old, new, 1), "it2.yaml")
    text = str(err.value)
    line, col = where
    assert re.search(rf"it2\.yaml:{line}:{col}: .*{message}", text), text


def test_smooth_output_terms_need_a_resolution() -> None:
    smooth = DOC.replace(
        "N: {shape: triangle, points: [-2, -1, 0]}", "N: {shape: gaussian, mean: -1, sigma: 0.4}"
    )
    with pytest.raises(RuleBaseError, match="needs piecewise-linear output terms"):
        loads(smooth)
    rb = loads(smooth.replace("rules:", "resolution: 101\nrules:"))
    assert footprint_of(rb) is not None and footprint_of(rb).resolution == 101


def test_lower_under_upper_is_exact_for_piecewise_linear_terms() -> None:
    # a lower spike 2e-7 wide at 0.05 + 1e-7 pokes above the upper triangle there; a grid of
    # 10001 points over the range steps over it, the vertex check finds it
    import numpy as np

    from fuzzkit.fuzzy.membership import evaluate_term
    from fuzzkit.fuzzy.model import Term

    du = load("macvicar_whelan_it2").output("du")
    upper = du.term("ZR")
    spike = Term("ZR", "triangle", (0.05, 0.05 + 1e-7, 0.05 + 2e-7))
    grid = np.linspace(-1, 1, 10_001)
    assert (evaluate_term(spike, grid) <= evaluate_term(upper, grid)).all()
    excess, at = lower_excess(upper, spike, 1.0, du)
    assert excess == pytest.approx(0.125, abs=1e-6) and at == pytest.approx(0.05 + 1e-7)
    inside = Term("ZR", "triangle", (-0.25, 0.0, 0.25))
    assert lower_excess(upper, inside, 0.8, du)[0] <= 0.0


def test_yaml_round_trip_keeps_the_footprint() -> None:
    for rb in (loads(DOC), load("macvicar_whelan_it2")):
        back = loads(dump(rb))
        assert back == rb
        assert footprint_of(back) == footprint_of(rb)
    rb = loads(DOC.replace("rules:", "type_reduction: nie-tan\nresolution: 201\nrules:"))
    assert "type_reduction: nie-tan" in dump(rb) and "resolution: 201" in dump(rb)
    assert loads(dump(rb)) == rb


def test_schema_accepts_it2_files_and_rejects_a_bad_scale() -> None:
    validator = jsonschema.Draft202012Validator(json_schema())
    doc = yaml.safe_load(DOC)
    assert not list(validator.iter_errors(doc))
    assert not list(validator.iter_errors(yaml.safe_load(dump(load("macvicar_whelan_it2")))))
    doc["inputs"]["e"]["terms"]["N"]["lower"]["scale"] = 1.5
    assert list(validator.iter_errors(doc))
    doc = yaml.safe_load(DOC)
    doc["type_reduction"] = "centre-of-sets"
    assert list(validator.iter_errors(doc))


@pytest.mark.parametrize("fmt", ["fis", "fcl", "fll"])
def test_foreign_writers_refuse_it2_even_with_loss_allowed(fmt: str) -> None:
    with pytest.raises(ExportError, match="interval type-2"):
        dumps(loads(DOC), fmt, allow_loss=True)


def _cli(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "fuzzkit", *args], capture_output=True, text=True, check=False
    )


def test_cli_info_validate_and_explain() -> None:  # explain in detail: test_type2_explain.py
    info = _cli("info", "macvicar_whelan_it2")
    assert info.returncode == 0
    assert "interval type-2: type_reduction=karnik-mendel (continuous)" in info.stdout
    assert "lower: triangle a=-0.25 b=0 c=0.25 scale=0.8" in info.stdout
    assert _cli("validate", "macvicar_whelan_it2").returncode == 0
    why = _cli("eval", "macvicar_whelan_it2", "-i", "e=0.1", "-i", "de=0", "--explain")
    assert why.returncode == 0 and "centroid interval [" in why.stdout


def test_plot_shades_the_footprint(tmp_path: object) -> None:
    import numpy as np
    from matplotlib.collections import PolyCollection

    from fuzzkit.viz.rulebase_plot import footprint_curves, plot_rulebase

    rb = load("macvicar_whelan_it2")
    fp = footprint_of(rb)
    assert fp is not None
    low = fp.lower("e", "ZR")
    assert low is not None
    x, upper, lower = footprint_curves(rb.input("e"), 3, low)
    # the curves are exact at the corners: upper triangle [-0.4, 0, 0.4], lower 0.8 [-0.25, 0.25]
    assert {-0.4, -0.25, 0.0, 0.25, 0.4} <= set(np.round(x, 12))
    assert upper[x == 0.0][0] == 1.0 and lower[x == 0.0][0] == pytest.approx(0.8)
    assert (lower <= upper + 1e-15).all()
    fig = plot_rulebase(rb)
    shaded = [c for ax in fig.axes[:3] for c in ax.collections if isinstance(c, PolyCollection)]
    assert len(shaded) == 21  # one footprint per term: 7 labels x 3 variables
    assert _cli("plot", "macvicar_whelan_it2", "--out", f"{tmp_path}/it2.png").returncode == 0


def test_the_closed_loop_takes_it2() -> None:
    # nothing keeps an IT2 rule base out of the loop (tests/test_type2_loop.py runs it)
    from fuzzkit.control.loop_rulebase import loop_problems

    assert loop_problems(load("macvicar_whelan_it2")) == []
