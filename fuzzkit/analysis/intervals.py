"""Outward-rounded interval arithmetic on numpy arrays, for the sound bounds of a surface.

An :class:`Interval` holds two arrays of one shape, ``lo <= hi``: every real number the
quantity can take lies between them. Each operation computes its ends in double and moves
them one step outwards (``np.nextafter``): IEEE 754 rounds ``+ - * /`` correctly, to half an
ulp, so the exact result of the operation on any reals inside the operands lies inside the
widened result. ``exp`` is not correctly rounded by numpy's libm (its error is well below 1
ulp, not guaranteed), so :func:`exp_decreasing` widens by :data:`EXP_ULPS`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]

EPS = float(np.finfo(np.float64).eps)
#: Ulps by which an ``exp`` result is widened (numpy's libm is within 1 ulp; 4 leaves room).
EXP_ULPS = 4


def down(x: FloatArray, steps: int = 1) -> FloatArray:
    """``x`` moved ``steps`` doubles towards minus infinity."""
    for _ in range(steps):
        x = np.nextafter(x, -np.inf)
    return x


def up(x: FloatArray, steps: int = 1) -> FloatArray:
    """``x`` moved ``steps`` doubles towards plus infinity."""
    for _ in range(steps):
        x = np.nextafter(x, np.inf)
    return x


@dataclass(frozen=True, slots=True)
class Interval:
    """Arrays ``lo <= hi`` enclosing a real quantity elementwise."""

    lo: FloatArray
    hi: FloatArray

    @staticmethod
    def point(x: npt.ArrayLike) -> Interval:
        """The degenerate interval of exactly representable values ``x``."""
        a = np.asarray(x, dtype=np.float64)
        return Interval(a, a)

    def __add__(self, other: Interval) -> Interval:
        return Interval(
            _exact_or(self.lo + other.lo, self.lo, other.lo, down),
            _exact_or(self.hi + other.hi, self.hi, other.hi, up),
        )

    def __sub__(self, other: Interval) -> Interval:
        return Interval(
            _exact_or(self.lo - other.hi, self.lo, other.hi, down),
            _exact_or(self.hi - other.lo, self.hi, other.lo, up),
        )

    def __neg__(self) -> Interval:
        return Interval(-self.hi, -self.lo)

    def __mul__(self, other: Interval) -> Interval:
        a = (self.lo, self.lo, self.hi, self.hi)
        b = (other.lo, other.hi, other.lo, other.hi)
        # a product with an exact 0 is exactly 0: only the others are rounded outwards
        # (0 * inf cannot occur: every quantity bounded here is finite)
        lo = np.min(
            [_exact_or(x * y, x, y, down, zero_only=True) for x, y in zip(a, b, strict=True)],
            axis=0,
        )
        hi = np.max(
            [_exact_or(x * y, x, y, up, zero_only=True) for x, y in zip(a, b, strict=True)], axis=0
        )
        return Interval(lo, hi)

    def scale(self, c: FloatArray) -> Interval:
        """``c * self`` for exact (representable) ``c >= 0``."""
        exact = c == 1.0
        return Interval(
            np.where(exact, self.lo, _exact_or(self.lo * c, self.lo, c, down)),
            np.where(exact, self.hi, _exact_or(self.hi * c, self.hi, c, up)),
        )

    def divide_positive(self, d: Interval) -> Interval:
        """``self / d`` where ``d.lo > 0`` (the caller checks it)."""
        q = np.stack([self.lo / d.lo, self.lo / d.hi, self.hi / d.lo, self.hi / d.hi])
        return Interval(down(q.min(axis=0)), up(q.max(axis=0)))

    def hull(self, other: Interval) -> Interval:
        """The smallest interval holding both."""
        return Interval(np.minimum(self.lo, other.lo), np.maximum(self.hi, other.hi))

    def intersect(self, other: Interval) -> Interval:
        """Both hold: the common part (the caller's operands both enclose the same value)."""
        return Interval(np.maximum(self.lo, other.lo), np.minimum(self.hi, other.hi))


def _exact_or(
    result: FloatArray,
    a: FloatArray,
    b: FloatArray,
    rounding: Callable[[FloatArray], FloatArray],
    zero_only: bool = False,
) -> FloatArray:
    """``result`` of ``a op b``, rounded by ``rounding`` unless an operand is 0 (then exact:
    ``x + 0``, ``x - 0``, ``x * 0``; for a sum, ``0 - x`` too)."""
    exact = (a == 0.0) | (b == 0.0)
    return np.where(exact, result, rounding(result))


def exp_decreasing(u_lo: FloatArray, u_hi: FloatArray) -> Interval:
    """``exp(-t)`` for ``t`` in ``[u_lo, u_hi]`` (``exp`` decreasing in ``t``), widened."""
    return Interval(np.maximum(down(np.exp(-u_hi), EXP_ULPS), 0.0), up(np.exp(-u_lo), EXP_ULPS))


def square(a: Interval) -> Interval:
    """``a**2`` (the dependency-free enclosure: 0 when ``a`` contains 0)."""
    lo2, hi2 = a.lo * a.lo, a.hi * a.hi
    mn = np.where((a.lo <= 0.0) & (a.hi >= 0.0), 0.0, np.minimum(lo2, hi2))
    return Interval(np.maximum(down(mn), 0.0), up(np.maximum(lo2, hi2)))


def sum_outward(lo: FloatArray, hi: FloatArray, axis: int) -> Interval:
    """``sum`` of intervals along ``axis``, widened by the recursive-summation error bound."""
    n = lo.shape[axis]
    s_lo, s_hi = lo.sum(axis=axis), hi.sum(axis=axis)
    err_lo = n * EPS * np.abs(lo).sum(axis=axis)
    err_hi = n * EPS * np.abs(hi).sum(axis=axis)
    return Interval(down(s_lo - err_lo), up(s_hi + err_hi))


def dot(a: Interval, b: Interval) -> Interval:
    """``sum_t a_t b_t`` over the last axis."""
    p = a * b
    return sum_outward(p.lo, p.hi, axis=-1)
