"""Sound enclosures of one membership function over an interval: its values and its slopes.

For the shapes whose surface the certificate can bound soundly:

* **piecewise linear** (triangle, trapezoid, shoulders), in the engine's form
  ``mu = clip(min(1 + (x - b) r, 1 + (c - x) f), 0, 1)``
  (:func:`fuzzkit.fuzzy.membership.trapezoid_form`): unimodal with its core ``[b, c]``, so the
  largest value on ``[x0, x1]`` is at the point nearest the core and the smallest at an end.
  The slope is ``r`` on the rise ``[b - 1/r, b]``, ``-f`` on the fall ``[c, c + 1/f]`` and 0
  elsewhere; the enclosure is the hull of the slopes of every piece the closed interval meets,
  so at a kink it holds both one-sided slopes (Clarke's generalised gradient).
* **gaussian** ``exp(-u^2 / 2)``, ``u = (x - mean) / sigma``: largest where ``|u|`` is
  smallest; the slope ``-u exp(-u^2 / 2) / sigma`` is monotone between its extremes at
  ``u = -1`` and ``u = 1``.

Every end is rounded outwards (:mod:`fuzzkit.analysis.intervals`). Other shapes have no
enclosure here: :func:`supported` says so, and the surface is then not covered.
"""

from __future__ import annotations

import math

import numpy as np

from fuzzkit.analysis.intervals import FloatArray, Interval, down, exp_decreasing, square, up
from fuzzkit.fuzzy.model import Term
from fuzzkit.fuzzy.shapes import shape

#: Smooth shapes with an enclosure here (besides the piecewise-linear ones).
SMOOTH = frozenset({"gaussian"})
#: Ulps by which a membership value computed in double is widened.
VALUE_ULPS = 4


def supported(term: Term, low: float = -1.0, high: float = 1.0) -> bool:
    """Whether :func:`enclose` bounds this term's membership on ``[low, high]`` (a vertical
    edge inside it is a jump: not bounded)."""
    if term.is_piecewise_linear:
        pts = shape(term.shape).points
        xs = np.array([x for x, _ in pts(term.params)]) if pts is not None else np.zeros(0)
        jumps = xs[1:][np.diff(xs) == 0.0]
        return not np.any((jumps > low) & (jumps < high))
    return term.shape in SMOOTH


def _vertices(term: Term) -> tuple[FloatArray, FloatArray]:
    """The term's vertices ``(x, mu)``, constant beyond the ends. A vertical edge (two points
    at one ``x``) keeps the upper value: the engine's formula takes it there (its rise or fall
    term is exactly 1 at the edge), and :func:`supported` allows such an edge only at the
    universe's ends, where nothing lies beyond."""
    pts = shape(term.shape).points
    if pts is None:
        raise ValueError(f"{term.name}: a {term.shape} term has no vertices")
    xs: list[float] = []
    ys: list[float] = []
    for x, y in pts(term.params):
        if xs and x == xs[-1]:
            ys[-1] = max(ys[-1], y)
        else:
            xs.append(float(x))
            ys.append(float(y))
    return np.array(xs, dtype=np.float64), np.array(ys, dtype=np.float64)


def _pieces(term: Term) -> list[tuple[float, float, float]]:
    """``(start, end, slope)`` of each linear piece, covering the whole axis; a computed slope
    is rounded outwards (a flat piece's 0 is exact), a vertical edge is left out (it is a
    jump, only at the universe's ends in a loop rule base: :func:`supported`)."""
    xs, ys = _vertices(term)
    out = [(-math.inf, float(xs[0]), 0.0)]
    for k in range(len(xs) - 1):
        slope = float((ys[k + 1] - ys[k]) / (xs[k + 1] - xs[k]))
        out.append((float(xs[k]), float(xs[k + 1]), slope))
    out.append((float(xs[-1]), math.inf, 0.0))
    return out


def _widen01(v_lo: FloatArray, v_hi: FloatArray) -> Interval:
    # 0 and 1 are the clip's exact results: only values between are rounded outwards
    lo = np.where((v_lo > 0.0) & (v_lo < 1.0), np.maximum(down(v_lo, VALUE_ULPS), 0.0), v_lo)
    hi = np.where((v_hi > 0.0) & (v_hi < 1.0), np.minimum(up(v_hi, VALUE_ULPS), 1.0), v_hi)
    return Interval(lo, hi)


def enclose(term: Term, x0: FloatArray, x1: FloatArray) -> tuple[Interval, Interval]:
    """``(mu, dmu/dx)`` of ``term`` over each ``[x0, x1]`` (closed), outward rounded."""
    if term.is_piecewise_linear:
        xs, ys = _vertices(term)
        v0, v1 = np.interp(x0, xs, ys), np.interp(x1, xs, ys)
        v_lo, v_hi = np.minimum(v0, v1), np.maximum(v0, v1)
        for xv, yv in zip(xs, ys, strict=True):  # a vertex inside the interval
            inside = (x0 <= xv) & (xv <= x1)
            v_lo = np.where(inside, np.minimum(v_lo, yv), v_lo)
            v_hi = np.where(inside, np.maximum(v_hi, yv), v_hi)
        value = _widen01(v_lo, v_hi)
        d_lo, d_hi = np.full_like(x0, np.inf), np.full_like(x0, -np.inf)
        for lo, hi, slope in _pieces(term):
            # a piece counts where it overlaps the interval in more than a point (a point
            # interval: where it holds the point); a neighbouring cell holds the other side
            meets = np.where(x0 < x1, (x0 < hi) & (x1 > lo), (x0 <= hi) & (x1 >= lo))
            s_lo = (
                slope
                if slope == 0.0
                else math.nextafter(math.nextafter(slope, -math.inf), -math.inf)
            )
            s_hi = (
                slope if slope == 0.0 else math.nextafter(math.nextafter(slope, math.inf), math.inf)
            )
            d_lo = np.where(meets, np.minimum(d_lo, s_lo), d_lo)
            d_hi = np.where(meets, np.maximum(d_hi, s_hi), d_hi)
        return value, Interval(d_lo, d_hi)
    if term.shape == "gaussian":
        mean, sigma = term.params
        s = np.full_like(x0, sigma)
        u = Interval(x0 - mean, x1 - mean)
        u = Interval(down(u.lo), up(u.hi)).divide_positive(Interval(s, s))
        half_u2 = square(u).scale(np.full_like(x0, 0.5))
        value = exp_decreasing(half_u2.lo, half_u2.hi)
        value = Interval(value.lo, np.minimum(value.hi, 1.0))
        return value, _gauss_slope(u, sigma)
    raise ValueError(f"no enclosure for a {term.shape} term")


def _gauss_slope(u: Interval, sigma: float) -> Interval:
    """``g(u) = -u exp(-u^2/2) / sigma`` over ``u``: ends, and the extremes at ``u = -1, 1``."""

    def g(t: FloatArray) -> Interval:
        t2 = square(Interval(t, t)).scale(np.full_like(t, 0.5))
        e = exp_decreasing(t2.lo, t2.hi)
        tt = Interval(t, t)
        return (-(tt * e)).divide_positive(Interval.point(np.full_like(t, sigma)))

    ends = g(u.lo).hull(g(u.hi))
    peak = -math.exp(-0.5) / sigma
    lo = np.where(
        (u.lo <= 1.0) & (u.hi >= 1.0),
        np.minimum(ends.lo, down(np.full_like(u.lo, peak), 8)),
        ends.lo,
    )
    hi = np.where(
        (u.lo <= -1.0) & (u.hi >= -1.0),
        np.maximum(ends.hi, up(np.full_like(u.lo, -peak), 8)),
        ends.hi,
    )
    return Interval(lo, hi)


def value_bounds(term: Term, y0: FloatArray, y1: FloatArray) -> Interval:
    """The membership's range over each ``[y0, y1]`` (any interval, closed)."""
    return enclose(term, y0, y1)[0]


def breakpoints(term: Term) -> list[float]:
    """Points between which the term is monotone (its kinks, or a gaussian's mean)."""
    if term.is_piecewise_linear:
        return [float(x) for x in _vertices(term)[0]]
    if term.shape == "gaussian":
        return [float(term.params[0])]
    return []
