"""Fast exact centroid for partition-style outputs, and a pure-Python scalar evaluator.

Used by :mod:`fuzzkit.fuzzy.inference` when the output uses min implication, max aggregation and
centroid, and no point of the output range lies in more than two terms (every partition).
Then, pointwise, ``max_k g_k = sum_k g_k - sum_{i<j} min(g_i, g_j)`` with
``g_k = min(L_k, mu_k)`` and ``min(g_i, g_j) = min(min(L_i, L_j), min(mu_i, mu_j))``: every
addend is a *fixed* piecewise-linear function ``phi`` clipped at a level ``L``.

For such a function the area ``A(L) = int min(L, phi)`` and moment ``M(L) = int y min(L, phi)``
are exactly polynomials in ``L`` (degree 2 and 3) between consecutive vertex values of ``phi``:
inside such an interval of levels, every edge of ``phi`` is either entirely below ``L``, entirely
above it, or crossed once at a point linear in ``L``. So the centroid reduces to evaluating a
few cubic polynomials: the tables are built once by sampling the closed-form segment integrals
at four levels per piece (a cubic through four exact values is the cubic), and checked at a
fifth level.
"""

from __future__ import annotations

import bisect
import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]


@dataclass(frozen=True, slots=True)
class Segment:
    """A linear piece of a fixed function: from ``(x0, v0)`` to ``(x1, v1)``."""

    x0: float
    x1: float
    v0: float
    v1: float
    function: int  # column of the level vector (a term, or a pair after the terms)
    sign: float  # +1 for a term, -1 for a pair overlap


def clipped_integrals(
    x0: FloatArray, x1: FloatArray, v0: FloatArray, v1: FloatArray, level: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Exact ``int min(L, v)`` and ``int y min(L, v)`` over linear segments (broadcast)."""
    h = x1 - x0
    dv = v1 - v0
    inv_dv = np.where(dv != 0.0, 1.0 / np.where(dv != 0.0, dv, 1.0), 0.0)
    # t: fraction of the segment before the edge meets the level (0 or 1 when it does not)
    t = np.clip((level - v0) * inv_dv, 0.0, 1.0)
    fa = np.minimum(level, v0)
    fb = np.minimum(level, v1)
    fc = np.minimum(level, v0 + t * dv)
    left = t * h
    right = h - left
    xc = x0 + left
    area = 0.5 * (left * (fa + fc) + right * (fc + fb))
    # moment of a linear piece [p, q]: (q - p)/6 (p (2 f_p + f_q) + q (f_p + 2 f_q))
    moment = (
        left * (x0 * (2 * fa + fc) + xc * (fa + 2 * fc))
        + right * (xc * (2 * fc + fb) + x1 * (fc + 2 * fb))
    ) / 6.0
    return area, moment


@dataclass(frozen=True)
class _PiecewiseCubic:
    """``A(L)`` and ``M(L)`` of one clipped function as cubics in a local variable per piece."""

    starts: tuple[float, ...]
    inv_width: tuple[float, ...]
    area: tuple[tuple[float, float, float, float], ...]  # c0..c3 per piece
    moment: tuple[tuple[float, float, float, float], ...]


_FIT_NODES = np.array([0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0])
_VANDERMONDE_INV = np.linalg.inv(np.vander(_FIT_NODES, 4, increasing=True))


def _fit_function(segs: Sequence[Segment]) -> _PiecewiseCubic:
    x0 = np.array([s.x0 for s in segs])
    x1 = np.array([s.x1 for s in segs])
    v0 = np.array([s.v0 for s in segs])
    v1 = np.array([s.v1 for s in segs])
    top = float(max(v0.max(), v1.max()))
    # vertex values that differ only by rounding (k/3 arithmetic) are one knot; the first
    # piece always starts at level 0
    knots = [0.0]
    for v in sorted(float(v) for v in np.concatenate([v0, v1, [top]])):
        if v - knots[-1] > 1e-12:
            knots.append(v)
    knots[-1] = max(knots[-1], top)
    starts, inv_w, ca, cm = [], [], [], []
    for a, b in [*itertools.pairwise(knots), (knots[-1], knots[-1] + 1.0)]:
        levels = a + (b - a) * _FIT_NODES
        ar, mo = clipped_integrals(x0[:, None], x1[:, None], v0[:, None], v1[:, None], levels)
        coef_a = _VANDERMONDE_INV @ ar.sum(axis=0)
        coef_m = _VANDERMONDE_INV @ mo.sum(axis=0)
        # a cubic through four exact values is exact: confirm at a fifth level
        s_chk = 0.5 + 1 / 7
        ar5, mo5 = clipped_integrals(x0, x1, v0, v1, np.array(a + (b - a) * s_chk))
        for coef, parts in ((coef_a, ar5), (coef_m, mo5)):
            got = float(np.polynomial.polynomial.polyval(s_chk, coef))
            # rounding scales with the addends, not with their (possibly cancelling) sum
            if abs(got - float(parts.sum())) > 1e-11 * max(1.0, float(np.abs(parts).sum())):
                raise RuntimeError("centroid tables: clipped integral is not cubic in the level")
        starts.append(a)
        inv_w.append(1.0 / (b - a))
        ca.append(tuple(float(c) for c in coef_a))
        cm.append(tuple(float(c) for c in coef_m))
    return _PiecewiseCubic(tuple(starts), tuple(inv_w), tuple(ca), tuple(cm))  # type: ignore[arg-type]


class PolyCentroid:
    """Centroid of a partition-style aggregated output from its per-term levels.

    The segments are given in unit coordinates ``(y - low) / width`` so the tables are equally
    well conditioned whatever the output's units; results are mapped back.
    """

    def __init__(
        self,
        segments: Sequence[Segment],
        pairs: Sequence[tuple[int, int]],
        n_terms: int,
        low: float = 0.0,
        width: float = 1.0,
    ) -> None:
        self.n_terms = n_terms
        self.low = low
        self.width = width
        self.pairs = tuple(pairs)
        n_funcs = n_terms + len(pairs)
        by_func: dict[int, list[Segment]] = {}
        for s in segments:
            by_func.setdefault(s.function, []).append(s)
        self.functions = [
            (f, by_func[f][0].sign, _fit_function(by_func[f]))
            for f in range(n_funcs)
            if f in by_func
        ]
        p_max = max(len(pc.starts) for _, _, pc in self.functions)
        nf = len(self.functions)
        self.func_index = np.array([f for f, _, _ in self.functions], dtype=np.intp)
        self.sign = np.array([s for _, s, _ in self.functions])
        self.starts = np.full((nf, p_max), np.inf)
        self.inv_w = np.ones((nf, p_max))
        self.ca = np.zeros((nf, p_max, 4))
        self.cm = np.zeros((nf, p_max, 4))
        for k, (_, _, pc) in enumerate(self.functions):
            n = len(pc.starts)
            self.starts[k, :n] = pc.starts
            self.inv_w[k, :n] = pc.inv_width
            self.ca[k, :n] = pc.area
            self.cm[k, :n] = pc.moment
        self.flat_offset = (np.arange(nf) * p_max)[None, :]
        self.p_max = p_max
        self.pair_i = np.array([i for i, _ in pairs], dtype=np.intp)
        self.pair_j = np.array([j for _, j in pairs], dtype=np.intp)
        # scalar path: per function, plain Python tuples
        self.scalar_funcs = [
            (f, s, list(pc.starts), pc.inv_width, pc.area, pc.moment) for f, s, pc in self.functions
        ]

    def area_moment(self, levels: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Total area and moment (B,) for per-term levels (B, T)."""
        lv = np.concatenate(
            [
                levels,
                np.minimum(
                    np.take(levels, self.pair_i, axis=1), np.take(levels, self.pair_j, axis=1)
                ),
            ],
            axis=1,
        )
        lev = np.take(lv, self.func_index, axis=1)  # (B, F)
        piece = (lev[:, :, None] >= self.starts[None, :, 1:]).sum(axis=2)  # (B, F)
        flat = piece + self.flat_offset
        s = (lev - np.take(self.starts.reshape(-1), flat)) * np.take(self.inv_w.reshape(-1), flat)
        ca = self.ca.reshape(-1, 4)
        cm = self.cm.reshape(-1, 4)
        area = np.take(ca[:, 3], flat)
        moment = np.take(cm[:, 3], flat)
        for k in (2, 1, 0):
            area = area * s + np.take(ca[:, k], flat)
            moment = moment * s + np.take(cm[:, k], flat)
        return area @ self.sign, moment @ self.sign

    def centroid(self, levels: FloatArray, default: float) -> FloatArray:
        """Centroid (B,) in output units; ``default`` where nothing fired."""
        area, moment = self.area_moment(levels)
        unit = np.divide(moment, area, out=np.full_like(area, np.nan), where=area > 1e-300)
        return np.where(area > 1e-300, self.low + self.width * unit, default)

    def centroid_scalar(self, levels: Sequence[float], default: float) -> float:
        """Centroid of one point in output units; ``default`` where nothing fired."""
        area, moment = self.area_moment_scalar(levels)
        return self.low + self.width * (moment / area) if area > 1e-300 else default

    def area_moment_scalar(self, levels: Sequence[float]) -> tuple[float, float]:
        """Area and moment for one point's per-term levels, in plain Python."""
        pi, pj = self.pairs, self.n_terms
        area = moment = 0.0
        for f, sign, starts, inv_w, ca, cm in self.scalar_funcs:
            lev = levels[f] if f < pj else min(levels[pi[f - pj][0]], levels[pi[f - pj][1]])
            if lev <= 0.0:
                continue
            k = max(0, bisect.bisect_right(starts, lev) - 1)
            s = (lev - starts[k]) * inv_w[k]
            a0, a1, a2, a3 = ca[k]
            m0, m1, m2, m3 = cm[k]
            area += sign * (((a3 * s + a2) * s + a1) * s + a0)
            moment += sign * (((m3 * s + m2) * s + m1) * s + m0)
        return area, moment


@dataclass(frozen=True)
class ScalarInput:
    """One input's piecewise-linear terms in trapezoid form, for the scalar path.

    ``cuts`` are the sorted term vertices; ``candidates[i]`` lists (index, form) of the terms
    that can be non-zero for ``cuts[i-1] <= x < cuts[i]`` (``i = bisect_right(cuts, x)``), so a
    call evaluates only the two or three terms that matter instead of all of them.
    """

    low: float
    high: float
    clamp: bool
    cuts: tuple[float, ...]
    candidates: tuple[tuple[tuple[int, tuple[float, float, float, float]], ...], ...]


def scalar_input(
    low: float,
    high: float,
    clamp: bool,
    forms: Sequence[tuple[float, float, float, float]],
    vertices: Sequence[float],
) -> ScalarInput:
    """Build a :class:`ScalarInput`: which terms can be non-zero between consecutive vertices."""

    def grade(form: tuple[float, float, float, float], x: float) -> float:
        b, c, sr, sf = form
        return min(1.0 + (x - b) * sr, 1.0 + (c - x) * sf)

    cuts = sorted(set(vertices))
    edges = [cuts[0] - 1.0, *cuts, cuts[-1] + 1.0]
    candidates = []
    for i in range(len(cuts) + 1):
        a, b = edges[i], edges[i + 1]
        # terms are linear strictly inside (a, b); the left end belongs to this interval
        probes = [a, a + 0.25 * (b - a), a + 0.5 * (b - a), a + 0.75 * (b - a)]
        if i == 0:
            probes = probes[1:]
        candidates.append(
            tuple((k, f) for k, f in enumerate(forms) if any(grade(f, x) > 0.0 for x in probes))
        )
    return ScalarInput(low, high, clamp, tuple(cuts), tuple(candidates))


class ScalarPath:
    """Pure-Python single-point evaluation for the commonest controller shape.

    Applies when every input term is piecewise linear, every rule is an AND of exactly one
    non-negated proposition per input, and every output uses :class:`PolyCentroid`. It touches
    only the terms with non-zero membership and the rules they can fire (at most 2^n for n
    inputs over a partition), so a call costs microseconds where numpy's per-call overhead
    would cost tens.
    """

    def __init__(
        self,
        inputs: Sequence[ScalarInput],
        rules: dict[tuple[int, ...], list[tuple[float, tuple[tuple[int, int], ...]]]],
        product_and: bool,
        outputs: Sequence[tuple[PolyCentroid, int, float]],
    ) -> None:
        self.inputs = list(inputs)
        self.rules = rules
        self.product_and = product_and
        self.outputs = list(outputs)  # (centroid tables, number of terms, default)

    def __call__(self, values: Sequence[float]) -> list[float]:
        actives: list[list[tuple[int, float]]] = []
        for inp, x in zip(self.inputs, values, strict=True):
            if x != x:  # NaN: never a correction
                return [math.nan] * len(self.outputs)
            if inp.clamp:
                x = inp.low if x < inp.low else inp.high if x > inp.high else x
            else:
                x = -1e100 if x < -1e100 else 1e100 if x > 1e100 else x
            act = []
            for k, (b, c, sr, sf) in inp.candidates[bisect.bisect_right(inp.cuts, x)]:
                rise = 1.0 + (x - b) * sr
                fall = 1.0 + (c - x) * sf
                m = rise if rise < fall else fall
                if m > 0.0:
                    act.append((k, m if m < 1.0 else 1.0))
            actives.append(act)
        levels = [[0.0] * n for _, n, _ in self.outputs]
        rules = self.rules
        if len(actives) == 2:  # the common controller shape: plain loops, no tuples of tuples
            prod = self.product_and
            for k0, m0 in actives[0]:
                for k1, m1 in actives[1]:
                    hit = rules.get((k0, k1))
                    if hit is None:
                        continue
                    strength = m0 * m1 if prod else (m0 if m0 < m1 else m1)
                    for weight, consequents in hit:
                        fired = strength * weight
                        for o, t in consequents:
                            if fired > levels[o][t]:
                                levels[o][t] = fired
        else:
            for combo in itertools.product(*actives):
                hit = rules.get(tuple(k for k, _ in combo))
                if hit is None:
                    continue
                if self.product_and:
                    strength = math.prod(m for _, m in combo)
                else:
                    strength = min(m for _, m in combo)
                for weight, consequents in hit:
                    fired = strength * weight
                    for o, t in consequents:
                        if fired > levels[o][t]:
                            levels[o][t] = fired
        result = []
        for (poly, _, default), lv in zip(self.outputs, levels, strict=True):
            result.append(poly.centroid_scalar(lv, default))
        return result
