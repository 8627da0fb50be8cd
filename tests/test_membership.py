"""Membership shapes against their formulas, written out here by hand at chosen points."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fuzzkit.fuzzy import membership
from fuzzkit.fuzzy.model import Term

CASES = [
    # shape, params, x, expected (worked by hand from the formula in the docstring)
    ("triangle", (0.0, 1.0, 3.0), 0.5, 0.5),
    ("triangle", (0.0, 1.0, 3.0), 2.0, 0.5),
    ("triangle", (0.0, 1.0, 3.0), 1.0, 1.0),
    ("triangle", (0.0, 1.0, 3.0), -0.1, 0.0),
    ("triangle", (0.0, 1.0, 3.0), 3.5, 0.0),
    ("triangle", (1.0, 1.0, 3.0), 1.0, 1.0),  # vertical left edge: the peak belongs to it
    ("triangle", (1.0, 1.0, 3.0), 0.999, 0.0),
    ("triangle", (1.0, 1.0, 3.0), 2.5, 0.25),
    ("triangle", (0.0, 2.0, 2.0), 1.5, 0.75),  # vertical right edge
    ("triangle", (0.0, 2.0, 2.0), 2.001, 0.0),
    ("trapezoid", (0.0, 1.0, 2.0, 4.0), 0.25, 0.25),
    ("trapezoid", (0.0, 1.0, 2.0, 4.0), 1.5, 1.0),
    ("trapezoid", (0.0, 1.0, 2.0, 4.0), 3.0, 0.5),
    ("trapezoid", (0.0, 1.0, 2.0, 4.0), 4.0, 0.0),
    ("left_shoulder", (-1.0, 1.0), -5.0, 1.0),
    ("left_shoulder", (-1.0, 1.0), 0.0, 0.5),
    ("left_shoulder", (-1.0, 1.0), 1.0, 0.0),
    ("right_shoulder", (-1.0, 1.0), 0.5, 0.75),
    ("right_shoulder", (-1.0, 1.0), 9.0, 1.0),
    ("right_shoulder", (-1.0, 1.0), -1.0, 0.0),
    ("gaussian", (1.0, 2.0), 1.0, 1.0),
    ("gaussian", (1.0, 2.0), 3.0, math.exp(-0.5)),
    ("gaussian", (1.0, 2.0), -3.0, math.exp(-2.0)),
    ("bell", (2.0, 1.5, 0.0), 0.0, 1.0),
    ("bell", (2.0, 1.5, 0.0), 2.0, 0.5),  # |x - c| = width gives 1/2 for any slope
    ("bell", (2.0, 1.5, 0.0), 4.0, 1.0 / (1.0 + 2.0**3)),
    ("sigmoid", (4.0, 1.0), 1.0, 0.5),
    ("sigmoid", (4.0, 1.0), 1.5, 1.0 / (1.0 + math.exp(-2.0))),
    ("sigmoid", (-4.0, 1.0), 1.5, 1.0 / (1.0 + math.exp(2.0))),
    ("singleton", (0.25,), 0.25, 1.0),
    ("singleton", (0.25,), 0.2500001, 0.0),
]


@pytest.mark.parametrize("shape, params, x, expected", CASES)
def test_shape_values(shape: str, params: tuple[float, ...], x: float, expected: float) -> None:
    got = float(membership.evaluate_term(Term("T", shape, params), x))
    assert got == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize("shape, params", sorted({(c[0], c[1]) for c in CASES}))
def test_nan_gives_nan_and_values_stay_in_unit_interval(
    shape: str, params: tuple[float, ...]
) -> None:
    term = Term("T", shape, params)
    x = np.array([np.nan, -1e300, -1e9, -1.0, 0.0, 1.0, 1e9, 1e300, np.inf, -np.inf])
    mu = membership.evaluate_term(term, x)
    assert np.isnan(mu[0])
    assert np.all((mu[1:] >= 0.0) & (mu[1:] <= 1.0))


@pytest.mark.parametrize(
    "params, low, high, expected",
    [
        (("triangle", (-1.3, -1.0, -0.7)), -1.0, 1.0, -1.0),
        (("trapezoid", (0.0, 0.2, 0.6, 1.0)), -1.0, 1.0, 0.4),
        (("left_shoulder", (-0.5, 0.0)), -1.0, 1.0, -0.75),
        (("right_shoulder", (0.0, 0.5)), -1.0, 1.0, 0.75),
        (("sigmoid", (-3.0, 0.0)), -1.0, 1.0, -1.0),
        (("gaussian", (2.0, 0.1)), -1.0, 1.0, 1.0),
    ],
)
def test_centre_is_midpoint_of_core_within_range(
    params: tuple[str, tuple[float, ...]], low: float, high: float, expected: float
) -> None:
    assert membership.centre(Term("T", *params), low, high) == pytest.approx(expected)
