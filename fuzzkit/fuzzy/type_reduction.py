"""Type reduction of interval type-2 sets: Karnik-Mendel, Nie-Tan and Wu-Mendel, vectorised.

**Continuous** (:func:`interval_of_row`, compiled, one evaluation point; the exact
engine's default, fused with the cut of the sets in :mod:`fuzzkit.fuzzy.type2_kernel`). The
upper and lower output sets ``U`` and ``L`` are piecewise linear between the points of a row
(the engine cuts them there). The centroid interval ``[y_l, y_r]`` of all embedded sets is
found exactly: with ``W = U - L >= 0``, the left end is the root of

    g_l(s) = s (A_L + int_a^s W) - (M_L + int_a^s y W),

``A``/``M`` the area and first moment. ``g_l' = A_L + int_a^s W > 0`` (g_l rises) and
``g_l'' = W >= 0`` (convex), so the root is unique: it is bracketed between two cut points
by a binary search on the signs of ``g_l`` there, and on that piece ``g_l`` is a cubic in
``s`` that Newton's method, started at the right end of the piece, approaches monotonically
from above. The right end
``y_r`` is the root of ``g_r(s) = s (A_U - int_a^s W) - (M_U - int_a^s y W)`` (rising and
concave: Newton from the left end). A fixed number of Newton steps (``NEWTON_STEPS``) leaves only
rounding. When the lower set is empty the interval is the upper set's support.

The other functions work on a batch, one row per evaluation point. **Discrete**
(:func:`discrete_interval`; ``resolution: N``, MATLAB's and pyit2fls's way, and
IT2 Sugeno on the rule consequents): the interval of the centroids of every embedded set over
sorted points ``y_i`` with weights in ``[lower_i, upper_i]``; every switch point is enumerated,
so the result is what the Karnik-Mendel iteration converges to, with no iteration at all.

Nie-Tan is the centroid of ``(U + L) / 2``; Wu-Mendel the midpoint of the inner and outer
uncertainty bounds of Wu and Mendel (2002) on each end (docs/type2.md has the formulas).
"""

from __future__ import annotations

from typing import cast

import numpy as np
import numpy.typing as npt

from fuzzkit.jit import jit

FloatArray = npt.NDArray[np.float64]
EPS = float(np.finfo(np.float64).eps)

#: Newton steps on the bracketing piece, at most. From the safe side the iterates are
#: monotone, and the root is simple (``g' = D > 0``) unless the lower set is empty, which is
#: solved apart; convergence is then quadratic, and 40 steps leave only rounding even from a
#: poor start. The loop stops early once a step is below 4 ulp of the piece.
NEWTON_STEPS = 40


@jit
def _root_on_piece(
    y: FloatArray, w: FloatArray, j: int, d0: float, n0: float, sign: float
) -> float:
    """The root of ``g(s) = s D(s) - N(s)`` on the piece ``[y[j], y[j + 1]]``.

    ``d0``/``n0`` are ``D`` and ``N`` at ``y[j]``, ``w`` is ``W`` at the cut points; inside the
    piece ``D' = sign * W`` and ``N' = sign * s W``. ``sign`` +1: left end (convex, Newton from
    the right); -1: right end (concave, Newton from the left).
    """
    p, q = y[j], y[j + 1]
    h = q - p
    w0, w1 = w[j], w[j + 1]
    k = (w1 - w0) / h if h > 0.0 else 0.0
    t = h if sign > 0 else 0.0
    tiny = 4.0 * EPS * (abs(p) + h)
    for _ in range(NEWTON_STEPS):
        d = d0 + sign * (w0 * t + 0.5 * k * t * t)
        n_t = n0 + sign * (p * w0 * t + 0.5 * (p * k + w0) * t * t + k * t * t * t / 3.0)
        g = (p + t) * d - n_t
        step = g / d if d > 0.0 else 0.0
        moved = min(max(t - step, 0.0), h)
        if not abs(moved - t) > tiny:
            t = moved
            break  # the steps are down to rounding (quadratic convergence: the last one)
        t = moved
    return float(p + t)


@jit
def _bracket(y: FloatArray, d: FloatArray, nn: FloatArray, n: int) -> int:
    """The piece ``j`` (0..n-2) where the rising ``g = y D - N`` turns non-negative: binary
    search for the number of cut points where ``g < 0``."""
    lo, hi = 0, n  # g < 0 on [0, lo), g >= 0 on [hi, n)
    while lo < hi:
        mid = (lo + hi) // 2
        if y[mid] * d[mid] - nn[mid] < 0.0:
            lo = mid + 1
        else:
            hi = mid
    return min(max(lo - 1, 0), n - 2)


@jit
def interval_of_row(
    y: FloatArray, upper: FloatArray, lower: FloatArray, n: int, out: FloatArray
) -> None:
    """Exact centroid interval of piecewise-linear IT2 sets cut at ``y[:n]`` (sorted, n >= 2).

    Writes ``y_l, y_r, A_U, M_U, A_L, M_L, first, last`` into ``out[:8]``: the interval (NaN
    where the upper set is empty, ``A_U == 0``), the sets' areas and first moments, and the
    ends of the upper set's support (the cut points just outside where it is above zero).
    """
    a_u = m_u = a_l = m_l = 0.0
    cw = np.empty(n)
    cmw = np.empty(n)
    w = np.empty(n)
    cw[0] = cmw[0] = 0.0
    for i in range(n):
        w[i] = upper[i] - lower[i]
    first, last = -1, -1
    for i in range(n - 1):
        y0, y1 = y[i], y[i + 1]
        h = y1 - y0
        au = 0.5 * h * (upper[i] + upper[i + 1])
        mu = h / 6.0 * (y0 * (2 * upper[i] + upper[i + 1]) + y1 * (upper[i] + 2 * upper[i + 1]))
        al = 0.5 * h * (lower[i] + lower[i + 1])
        ml = h / 6.0 * (y0 * (2 * lower[i] + lower[i + 1]) + y1 * (lower[i] + 2 * lower[i + 1]))
        a_u += au
        m_u += mu
        a_l += al
        m_l += ml
        cw[i + 1] = cw[i] + (au - al)
        cmw[i + 1] = cmw[i] + (mu - ml)
    for i in range(n):
        if upper[i] > 0.0:
            if first < 0:
                first = i
            last = i
    d = np.empty(n)
    nn = np.empty(n)
    for i in range(n):
        d[i] = a_l + cw[i]
        nn[i] = m_l + cmw[i]
    j = _bracket(y, d, nn, n)
    y_l = _root_on_piece(y, w, j, d[j], nn[j], 1.0)
    for i in range(n):
        d[i] = a_u - cw[i]
        nn[i] = m_u - cmw[i]
    j = _bracket(y, d, nn, n)
    y_r = _root_on_piece(y, w, j, d[j], nn[j], -1.0)
    lo_end = y[max(first - 1, 0)] if first >= 0 else y[0]
    hi_end = y[min(last + 1, n - 1)] if last >= 0 else y[n - 1]
    if not a_l > 0.0:
        # An empty lower set is the one case of a multiple root (g' = D vanishes there), which
        # rounding would blur to ~1e-8: every sub-support of the upper set is then embedded,
        # and the interval is the support itself.
        y_l, y_r = lo_end, hi_end
    if not a_u > 1e-300:
        y_l = y_r = np.nan
    out[0], out[1], out[2], out[3] = y_l, y_r, a_u, m_u
    out[4], out[5], out[6], out[7] = a_l, m_l, lo_end, hi_end


def discrete_interval(
    y: FloatArray, lower: FloatArray, upper: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Karnik-Mendel interval over points ``y`` (B, n), rows sorted, weights in [lower, upper].

    Every switch point is tried: ``y_l`` takes the upper weights up to the switch and the lower
    ones after it, ``y_r`` the reverse. NaN where every upper weight is zero.
    """
    zeros = np.zeros((y.shape[0], 1))
    cu = np.concatenate([zeros, np.cumsum(upper, axis=1)], axis=1)
    cl = np.concatenate([zeros, np.cumsum(lower, axis=1)], axis=1)
    cyu = np.concatenate([zeros, np.cumsum(y * upper, axis=1)], axis=1)
    cyl = np.concatenate([zeros, np.cumsum(y * lower, axis=1)], axis=1)
    tl, tu, tyl, tyu = cl[:, -1:], cu[:, -1:], cyl[:, -1:], cyu[:, -1:]
    with np.errstate(divide="ignore", invalid="ignore"):
        left = (cyu + (tyl - cyl)) / (cu + (tl - cl))
        right = (cyl + (tyu - cyu)) / (cl + (tu - cu))
    ok = tu[:, 0] > 0.0
    left = np.where(np.isfinite(left), left, np.inf)
    right = np.where(np.isfinite(right), right, -np.inf)
    y_l = np.where(ok, left.min(axis=1), np.nan)
    y_r = np.where(ok, right.max(axis=1), np.nan)
    return y_l, y_r


def nie_tan(a_u: FloatArray, m_u: FloatArray, a_l: FloatArray, m_l: FloatArray) -> FloatArray:
    """Nie-Tan: the centroid of the average of the upper and lower sets (NaN if both empty)."""
    tot = a_u + a_l
    with np.errstate(divide="ignore", invalid="ignore"):
        return cast(FloatArray, np.where(tot > 1e-300, (m_u + m_l) / tot, np.nan))


def wu_mendel(
    sums_l: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
    sums_u: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
) -> FloatArray:
    """Wu-Mendel: the midpoint of ``(lower bound + upper bound) / 2`` of each interval end.

    ``sums_l`` and ``sums_u`` are, for the lower and the upper set, ``(A, M, D1, DN)``: the
    weight, the first moment, ``sum w (y - y_1)`` and ``sum w (y_N - y)``, with ``y_1``/``y_N``
    the ends of the support (integrals in the continuous case, sums in the discrete one).
    """
    a_l, m_l, d1_l, dn_l = sums_l
    a_u, m_u, d1_u, dn_u = sums_u
    with np.errstate(divide="ignore", invalid="ignore"):
        c_lower = m_l / a_l
        c_upper = m_u / a_u
        c_lower = np.where(a_l > 1e-300, c_lower, c_upper)
        gap = (a_u - a_l) / (a_u * a_l)
        gap = np.where(a_l > 1e-300, gap, 0.0)
        yl_outer = np.minimum(c_lower, c_upper)
        yr_inner = np.maximum(c_lower, c_upper)
        den_l = d1_l + dn_u
        den_r = d1_u + dn_l
        yl_inner = yl_outer - gap * np.where(den_l > 0, d1_l * dn_u / den_l, 0.0)
        yr_outer = yr_inner + gap * np.where(den_r > 0, d1_u * dn_l / den_r, 0.0)
    y_l = 0.5 * (yl_outer + yl_inner)
    y_r = 0.5 * (yr_inner + yr_outer)
    return cast(FloatArray, np.where(a_u > 1e-300, 0.5 * (y_l + y_r), np.nan))
