"""Membership-function shapes, vectorised over numpy arrays.

Each function takes an array ``x`` and the shape's parameters and returns ``mu(x)`` in [0, 1]
with the same shape as ``x``. NaN in ``x`` gives NaN (the engine masks NaN inputs before it gets
here, so this only matters to direct callers). Parameters are assumed valid (see
``fuzzkit.fuzzy.validation``): ordered, finite, positive widths.

The piecewise-linear shapes (triangle, trapezoid, shoulders) are also available as a vertex list
(:func:`vertices`) from which the exact engine integrates in closed form.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import cast

import numpy as np
import numpy.typing as npt

from fuzzkit.fuzzy.model import Term

FloatArray = npt.NDArray[np.float64]

#: Slope standing in for a vertical edge (a == b); with inputs bounded by _XMAX no product
#: overflows, and the edge point itself has membership 1.
_VERTICAL = 1e200
_XMAX = 1e100


def _ramp_slope(lo: float, hi: float) -> float:
    """The slope of an edge from ``lo`` to ``hi``: ``1/(hi - lo)``, rounded so the foot is 0.

    A piecewise-linear membership is ``clip(1 + (x - peak) * slope, 0, 1)`` (and its mirror):
    exactly 1 at the peak. At the foot the product is ``-(hi - lo) * slope``, and the nearest
    double to ``1/(hi - lo)`` can round it to ``-(1 - 2**-53)``: a membership of 1e-16 where
    the term ends, so at a partition's label peak (its neighbours' foot) a rule fires that
    should not. There the next double up is taken (the product then rounds to at least 1,
    as the exact one is): the foot is exactly 0 in the engine and in the generated code that
    embeds the slope. Slopes whose foot was already exact are left as they are.
    """
    if hi <= lo:
        return _VERTICAL
    width = hi - lo  # the rounded difference that x - peak also gives at x = foot
    slope = 1.0 / width
    if width * slope < 1.0:
        slope = math.nextafter(slope, math.inf)
    return slope


def _trapezoid_core(x: FloatArray, b: float, c: float, s_rise: float, s_fall: float) -> FloatArray:
    # mu = clip(min(1 + (x - b) s_rise, 1 + (c - x) s_fall), 0, 1): one formula for all
    # piecewise-linear shapes; a shoulder has slope 0 on its open side.
    xs = np.clip(x, -_XMAX, _XMAX)
    with np.errstate(invalid="ignore"):
        rise = 1.0 + (xs - b) * s_rise
        fall = 1.0 + (c - xs) * s_fall
        return np.clip(np.minimum(rise, fall), 0.0, 1.0)


def triangle(x: FloatArray, a: float, b: float, c: float) -> FloatArray:
    """Triangle: 0 at ``a``, 1 at ``b``, 0 at ``c``.

    ``mu = max(0, min((x - a)/(b - a), (c - x)/(c - b)))``; ``a == b`` (or ``b == c``) makes a
    vertical edge with ``mu(b) = 1``.
    """
    return _trapezoid_core(x, b, b, _ramp_slope(a, b), _ramp_slope(b, c))


def trapezoid(x: FloatArray, a: float, b: float, c: float, d: float) -> FloatArray:
    """Trapezoid: rises from ``a`` to 1 at ``b``, stays 1 to ``c``, falls to 0 at ``d``.

    ``mu = max(0, min((x - a)/(b - a), 1, (d - x)/(d - c)))``.
    """
    return _trapezoid_core(x, b, c, _ramp_slope(a, b), _ramp_slope(c, d))


def left_shoulder(x: FloatArray, a: float, b: float) -> FloatArray:
    """Left shoulder: 1 for ``x <= a``, falls linearly to 0 at ``b``, 0 beyond.

    ``mu = clip((b - x)/(b - a), 0, 1)``.
    """
    return _trapezoid_core(x, 0.0, a, 0.0, _ramp_slope(a, b))


def right_shoulder(x: FloatArray, a: float, b: float) -> FloatArray:
    """Right shoulder: 0 for ``x <= a``, rises linearly to 1 at ``b``, 1 beyond.

    ``mu = clip((x - a)/(b - a), 0, 1)``.
    """
    return _trapezoid_core(x, b, 0.0, _ramp_slope(a, b), 0.0)


def gaussian(x: FloatArray, mean: float, sigma: float) -> FloatArray:
    """Gaussian: ``mu = exp(-(x - mean)^2 / (2 sigma^2))``."""
    xs = np.clip(x, -_XMAX, _XMAX)
    with np.errstate(over="ignore", under="ignore"):
        return np.exp(-0.5 * ((xs - mean) / sigma) ** 2)


def bell(x: FloatArray, width: float, slope: float, centre: float) -> FloatArray:
    """Generalised bell: ``mu = 1 / (1 + |(x - centre)/width|^(2 slope))``."""
    xs = np.clip(x, -_XMAX, _XMAX)
    with np.errstate(over="ignore", under="ignore"):
        return 1.0 / (1.0 + np.abs((xs - centre) / width) ** (2.0 * slope))


def sigmoid(x: FloatArray, slope: float, centre: float) -> FloatArray:
    """Sigmoid: ``mu = 1 / (1 + exp(-slope (x - centre)))``; opens right for slope > 0."""
    xs = np.clip(x, -_XMAX, _XMAX)
    with np.errstate(over="ignore", under="ignore"):
        return 1.0 / (1.0 + np.exp(-slope * (xs - centre)))


def singleton(x: FloatArray, value: float) -> FloatArray:
    """Singleton: ``mu = 1`` where ``x == value``, else 0 (NaN stays NaN)."""
    out = np.where(np.isnan(x), np.nan, (x == value).astype(np.float64))
    return cast(FloatArray, out)


def _keep_nan(x: FloatArray, mu: FloatArray) -> FloatArray:
    return cast(FloatArray, np.where(np.isnan(x), np.nan, mu))


def gaussian_product(
    x: FloatArray, mean1: float, sigma1: float, mean2: float, sigma2: float
) -> FloatArray:
    """Two-sided gaussian (MATLAB ``gauss2mf``, fuzzylite ``GaussianProduct``).

    ``mu = f1 * f2`` with ``f1 = exp(-(x - mean1)^2 / (2 sigma1^2))`` for ``x < mean1`` (else 1)
    and ``f2 = exp(-(x - mean2)^2 / (2 sigma2^2))`` for ``x > mean2`` (else 1): a plateau of 1
    on ``[mean1, mean2]`` when ``mean1 <= mean2``, a peak below 1 otherwise. NaN gives NaN.
    """
    xs = np.clip(x, -_XMAX, _XMAX)
    with np.errstate(over="ignore", under="ignore", invalid="ignore"):
        f1 = np.where(xs < mean1, np.exp(-0.5 * ((xs - mean1) / sigma1) ** 2), 1.0)
        f2 = np.where(xs > mean2, np.exp(-0.5 * ((xs - mean2) / sigma2) ** 2), 1.0)
    return _keep_nan(x, f1 * f2)


def s_shape(x: FloatArray, start: float, end: float) -> FloatArray:
    """S-shaped spline (MATLAB ``smf``, fuzzylite ``SShape``), 0 before ``start``, 1 after ``end``.

    With ``m = (start + end)/2`` and ``w = end - start``: ``mu = 2 ((x - start)/w)^2`` on
    ``[start, m]``, ``1 - 2 ((x - end)/w)^2`` on ``[m, end]``. NaN gives NaN.
    """
    xs = np.clip(x, -_XMAX, _XMAX)
    w = end - start
    mid = 0.5 * (start + end)
    with np.errstate(over="ignore", invalid="ignore"):
        rising = np.where(
            xs <= mid, 2.0 * ((xs - start) / w) ** 2, 1.0 - 2.0 * ((xs - end) / w) ** 2
        )
        mu = np.where(xs <= start, 0.0, np.where(xs >= end, 1.0, rising))
    return _keep_nan(x, mu)


def z_shape(x: FloatArray, start: float, end: float) -> FloatArray:
    """Z-shaped spline (MATLAB ``zmf``, fuzzylite ``ZShape``), 1 before ``start``, 0 after ``end``.

    ``mu = 1 - s_shape(x, start, end)``: ``1 - 2 ((x - start)/w)^2`` on ``[start, m]``,
    ``2 ((x - end)/w)^2`` on ``[m, end]``. NaN gives NaN.
    """
    return 1.0 - s_shape(x, start, end)


def pi_shape(x: FloatArray, a: float, b: float, c: float, d: float) -> FloatArray:
    """Pi-shaped spline (MATLAB ``pimf``, fuzzylite ``PiShape``).

    ``mu = s_shape(x, a, b) * z_shape(x, c, d)``: rises from 0 at ``a`` to 1 at ``b``, stays 1
    to ``c``, falls to 0 at ``d``. NaN gives NaN.
    """
    return s_shape(x, a, b) * z_shape(x, c, d)


def sigmoid_difference(
    x: FloatArray, slope1: float, centre1: float, slope2: float, centre2: float
) -> FloatArray:
    """Difference of two sigmoids (MATLAB ``dsigmf``, fuzzylite ``SigmoidDifference``).

    ``mu = |sigmoid(x, slope1, centre1) - sigmoid(x, slope2, centre2)|``. NaN gives NaN.
    """
    return cast(FloatArray, np.abs(sigmoid(x, slope1, centre1) - sigmoid(x, slope2, centre2)))


def sigmoid_product(
    x: FloatArray, slope1: float, centre1: float, slope2: float, centre2: float
) -> FloatArray:
    """Product of two sigmoids (MATLAB ``psigmf``, fuzzylite ``SigmoidProduct``).

    ``mu = sigmoid(x, slope1, centre1) * sigmoid(x, slope2, centre2)``. NaN gives NaN.
    """
    return sigmoid(x, slope1, centre1) * sigmoid(x, slope2, centre2)


SHAPES: dict[str, Callable[..., FloatArray]] = {
    "triangle": triangle,
    "trapezoid": trapezoid,
    "left_shoulder": left_shoulder,
    "right_shoulder": right_shoulder,
    "gaussian": gaussian,
    "bell": bell,
    "sigmoid": sigmoid,
    "singleton": singleton,
    "gaussian_product": gaussian_product,
    "s_shape": s_shape,
    "z_shape": z_shape,
    "pi_shape": pi_shape,
    "sigmoid_difference": sigmoid_difference,
    "sigmoid_product": sigmoid_product,
}


def evaluate_term(term: Term, x: npt.ArrayLike) -> FloatArray:
    """Membership of ``x`` (any shape) in ``term``.

    Raises
    ------
    ValueError
        For a Sugeno term (``constant``, ``linear``): it is an output value, not a membership
        function (see :func:`sugeno_value`).
    """
    if term.is_sugeno:
        raise ValueError(
            f"term {term.name!r}: {term.shape} is a Sugeno output term, not a membership function"
        )
    return SHAPES[term.shape](np.asarray(x, dtype=np.float64), *term.params)


def sugeno_value(term: Term, inputs: Sequence[FloatArray]) -> FloatArray:
    """The output value of a Sugeno term at the given input values (arrays of one shape).

    ``constant``: its value everywhere. ``linear``: ``c_1 x_1 + ... + c_n x_n + constant`` with
    ``inputs`` in the rule base's input order. NaN in a used input gives NaN.
    """
    if term.shape == "constant":
        return np.full(np.shape(inputs[0]) if inputs else (), term.params[0])
    if term.shape == "linear":
        z = np.full(np.shape(inputs[0]) if inputs else (), term.params[-1])
        for c, x in zip(term.params[:-1], inputs, strict=True):
            if c != 0.0:
                z = z + c * x
        return z
    raise ValueError(f"term {term.name!r}: shape {term.shape!r} is not a Sugeno term")


def trapezoid_form(term: Term) -> tuple[float, float, float, float]:
    """A piecewise-linear term as ``(core_start, core_end, rise_slope, fall_slope)``.

    ``mu = clip(min(1 + (x - core_start) rise, 1 + (core_end - x) fall), 0, 1)``; a shoulder's
    open side has slope 0. This is how the engine fuzzifies all piecewise-linear terms at once.
    """
    p = term.params
    if term.shape == "triangle":
        return p[1], p[1], _ramp_slope(p[0], p[1]), _ramp_slope(p[1], p[2])
    if term.shape == "trapezoid":
        return p[1], p[2], _ramp_slope(p[0], p[1]), _ramp_slope(p[2], p[3])
    if term.shape == "left_shoulder":
        return 0.0, p[0], 0.0, _ramp_slope(p[0], p[1])
    if term.shape == "right_shoulder":
        return p[1], 0.0, _ramp_slope(p[0], p[1]), 0.0
    raise ValueError(f"term {term.name!r}: shape {term.shape!r} is not piecewise linear")


def breakpoints(term: Term) -> tuple[float, ...]:
    """The x positions where a piecewise-linear term changes slope (its vertices)."""
    if not term.is_piecewise_linear:
        raise ValueError(f"term {term.name!r}: shape {term.shape!r} is not piecewise linear")
    return tuple(term.params)


def centre(term: Term, low: float, high: float) -> float:
    """Representative value of a term for the weighted-average defuzzifier (paper eq. 10).

    The midpoint of the set of points of ``[low, high]`` where the term reaches its largest
    membership: the peak of a triangle, the middle of a trapezoid's core, the middle of a
    shoulder's core within the range, the mean of a gaussian or bell (clamped to the range),
    the range end a sigmoid opens towards, a singleton's value. The smooth MATLAB shapes follow
    the same rule (the difference and product of sigmoids on a grid of 65537 points).
    """
    p = term.params
    if term.shape == "triangle":
        return float(np.clip(p[1], low, high))
    if term.shape == "trapezoid":
        lo, hi = max(p[1], low), min(p[2], high)
        return (lo + hi) / 2 if lo <= hi else float(np.clip((p[1] + p[2]) / 2, low, high))
    if term.shape == "left_shoulder":
        return (low + float(np.clip(p[0], low, high))) / 2
    if term.shape == "right_shoulder":
        return (float(np.clip(p[1], low, high)) + high) / 2
    if term.shape == "gaussian":
        return float(np.clip(p[0], low, high))
    if term.shape == "bell":
        return float(np.clip(p[2], low, high))
    if term.shape == "sigmoid":
        return high if p[0] > 0 else low
    if term.shape == "s_shape":
        return (float(np.clip(p[1], low, high)) + high) / 2
    if term.shape == "z_shape":
        return (low + float(np.clip(p[0], low, high))) / 2
    if term.shape == "pi_shape":
        lo, hi = max(p[1], low), min(p[2], high)
        return (lo + hi) / 2 if lo <= hi else float(np.clip((p[1] + p[2]) / 2, low, high))
    if term.shape == "gaussian_product":
        m1, s1, m2, s2 = p
        if m1 <= m2:
            lo, hi = max(m1, low), min(m2, high)
            return (lo + hi) / 2 if lo <= hi else float(np.clip((m1 + m2) / 2, low, high))
        # the two tails overlap: their product is a gaussian with this mean
        return float(np.clip((m1 * s2**2 + m2 * s1**2) / (s1**2 + s2**2), low, high))
    if term.shape in ("sigmoid_difference", "sigmoid_product"):
        # no closed form for the maximum in general: a grid of 2^16 + 1 points
        grid = np.linspace(low, high, 65537)
        mu = evaluate_term(term, grid)
        at_max = grid[mu >= mu.max() - 1e-12]
        return float(0.5 * (at_max[0] + at_max[-1]))
    return float(p[0])  # singleton
