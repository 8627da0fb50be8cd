"""The membership-shape registry: everything fuzzkit knows about each shape, in one record.

A :class:`Shape` holds a shape's parameters (their names and order), its membership formula
(the function's docstring states it and what NaN does), its parameter checks, its support
(where it is above zero, exactly), its centre (what the weighted-average defuzzifier uses), its
piecewise-linear form if it has one, how MATLAB (``.fis``), fuzzylite (``.fll`` and the named
FCL dialect) and jFuzzyLogic (FCL) spell it, and how the exact code generator fuzzifies it.
The model, the engine, the validation, the readers and writers of every format, the plots and
the code generators all read this table; a shape that is not in it raises
:class:`UnknownShapeError` wherever it turns up (validation reports it as a problem instead).

Adding a shape is one new record in ``_ENTRIES`` below (and its tests): see
``docs/rulebase-format.md``, "Adding a membership shape". That is why this module is longer
than most (about 850 lines): every fact about every shape is here, and nowhere else.

Membership functions take an array ``x`` and the shape's parameters and return ``mu(x)`` in
[0, 1] with the shape of ``x``. NaN in ``x`` gives NaN (the engine masks NaN inputs before it
gets here, so this only matters to direct callers). Parameters are assumed valid (see
:attr:`Shape.check`): ordered, finite, positive widths.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from itertools import pairwise
from typing import TypeAlias, cast

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
Params: TypeAlias = tuple[float, ...]
#: A piece of a term's support: (low, low included, high, high included).
Piece: TypeAlias = tuple[float, bool, float, bool]
#: A parameter problem: (the document key it belongs to, the message).
ParamIssue: TypeAlias = tuple[str, str]
#: A feature of a term: (how to say it, with ``{}`` for its size; its size).
Feature: TypeAlias = tuple[str, float]

#: Slope standing in for a vertical edge (a == b); with inputs bounded by _XMAX no product
#: overflows, and the edge point itself has membership 1.
_VERTICAL = 1e200
_XMAX = 1e100
_INF = math.inf


class UnknownShapeError(ValueError):
    """A term names a shape that is not in the registry (a model built without validation)."""


# ---------------------------------------------------------------------------- spellings


@dataclass(frozen=True, slots=True)
class Spelling:
    """How a file format writes a shape: its name there and what each parameter holds.

    ``layout`` has one entry per parameter in the file: a parameter name of the shape, or a
    constant the format writes in that place (``"-inf"``, ``"inf"``); ``("*",)`` means all the
    shape's parameters in fuzzkit's order, however many (Sugeno ``linear``). ``condition``
    (with ``condition_text`` saying it) limits which files mean the shape.
    """

    name: str
    layout: tuple[str, ...]
    condition: Callable[[Params], bool] | None = None
    condition_text: str = ""

    @property
    def arity(self) -> int | None:
        """The number of parameters in the file (None: as many as the shape has)."""
        return None if self.layout == ("*",) else len(self.layout)

    def write(self, names: Sequence[str], params: Params) -> Params:
        """The file's parameters for a term with ``params`` (named ``names``)."""
        if self.layout == ("*",):
            return params
        return tuple(
            params[names.index(item)] if item in names else float(item) for item in self.layout
        )

    def read(self, names: Sequence[str], values: Sequence[float]) -> Params | None:
        """The shape's parameters from the file's ``values``; None when a constant differs."""
        if self.layout == ("*",):
            return tuple(values)
        for item, v in zip(self.layout, values, strict=True):
            if item not in names and v != float(item):
                return None
        by_name = {item: v for item, v in zip(self.layout, values, strict=True) if item in names}
        return tuple(by_name[n] for n in names)


def _sp(
    name: str,
    layout: str,
    condition: Callable[[Params], bool] | None = None,
    condition_text: str = "",
) -> Spelling:
    return Spelling(name, tuple(layout.split()), condition, condition_text)


@dataclass(frozen=True, slots=True)
class ExactForm:
    """How the exact code generator fuzzifies an input term of this shape.

    ``kind`` is the template branch (``linear``: the trapezoid form ``(b, c, rise, fall)``;
    ``gaussian``: ``(mean, sigma)``; ``bell``: ``(centre, width, 2 slope)``; ``sigmoid``:
    ``(slope, centre)``; ``singleton``: ``(value,)``; ``gaussian_product``: its parameters;
    ``s_shape`` and ``z_shape``: ``(start, end, end - start, midpoint)``, the differences the
    engine's formula takes; ``pi_shape``: those of its rising and of its falling half;
    ``sigmoid_difference`` and ``sigmoid_product``: their parameters), ``constants`` the
    numbers it needs and ``libm`` the C functions it calls. Each template branch computes the
    engine's formula (the shape's function here) operation for operation.
    """

    kind: str
    constants: Callable[[Params], Params]
    libm: tuple[str, ...] = ()


# ---------------------------------------------------------------------------- the record


@dataclass(frozen=True, slots=True)
class Shape:
    """One membership shape (or Sugeno output term): everything every part of fuzzkit needs.

    ``check`` returns the problems of finite parameters of the right count (count and
    finiteness are checked for every shape alike). ``trapezoid`` is the piecewise-linear form
    ``(core_start, core_end, rise, fall)`` (None for a smooth shape); ``points`` the same as a
    point list, constant beyond its ends. ``fis``, ``fll`` and ``fcl`` list the spellings each
    format reads, the first being the one written (``fcl`` holds jFuzzyLogic's names, read
    only: fuzzkit's FCL writes fuzzylite's names, ``fll``). ``exact`` is None when the exact
    code generator cannot fuzzify the shape (``--method table`` can). ``impulse`` marks a
    shape without area (a singleton). ``span`` says where a term lies on its axis, for an FCL
    variable without ``RANGE`` (None: no such place, as for a difference of sigmoids).
    ``features`` lists the sizes the engines must resolve (distances between points, widths,
    inverse slopes) with how to say each, for :mod:`fuzzkit.fuzzy.resolution`.
    """

    name: str
    params: tuple[str, ...]
    mu: Callable[..., FloatArray] | None
    check: Callable[[Params], list[ParamIssue]]
    support: Callable[[Params], list[Piece]]
    centre: Callable[[Params, float, float], float] | None
    trapezoid: Callable[[Params], tuple[float, float, float, float]] | None = None
    points: Callable[[Params], list[tuple[float, float]]] | None = None
    fis: tuple[Spelling, ...] = ()
    fll: tuple[Spelling, ...] = ()
    fcl: tuple[Spelling, ...] = ()
    exact: ExactForm | None = None
    sugeno: bool = False
    impulse: bool = False
    span: Callable[[Params], tuple[float, float] | None] | None = None
    features: Callable[[Params], list[Feature]] = lambda p: []

    @property
    def piecewise_linear(self) -> bool:
        return self.trapezoid is not None

    def evaluate(self, x: npt.ArrayLike, params: Params) -> FloatArray:
        """``mu(x)`` for a term of this shape with ``params``."""
        if self.mu is None:
            raise ValueError(f"{self.name} is a Sugeno output term, not a membership function")
        return self.mu(np.asarray(x, dtype=np.float64), *params)


# ---------------------------------------------------------------------------- formulas


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


def _keep_nan(x: FloatArray, mu: FloatArray) -> FloatArray:
    return cast(FloatArray, np.where(np.isnan(x), np.nan, mu))


def triangle(x: FloatArray, a: float, b: float, c: float) -> FloatArray:
    """Triangle: 0 at ``a``, 1 at ``b``, 0 at ``c``.

    ``mu = max(0, min((x - a)/(b - a), (c - x)/(c - b)))``; ``a == b`` (or ``b == c``) makes a
    vertical edge with ``mu(b) = 1``. NaN gives NaN.
    """
    return _trapezoid_core(x, b, b, _ramp_slope(a, b), _ramp_slope(b, c))


def trapezoid(x: FloatArray, a: float, b: float, c: float, d: float) -> FloatArray:
    """Trapezoid: rises from ``a`` to 1 at ``b``, stays 1 to ``c``, falls to 0 at ``d``.

    ``mu = max(0, min((x - a)/(b - a), 1, (d - x)/(d - c)))``. NaN gives NaN.
    """
    return _trapezoid_core(x, b, c, _ramp_slope(a, b), _ramp_slope(c, d))


def left_shoulder(x: FloatArray, a: float, b: float) -> FloatArray:
    """Left shoulder: 1 for ``x <= a``, falls linearly to 0 at ``b``, 0 beyond.

    ``mu = clip((b - x)/(b - a), 0, 1)``. NaN gives NaN.
    """
    return _trapezoid_core(x, 0.0, a, 0.0, _ramp_slope(a, b))


def right_shoulder(x: FloatArray, a: float, b: float) -> FloatArray:
    """Right shoulder: 0 for ``x <= a``, rises linearly to 1 at ``b``, 1 beyond.

    ``mu = clip((x - a)/(b - a), 0, 1)``. NaN gives NaN.
    """
    return _trapezoid_core(x, b, 0.0, _ramp_slope(a, b), 0.0)


def gaussian(x: FloatArray, mean: float, sigma: float) -> FloatArray:
    """Gaussian: ``mu = exp(-(x - mean)^2 / (2 sigma^2))``. NaN gives NaN."""
    xs = np.clip(x, -_XMAX, _XMAX)
    with np.errstate(over="ignore", under="ignore"):
        return np.exp(-0.5 * ((xs - mean) / sigma) ** 2)


def bell(x: FloatArray, width: float, slope: float, centre: float) -> FloatArray:
    """Generalised bell: ``mu = 1 / (1 + |(x - centre)/width|^(2 slope))``. NaN gives NaN."""
    xs = np.clip(x, -_XMAX, _XMAX)
    with np.errstate(over="ignore", under="ignore"):
        return 1.0 / (1.0 + np.abs((xs - centre) / width) ** (2.0 * slope))


def sigmoid(x: FloatArray, slope: float, centre: float) -> FloatArray:
    """Sigmoid: ``mu = 1 / (1 + exp(-slope (x - centre)))``; opens right for slope > 0.

    NaN gives NaN.
    """
    xs = np.clip(x, -_XMAX, _XMAX)
    with np.errstate(over="ignore", under="ignore"):
        return 1.0 / (1.0 + np.exp(-slope * (xs - centre)))


def singleton(x: FloatArray, value: float) -> FloatArray:
    """Singleton: ``mu = 1`` where ``x == value``, else 0. NaN gives NaN."""
    out = np.where(np.isnan(x), np.nan, (x == value).astype(np.float64))
    return cast(FloatArray, out)


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


# ---------------------------------------------------------------------------- checks


def _fmt(v: float) -> str:
    return repr(float(v))


def _fmt_list(values: Sequence[float]) -> str:
    return "[" + ", ".join(_fmt(v) for v in values) + "]"


def _check_triangle(p: Params) -> list[ParamIssue]:
    a, b, c = p
    if not a <= b <= c:
        return [("points", f"triangle points must be ordered a <= b <= c, got {_fmt_list(p)}")]
    if not a < c:
        return [
            (
                "points",
                f"triangle is degenerate (a == c), got {_fmt_list(p)}; "
                "use a singleton for a single point",
            )
        ]
    return []


def _check_trapezoid(p: Params) -> list[ParamIssue]:
    a, b, c, d = p
    if not a <= b <= c <= d:
        return [
            ("points", f"trapezoid points must be ordered a <= b <= c <= d, got {_fmt_list(p)}")
        ]
    if not a < d:
        return [("points", f"trapezoid is degenerate (a == d), got {_fmt_list(p)}")]
    return []


def _check_ordered_pair(shape: str, key: str, names: str) -> Callable[[Params], list[ParamIssue]]:
    def check(p: Params) -> list[ParamIssue]:
        if not p[0] < p[1]:
            what = "points must be ordered" if key == "points" else "needs"
            return [(key, f"{shape} {what} {names}, got {_fmt_list(p)}")]
        return []

    return check


def _check_positive(shape: str, *names: str) -> Callable[[Params], list[ParamIssue]]:
    def check(p: Params) -> list[ParamIssue]:
        params = REGISTRY[shape].params
        return [
            (n, f"{shape} {n} must be > 0, got {_fmt(p[params.index(n)])}")
            for n in names
            if not p[params.index(n)] > 0
        ]

    return check


def _check_nonzero(shape: str, *names: str) -> Callable[[Params], list[ParamIssue]]:
    def check(p: Params) -> list[ParamIssue]:
        params = REGISTRY[shape].params
        return [
            (n, f"{shape} {n} must be non-zero, got 0.0") for n in names if p[params.index(n)] == 0
        ]

    return check


def _check_pi(p: Params) -> list[ParamIssue]:
    if not (p[0] < p[1] and p[2] < p[3]):
        return [("a", f"pi_shape needs a < b and c < d, got {_fmt_list(p)}")]
    return []


def _no_check(p: Params) -> list[ParamIssue]:
    return []


# ---------------------------------------------------------------------------- supports


def _everywhere(p: Params) -> list[Piece]:
    # gaussian, bell, sigmoid, gaussian_product, sigmoid_product: > 0 everywhere
    return [(-_INF, False, _INF, False)]


def _nowhere(p: Params) -> list[Piece]:
    return []


def _support_sigmoid_difference(p: Params) -> list[Piece]:
    a1, c1, a2, c2 = p
    if a1 == a2:
        return [] if c1 == c2 else [(-_INF, False, _INF, False)]
    x0 = (a1 * c1 - a2 * c2) / (a1 - a2)  # where the two sigmoids are equal
    return [(-_INF, False, x0, False), (x0, False, _INF, False)]


# ---------------------------------------------------------------------------- centres


def _clip(v: float, low: float, high: float) -> float:
    return float(np.clip(v, low, high))


def _core_middle(b: float, c: float, low: float, high: float) -> float:
    """The middle of the core ``[b, c]`` within ``[low, high]`` (of ``[b, c]`` clipped if none)."""
    lo, hi = max(b, low), min(c, high)
    return (lo + hi) / 2 if lo <= hi else _clip((b + c) / 2, low, high)


def _centre_gaussian_product(p: Params, low: float, high: float) -> float:
    m1, s1, m2, s2 = p
    if m1 <= m2:
        return _core_middle(m1, m2, low, high)
    # the two tails overlap: their product is a gaussian with this mean
    return _clip((m1 * s2**2 + m2 * s1**2) / (s1**2 + s2**2), low, high)


def _centre_on_grid(mu_of: Callable[..., FloatArray]) -> Callable[[Params, float, float], float]:
    def centre(p: Params, low: float, high: float) -> float:
        # no closed form for the maximum in general: a grid of 2^16 + 1 points
        grid = np.linspace(low, high, 65537)
        mu = mu_of(grid, *p)
        at_max = grid[mu >= mu.max() - 1e-12]
        return float(0.5 * (at_max[0] + at_max[-1]))

    return centre


# ---------------------------------------------------------------------------- spans
#
# Where a term lies on its axis (an FCL variable without RANGE spans its terms). Smooth shapes
# have no ends: jFuzzyLogic's estimates of where the membership is negligible are used.


def _param_span(p: Params) -> tuple[float, float]:
    """Parameters that are all positions on the axis span themselves."""
    return min(p), max(p)


def _around(centre: float, half: float | None) -> tuple[float, float] | None:
    if half is None or not math.isfinite(half):
        return None
    return centre - half, centre + half


def _span_gaussian_product(p: Params) -> tuple[float, float]:
    # both halves of the two-sided gaussian, mean -+ 4 sigma beyond each
    return min(p[0] - 4.0 * abs(p[1]), p[2]), max(p[0], p[2] + 4.0 * abs(p[3]))


def _span_bell(p: Params) -> tuple[float, float] | None:
    # 1/(1 + |d/width|^(2 slope)) falls to 0.001 at |d| = width * 999^(1/(2 slope))
    return _around(p[2], abs(p[0]) * 999.0 ** (1.0 / (2.0 * p[1])) if p[1] > 0 else None)


# ---------------------------------------------------------------------------- features
#
# The sizes the engines must resolve beside the range width (fuzzkit.fuzzy.resolution).


def _g(x: float) -> str:
    return f"{x:.6g}"


def _point_gaps(p: Params) -> list[Feature]:
    return [(f"points {_g(a)} and {_g(b)} are {{}} apart", b - a) for a, b in pairwise(p) if b > a]


def _widths(*index: int) -> Callable[[Params], list[Feature]]:
    return lambda p: [("its width is {}", p[i]) for i in index]


def _slopes(*index: int) -> Callable[[Params], list[Feature]]:
    return lambda p: [(f"its slope {_g(p[i])} makes it {{}} wide", 1.0 / abs(p[i])) for i in index]


def _spans(*pairs: tuple[int, int]) -> Callable[[Params], list[Feature]]:
    return lambda p: [(f"its span {_g(p[i])} .. {_g(p[j])} is {{}}", p[j] - p[i]) for i, j in pairs]


# ---------------------------------------------------------------------------- exact forms


def _triangle_form(p: Params) -> tuple[float, float, float, float]:
    return p[1], p[1], _ramp_slope(p[0], p[1]), _ramp_slope(p[1], p[2])


def _trapezoid_form(p: Params) -> tuple[float, float, float, float]:
    return p[1], p[2], _ramp_slope(p[0], p[1]), _ramp_slope(p[2], p[3])


def _left_form(p: Params) -> tuple[float, float, float, float]:
    return 0.0, p[0], 0.0, _ramp_slope(p[0], p[1])


def _right_form(p: Params) -> tuple[float, float, float, float]:
    return p[1], 0.0, _ramp_slope(p[0], p[1]), 0.0


def _linear(form: Callable[[Params], tuple[float, float, float, float]]) -> ExactForm:
    return ExactForm("linear", form)


def _same(p: Params) -> Params:
    return p


def _spline(start: float, end: float) -> Params:
    """An S/Z spline's constants as :func:`s_shape` computes them: ends, width, midpoint."""
    return (start, end, end - start, 0.5 * (start + end))


# ---------------------------------------------------------------------------- the registry


def _gauss2_ordered(p: Params) -> bool:
    return p[0] <= p[2]


_ENTRIES = (
    Shape(
        "triangle",
        ("a", "b", "c"),
        triangle,
        _check_triangle,
        lambda p: [(p[0], p[0] == p[1], p[2], p[1] == p[2])],
        lambda p, lo, hi: _clip(p[1], lo, hi),
        trapezoid=_triangle_form,
        points=lambda p: [(p[0], 0.0), (p[1], 1.0), (p[2], 0.0)],
        fis=(_sp("trimf", "a b c"),),
        fll=(_sp("Triangle", "a b c"),),
        fcl=(_sp("TRIAN", "a b c"),),
        exact=_linear(_triangle_form),
        span=_param_span,
        features=_point_gaps,
    ),
    Shape(
        "trapezoid",
        ("a", "b", "c", "d"),
        trapezoid,
        _check_trapezoid,
        lambda p: [(p[0], p[0] == p[1], p[3], p[2] == p[3])],
        lambda p, lo, hi: _core_middle(p[1], p[2], lo, hi),
        trapezoid=_trapezoid_form,
        points=lambda p: [(p[0], 0.0), (p[1], 1.0), (p[2], 1.0), (p[3], 0.0)],
        fis=(_sp("trapmf", "a b c d"),),
        fll=(_sp("Trapezoid", "a b c d"),),
        fcl=(_sp("TRAPE", "a b c d"),),
        exact=_linear(_trapezoid_form),
        span=_param_span,
        features=_point_gaps,
    ),
    Shape(
        "left_shoulder",
        ("a", "b"),
        left_shoulder,
        _check_ordered_pair("left_shoulder", "points", "a < b"),
        lambda p: [(-_INF, False, p[1], False)],
        lambda p, lo, hi: (lo + _clip(p[0], lo, hi)) / 2,
        trapezoid=_left_form,
        points=lambda p: [(p[0], 1.0), (p[1], 0.0)],
        # MATLAB's and fuzzylite's trapezoid formulas give exactly this with -inf feet
        fis=(_sp("trapmf", "-inf -inf a b"), _sp("linzmf", "a b"), _sp("rampmf", "b a")),
        fll=(_sp("Ramp", "b a"), _sp("Trapezoid", "-inf -inf a b")),
        fcl=(_sp("TRAPE", "-inf -inf a b"),),
        exact=_linear(_left_form),
        span=_param_span,
        features=_point_gaps,
    ),
    Shape(
        "right_shoulder",
        ("a", "b"),
        right_shoulder,
        _check_ordered_pair("right_shoulder", "points", "a < b"),
        lambda p: [(p[0], False, _INF, False)],
        lambda p, lo, hi: (_clip(p[1], lo, hi) + hi) / 2,
        trapezoid=_right_form,
        points=lambda p: [(p[0], 0.0), (p[1], 1.0)],
        fis=(_sp("trapmf", "a b inf inf"), _sp("linsmf", "a b"), _sp("rampmf", "a b")),
        fll=(_sp("Ramp", "a b"), _sp("Trapezoid", "a b inf inf")),
        fcl=(_sp("TRAPE", "a b inf inf"),),
        exact=_linear(_right_form),
        span=_param_span,
        features=_point_gaps,
    ),
    Shape(
        "gaussian",
        ("mean", "sigma"),
        gaussian,
        _check_positive("gaussian", "sigma"),
        _everywhere,
        lambda p, lo, hi: _clip(p[0], lo, hi),
        fis=(_sp("gaussmf", "sigma mean"),),
        fll=(_sp("Gaussian", "mean sigma"),),
        fcl=(_sp("GAUSS", "mean sigma"),),
        exact=ExactForm("gaussian", _same, ("exp",)),
        span=lambda p: _around(p[0], 4.0 * abs(p[1])),
        features=_widths(1),
    ),
    Shape(
        "bell",
        ("width", "slope", "centre"),
        bell,
        _check_positive("bell", "width", "slope"),
        _everywhere,
        lambda p, lo, hi: _clip(p[2], lo, hi),
        fis=(_sp("gbellmf", "width slope centre"),),
        fll=(_sp("Bell", "centre width slope"),),
        fcl=(_sp("GBELL", "width slope centre"),),
        exact=ExactForm("bell", lambda p: (p[2], p[0], 2.0 * p[1]), ("pow", "fabs")),
        span=_span_bell,
        features=_widths(0),
    ),
    Shape(
        "sigmoid",
        ("slope", "centre"),
        sigmoid,
        _check_nonzero("sigmoid", "slope"),
        _everywhere,
        lambda p, lo, hi: hi if p[0] > 0 else lo,  # the range end it opens towards
        fis=(_sp("sigmf", "slope centre"),),
        fll=(_sp("Sigmoid", "centre slope"),),
        fcl=(_sp("SIGM", "slope centre"),),
        exact=ExactForm("sigmoid", _same, ("exp",)),
        span=lambda p: _around(p[1], 9.0 / abs(p[0]) if p[0] != 0 else None),
        features=_slopes(0),
    ),
    Shape(
        "singleton",
        ("value",),
        singleton,
        _no_check,
        lambda p: [(p[0], True, p[0], True)],
        lambda p, lo, hi: p[0],
        exact=ExactForm("singleton", _same),
        impulse=True,
        span=_param_span,
    ),
    # Smooth shapes as in MATLAB's Fuzzy Logic Toolbox and fuzzylite.
    Shape(
        "gaussian_product",
        ("mean1", "sigma1", "mean2", "sigma2"),
        gaussian_product,
        _check_positive("gaussian_product", "sigma1", "sigma2"),
        _everywhere,
        _centre_gaussian_product,
        fis=(_sp("gauss2mf", "sigma1 mean1 sigma2 mean2"),),
        fll=(_sp("GaussianProduct", "mean1 sigma1 mean2 sigma2"),),
        # jFuzzyLogic refuses mean1 > mean2; up to there its GAUSS2 is this shape
        fcl=(
            _sp(
                "GAUSS2",
                "mean1 sigma1 mean2 sigma2",
                condition=_gauss2_ordered,
                condition_text="GAUSS2 needs mean1 <= mean2 (jFuzzyLogic)",
            ),
        ),
        exact=ExactForm("gaussian_product", _same, ("exp",)),
        span=_span_gaussian_product,
        features=_widths(1, 3),
    ),
    Shape(
        "s_shape",
        ("start", "end"),
        s_shape,
        _check_ordered_pair("s_shape", "start", "start < end"),
        lambda p: [(p[0], False, _INF, False)],
        lambda p, lo, hi: (_clip(p[1], lo, hi) + hi) / 2,
        fis=(_sp("smf", "start end"),),
        fll=(_sp("SShape", "start end"),),
        exact=ExactForm("s_shape", lambda p: _spline(p[0], p[1])),
        span=_param_span,
        features=_spans((0, 1)),
    ),
    Shape(
        "z_shape",
        ("start", "end"),
        z_shape,
        _check_ordered_pair("z_shape", "start", "start < end"),
        lambda p: [(-_INF, False, p[1], False)],
        lambda p, lo, hi: (lo + _clip(p[0], lo, hi)) / 2,
        fis=(_sp("zmf", "start end"),),
        fll=(_sp("ZShape", "start end"),),
        exact=ExactForm("z_shape", lambda p: _spline(p[0], p[1])),
        span=_param_span,
        features=_spans((0, 1)),
    ),
    Shape(
        "pi_shape",
        ("a", "b", "c", "d"),
        pi_shape,
        _check_pi,
        lambda p: [(p[0], False, p[3], False)] if p[0] < p[3] else [],
        lambda p, lo, hi: _core_middle(p[1], p[2], lo, hi),
        fis=(_sp("pimf", "a b c d"),),
        fll=(_sp("PiShape", "a b c d"),),
        exact=ExactForm("pi_shape", lambda p: _spline(p[0], p[1]) + _spline(p[2], p[3])),
        span=_param_span,
        features=_spans((0, 1), (2, 3)),
    ),
    Shape(
        "sigmoid_difference",
        ("slope1", "centre1", "slope2", "centre2"),
        sigmoid_difference,
        _check_nonzero("sigmoid_difference", "slope1", "slope2"),
        _support_sigmoid_difference,
        _centre_on_grid(sigmoid_difference),
        fis=(_sp("dsigmf", "slope1 centre1 slope2 centre2"),),
        fll=(_sp("SigmoidDifference", "centre1 slope1 slope2 centre2"),),
        exact=ExactForm("sigmoid_difference", _same, ("exp", "fabs")),
        features=_slopes(0, 2),
    ),
    Shape(
        "sigmoid_product",
        ("slope1", "centre1", "slope2", "centre2"),
        sigmoid_product,
        _check_nonzero("sigmoid_product", "slope1", "slope2"),
        _everywhere,
        _centre_on_grid(sigmoid_product),
        fis=(_sp("psigmf", "slope1 centre1 slope2 centre2"),),
        fll=(_sp("SigmoidProduct", "centre1 slope1 slope2 centre2"),),
        exact=ExactForm("sigmoid_product", _same, ("exp",)),
        features=_slopes(0, 2),
    ),
    # Sugeno (Takagi-Sugeno-Kang) output terms: not membership functions but the rule's output
    # value. ``linear`` has one coefficient per input, in the rule base's input order, then the
    # constant term: ``z = c_1 x_1 + ... + c_n x_n + constant`` (its params have n + 1 entries;
    # the names here are the YAML keys; its count is checked against the inputs).
    Shape(
        "constant",
        ("value",),
        None,
        _no_check,
        _nowhere,
        None,
        fis=(_sp("constant", "value"),),
        fll=(_sp("Constant", "value"),),
        sugeno=True,
        span=_param_span,
    ),
    Shape(
        "linear",
        ("coefficients", "constant"),
        None,
        _no_check,
        _nowhere,
        None,
        fis=(_sp("linear", "*"),),
        fll=(_sp("Linear", "*"),),
        sugeno=True,
    ),
)

#: Every shape by name, in the order the documentation and the JSON Schema list them.
REGISTRY: dict[str, Shape] = {s.name: s for s in _ENTRIES}

#: Membership-function shapes and the names of their parameters, in order.
SHAPE_PARAMS: dict[str, tuple[str, ...]] = {s.name: s.params for s in _ENTRIES}
#: Sugeno output terms (zero order ``constant``, first order ``linear``).
SUGENO_SHAPES = frozenset(s.name for s in _ENTRIES if s.sugeno)
#: Shapes that are piecewise linear (the exact engine integrates these in closed form).
PIECEWISE_LINEAR_SHAPES = frozenset(s.name for s in _ENTRIES if s.piecewise_linear)


def shape(name: str) -> Shape:
    """The registry record of shape ``name``.

    Raises
    ------
    UnknownShapeError
        For a name that is not registered: nothing falls back to another shape.
    """
    found = REGISTRY.get(name)
    if found is None:
        raise UnknownShapeError(
            f"unknown membership shape {name!r}; registered: {', '.join(REGISTRY)}"
        )
    return found


Format: TypeAlias = str  # "fis", "fll" or "fcl"


@functools.cache
def spellings(fmt: Format) -> dict[str, list[tuple[Shape, Spelling]]]:
    """Every name ``fmt`` reads, with the (shape, spelling) pairs it may mean.

    Candidates holding constants (``trapmf [-inf -inf a b]``) come before those that do not,
    so a shoulder written as a trapezoid with infinite feet reads back as the shoulder.
    """
    out: dict[str, list[tuple[Shape, Spelling]]] = {}
    for s in REGISTRY.values():
        for sp in getattr(s, fmt):
            out.setdefault(sp.name, []).append((s, sp))
    for pairs in out.values():
        pairs.sort(key=lambda pair: -sum(item not in pair[0].params for item in pair[1].layout))
    return out


def read_term(fmt: Format, name: str, values: Sequence[float]) -> tuple[str, Params] | str:
    """The shape and parameters a format's ``name values`` mean, or why none.

    Among the shapes ``name`` can mean, the first whose constants match and whose parameters
    are valid wins; when none is valid, the first whose constants match (its problems are
    then reported by validation). The caller has checked that ``name`` is known.
    """
    matched: list[tuple[Shape, Params]] = []
    why = ""
    for s, sp in spellings(fmt)[name]:
        if sp.arity is not None and len(values) != sp.arity:
            continue
        params = sp.read(s.params, values)
        if params is None:
            continue
        if sp.condition is not None and not sp.condition(params):
            why = sp.condition_text
            continue
        if all(math.isfinite(v) for v in params) and not s.check(params):
            return s.name, params
        matched.append((s, params))
    if not matched:
        return why or f"{name}: no shape matches {', '.join(map(repr, values))}"
    return matched[0][0].name, matched[0][1]


def write_term(fmt: Format, shape_name: str, params: Params) -> tuple[str, Params] | None:
    """A term as ``fmt`` writes it (its name there and parameters), or None if it cannot."""
    s = shape(shape_name)
    written: tuple[Spelling, ...] = getattr(s, fmt)
    if not written:
        return None
    return written[0].name, written[0].write(s.params, params)
