"""Where every firing strength is tiny: the engine and the generated code against an exact centroid.

Between Gaussian input terms of small sigma every membership is 1e-20 or less. A clipped output
term is then a flat top of that height over nearly its whole support; an output stage that
reads the set at the points where an edge meets the level (the edge's foot, to the last bit)
sees 0 there and integrates a ramp instead. The reference is tests/_exact_centroid.py: the
aggregated set in rational arithmetic, exact whatever the levels' size.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _codegen_util import needs_cc, skip_no_cc
from _exact_centroid import exact_output
from _mamdani_reference import firing

from fuzzkit.cli import main
from fuzzkit.codegen.exact import emit_exact
from fuzzkit.codegen.toolchain import CompiledTable
from fuzzkit.codegen.verify import (
    compare_exact,
    load_module,
    python_outputs,
    verify_exact_python,
    weak_values,
)
from fuzzkit.formats.registry import load
from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.model import Consequent, Operators, Proposition, Rule, RuleBase, Term, Variable

FIS = Path(__file__).parent / "data" / "fis" / "tiny_strengths.fis"
MAXIMA = ("mean_of_maximum", "smallest_of_maximum", "largest_of_maximum")
DTYPE = {"double": np.float64, "float": np.float32}


def overlapping(implication: str, aggregation: str, defuzzifier: str) -> RuleBase:
    """Gaussian inputs of sigma 0.05 and three output terms that overlap three-fold (so the
    engine takes its general breakpoint sweep, not the partition centroid)."""
    x = Variable(
        "x",
        -1.0,
        1.0,
        tuple(Term(n, "gaussian", (c, 0.05)) for n, c in (("A", -1.0), ("B", 0.0), ("C", 1.0))),
    )
    y = Variable(
        "y",
        -1.0,
        1.0,
        (
            Term("T0", "triangle", (-1.0, -0.2, 0.6)),
            Term("T1", "trapezoid", (-0.6, 0.0, 0.2, 0.9)),
            Term("T2", "triangle", (-0.9, 0.5, 1.0)),
        ),
    )
    rules = tuple(
        Rule(Proposition("x", a), (Consequent("y", t),), w)
        for a, t, w in (("A", "T0", 1.0), ("B", "T1", 1.0), ("C", "T2", 0.7), ("B", "T2", 0.3))
    )
    ops = Operators("min", "max", implication, aggregation)
    return RuleBase(f"tiny_{implication}_{aggregation}", (x,), (y,), rules, ops, defuzzifier)


CASES = [
    (imp, agg, d)
    for imp in ("min", "product")
    for agg in ("max", "bounded_sum", "probabilistic_sum")
    for d in ("centroid", "bisector", *MAXIMA)
    if not (agg == "probabilistic_sum" and d in MAXIMA)  # curved tops: the reference is linear
]
TINY_X = (0.45, -0.55, 0.42, 0.58)


def test_the_points_are_where_every_strength_is_tiny() -> None:
    rb = overlapping("min", "max", "centroid")
    for x in TINY_X:
        strengths = firing(rb, {"x": x})
        assert 0.0 < max(strengths) < 1e-15, (x, strengths)
    # and the verification of generated code looks there too
    assert all(max(firing(rb, {"x": x})) < 1e-15 for x in weak_values(rb.inputs[0]))


@pytest.mark.parametrize("implication, aggregation, defuzzifier", CASES)
def test_engine_equals_the_exact_set_where_every_strength_is_tiny(
    implication: str, aggregation: str, defuzzifier: str
) -> None:
    rb = overlapping(implication, aggregation, defuzzifier)
    got = Engine(rb).evaluate({"x": np.array(TINY_X)})["y"]
    want = [exact_output(rb, {"x": x}) for x in TINY_X]
    np.testing.assert_allclose(got, np.array(want, dtype=np.float64), rtol=0, atol=1e-12)


def test_fis_engine_equals_the_exact_set_where_every_strength_is_tiny() -> None:
    rb = load(FIS)
    points = [(0.3, 0.5), (0.3, -0.45), (0.1, 0.55), (-0.25, 0.5), (0.22, 0.45)]
    for e, de in points:
        point = {"e": e, "de": de}
        assert 0.0 < max(firing(rb, point)) < 1e-15, point
        want = exact_output(rb, point)
        assert want is not None
        assert Engine(rb).evaluate_point(point)["u"] == pytest.approx(want, abs=1e-12)


def _tiny_points(rb: RuleBase) -> np.ndarray:
    rng = np.random.default_rng(0)
    weak = [weak_values(v, 6) for v in rb.inputs]
    return np.array([[float(rng.choice(w)) for w in weak] for _ in range(200)])


@pytest.mark.parametrize("implication, aggregation, defuzzifier", CASES)
def test_generated_python_equals_the_engine_where_every_strength_is_tiny(
    implication: str, aggregation: str, defuzzifier: str
) -> None:
    rb = overlapping(implication, aggregation, defuzzifier)
    module = load_module(emit_exact(rb, "python"), rb.name)
    points = np.array([[x] for x in TINY_X])
    got = python_outputs(module.eval, points)
    want = Engine(rb).evaluate({"x": points[:, 0]})["y"][:, None]
    result = compare_exact(rb, "double", "python", got, want)
    assert result.ok and result.tie_jumps == 0, result.describe()


@needs_cc
@skip_no_cc
@pytest.mark.parametrize("number_type", ["double", "float"])
def test_generated_c_equals_the_engine_where_every_strength_is_tiny(number_type: str) -> None:
    for implication, aggregation, defuzzifier in CASES[::5]:  # every operator pair once
        rb = overlapping(implication, aggregation, defuzzifier)
        args = np.array([[x] for x in TINY_X], dtype=DTYPE[number_type])
        with CompiledTable(
            emit_exact(rb, "c", number_type), rb.name, number_type, 1, 1, fpi=False
        ) as lib:
            got = lib.eval_batch(args)
        want = Engine(rb).evaluate({"x": args[:, 0].astype(np.float64)})["y"][:, None]
        result = compare_exact(rb, number_type, "c", got.astype(np.float64), want)
        assert result.ok and result.tie_jumps == 0, (rb.name, defuzzifier, result.describe())


def test_fis_generated_python_equals_the_engine_and_the_exact_set() -> None:
    rb = load(FIS)
    module = load_module(emit_exact(rb, "python"), rb.name)
    points = _tiny_points(rb)
    got = python_outputs(module.eval, points)
    want = np.column_stack([Engine(rb).evaluate({"e": points[:, 0], "de": points[:, 1]})["u"]])
    result = compare_exact(rb, "double", "python", got, want)
    assert result.ok, result.describe()
    exact = [exact_output(rb, {"e": e, "de": de}) for e, de in points[:20]]
    np.testing.assert_allclose(got[:20, 0], np.array(exact, dtype=np.float64), atol=1e-12)
    assert verify_exact_python(rb, emit_exact(rb, "python"), n=2000).ok


@pytest.mark.slow  # the Python --verify runs 1e5 points through the generated module
@needs_cc
@skip_no_cc
@pytest.mark.parametrize(
    "target, number_type", [("python", "double"), ("c", "double"), ("c", "float")]
)
def test_fis_compiles_and_verifies_from_the_command_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], target: str, number_type: str
) -> None:
    args = ["compile", str(FIS), "--target", target, "--type", number_type]
    code = main([*args, "--method", "exact", "--verify", "--out", str(tmp_path / "out"), "--quiet"])
    text = capsys.readouterr().out
    assert code == 0, text
    assert "verify" in text and ": ok on" in text
    assert (tmp_path / "out").is_dir()
