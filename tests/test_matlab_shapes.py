"""The smooth MATLAB shapes (gauss2mf, smf, zmf, pimf, dsigmf, psigmf) against closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _fis_probe import fis_with_input_mf
from _mamdani_reference import mu as reference_mu
from _mamdani_reference import reference, smf, zmf

from fuzzkit.codegen.exact import ROUNDING_BOUND, unsupported_reason
from fuzzkit.codegen.method import compile_rulebase
from fuzzkit.codegen.verify import load_module
from fuzzkit.errors import RuleBaseError
from fuzzkit.formats import fcl, fis, fll
from fuzzkit.formats.foreign_common import ExportError
from fuzzkit.formats.registry import dumps, loads
from fuzzkit.fuzzy import membership
from fuzzkit.fuzzy.inference import Engine
from fuzzkit.fuzzy.model import Term, Variable
from fuzzkit.fuzzy.validation import uncovered

SHAPES = [
    ("gaussian_product", (2.0, 0.5, 5.0, 1.5)),  # plateau [2, 5]
    ("gaussian_product", (6.0, 1.0, 3.0, 2.0)),  # tails overlap: a peak below 1
    ("s_shape", (1.0, 8.0)),
    ("z_shape", (1.0, 8.0)),
    ("pi_shape", (1.0, 4.0, 5.0, 9.0)),
    ("sigmoid_difference", (5.0, 2.0, 5.0, 7.0)),
    ("sigmoid_difference", (2.0, 3.0, 6.0, 5.0)),  # unequal slopes: crosses zero once
    ("sigmoid_product", (2.0, 3.0, -5.0, 8.0)),
]

HAND = [
    # shape, params, x, expected (worked by hand from MATLAB's documented formulas)
    ("s_shape", (1.0, 8.0), 4.5, 0.5),  # the midpoint
    ("s_shape", (1.0, 8.0), 2.75, 2 * (1.75 / 7) ** 2),
    ("s_shape", (1.0, 8.0), 6.25, 1 - 2 * (1.75 / 7) ** 2),
    ("s_shape", (1.0, 8.0), 0.0, 0.0),
    ("s_shape", (1.0, 8.0), 9.0, 1.0),
    ("z_shape", (1.0, 8.0), 2.75, 1 - 2 * (1.75 / 7) ** 2),
    ("z_shape", (1.0, 8.0), 8.0, 0.0),
    ("pi_shape", (1.0, 4.0, 5.0, 9.0), 4.5, 1.0),
    ("pi_shape", (1.0, 4.0, 5.0, 9.0), 7.0, 0.5),
    ("gaussian_product", (2.0, 0.5, 5.0, 1.5), 3.5, 1.0),
    ("gaussian_product", (2.0, 0.5, 5.0, 1.5), 1.5, math.exp(-0.5)),
    ("gaussian_product", (2.0, 0.5, 5.0, 1.5), 8.0, math.exp(-2.0)),
    (
        "sigmoid_difference",
        (5.0, 2.0, 5.0, 7.0),
        4.5,
        1 / (1 + math.exp(-12.5)) - 1 / (1 + math.exp(12.5)),
    ),
    ("sigmoid_product", (2.0, 3.0, -5.0, 8.0), 3.0, 0.5 / (1 + math.exp(-25.0))),
]


@pytest.mark.parametrize(("shape", "params", "x", "want"), HAND)
def test_values_worked_by_hand(
    shape: str, params: tuple[float, ...], x: float, want: float
) -> None:
    got = float(membership.evaluate_term(Term("t", shape, params), x))
    assert got == pytest.approx(want, rel=1e-14, abs=1e-15)


@pytest.mark.parametrize(("shape", "params"), SHAPES)
def test_shape_matches_the_independent_formula_and_keeps_nan(
    shape: str, params: tuple[float, ...]
) -> None:
    term = Term("t", shape, params)
    x = np.linspace(-3.0, 13.0, 4001)
    got = membership.evaluate_term(term, x)
    np.testing.assert_allclose(got, reference_mu(term, x), rtol=1e-12, atol=1e-15)
    assert np.all((got >= 0) & (got <= 1))
    assert np.isnan(membership.evaluate_term(term, np.array([np.nan]))[0])
    assert np.all(np.isfinite(membership.evaluate_term(term, np.array([-1e300, 1e300]))))


@pytest.mark.parametrize(("shape", "params"), SHAPES)
def test_coverage_is_where_the_shape_is_positive(shape: str, params: tuple[float, ...]) -> None:
    var = Variable("x", -3.0, 13.0, (Term("t", shape, params),))
    gaps = uncovered(var)
    x = np.linspace(-3.0, 13.0, 16001)
    mu = membership.evaluate_term(var.terms[0], x)
    in_gap = np.zeros_like(x, dtype=bool)
    for lo, hi in gaps:
        in_gap |= (x >= lo) & (x <= hi)
    # exact zero only in the gaps (underflow to 0 far out in a tail is rounding, not a gap)
    assert np.all(mu[in_gap] == 0.0)
    assert np.all(reference_mu(var.terms[0], x[~in_gap]) > 0.0)


SMOOTH_OUT = """\
name: smooth_out
inputs:
  e: {range: [-1, 1], terms: {partition: triangular, labels: [N, Z, P]}}
outputs:
  u:
    range: [0, 10]
    terms:
      N: {shape: z_shape, start: 1, end: 4}
      Z: {shape: gaussian_product, mean1: 4, sigma1: 0.7, mean2: 6, sigma2: 1.2}
      P: {shape: pi_shape, a: 5, b: 7, c: 8, d: 9.5}
defuzzifier: $defuzz
rules:
  - {if: {e: N}, then: {u: N}}
  - {if: {e: Z}, then: {u: Z}}
  - {if: {e: P}, then: {u: P}}
"""


@pytest.mark.parametrize("defuzz", ["centroid", "bisector"])
def test_smooth_output_shapes_defuzzify_like_the_fine_grid_reference(defuzz: str) -> None:
    rb = loads(SMOOTH_OUT.replace("$defuzz", defuzz))
    eng = Engine(rb)
    for e in (-0.9, -0.3, 0.0, 0.45, 1.0):
        want = reference(rb, {"e": e})
        assert eng.evaluate_point(e=e)["u"] == pytest.approx(want, abs=2e-6)


def test_weighted_average_uses_the_plateau_middles() -> None:
    rb = loads(SMOOTH_OUT.replace("$defuzz", "weighted_average"))
    # e = 0.5: Z and P fire at 0.5 each; centres 5 (plateau [4, 6]) and 7.5 (core [7, 8])
    assert Engine(rb).evaluate_point(e=0.5)["u"] == pytest.approx((5.0 + 7.5) / 2, abs=1e-12)
    # e = -1: only N, whose core is [0, 1] inside the range
    assert Engine(rb).evaluate_point(e=-1.0)["u"] == pytest.approx(0.5, abs=1e-12)


# ---------------------------------------------------------------------------- in files
#
# Each format's own spelling and parameter order of the six shapes, written out here from
# MATLAB's documentation (gauss2mf [sig1 c1 sig2 c2], smf/zmf [a b], pimf [a b c d],
# dsigmf/psigmf [a1 c1 a2 c2]), fuzzylite's term classes (GaussianProduct meanA sdA meanB sdB,
# SShape/ZShape start end, PiShape bottomLeft topLeft topRight bottomRight, SigmoidDifference
# and SigmoidProduct left rising falling right) and jFuzzyLogic's GAUSS2 mean1 sd1 mean2 sd2.


def _sig(x: np.ndarray, a: float, c: float) -> np.ndarray:
    return 1.0 / (1.0 + np.exp(-a * (x - c)))


def _matlab_gauss2mf(x: np.ndarray, s1: float, c1: float, s2: float, c2: float) -> np.ndarray:
    left = np.where(x <= c1, np.exp(-((x - c1) ** 2) / (2 * s1**2)), 1.0)
    right = np.where(x >= c2, np.exp(-((x - c2) ** 2) / (2 * s2**2)), 1.0)
    return left * right


#: (MATLAB name and parameters, MATLAB's formula over those parameters as written in the file)
MATLAB_FILE_TERMS = {
    "gaussian_product": ("gauss2mf", (0.5, 2.0, 1.5, 5.0), _matlab_gauss2mf),
    "s_shape": ("smf", (1.0, 8.0), smf),
    "z_shape": ("zmf", (1.0, 8.0), zmf),
    "pi_shape": (
        "pimf",
        (1.0, 4.0, 5.0, 9.0),
        lambda x, a, b, c, d: smf(x, a, b) * zmf(x, c, d),
    ),
    "sigmoid_difference": (
        "dsigmf",
        (2.0, 3.0, 6.0, 5.0),
        lambda x, a1, c1, a2, c2: np.abs(_sig(x, a1, c1) - _sig(x, a2, c2)),
    ),
    "sigmoid_product": (
        "psigmf",
        (2.0, 3.0, -5.0, 8.0),
        lambda x, a1, c1, a2, c2: _sig(x, a1, c1) * _sig(x, a2, c2),
    ),
}


def _fuzzylite_params(shape: str, p: tuple[float, ...]) -> tuple[str, tuple[float, ...]]:
    """The fuzzylite class and its parameters for MATLAB's parameters ``p``."""
    if shape == "gaussian_product":  # [sig1 c1 sig2 c2] -> meanA sdA meanB sdB
        return "GaussianProduct", (p[1], p[0], p[3], p[2])
    if shape in ("sigmoid_difference", "sigmoid_product"):  # [a1 c1 a2 c2] -> left rising ...
        cls = "SigmoidDifference" if shape == "sigmoid_difference" else "SigmoidProduct"
        return cls, (p[1], p[0], p[2], p[3])
    return {"s_shape": "SShape", "z_shape": "ZShape", "pi_shape": "PiShape"}[shape], p


def _num(v: float) -> str:
    return str(int(v)) if float(v).is_integer() else repr(v)


FLL_TEXT = """\
Engine: t
InputVariable: x
  range: 0 10
  term: probe $TERM
  term: all Trapezoid -1 0 10 11
OutputVariable: y
  range: 0 1
  aggregation: Maximum
  defuzzifier: Centroid 10000
  default: 0.5
  term: lo Triangle 0 0.25 0.5
  term: hi Triangle 0.5 0.75 1
RuleBlock: rules
  conjunction: Minimum
  disjunction: Maximum
  implication: Minimum
  activation: General
  rule: if x is probe then y is hi
  rule: if x is all then y is lo
"""

FCL_TEXT = """\
FUNCTION_BLOCK t
VAR_INPUT
  x : REAL;
END_VAR
VAR_OUTPUT
  y : REAL;
END_VAR
FUZZIFY x
  RANGE := (0 .. 10);
  TERM probe := $TERM;
  TERM all := Trapezoid -1 0 10 11;
END_FUZZIFY
DEFUZZIFY y
  RANGE := (0 .. 1);
  TERM lo := Triangle 0 0.25 0.5;
  TERM hi := Triangle 0.5 0.75 1;
  METHOD : COG;
  ACCU : MAX;
  DEFAULT := 0.5;
END_DEFUZZIFY
RULEBLOCK rules
  AND : MIN;
  OR : MAX;
  ACT : MIN;
  RULE 1 : IF x IS probe THEN y IS hi;
  RULE 2 : IF x IS all THEN y IS lo;
END_RULEBLOCK
END_FUNCTION_BLOCK
"""


READ = {"fis": fis.loads, "fll": fll.loads, "fcl": fcl.loads}


def _file_terms(shape: str) -> dict[str, str]:
    """The shape as each format writes it, in that format's own parameter order."""
    mf, p, _ = MATLAB_FILE_TERMS[shape]
    cls, fl = _fuzzylite_params(shape, p)
    fl_term = f"{cls} {' '.join(map(_num, fl))}"
    return {"fis": f"'{mf}',[{' '.join(map(_num, p))}]", "fll": fl_term, "fcl": fl_term}


def _file_texts(shape: str) -> dict[str, str]:
    """The test file of every format with the shape in it (input term ``probe`` of ``x``)."""
    terms = _file_terms(shape)
    return {
        # the range of the other formats' files: the terms lie on [0, 10], and a term wholly
        # outside its input's range is an error (issue 29 item 7)
        "fis": fis_with_input_mf(terms["fis"], "[0 10]"),
        "fll": FLL_TEXT.replace("$TERM", terms["fll"]),
        "fcl": FCL_TEXT.replace("$TERM", terms["fcl"]),
    }


@pytest.mark.parametrize("fmt", ["fis", "fll", "fcl"])
@pytest.mark.parametrize("shape", list(MATLAB_FILE_TERMS))
def test_smooth_shapes_read_from_every_format_match_matlabs_formula(fmt: str, shape: str) -> None:
    _, p, formula = MATLAB_FILE_TERMS[shape]
    rb = READ[fmt](_file_texts(shape)[fmt], f"t.{fmt}")
    term = rb.inputs[0].term("probe")
    assert term.shape == shape
    x = np.linspace(-2.0, 12.0, 2801)
    np.testing.assert_allclose(
        membership.evaluate_term(term, x), formula(x, *p), rtol=1e-12, atol=1e-15
    )


@pytest.mark.parametrize("fmt", ["fis", "fll", "fcl"])
@pytest.mark.parametrize("shape", list(MATLAB_FILE_TERMS))
def test_smooth_shapes_are_written_in_each_formats_order_and_read_back(
    fmt: str, shape: str
) -> None:
    rb = READ[fmt](_file_texts(shape)[fmt], f"t.{fmt}")
    written = dumps(rb, fmt, allow_loss=True)
    assert _file_terms(shape)[fmt] in written, written
    assert READ[fmt](written, f"back.{fmt}") == rb


def test_jfuzzylogic_gauss2_is_the_gaussian_product_in_fcl() -> None:
    # jFuzzyLogic: GAUSS2 mean1 stdev1 mean2 stdev2, left gaussian below mean1, right above mean2
    rb = fcl.loads(FCL_TEXT.replace("$TERM", "gauss2 2 0.5 5 1.5"), "t.fcl")
    term = rb.inputs[0].term("probe")
    x = np.linspace(-2.0, 12.0, 1401)
    np.testing.assert_allclose(
        membership.evaluate_term(term, x), _matlab_gauss2mf(x, 0.5, 2.0, 1.5, 5.0), rtol=1e-12
    )


@pytest.mark.parametrize(
    ("term", "match"),
    [
        ("GAUSS2 5 0.5 2 1.5", r"t\.fcl:10:\d+: .*GAUSS2 needs mean1 <= mean2"),
        ("DSIGM 2 3 6 5", r"t\.fcl:10:\d+: .*DSIGM is jFuzzyLogic's max\(s1 - s2, 0\)"),
        ("SShape 1", r"t\.fcl:10:\d+: .*SShape needs 2 parameters, got 1"),
    ],
)
def test_fcl_refuses_what_is_not_the_shape(term: str, match: str) -> None:
    with pytest.raises(RuleBaseError, match=match):
        fcl.loads(FCL_TEXT.replace("$TERM", term), "t.fcl")


@pytest.mark.parametrize("shape", list(MATLAB_FILE_TERMS))
def test_fcl_iec_dialect_refuses_smooth_shapes_by_name(shape: str) -> None:
    rb = fll.loads(_file_texts(shape)["fll"], "t.fll")
    with pytest.raises(ExportError, match=rf"term x\.probe: shape '{shape}' \(IEC point lists"):
        fcl.dumps(rb, dialect="iec", allow_loss=True)


@pytest.mark.parametrize("shape", list(MATLAB_FILE_TERMS))
def test_exact_codegen_fuzzifies_smooth_input_shapes_as_the_engine(shape: str) -> None:
    rb = fll.loads(_file_texts(shape)["fll"], "t.fll")
    assert unsupported_reason(rb) is None
    done = compile_rulebase(rb, "python", "double", method="exact")
    module = load_module(done.files, rb.name)
    x = np.linspace(-1.0, 11.0, 997)
    got = np.array([module.eval([v])[0] for v in x])
    want = Engine(rb).evaluate({"x": x})["y"]
    np.testing.assert_allclose(got, want, rtol=0, atol=ROUNDING_BOUND["double"] * 10)


def test_the_table_method_compiles_smooth_input_shapes_and_the_code_runs() -> None:
    text = _file_texts("sigmoid_difference")["fll"].replace("lock-range: false", "")
    rb = fll.loads(text.replace("range: 0 10", "range: 0 10\n  lock-range: true"), "t.fll")
    assert rb.out_of_range == "clamp"  # a table clamps its inputs
    done = compile_rulebase(rb, "python", "double", method="auto", resolution=257)
    assert done.method == "table"
    module = load_module(done.files, rb.name)
    x = np.linspace(-1.0, 11.0, 997)
    got = np.array([module.eval([v])[0] for v in x])
    want = Engine(rb).evaluate({"x": x})["y"]
    assert done.table is not None
    assert np.max(np.abs(got - want)) <= done.table.bound[0] * (1 + 1e-9)
