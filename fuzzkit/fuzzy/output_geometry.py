"""The output stage's geometry: the aggregated output set of every firing and its integrals.

:class:`OutputPieces` maps rules to the output terms they imply; :class:`PiecewiseLinearGeometry`
integrates outputs whose terms are all piecewise linear in closed form, :class:`GridGeometry`
those with smooth terms on a grid; :func:`partition_centroid` is the fast centroid of a
partition-style output. The engine that uses them: :mod:`fuzzkit.fuzzy.inference`.

For outputs whose terms are all piecewise linear (triangle, trapezoid, shoulders) the centroid
and bisector are computed in **closed form**: the output range is cut into elementary intervals
on which every term is linear (term vertices, and for min/max the crossings of term edges), and
inside each interval at the points where an edge meets a firing level (or, for product/max, two
scaled edges meet). Between those points the aggregated set is linear (max or bounded sum; a
bounded sum also gets the points where it reaches 1), or it is a polynomial of known degree
(probabilistic sum); either way Gauss-Legendre quadrature of sufficient order (two nodes for a
line) integrates it exactly. The set is read at those interior nodes only, never at the points
(see :meth:`PiecewiseLinearGeometry.integrals`: at a tiny level the point where an edge meets
it is the edge's foot to the last bit). The only error is floating-point rounding, relative to
the levels (about 1e-15 of the output range however small the firing strengths).

Outputs with smooth terms (gaussian, bell, sigmoid) are integrated on a uniform grid whose
spacing is chosen from an a-priori trapezoid-rule bound (second-derivative and kink terms) so
that the area and moment errors are below 1e-9 of the output range (see :class:`GridGeometry`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from typing import cast

import numpy as np
import numpy.typing as npt

from fuzzkit.fuzzy import membership
from fuzzkit.fuzzy.fastpath import PolyCentroid, Segment
from fuzzkit.fuzzy.model import RuleBase, Variable

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]


def _reduce_columns(values: FloatArray, order: IntArray, starts: IntArray, op: str) -> FloatArray:
    """Reduce groups of columns (``values[:, order]`` cut at ``starts``) with ``op``."""
    cols = np.take(values, order, axis=1)
    if op == "max":
        return np.maximum.reduceat(cols, starts, axis=1)
    if op == "sum":
        return np.add.reduceat(cols, starts, axis=1)
    # probabilistic sum 1 - prod(1 - a): through logs so that it is one reduceat
    with np.errstate(divide="ignore"):
        return -np.expm1(np.add.reduceat(np.log1p(-cols), starts, axis=1))


class OutputPieces:
    """The implied sets of one output as (level, term) pieces.

    With max aggregation (or bounded sum with product implication) the rules of one term
    collapse exactly into one piece per term; otherwise each consequent is its own piece.
    """

    def __init__(self, rb: RuleBase, out: Variable) -> None:
        ops = rb.operators
        inst = [
            (r, out.term_index(c.term))
            for r, rule in enumerate(rb.rules)
            for c in rule.consequents
            if c.variable == out.name
        ]
        self.n_terms = len(out.terms)
        inst.sort(key=lambda rt: rt[1])
        self.inst_rules = np.array([r for r, _ in inst], dtype=np.intp)
        inst_terms = np.array([t for _, t in inst], dtype=np.intp)
        used, starts = np.unique(inst_terms, return_index=True)
        self.used_terms = used.astype(np.intp)
        self.starts = starts.astype(np.intp)
        self.aggregation = ops.aggregation
        self.per_term = ops.aggregation == "max" or (
            ops.aggregation == "bounded_sum" and ops.implication == "product"
        )
        if self.per_term:
            self.piece_term = np.arange(self.n_terms, dtype=np.intp)
        else:
            self.piece_term = inst_terms
        self.n_pieces = len(self.piece_term)
        self.empty = len(inst) == 0

    def levels(self, firing: FloatArray) -> FloatArray:
        """Piece levels (B, K)."""
        if not self.per_term:
            return firing[:, self.inst_rules]
        op = "max" if self.aggregation == "max" else "sum"
        red = _reduce_columns(firing, self.inst_rules, self.starts, op)
        if len(self.used_terms) == self.n_terms:
            return red
        out = np.zeros((firing.shape[0], self.n_terms))
        out[:, self.used_terms] = red
        return out

    def activations(self, firing: FloatArray) -> FloatArray:
        """Per-term activation (B, T): the term's firing strengths aggregated."""
        op = {"max": "max", "bounded_sum": "sum", "probabilistic_sum": "probsum"}[self.aggregation]
        red = _reduce_columns(firing, self.inst_rules, self.starts, op)
        if op == "sum":
            red = np.minimum(red, 1.0)
        out = np.zeros((firing.shape[0], self.n_terms))
        out[:, self.used_terms] = red
        return out


def _probabilistic_sum(parts: FloatArray) -> FloatArray:
    """``1 - prod(1 - p)`` over the last axis, through logs (accurate for small p)."""
    with np.errstate(divide="ignore"):
        return cast(FloatArray, -np.expm1(np.log1p(-np.minimum(parts, 1.0)).sum(axis=-1)))


def _merge_close(z: FloatArray, width: float) -> FloatArray:
    """Sorted breakpoints with near-duplicates (rounding of k/3 and the like) merged."""
    keep = np.concatenate([[True], np.diff(z) > 1e-12 * width])
    return cast(FloatArray, z[keep])


# Gauss-Legendre nodes/weights on [-1, 1] by order.
def _gauss_legendre(n: int) -> tuple[FloatArray, FloatArray]:
    x, w = np.polynomial.legendre.leggauss(n)
    return x.astype(np.float64), w.astype(np.float64)


#: Values within this share of the height count as one maximum: relative, so that a set whose
#: levels are all 1e-20 has maxima as distinct as one whose levels are near 1, and above the
#: noise of an edge read far from 0 (an output range at 1000 with terms 0.1 wide puts 1e-12 of
#: rounding on every membership; an absolute 1e-12 made every point of a tiny set a maximum).
TIE = 1e-10

#: Two Gauss-Legendre nodes: exact for the area and moment of a linear piece.
LINEAR_NODES = _gauss_legendre(2)


class PiecewiseLinearGeometry:
    """Closed-form integration of the aggregated set of a piecewise-linear output."""

    def __init__(
        self,
        rb: RuleBase,
        out: Variable,
        pieces: OutputPieces,
        heights: Sequence[float] | None = None,
    ) -> None:
        """``heights`` scales each term (an IT2 lower set, ``fuzzy.type2_inference``)."""
        self.implication = rb.operators.implication
        self.aggregation = rb.operators.aggregation
        self.heights = None if heights is None else np.asarray(heights, dtype=np.float64)
        lo, hi = out.low, out.high
        zs = {lo, hi}
        for t in out.terms:
            zs.update(v for v in membership.breakpoints(t) if lo < v < hi)
        z = _merge_close(np.array(sorted(zs)), hi - lo)
        if self.implication == "min" and self.aggregation == "max":
            # edges of different terms crossing inside an interval are static breakpoints
            extra = []
            for z0, z1 in itertools.pairwise(z):
                s, c = self._scaled_lines(out, z0, z1)
                for i in range(len(s)):
                    for j in range(i + 1, len(s)):
                        if s[i] != s[j]:
                            y = (c[j] - c[i]) / (s[i] - s[j])
                            if z0 < y < z1:
                                extra.append(y)
            z = _merge_close(np.sort(np.concatenate([z, np.array(extra)])), hi - lo)
        self.z0, self.z1 = z[:-1], z[1:]
        m = len(self.z0)
        slots: list[list[tuple[int, float, float]]] = []
        for k in range(m):
            s, c = self._scaled_lines(out, self.z0[k], self.z1[k])
            active = [
                (p, s[t], c[t])
                for p, t in enumerate(pieces.piece_term)
                if not (s[t] == 0.0 and c[t] == 0.0)
            ]
            slots.append(active)
        kmax = max(1, max(len(a) for a in slots))
        dummy = pieces.n_pieces  # index of an always-zero level column
        self.slot_piece = np.full((m, kmax), dummy, dtype=np.intp)
        self.slope = np.zeros((m, kmax))
        self.icpt = np.zeros((m, kmax))
        for k, active in enumerate(slots):
            for q, (p, s_, c_) in enumerate(active):
                self.slot_piece[k, q] = p
                self.slope[k, q] = s_
                self.icpt[k, q] = c_
        # a sloped line as slope * (y - root): accurate to the last bits near its root, where
        # slope * y + intercept cancels to an absolute 1e-16 (which a level of 1e-20 is not)
        with np.errstate(divide="ignore", invalid="ignore"):
            self.root = np.where(self.slope != 0.0, -self.icpt / self.slope, 0.0)
        self.kmax = kmax
        self.gl = _gauss_legendre(kmax // 2 + 2)

    def _scaled_lines(self, out: Variable, z0: float, z1: float) -> tuple[FloatArray, FloatArray]:
        s, c = self._lines(out, z0, z1)
        if self.heights is None:
            return s, c
        return s * self.heights, c * self.heights

    @staticmethod
    def _lines(out: Variable, z0: float, z1: float) -> tuple[FloatArray, FloatArray]:
        # every term is linear on [z0, z1]: fit it from two interior points (exact)
        ya, yb = z0 + (z1 - z0) / 3, z0 + 2 * (z1 - z0) / 3
        ma = np.array([membership.evaluate_term(t, ya) for t in out.terms], dtype=np.float64)
        mb = np.array([membership.evaluate_term(t, yb) for t in out.terms], dtype=np.float64)
        s = (mb - ma) / (yb - ya)
        s[np.abs(s) < 1e-14] = 0.0
        c = ma - s * ya
        c[np.abs(c) < 1e-14] = 0.0
        return s, c

    @staticmethod
    def _line_values(
        slope: FloatArray, icpt: FloatArray, root: FloatArray, y: FloatArray
    ) -> FloatArray:
        """The lines' values at ``y``, clipped at 0: ``slope * (y - root)``, or a flat one's
        intercept (all broadcast together)."""
        return np.maximum(np.where(slope != 0.0, slope * (y - root), icpt), 0.0)

    def _aggregate(self, y: FloatArray, lv: FloatArray, final: bool = True) -> FloatArray:
        """Aggregated membership at points y (B, m, C), slot levels lv (B, m, K)."""
        ell = self._line_values(
            self.slope[None, :, None, :],
            self.icpt[None, :, None, :],
            self.root[None, :, None, :],
            y[..., None],
        )
        lvb = lv[:, :, None, :]
        imp = np.minimum(lvb, ell) if self.implication == "min" else lvb * ell
        if self.aggregation == "max":
            return cast(FloatArray, imp.max(axis=-1))
        if self.aggregation == "bounded_sum":
            s = imp.sum(axis=-1)
            return cast(FloatArray, np.minimum(s, 1.0) if final else s)
        return _probabilistic_sum(imp)

    def sample_points(self, levels: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Sorted breakpoints (B, m, C) and the slot levels (B, m, K) for these piece levels."""
        b = levels.shape[0]
        lv = np.concatenate([levels, np.zeros((b, 1))], axis=1)[:, self.slot_piece]
        s = self.slope[None]
        c = self.icpt[None]
        r = self.root[None]
        z0 = np.broadcast_to(self.z0[None, :, None], (b, len(self.z0), 1))
        z1 = np.broadcast_to(self.z1[None, :, None], (b, len(self.z0), 1))
        with np.errstate(divide="ignore", invalid="ignore"):
            if self.implication == "min" and self.aggregation == "max":
                cand = r[..., :, None] + lv[:, :, None, :] / s[..., :, None]
                cand = cand.reshape(b, len(self.z0), -1)
            elif self.implication == "min":
                cand = r + lv / s
            elif self.aggregation == "max":
                k = self.kmax
                ii, kk = np.triu_indices(k, 1)
                num = lv[..., kk] * c[..., kk] - lv[..., ii] * c[..., ii]
                den = lv[..., ii] * s[..., ii] - lv[..., kk] * s[..., kk]
                cand = num / den
            else:
                cand = np.empty((b, len(self.z0), 0))
        cand = np.where(np.isfinite(cand), cand, z0)
        cand = np.clip(cand, z0, z1)
        pts = np.sort(np.concatenate([z0, z1, cand], axis=-1), axis=-1)
        if self.aggregation == "bounded_sum":
            # the bounded sum bends where the plain sum reaches 1
            sm = self._aggregate(pts, lv, final=False) - 1.0
            s0, s1 = sm[..., :-1], sm[..., 1:]
            with np.errstate(divide="ignore", invalid="ignore"):
                t = np.where(s0 * s1 < 0, s0 / (s0 - s1), 0.0)
            cross = pts[..., :-1] + t * (pts[..., 1:] - pts[..., :-1])
            pts = np.sort(np.concatenate([pts, cross], axis=-1), axis=-1)
        return pts, lv

    def values_at(self, y: FloatArray, lv: FloatArray) -> FloatArray:
        """The aggregated set at any points ``y`` (B, n) of the range, for the slot levels
        ``lv`` (B, m, K) that :meth:`sample_points` returns."""
        k = np.clip(np.searchsorted(self.z1, y, side="left"), 0, len(self.z0) - 1)
        lvk = lv[np.arange(y.shape[0])[:, None], k]
        ell = self._line_values(self.slope[k], self.icpt[k], self.root[k], y[..., None])
        imp = np.minimum(lvk, ell) if self.implication == "min" else lvk * ell
        if self.aggregation == "max":
            return cast(FloatArray, imp.max(axis=-1))
        if self.aggregation == "bounded_sum":
            return cast(FloatArray, np.minimum(imp.sum(axis=-1), 1.0))
        return _probabilistic_sum(imp)

    def integrals(
        self, levels: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        """Per-segment area and moment (B, S), segment starts/ends (B, S), and the set's values
        at each segment's two ends (B, S, 2).

        The set is read only *inside* segments, at Gauss-Legendre nodes (two for a linear set,
        exact for its area and moment), never at the points themselves: a point where an edge
        meets a tiny level (1e-20) is the edge's foot to the last bit, and the set there reads
        0 instead of the level, which turns a clipped term's flat top into a ramp. The values
        at the ends are the segment's line through its two nodes (a flat top gives its level
        exactly); a probabilistic sum, polynomial between points, gives its values at them.
        """
        pts, lv = self.sample_points(levels)
        b = pts.shape[0]
        p0, p1 = pts[..., :-1], pts[..., 1:]
        h = p1 - p0
        psum = self.aggregation == "probabilistic_sum"
        xg, wg = self.gl if psum else LINEAR_NODES
        mid, half = 0.5 * (p0 + p1), 0.5 * h
        nodes = mid[..., None] + half[..., None] * xg  # (B, m, C-1, n)
        fn = self._aggregate(nodes.reshape(b, nodes.shape[1], -1), lv).reshape(nodes.shape)
        area = half * (fn * wg).sum(-1)
        moment = half * (fn * wg * nodes).sum(-1)
        if psum:
            f = self._aggregate(pts, lv)
            f0, f1 = f[..., :-1], f[..., 1:]
        else:
            f0, f1 = segment_ends(p0, p1, nodes[..., 0], nodes[..., 1], fn[..., 0], fn[..., 1])
            # a crossing rounded by an ulp leaves a kink inside a segment a few ulps wide, and
            # its line overshoots: no value exceeds what the slot levels allow
            top = lv.max(axis=-1) if self.aggregation == "max" else np.minimum(lv.sum(-1), 1.0)
            f0 = np.minimum(f0, top[..., None])
            f1 = np.minimum(f1, top[..., None])
        return (
            area.reshape(b, -1),
            moment.reshape(b, -1),
            p0.reshape(b, -1),
            p1.reshape(b, -1),
            np.stack([f0, f1], axis=-1).reshape(b, -1, 2),
        )

    def bisector(self, levels: FloatArray) -> FloatArray:
        area, _, p0, p1, fv = self.integrals(levels)
        total = area.sum(axis=1)
        half = 0.5 * total
        cum = np.cumsum(area, axis=1)
        idx = np.argmax(cum >= half[:, None] * (1 - 1e-15), axis=1)
        rows = np.arange(area.shape[0])
        r = half - (cum[rows, idx] - area[rows, idx])
        a0, a1 = p0[rows, idx], p1[rows, idx]
        h = a1 - a0
        if self.aggregation != "probabilistic_sum":
            f0, f1 = fv[rows, idx, 0], fv[rows, idx, 1]
            with np.errstate(divide="ignore", invalid="ignore"):
                k = np.where(h > 0, (f1 - f0) / h, 0.0)
                t = 2 * r / (f0 + np.sqrt(np.maximum(f0 * f0 + 2 * k * r, 0.0)))
            t = np.where(np.isfinite(t), np.clip(t, 0.0, h), 0.0)
            return cast(FloatArray, a0 + t)
        # polynomial segment: bisect on the partial integral (exact by Gauss-Legendre)
        lo = np.zeros_like(h)
        hi = h.copy()
        xg, wg = self.gl
        for _ in range(60):
            mid_t = 0.5 * (lo + hi)
            part = self._partial_area(levels, a0, mid_t, xg, wg)
            below = part < r
            lo = np.where(below, mid_t, lo)
            hi = np.where(below, hi, mid_t)
        return cast(FloatArray, a0 + 0.5 * (lo + hi))

    def _partial_area(
        self,
        levels: FloatArray,
        a0: FloatArray,
        t: FloatArray,
        xg: FloatArray,
        wg: FloatArray,
    ) -> FloatArray:
        b = levels.shape[0]
        lv = np.concatenate([levels, np.zeros((b, 1))], axis=1)[:, self.slot_piece]
        # which elementary interval holds the segment: the segment's start lies in it
        interval = np.clip(np.searchsorted(self.z1, a0, side="right"), 0, len(self.z0) - 1)
        interval = np.where(
            (a0 >= self.z1[interval]) & (interval < len(self.z0) - 1), interval + 1, interval
        )
        nodes = a0[:, None] + 0.5 * t[:, None] * (xg + 1.0)  # (B, n)
        lv_i = lv[np.arange(b), interval][:, None, None, :]  # (B,1,1,K)
        y = nodes[:, None, :]  # (B,1,n)
        ell = self._line_values(
            self.slope[interval][:, None, None, :],
            self.icpt[interval][:, None, None, :],
            self.root[interval][:, None, None, :],
            y[..., None],
        )
        imp = np.minimum(lv_i, ell) if self.implication == "min" else lv_i * ell
        f = _probabilistic_sum(imp)[:, 0, :]
        return cast(FloatArray, 0.5 * t * (f * wg).sum(-1))

    def maxima(self, levels: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Height, smallest and largest point of maximum (B,).

        A linear set's values at the points are its segments' ends (see :meth:`integrals`), so
        a clipped term's flat top starts where its edge meets the level even when that level
        is tiny; a probabilistic sum is read at the points.
        """
        if self.aggregation == "probabilistic_sum":
            pts, lv = self.sample_points(levels)
            b = pts.shape[0]
            f = self._aggregate(pts, lv).reshape(b, -1)
            y = pts.reshape(b, -1)
        else:
            _, _, p0, p1, fv = self.integrals(levels)
            f = fv.reshape(fv.shape[0], -1)
            y = np.stack([p0, p1], axis=-1).reshape(f.shape)
        height = f.max(axis=1)
        at_max = f >= height[:, None] * (1.0 - TIE)  # relative: the levels may be tiny
        som = np.where(at_max, y, np.inf).min(axis=1)
        lom = np.where(at_max, y, -np.inf).max(axis=1)
        return height, som, lom


def segment_ends(
    p0: FloatArray, p1: FloatArray, g0: FloatArray, g1: FloatArray, f0: FloatArray, f1: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """A linear segment's values at its ends ``p0``, ``p1`` from its values ``f0``, ``f1`` at
    two interior nodes ``g0 < g1`` (the line through them; a zero-width segment: the node's)."""
    d = g1 - g0
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = np.where(d > 0, (f1 - f0) / d, 0.0)
    return f0 - (g0 - p0) * slope, f1 + (p1 - g1) * slope


def partition_centroid(
    geo: PiecewiseLinearGeometry, rb: RuleBase, n_terms: int
) -> PolyCentroid | None:
    """Centroid tables when at most two terms overlap anywhere (see
    :mod:`fuzzkit.fuzzy.fastpath`)."""
    ops = rb.operators
    if not (ops.implication == "min" and ops.aggregation == "max" and geo.kmax <= 2):
        return None
    segs: list[Segment] = []
    pairs: dict[tuple[int, int], int] = {}
    low, width = float(geo.z0[0]), float(geo.z1[-1] - geo.z0[0])
    for k in range(len(geo.z0)):
        z0, z1 = float(geo.z0[k]), float(geo.z1[k])
        u0, u1 = (z0 - low) / width, (z1 - low) / width
        vals = {}
        for q in range(geo.kmax):
            t = int(geo.slot_piece[k, q])
            if t >= n_terms:
                continue
            v0 = max(0.0, float(geo.slope[k, q] * z0 + geo.icpt[k, q]))
            v1 = max(0.0, float(geo.slope[k, q] * z1 + geo.icpt[k, q]))
            vals[t] = (v0, v1)
            segs.append(Segment(u0, u1, v0, v1, t, 1.0))
        if len(vals) == 2:
            ti, tj = sorted(vals)
            col = pairs.setdefault((ti, tj), n_terms + len(pairs))
            v0 = min(vals[ti][0], vals[tj][0])
            v1 = min(vals[ti][1], vals[tj][1])
            segs.append(Segment(u0, u1, v0, v1, col, -1.0))
    return PolyCentroid(segs, list(pairs), n_terms, low, width)


class GridGeometry:
    """Grid integration of an output with smooth terms, spacing from an a-priori bound.

    The trapezoid rule's error on a cell is at most ``h^3 M2 / 12`` where the aggregated set is
    twice differentiable with ``|f''| <= M2``, and at most ``L h^2 / 4`` on a cell holding a
    kink (``|f'| <= L``). With at most ``n_kinks`` kinks the total error is below
    ``W h^2 M2 / 12 + n_kinks L h^2 / 4`` (``W`` the range width); ``h`` is chosen to keep it
    under 1e-9 W for the area (the moment's bound is the same times max |y|).
    """

    tolerance = 1e-9
    max_points = 1 << 20
    #: Points of the fine probe the derivative bounds are read on, per term.
    probe_points = 200_001

    def __init__(self, rb: RuleBase, out: Variable, pieces: OutputPieces) -> None:
        self.implication = rb.operators.implication
        self.aggregation = rb.operators.aggregation
        lo, hi = out.low, out.high
        width = hi - lo
        probe = np.linspace(lo, hi, self.probe_points)
        dh = probe[1] - probe[0]
        m2 = 0.0
        l1 = 0.0
        for t in out.terms:
            mu = membership.evaluate_term(t, probe)
            d1 = np.gradient(mu, dh)
            l1 = max(l1, float(np.max(np.abs(d1))))
            if not t.is_piecewise_linear:
                m2 = max(m2, float(np.max(np.abs(np.gradient(d1, dh)))))
        n_terms, n_pieces = len(out.terms), pieces.n_pieces
        n_kinks = 4 * (n_terms + n_pieces) ** 2
        coeff = width * m2 / 12 + n_kinks * l1 / 4
        h = math.sqrt(self.tolerance * width / max(coeff, 1e-300))
        n = int(min(self.max_points, max(1025, math.ceil(width / h) + 1)))
        self.y = np.linspace(lo, hi, n)
        self.dy = self.y[1] - self.y[0]
        mus = np.stack([membership.evaluate_term(t, self.y) for t in out.terms], axis=1)
        # piece-major (K, N): the compiled integration reads only the firing pieces' rows
        self.piece_mu_t = np.ascontiguousarray(mus[:, pieces.piece_term].T)
