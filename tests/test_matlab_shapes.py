"""The smooth MATLAB shapes (gauss2mf, smf, zmf, pimf, dsigmf, psigmf) against closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _mamdani_reference import mu as reference_mu
from _mamdani_reference import reference

from fuzzkit.formats.registry import loads
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
