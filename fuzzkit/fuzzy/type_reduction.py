"""Type reduction of interval type-2 sets: Karnik-Mendel, Nie-Tan and Wu-Mendel, vectorised.

Every function works on a batch: one row per evaluation point.

**Continuous** (:func:`continuous_interval`, the exact engine's default). The upper and lower
output sets ``U`` and ``L`` are piecewise linear between the points of a row (the engine cuts
them there). The centroid interval ``[y_l, y_r]`` of all embedded sets is found exactly: with
``W = U - L >= 0``, the left end is the root of

    g_l(s) = s (A_L + int_a^s W) - (M_L + int_a^s y W),

``A``/``M`` the area and first moment. ``g_l' = A_L + int_a^s W > 0`` (g_l rises) and
``g_l'' = W >= 0`` (convex), so the root is unique: it is bracketed between two cut points by
the signs of ``g_l`` there, and on that piece ``g_l`` is a cubic in ``s`` that Newton's method,
started at the right end of the piece, approaches monotonically from above. The right end
``y_r`` is the root of ``g_r(s) = s (A_U - int_a^s W) - (M_U - int_a^s y W)`` (rising and
concave: Newton from the left end). A fixed number of Newton steps (``NEWTON_STEPS``) leaves only
rounding. When the lower set is empty the interval is the upper set's support.

**Discrete** (:func:`discrete_interval`; ``resolution: N``, MATLAB's and pyit2fls's way, and
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

FloatArray = npt.NDArray[np.float64]

#: Newton steps on the bracketing piece, at most. From the safe side the iterates are
#: monotone, and the root is simple (``g' = D > 0``) unless the lower set is empty, which is
#: solved apart; convergence is then quadratic, and 40 steps leave only rounding even from a
#: poor start. The loop stops early once every step is below 4 ulp of the piece.
NEWTON_STEPS = 40


def _segment_integrals(y: FloatArray, f: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Area and first moment of the piecewise-linear ``f`` on each segment of ``y`` (B, n-1)."""
    y0, y1 = y[:, :-1], y[:, 1:]
    f0, f1 = f[:, :-1], f[:, 1:]
    h = y1 - y0
    area = 0.5 * h * (f0 + f1)
    moment = h / 6.0 * (y0 * (2 * f0 + f1) + y1 * (f0 + 2 * f1))
    return area, moment


def _cumulative(parts: FloatArray) -> FloatArray:
    """Cumulative sums from 0 at the first point: (B, n-1) -> (B, n)."""
    out = np.zeros((parts.shape[0], parts.shape[1] + 1))
    np.cumsum(parts, axis=1, out=out[:, 1:])
    return out


def _root_on_piece(
    y: FloatArray,
    w: FloatArray,
    d_at: FloatArray,
    n_at: FloatArray,
    g_at: FloatArray,
    sign: float,
) -> FloatArray:
    """The root of ``g(s) = s D(s) - N(s)`` on the piece where ``g`` changes sign.

    ``d_at``/``n_at``/``g_at`` are ``D``, ``N`` and ``g`` at the cut points, ``w`` is ``W`` there;
    inside a piece ``D' = sign * W`` and ``N' = sign * s W``. ``sign`` +1: left end (convex,
    Newton from the right); -1: right end (concave, Newton from the left).
    """
    b, n = y.shape
    rows = np.arange(b)
    below = np.count_nonzero(g_at < 0.0, axis=1)
    j = np.clip(below - 1, 0, n - 2)
    p, q = y[rows, j], y[rows, j + 1]
    h = q - p
    w0, w1 = w[rows, j], w[rows, j + 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(h > 0.0, (w1 - w0) / h, 0.0)
    d0, n0 = d_at[rows, j], n_at[rows, j]

    def d_of(t: FloatArray) -> FloatArray:
        return cast(FloatArray, d0 + sign * (w0 * t + 0.5 * k * t * t))

    def g_of(t: FloatArray) -> FloatArray:
        n_t = n0 + sign * (p * w0 * t + 0.5 * (p * k + w0) * t * t + k * t * t * t / 3.0)
        return cast(FloatArray, (p + t) * d_of(t) - n_t)

    t = h.copy() if sign > 0 else np.zeros_like(h)
    tiny = 4.0 * np.finfo(np.float64).eps * (np.abs(p) + h)
    with np.errstate(divide="ignore", invalid="ignore"):
        for _ in range(NEWTON_STEPS):
            d = d_of(t)
            step = np.where(d > 0.0, g_of(t) / d, 0.0)
            moved = np.clip(t - step, 0.0, h)
            done = bool(np.all(np.abs(moved - t) <= tiny))
            t = moved
            if done:
                break  # the steps are down to rounding (quadratic convergence: the last one)
    return cast(FloatArray, p + t)


def continuous_interval(
    y: FloatArray, upper: FloatArray, lower: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """Exact centroid interval of piecewise-linear IT2 sets cut at ``y`` (B, n), sorted rows.

    Returns ``y_l, y_r, A_U, M_U, A_L, M_L`` (each (B,)); ``y_l``/``y_r`` are NaN where the
    upper set is empty (``A_U == 0``).
    """
    area_u, mom_u = _segment_integrals(y, upper)
    area_l, mom_l = _segment_integrals(y, lower)
    a_u, m_u = area_u.sum(axis=1), mom_u.sum(axis=1)
    a_l, m_l = area_l.sum(axis=1), mom_l.sum(axis=1)
    cw = _cumulative(area_u - area_l)
    cmw = _cumulative(mom_u - mom_l)
    w = upper - lower
    d_l = a_l[:, None] + cw
    n_l = m_l[:, None] + cmw
    d_r = a_u[:, None] - cw
    n_r = m_u[:, None] - cmw
    y_l = _root_on_piece(y, w, d_l, n_l, y * d_l - n_l, 1.0)
    y_r = _root_on_piece(y, w, d_r, n_r, y * d_r - n_r, -1.0)
    # An empty lower set is the one case of a multiple root (g' = D vanishes there), which
    # rounding would blur to ~1e-8: every sub-support of the upper set is then embedded, and
    # the interval is the support itself.
    no_lower = ~(a_l > 0.0)
    if no_lower.any():
        first, last = continuous_support(y, upper)
        y_l = np.where(no_lower, first, y_l)
        y_r = np.where(no_lower, last, y_r)
    empty = ~(a_u > 1e-300)
    y_l = np.where(empty, np.nan, y_l)
    y_r = np.where(empty, np.nan, y_r)
    return y_l, y_r, a_u, m_u, a_l, m_l


def continuous_support(y: FloatArray, upper: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The ends of the upper set's support (where it is above zero), per row."""
    b, n = y.shape
    rows = np.arange(b)
    pos = upper > 0.0
    first = np.argmax(pos, axis=1)
    last = n - 1 - np.argmax(pos[:, ::-1], axis=1)
    return y[rows, np.maximum(first - 1, 0)], y[rows, np.minimum(last + 1, n - 1)]


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
