"""Closed-form integrals of an output whose terms are all Gaussian, under max aggregation.

With min implication a term clipped at level ``L`` is a plateau between its clip points
``m -+ sigma sqrt(-2 ln L)`` and its Gaussian tails outside them; with product implication it
is the Gaussian scaled by ``L``. Their maximum changes hands only where two of them cross: two
tails (``g_i = g_j``: fixed points, a quadratic), a tail and a plateau (``g_i = L_j``: a clip
point of ``i`` at ``j``'s level), two scaled Gaussians (``L_i g_i = L_j g_j``: a quadratic in
``y`` with ``ln(L_i / L_j)`` in it). Between consecutive such points one piece is the maximum
(chosen at the middle), and its area and moment are closed forms: a plateau's, or a
Gaussian's through ``erf`` (``erfc`` in the tails, where ``erf`` differences cancel):
``int g = sigma sqrt(pi/2) [erf((y - m) / (sigma sqrt 2))]`` and
``int y g = m int g + sigma^2 [-g]``. The bisector solves ``int_u^y = r`` inside its segment with
``erfinv`` and two Newton steps; the maxima are the highest plateaus or peaks. The only error
is rounding (and ``erf``'s, about 1e-16 relative), against the grid's 1e-9 of
:class:`fuzzkit.fuzzy.output_geometry.GridGeometry`, which every other smooth output keeps.
"""

from __future__ import annotations

import itertools
import math
from typing import cast

import numpy as np
import numpy.typing as npt
from scipy import special

from fuzzkit.fuzzy.model import RuleBase, Variable
from fuzzkit.fuzzy.output_geometry import TIE, OutputPieces

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]
BoolArray = npt.NDArray[np.bool_]

_SQRT_HALF_PI = math.sqrt(0.5 * math.pi)


def applies(rb: RuleBase, out: Variable, pieces: OutputPieces) -> bool:
    """Whether :class:`GaussianGeometry` integrates ``out``: Gaussian terms, max aggregation."""
    return (
        rb.operators.aggregation == "max"
        and pieces.per_term
        and bool(out.terms)
        and all(t.shape == "gaussian" for t in out.terms)
    )


class GaussianGeometry:
    """The aggregated set of Gaussian output terms (max aggregation), integrated exactly."""

    def __init__(self, rb: RuleBase, out: Variable, pieces: OutputPieces) -> None:
        self.product = rb.operators.implication == "product"
        self.lo, self.hi = float(out.low), float(out.high)
        terms = [out.terms[int(t)] for t in pieces.piece_term]
        self.m = np.array([t.params[0] for t in terms], dtype=np.float64)
        self.s = np.array([t.params[1] for t in terms], dtype=np.float64)
        self.k = len(terms)
        # where two unscaled Gaussians cross (min implication: tail against tail)
        fixed = []
        for i, j in itertools.combinations(range(self.k), 2):
            fixed.extend(_crossings(self.m[i], self.s[i], self.m[j], self.s[j], 0.0))
        self.fixed = np.array([y for y in fixed if self.lo < y < self.hi], dtype=np.float64)
        # the peak of each term inside the range: where its maximum is
        self.peak = np.clip(self.m, self.lo, self.hi)

    def _g(self, y: FloatArray) -> FloatArray:
        """Every term at ``y`` (..., K)."""
        d = (y[..., None] - self.m) / self.s
        return cast(FloatArray, np.exp(-0.5 * d * d))

    def _points(self, levels: FloatArray) -> FloatArray:
        """Sorted points (B, C) between which one piece is the maximum."""
        b = levels.shape[0]
        parts = [np.full((b, 1), self.lo), np.full((b, 1), self.hi)]
        parts.append(np.broadcast_to(self.fixed, (b, len(self.fixed))))
        with np.errstate(divide="ignore", invalid="ignore"):
            if self.product:
                for i, j in itertools.combinations(range(self.k), 2):
                    ratio = np.log(levels[:, i]) - np.log(levels[:, j])
                    parts.extend(
                        _crossings_batch(self.m[i], self.s[i], self.m[j], self.s[j], ratio)
                    )
            else:
                # each term meets each level at m -+ sigma sqrt(-2 ln L)
                reach = np.sqrt(-2.0 * np.log(levels))  # (B, K): inf at 0, nan above 1
                for t in range(self.k):
                    d = self.s[t] * reach
                    parts.extend([self.m[t] - d, self.m[t] + d])
        pts = np.concatenate(parts, axis=1)
        pts = np.where(np.isfinite(pts), pts, self.lo)
        return np.sort(np.clip(pts, self.lo, self.hi), axis=1)

    def _winner(self, levels: FloatArray, y: FloatArray) -> tuple[IntArray, BoolArray]:
        """At ``y`` (B, S): the piece that is the maximum and whether it is a plateau."""
        g = self._g(y)  # (B, S, K)
        lv = levels[:, None, :]
        if self.product:
            q = np.argmax(lv * g, axis=-1)
            return q, np.zeros(q.shape, dtype=bool)
        q = np.argmax(np.minimum(lv, g), axis=-1)
        flat = np.take_along_axis(lv <= g, q[..., None], axis=-1)[..., 0]
        return q, flat

    def _segments(
        self, levels: FloatArray
    ) -> tuple[FloatArray, FloatArray, IntArray, BoolArray, FloatArray, FloatArray, FloatArray]:
        """Segments (u, v), their winning piece, plateau flag and level, area and moment."""
        pts = self._points(levels)
        u, v = pts[:, :-1], pts[:, 1:]
        q, flat = self._winner(levels, 0.5 * (u + v))
        level = np.take_along_axis(levels, q, axis=1)
        scale = level if self.product else np.ones_like(level)
        area, moment = self._integrals(u, v, q, flat, level, scale)
        return u, v, q, flat, level, area, moment

    def _integrals(
        self,
        u: FloatArray,
        v: FloatArray,
        q: IntArray,
        flat: BoolArray,
        level: FloatArray,
        scale: FloatArray,
    ) -> tuple[FloatArray, FloatArray]:
        area = level * (v - u)
        moment = level * 0.5 * (v - u) * (v + u)
        # the Gaussian pieces only (most segments are plateaus, or empty at the range ends)
        tail = ~flat & (v > u)
        m, s = self.m[q[tail]], self.s[q[tail]]
        c, ut, vt = scale[tail], u[tail], v[tail]
        du, dv = (ut - m) / s, (vt - m) / s
        gauss = c * s * _SQRT_HALF_PI * _erf_diff(du / math.sqrt(2), dv / math.sqrt(2))
        area[tail] = gauss
        moment[tail] = m * gauss + c * s * s * (np.exp(-0.5 * du * du) - np.exp(-0.5 * dv * dv))
        return area, moment

    def centroid(self, levels: FloatArray, default: float) -> FloatArray:
        """Centroid (B,); ``default`` where nothing fired."""
        *_, area_s, moment_s = self._segments(levels)
        area, moment = area_s.sum(axis=1), moment_s.sum(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(area > 1e-300, moment / area, default)

    def bisector(self, levels: FloatArray, default: float) -> FloatArray:
        """Bisector (B,): where the area to the left is half; ``default`` where none fired."""
        u, v, qs, flats, level, area, _ = self._segments(levels)
        total = area.sum(axis=1)
        cum = np.cumsum(area, axis=1)
        idx = np.argmax(cum >= 0.5 * total[:, None] * (1 - 1e-15), axis=1)
        rows = np.arange(area.shape[0])
        r = 0.5 * total - (cum[rows, idx] - area[rows, idx])
        a0, a1 = u[rows, idx], v[rows, idx]
        q = qs[rows, idx]
        flat = flats[rows, idx]
        lev = level[rows, idx]
        with np.errstate(invalid="ignore", divide="ignore"):
            y_flat = a0 + r / lev
            m, s = self.m[q], self.s[q]
            sc = lev if self.product else np.ones_like(lev)
            # erf((y - m) / (s sqrt 2)) = erf((a0 - m) / (s sqrt 2)) + r / (sc s sqrt(pi/2))
            target = special.erf((a0 - m) / (s * math.sqrt(2))) + r / (sc * s * _SQRT_HALF_PI)
            y = m + s * math.sqrt(2) * special.erfinv(np.clip(target, -1.0, 1.0))
            y = np.where(np.isfinite(y), np.clip(y, a0, a1), a0)
            for _ in range(2):  # Newton on the partial area: erfinv loses digits near +-1
                part, _m = self._integrals(
                    a0[:, None], y[:, None], q[:, None], np.zeros((len(y), 1), bool),
                    lev[:, None], sc[:, None],
                )  # fmt: skip
                dens = sc * np.exp(-0.5 * ((y - m) / s) ** 2)
                step = np.where(dens > 0, (part[:, 0] - r) / dens, 0.0)
                y = np.clip(y - np.where(np.isfinite(step), step, 0.0), a0, a1)
        out = np.where(flat, np.clip(y_flat, a0, a1), y)
        return np.where(total > 1e-300, out, default)

    def maxima(self, levels: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Height, smallest and largest point of maximum (B,).

        Values within :data:`~fuzzkit.fuzzy.output_geometry.TIE` of the height (a share of
        it) are maximal, as everywhere in the engine: around a smooth peak that is the
        interval where the Gaussian stays above that, a plateau's clip points at that level.
        """
        gpeak = np.exp(-0.5 * ((self.peak - self.m) / self.s) ** 2)  # (K,): each term's top
        top = levels * gpeak if self.product else np.minimum(levels, gpeak)
        height = top.max(axis=1)
        tie = (height * (1.0 - TIE))[:, None]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            # the term's own value g must reach this for its implied set to reach the tie
            need = tie / levels if self.product else np.broadcast_to(tie, levels.shape)
            ok = (need <= gpeak) & (levels >= tie)
            d = self.s * np.sqrt(np.maximum(-2.0 * np.log(np.where(ok, need, 1.0)), 0.0))
        som = np.where(ok, np.clip(self.m - d, self.lo, self.hi), np.inf).min(axis=1)
        lom = np.where(ok, np.clip(self.m + d, self.lo, self.hi), -np.inf).max(axis=1)
        return height, som, lom


def _erf_diff(a: FloatArray, b: FloatArray) -> FloatArray:
    """``erf(b) - erf(a)`` for ``a <= b`` from ``erfc(|a|)`` and ``erfc(|b|)``: no cancelling
    in the tails, where both ``erf`` are near the same +-1."""
    ea, eb = special.erfc(np.abs(a)), special.erfc(np.abs(b))
    return cast(FloatArray, np.where(a >= 0, ea - eb, np.where(b <= 0, eb - ea, 2.0 - ea - eb)))


def _crossings(m1: float, s1: float, m2: float, s2: float, log_ratio: float) -> list[float]:
    """Where ``ln g_1 + log_ratio = ln g_2``: a quadratic in ``y`` (at most two roots)."""
    roots = _crossings_batch(m1, s1, m2, s2, np.array([log_ratio]))
    return [float(r[0, 0]) for r in roots if np.isfinite(r[0, 0])]


def quadratic(m1: float, s1: float, m2: float, s2: float) -> tuple[float, float, float]:
    """``(a, b, c0)``: ``ln L_1 g_1 = ln L_2 g_2`` is ``a y^2 + b y + c0 + ln(L_1 / L_2) = 0``."""
    a = 0.5 / (s2 * s2) - 0.5 / (s1 * s1)
    bq = m1 / (s1 * s1) - m2 / (s2 * s2)
    c0 = 0.5 * m2 * m2 / (s2 * s2) - 0.5 * m1 * m1 / (s1 * s1)
    return float(a), float(bq), float(c0)


def _crossings_batch(
    m1: float, s1: float, m2: float, s2: float, log_ratio: FloatArray
) -> list[FloatArray]:
    """Both roots (B, 1) each of ``log_ratio - (y - m1)^2 / 2 s1^2 + (y - m2)^2 / 2 s2^2 = 0``
    (NaN where there is none)."""
    a, bq, c0 = quadratic(m1, s1, m2, s2)
    c = c0 + log_ratio
    with np.errstate(divide="ignore", invalid="ignore"):
        if a == 0.0:
            one = np.where(bq != 0.0, -c / bq, np.nan)
            return [one[:, None], one[:, None]]
        disc = np.sqrt(bq * bq - 4.0 * a * c)
        # the stable pair of roots: no cancellation in -b -+ sqrt(disc)
        qq = -0.5 * (bq + np.copysign(disc, bq))
        r1 = qq / a
        r2 = np.where(qq != 0.0, c / qq, np.nan)
        return [r1[:, None], r2[:, None]]
