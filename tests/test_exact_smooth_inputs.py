"""Every smooth input shape in the exact method's generated code (C float, C double, Python).

MATLAB's gauss2mf, smf, zmf, pimf, dsigmf and psigmf (fuzzkit's gaussian_product, s_shape,
z_shape, pi_shape, sigmoid_difference, sigmoid_product), with gbellmf and sigmf beside them, in
tests/data/fis/smooth_inputs.fis: the generated code against the engine on 1e5 random points,
every combination of edge values and the weak points (``verification_points``), and code and
engine against an exact centroid of memberships written out independently
(tests/_mamdani_reference.py: MATLAB's documented formulas; tests/_exact_centroid.py: the
aggregated set in rational arithmetic). :func:`narrow` puts every membership at 1e-15 or less
between its terms, where a fuzzification that loses the levels' scale shows.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _codegen_util import needs_cc, skip_no_cc
from _exact_centroid import exact_output
from _mamdani_reference import firing
from _random_rulebases import MATLAB_SHAPES

from fuzzkit.codegen.exact import emit_exact, unsupported_reason
from fuzzkit.codegen.toolchain import CompiledTable
from fuzzkit.codegen.verify import (
    load_module,
    python_outputs,
    verify_exact_c,
    verify_exact_python,
    weak_values,
)
from fuzzkit.formats.registry import load
from fuzzkit.fuzzy import shapes
from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.model import Consequent, Operators, Proposition, Rule, RuleBase, Term, Variable
from fuzzkit.fuzzy.validation import check

FIS = Path(__file__).parent / "data" / "fis" / "smooth_inputs.fis"
DTYPE = {"double": np.float64, "float": np.float32}
#: |generated - exact centroid| in output units (range [-1, 1]): double rounding, and float's
#: stated bound (256 float epsilons of the full scale, codegen.exact.ROUNDING_BOUND)
ATOL = {"double": 1e-12, "float": 256 * 2.0**-23}


def narrow() -> RuleBase:
    """One input whose smooth terms are narrow: between them every membership is 1e-15 or
    less, and above 1e-30 (a float holds it)."""
    x = Variable(
        "x",
        -1.0,
        1.0,
        (
            Term("Z", "z_shape", (-1.0, -0.9)),
            Term("A", "gaussian_product", (-0.8, 0.03, -0.7, 0.03)),
            Term("B", "sigmoid_product", (200.0, -0.15, -200.0, 0.15)),
            Term("C", "sigmoid_difference", (200.0, 0.55, 200.0, 0.65)),
            Term("D", "pi_shape", (0.6, 0.7, 0.8, 0.9)),
            Term("S", "s_shape", (0.85, 1.0)),
        ),
    )
    y = Variable(
        "y",
        -1.0,
        1.0,
        (
            Term("T0", "triangle", (-1.0, -0.5, 0.1)),
            Term("T1", "trapezoid", (-0.7, -0.2, 0.3, 0.8)),
            Term("T2", "triangle", (-0.1, 0.6, 1.0)),
        ),
    )
    cons = {"Z": "T0", "A": "T0", "B": "T1", "C": "T2", "D": "T2", "S": "T1"}
    rules = tuple(Rule(Proposition("x", a), (Consequent("y", t),)) for a, t in cons.items())
    return RuleBase("narrow_smooth", (x,), (y,), rules, Operators("min", "max", "min", "max"))


#: Between A and B, and between B and C: every firing strength in (1e-30, 1e-15).
TINY_X = (-0.42, -0.40, 0.33, 0.35)


def _generated(rb: RuleBase, target: str, number_type: str, points: np.ndarray) -> np.ndarray:
    files = emit_exact(rb, target, number_type)
    if target == "python":
        return python_outputs(load_module(files, rb.name).eval, points)
    n = len(rb.inputs)
    with CompiledTable(files, rb.name, number_type, n, 1, fpi=n == 2) as lib:
        return lib.eval_batch(points.astype(DTYPE[number_type])).astype(np.float64)


TARGETS = [("python", "double"), ("c", "double"), ("c", "float")]


def test_every_input_shape_has_generated_fuzzification() -> None:
    inputs = [s for s in shapes.REGISTRY.values() if not s.sugeno]
    assert {s.name for s in inputs} >= set(MATLAB_SHAPES)
    assert [s.name for s in inputs if s.exact is None] == []
    rb = load(FIS)
    assert check(rb) == []
    assert {t.shape for v in rb.inputs for t in v.terms} >= {*MATLAB_SHAPES, "bell", "sigmoid"}
    assert unsupported_reason(rb, "double") is None
    assert unsupported_reason(rb, "float") is None


#: rule base, random points for C (the engine takes about 70 us a point on the narrow one)
CASES = {"fis": (lambda: load(FIS), 100_000), "narrow": (narrow, 5_000)}


@needs_cc
@skip_no_cc
@pytest.mark.parametrize("number_type", ["double", "float"])
@pytest.mark.parametrize("case", sorted(CASES))
def test_in_c_matches_the_engine_to_rounding(case: str, number_type: str) -> None:
    make, n = CASES[case]
    rb = make()
    result = verify_exact_c(rb, number_type, emit_exact(rb, "c", number_type), n=n)
    assert result.n_points >= n
    assert result.ok, result.describe()


@pytest.mark.parametrize("case", sorted(CASES))
def test_in_python_matches_the_engine_to_rounding(case: str) -> None:
    rb = CASES[case][0]()
    result = verify_exact_python(rb, emit_exact(rb, "python"), n=2000)
    assert result.ok, result.describe()


@pytest.fixture(scope="module")
def fis_reference() -> tuple[np.ndarray, np.ndarray]:
    """Random points and range corners (each a float, so float code sees them as they are)
    with the exact centroid there."""
    rb = load(FIS)
    rng = np.random.default_rng(3)
    points = np.vstack([rng.uniform(-1, 1, (16, 2)), [[-1, -1], [1, 1], [-1, 1], [0, 0]]])
    points = points.astype(np.float32).astype(np.float64)
    return points, np.array([exact_output(rb, {"e": e, "de": de}) for e, de in points])


def test_engine_equals_the_exact_centroid_of_the_documented_formulas(
    fis_reference: tuple[np.ndarray, np.ndarray],
) -> None:
    points, want = fis_reference
    engine = Engine(load(FIS)).evaluate({"e": points[:, 0], "de": points[:, 1]})["u"]
    np.testing.assert_allclose(engine, want, rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    "target, number_type",
    [pytest.param(*t, marks=[needs_cc, skip_no_cc] if t[0] == "c" else []) for t in TARGETS],
)
def test_code_equals_the_exact_centroid_of_the_documented_formulas(
    fis_reference: tuple[np.ndarray, np.ndarray], target: str, number_type: str
) -> None:
    points, want = fis_reference
    got = _generated(load(FIS), target, number_type, points)[:, 0]
    np.testing.assert_allclose(got, want, rtol=0, atol=ATOL[number_type])


def test_the_narrow_points_are_where_every_strength_is_tiny() -> None:
    rb = narrow()
    assert check(rb) == []
    for x in TINY_X:
        strengths = firing(rb, {"x": x})
        assert 1e-30 < max(strengths) < 1e-15, (x, strengths)
    # and the verification of generated code looks there too
    assert all(max(firing(rb, {"x": x})) < 1e-15 for x in weak_values(rb.inputs[0]))
    want = [exact_output(rb, {"x": x}) for x in TINY_X]
    got = Engine(rb).evaluate({"x": np.array(TINY_X)})["y"]
    np.testing.assert_allclose(got, np.array(want, dtype=np.float64), rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    "target, number_type",
    [pytest.param(*t, marks=[needs_cc, skip_no_cc] if t[0] == "c" else []) for t in TARGETS],
)
def test_narrow_terms_where_every_strength_is_tiny(target: str, number_type: str) -> None:
    rb = narrow()
    points = np.array([[x] for x in TINY_X])
    want = np.array([exact_output(rb, {"x": x}) for x in TINY_X])
    got = _generated(rb, target, number_type, points)[:, 0]
    np.testing.assert_allclose(got, want, rtol=0, atol=ATOL[number_type])
