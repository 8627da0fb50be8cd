"""Sound enclosures of a two-input rule base's exact surface and its slopes over rectangles.

For each rectangle ``[x0, x1] x [y0, y1]`` of the (clipped) inputs, :meth:`Enclosure.enclose`
returns intervals holding ``F``, ``dF/dx`` and ``dF/dy`` at every point of the rectangle, kinks
included (the hull of the one-sided slopes: Clarke's generalised gradient). The route:

1. **Firing strengths.** Each term's membership and slope over the rectangle's side
   (:mod:`fuzzkit.analysis.term_intervals`); a rule's strength ``alpha = AND(mu...)`` times its
   weight: ``min`` (its slope in the hull of the slopes of the terms that can be the minimum)
   or ``product`` (the product rule).
2. **Output stage**, by its closed-form derivative in the firing levels:

   * *centroid* (Mamdani, max aggregation with min or product implication, or bounded sum
     with product implication): the output term ``t``'s level ``L_t`` (the max, or the sum, of
     its rules' strengths) moves ``F = N / D`` (``N = int y mu``, ``D = int mu``) by
     ``dF/dL_t = int (y - F) dmu/dL_t dy / D`` (Leibniz: ``mu`` is continuous in ``y`` and
     ``L``, so no boundary term). ``dmu/dL_t`` is 1 where ``t`` is the largest clipped term and
     ``C_t(y) > L_t`` (min implication), ``C_t(y)`` where ``L_t C_t`` is the largest (product),
     ``C_t(y)`` where the bounded sum is below 1. The output axis is cut into bins between the
     terms' kinks and peaks, on which each ``C_t`` is monotone: per bin ``dmu/dL_t`` lies in
     ``[0 or its certain value, 0 or its possible value]``, and ``y - F`` in
     ``[y0 - F_hi, y1 - F_lo]``. ``D`` and ``N`` are bounded the same way from ``mu`` between
     its values at the lowest and highest levels. On the bins where a bounded sum with
     product implication is surely below 1, ``mu = sum_t L_t C_t`` is linear in the levels:
     there ``N`` and ``D`` take ``sum_t L_t`` times the term's own integrals (closed form, each
     term being linear on each bin) and ``dF/dL_t`` their part ``n_t - F d_t`` exactly, with no
     bin-width term.
   * *weighted average* (a Mamdani output's term centres, or Sugeno constant or linear
     terms): ``F = sum w z / sum w``, ``dF = (sum dw (z - F) + sum w dz) / sum w``, and ``F`` in
     the hull of the ``z`` (a convex combination).

3. ``dF/dx = sum_t dF/dL_t dL_t/dx`` in interval arithmetic, every operation rounded outwards
   (:mod:`fuzzkit.analysis.intervals`; a sum of ``n`` doubles is widened by ``n`` eps times
   the sum of magnitudes, the bound of recursive summation).

The enclosure bounds the real-valued function the engine's formulas define; the engine's own
floating-point result differs from it by rounding (relative 1e-15 of the output range for the
closed-form centroids). :func:`why_unsupported` names what has no enclosure here (other shapes,
smooth output terms,
OR or nested conditions, bisector and maxima defuzzifiers, grid-integrated smooth outputs,
other aggregations): such a surface is not covered and nothing is certified on it.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import cast

import numpy as np
import numpy.typing as npt

from fuzzkit.analysis.intervals import EPS, FloatArray, Interval, dot, down, sum_outward, up
from fuzzkit.analysis.switch_lines import refine
from fuzzkit.analysis.term_intervals import breakpoints, enclose, supported, value_bounds
from fuzzkit.fuzzy import membership
from fuzzkit.fuzzy.model import Compound, Proposition, RuleBase

#: Bins of the output axis (besides the terms' kinks and peaks) for the centroid's integrals.
OUTPUT_BINS = 256
#: Levels (in [0, 1]) at one point closer than this are not ordered (rounding).
ORDER_MARGIN = 1e-12
BoolArray = npt.NDArray[np.bool_]
IntArray = npt.NDArray[np.intp]
#: Rectangles per chunk of the centroid's (rectangles x terms x bins) arrays.
_CHUNK = 128


@dataclass(frozen=True, slots=True)
class CellEnclosure:
    """``F``, ``dF/dx``, ``dF/dy`` over each rectangle (arrays of one length)."""

    f: Interval
    gx: Interval
    gy: Interval
    #: ``dF/dL_t`` per output term, (n, T) (the centroid only; None otherwise)
    dfdl: Interval | None = None


def _propositions(expr: object) -> list[Proposition] | None:
    if isinstance(expr, Proposition):
        return [expr]
    if isinstance(expr, Compound) and expr.op == "and":
        props = [e for e in expr.operands if isinstance(e, Proposition)]
        return props if len(props) == len(expr.operands) else None
    return None


def why_unsupported(rb: RuleBase) -> str | None:
    """Why this rule base's surface has no sound enclosure here (None: it has one)."""
    out = rb.outputs[0]
    for var in rb.inputs:
        for t in var.terms:
            if not supported(t):
                return f"input term {var.name}.{t.name} is a {t.shape} (no sound enclosure yet)"
    for i, rule in enumerate(rb.rules):
        if _propositions(rule.antecedent) is None:
            return f"rule {i + 1} has an OR or a nested condition (no sound enclosure yet)"
    ops = rb.operators
    if out.is_sugeno:
        if rb.defuzzifier != "weighted_average":
            return f"Sugeno {rb.defuzzifier} (no sound enclosure yet)"
        return None
    if rb.defuzzifier == "weighted_average":
        if ops.aggregation != "max":
            return f"weighted average with {ops.aggregation} aggregation (no enclosure yet)"
        return None
    if rb.defuzzifier != "centroid":
        return f"the {rb.defuzzifier} defuzzifier (no sound enclosure yet)"
    if not (
        ops.aggregation == "max"
        or (ops.aggregation == "bounded_sum" and ops.implication == "product")
    ):
        return (
            f"{ops.aggregation} aggregation with {ops.implication} implication (no sound "
            "enclosure yet)"
        )
    for t in out.terms:
        # smooth output terms: the engine integrates them in closed form (all-Gaussian, max)
        # or on a grid; their enclosure is not tested against it yet
        if not (t.is_piecewise_linear and supported(t, out.low, out.high)):
            return f"output term {out.name}.{t.name} is a {t.shape} (no sound enclosure yet)"
    return None


@dataclass(frozen=True, slots=True)
class _Rule:
    props: tuple[tuple[int, int, bool], ...]  # (input, term, negated)
    weight: float
    consequent: int  # output term index


class Enclosure:
    """The enclosures of one rule base's surface (inputs in role order; see module doc);
    ``bins``: the output axis's bins (the value enclosure's resolution, about one bin's
    width)."""

    def __init__(self, rb: RuleBase, bins: int = OUTPUT_BINS) -> None:
        why = why_unsupported(rb)
        if why is not None:
            raise ValueError(why)
        self.rb = rb
        out = rb.outputs[0]
        pos = {v.name: i for i, v in enumerate(rb.inputs)}
        rules = []
        for rule in rb.rules:
            props = _propositions(rule.antecedent) or []
            for c in rule.consequents:
                if c.variable == out.name:
                    rules.append(
                        _Rule(
                            tuple(
                                (
                                    pos[p.variable],
                                    rb.input(p.variable).term_index(p.term),
                                    p.negated,
                                )
                                for p in props
                            ),
                            float(rule.weight),
                            out.term_index(c.term),
                        )
                    )
        self.rules = tuple(rules)
        self.and_min = rb.operators.and_ == "min"
        self.out = out
        self.bins = bins
        #: every input term is piecewise linear: affine inside a rectangle between kinks
        self.affine_inputs = all(t.is_piecewise_linear for v in rb.inputs for t in v.terms)

    def input_kinks(self, axis: int) -> FloatArray:
        """The input terms' kinks on ``axis`` inside (-1, 1) (rectangles are cut at them)."""
        pts = [p for t in self.rb.inputs[axis].terms for p in breakpoints(t)]
        return np.unique([p for p in pts if -1.0 < p < 1.0])

    # ------------------------------------------------------------------ firing
    def firing(
        self, x0: FloatArray, x1: FloatArray, y0: FloatArray, y1: FloatArray
    ) -> list[tuple[Interval, Interval, Interval]]:
        """Per rule: its weighted strength and its slopes along x and y."""
        sides = ((x0, x1), (y0, y1))
        terms: dict[tuple[int, int], tuple[Interval, Interval]] = {}
        zero = Interval.point(np.zeros_like(x0))
        out = []
        for rule in self.rules:
            parts = []
            for i, t, neg in rule.props:
                if (i, t) not in terms:
                    terms[(i, t)] = enclose(self.rb.inputs[i].terms[t], *sides[i])
                v, d = terms[(i, t)]
                if neg:
                    one = Interval.point(np.ones_like(x0))
                    v, d = one - v, -d
                parts.append((v, d, i))
            alpha, slopes = self._and(parts, zero)
            w = np.full_like(x0, rule.weight)
            out.append((alpha.scale(w), slopes[0].scale(w), slopes[1].scale(w)))
        return out

    def _and(
        self, parts: list[tuple[Interval, Interval, int]], zero: Interval
    ) -> tuple[Interval, tuple[Interval, Interval]]:
        if not parts:
            return Interval.point(np.ones_like(zero.lo)), (zero, zero)
        # a term that is 0 on the whole rectangle makes the rule 0 there: no slope
        off = np.any([v.hi == 0.0 for v, _, _ in parts], axis=0)
        alpha, (gx, gy) = self._and_parts(parts, zero)
        return Interval(np.where(off, 0.0, alpha.lo), np.where(off, 0.0, alpha.hi)), (
            Interval(np.where(off, 0.0, gx.lo), np.where(off, 0.0, gx.hi)),
            Interval(np.where(off, 0.0, gy.lo), np.where(off, 0.0, gy.hi)),
        )

    def _and_parts(
        self, parts: list[tuple[Interval, Interval, int]], zero: Interval
    ) -> tuple[Interval, tuple[Interval, Interval]]:
        if self.and_min:
            lo = np.min([v.lo for v, _, _ in parts], axis=0)
            hi = np.min([v.hi for v, _, _ in parts], axis=0)
            slopes = []
            for axis in (0, 1):
                s_lo, s_hi = np.full_like(lo, np.inf), np.full_like(lo, -np.inf)
                for v, d, i in parts:
                    can = v.lo <= hi  # this term can be the minimum
                    dl, dh = (d.lo, d.hi) if i == axis else (zero.lo, zero.hi)
                    s_lo = np.where(can, np.minimum(s_lo, dl), s_lo)
                    s_hi = np.where(can, np.maximum(s_hi, dh), s_hi)
                slopes.append(Interval(s_lo, s_hi))
            return Interval(lo, hi), (slopes[0], slopes[1])
        alpha = parts[0][0]
        for v, _, _ in parts[1:]:
            alpha = alpha * v
        alpha = Interval(np.maximum(alpha.lo, 0.0), alpha.hi)
        grads = []
        for axis in (0, 1):
            g = zero
            for k, (_, d, i) in enumerate(parts):
                if i != axis:
                    continue
                term = d
                for m, (v, _, _) in enumerate(parts):
                    if m != k:
                        term = term * v
                g = g + term
            grads.append(g)
        return alpha, (grads[0], grads[1])

    # ------------------------------------------------------------------ output
    def enclose(
        self,
        x0: FloatArray,
        x1: FloatArray,
        y0: FloatArray,
        y1: FloatArray,
        tighten: bool = True,
    ) -> CellEnclosure:
        """``F`` and its slopes over each rectangle ``[x0, x1] x [y0, y1]`` (``tighten``: along
        the switch lines, :mod:`fuzzkit.analysis.switch_lines`; only the slopes change)."""
        with np.errstate(invalid="ignore", over="ignore"):
            return self._enclose(x0, x1, y0, y1, tighten)

    def _enclose(
        self, x0: FloatArray, x1: FloatArray, y0: FloatArray, y1: FloatArray, tighten: bool
    ) -> CellEnclosure:
        firing = self.firing(x0, x1, y0, y1)
        if self.out.is_sugeno or self.rb.defuzzifier == "weighted_average":
            return self._weighted_average(firing, x0, x1, y0, y1)
        parts = [self._centroid(firing, slice(k, k + _CHUNK)) for k in range(0, x0.size, _CHUNK)]
        cells = CellEnclosure(
            *(_concat([getattr(p, a) for p in parts]) for a in ("f", "gx", "gy", "dfdl"))
        )
        if tighten and self.and_min and self.affine_inputs and cells.dfdl is not None:
            gx, gy = refine(
                self, np.stack([x0, x1, y0, y1], 1), firing, cells.gx, cells.gy, cells.dfdl
            )
            cells = CellEnclosure(cells.f, gx, gy, cells.dfdl)
        return cells

    def levels(
        self, firing: list[tuple[Interval, Interval, Interval]], sl: slice
    ) -> tuple[Interval, Interval, Interval]:
        """Per output term (arrays (n, T)): its level and the level's slopes."""
        n_terms = len(self.out.terms)
        n = firing[0][0].lo[sl].size if firing else 0
        lv = [np.zeros((n, n_terms)) for _ in range(6)]
        by_term: dict[int, list[int]] = {}
        for r, rule in enumerate(self.rules):
            by_term.setdefault(rule.consequent, []).append(r)
        summed = self.rb.operators.aggregation != "max"
        for t, rs in by_term.items():
            strengths = [firing[r][0] for r in rs]
            if summed:
                level, gx, gy = firing[rs[0]][0], firing[rs[0]][1], firing[rs[0]][2]
                for r in rs[1:]:
                    level, gx, gy = level + firing[r][0], gx + firing[r][1], gy + firing[r][2]
                level, gx, gy = _sub(level, sl), _sub(gx, sl), _sub(gy, sl)
            else:
                lo = np.max([s.lo[sl] for s in strengths], axis=0)
                hi = np.max([s.hi[sl] for s in strengths], axis=0)
                level = Interval(lo, hi)
                g = []
                for axis in (1, 2):
                    s_lo, s_hi = np.full(n, np.inf), np.full(n, -np.inf)
                    for r in rs:
                        can = firing[r][0].hi[sl] >= lo  # this rule can be the largest
                        d = firing[r][axis]
                        s_lo = np.where(can, np.minimum(s_lo, d.lo[sl]), s_lo)
                        s_hi = np.where(can, np.maximum(s_hi, d.hi[sl]), s_hi)
                    g.append(Interval(s_lo, s_hi))
                gx, gy = g
            for k, part in enumerate((level, gx, gy)):
                lv[2 * k][:, t], lv[2 * k + 1][:, t] = part.lo, part.hi
        return Interval(lv[0], lv[1]), Interval(lv[2], lv[3]), Interval(lv[4], lv[5])

    @cached_property
    def _bins(self) -> tuple[FloatArray, FloatArray, Interval]:
        """Output bins ``(y0, y1)`` and each term's value range on them, (T, B)."""
        out = self.out
        pts = [p for t in out.terms for p in breakpoints(t) if out.low < p < out.high]
        edges = np.union1d(np.linspace(out.low, out.high, self.bins + 1), pts)
        y0, y1 = edges[:-1], edges[1:]
        c = [value_bounds(t, y0, y1) for t in out.terms]
        return y0, y1, Interval(np.array([v.lo for v in c]), np.array([v.hi for v in c]))

    def ordered_dfdl(
        self, firing: list[tuple[Interval, Interval, Interval]], rows: IntArray, at: FloatArray
    ) -> Interval:
        """``dF/dL_t`` (m, T) on the rectangles ``rows`` of ``firing``, on a part of each where
        the levels' order, and which are above 0, is that of ``at`` (m, T), the levels at one
        point of that part (min implication, max aggregation; the caller,
        :mod:`fuzzkit.analysis.switch_lines`, checks that no comparison changes sign there)."""
        # a difference within rounding is no order (the caller's comparisons snap the same)
        order = at[:, :, None] > at[:, None, :] + ORDER_MARGIN
        order |= np.eye(at.shape[1], dtype=bool)[None] & (at[:, :, None] > ORDER_MARGIN)
        sub = [(_rows(a, rows), _rows(gx, rows), _rows(gy, rows)) for a, gx, gy in firing]
        parts = []
        for k in range(0, rows.size, _CHUNK):
            sl = slice(k, k + _CHUNK)
            parts.append(cast(Interval, self._centroid(sub, sl, order[sl]).dfdl))
        return _concat(parts)

    @cached_property
    def _term_integrals(self) -> tuple[Interval, Interval]:
        """Per output term and bin, (T, B): ``int C_t dy`` and ``int y C_t dy`` (each term is
        linear on each bin: the bins are cut at its kinks)."""
        y0, y1, _ = self._bins
        h = Interval.point(y1 - y0)
        a, b = Interval.point(y0), Interval.point(y1)
        half, sixth = (
            Interval.point(np.full_like(y0, 0.5)),
            Interval(down(np.full_like(y0, 1 / 6)), up(np.full_like(y0, 1 / 6))),
        )
        ic, iyc = [], []
        for t in self.out.terms:
            c0, c1 = value_bounds(t, y0, y0), value_bounds(t, y1, y1)
            ic.append(h * (c0 + c1) * half)
            iyc.append(h * (a * (c0 + c0 + c1) + b * (c0 + c1 + c1)) * sixth)
        return (
            Interval(np.array([v.lo for v in ic]), np.array([v.hi for v in ic])),
            Interval(np.array([v.lo for v in iyc]), np.array([v.hi for v in iyc])),
        )

    def _linear_parts(self, lin: BoolArray) -> tuple[Interval, Interval]:
        """Per rectangle and term, (n, T): the sums of :attr:`_term_integrals` over the bins
        ``lin`` (n, B) marks."""
        ic, iyc = self._term_integrals
        m = lin.astype(np.float64)
        out = []
        for iv in (ic, iyc):
            err = lin.shape[1] * EPS * (m @ np.maximum(np.abs(iv.lo), np.abs(iv.hi)).T)
            out.append(Interval(down(m @ iv.lo.T - err), up(m @ iv.hi.T + err)))
        return out[0], out[1]

    def _centroid(
        self,
        firing: list[tuple[Interval, Interval, Interval]],
        sl: slice,
        order: BoolArray | None = None,
    ) -> CellEnclosure:
        y0, y1, c = self._bins
        h = y1 - y0  # exact: neighbouring doubles of one binade or close ends
        level, lgx, lgy = self.levels(firing, sl)
        clip = self.rb.operators.implication == "min"
        summed = self.rb.operators.aggregation != "max"
        l_lo, l_hi = level.lo[:, :, None], level.hi[:, :, None]  # (n, T, 1)
        c_lo, c_hi = c.lo[None], c.hi[None]  # (1, T, B)
        if clip:
            p_lo, p_hi = np.minimum(l_lo, c_lo), np.minimum(l_hi, c_hi)
        else:
            p_lo, p_hi = down(l_lo * c_lo), up(l_hi * c_hi)
        if summed:
            s = sum_outward(p_lo, p_hi, axis=1)
            mu = Interval(np.minimum(s.lo, 1.0), np.minimum(s.hi, 1.0))
            possible = s.lo <= 1.0  # the sum can be below 1 (where dmu/dL = C)
            certain = s.hi < 1.0
            can = np.broadcast_to(possible[:, None, :], p_lo.shape)
            sure = np.broadcast_to(certain[:, None, :], p_lo.shape)
        else:
            mu = Interval(p_lo.max(axis=1), p_hi.max(axis=1))
            other_lo, other_hi = _others_max(p_lo), _others_max(p_hi)
            can, sure = p_hi >= other_lo, p_lo > other_hi
            if clip:
                can = can & (c_hi > l_lo)  # the clip can be active: C > L
                sure = sure & (c_lo > l_hi)
                if order is not None:
                    can, sure = _ordered(can, sure, order, level, c, p_lo, p_hi)
        # bins where a bounded sum of scaled terms is surely below 1: there mu is linear in the
        # levels, so their part of N and D is sum_t L_t * (the term's own integrals), exactly
        lin = certain if (summed and not clip) else np.zeros(mu.lo.shape, dtype=bool)
        mu_s = Interval(np.where(lin, 0.0, mu.lo), np.where(lin, 0.0, mu.hi))
        hb = np.broadcast_to(h, mu.lo.shape)
        d = sum_outward(down(mu_s.lo * hb), up(mu_s.hi * hb), axis=1)
        d_lin, n_lin = self._linear_parts(lin)
        d = d + dot(level, d_lin)
        bad = ~(d.lo > 0.0)
        d = Interval(np.where(bad, 1.0, d.lo), np.where(bad, 1.0, d.hi))
        f = _centroid_range(mu, y0, y1, h)
        if np.any(lin):
            ym = Interval(np.broadcast_to(y0, hb.shape), np.broadcast_to(y1, hb.shape)) * mu_s
            n_s = sum_outward(down(ym.lo * hb), up(ym.hi * hb), axis=1)
            f = f.intersect((n_s + dot(level, n_lin)).divide_positive(d))
        f = Interval(np.maximum(f.lo, self.out.low), np.minimum(f.hi, self.out.high))
        # dmu/dL_t per bin: [certain value or 0, possible value or 0]
        if clip:
            k_lo, k_hi = sure.astype(np.float64), can.astype(np.float64)
        else:
            k_lo = np.where(sure, c_lo, 0.0)
            k_hi = np.where(can, c_hi, 0.0)
        k_lo, k_hi = np.where(lin[:, None, :], 0.0, k_lo), np.where(lin[:, None, :], 0.0, k_hi)
        f3 = f.lo[:, None, None], f.hi[:, None, None]
        # y - F over the bin; where dmu/dL is exactly 1 on the whole bin (a sure clip), the
        # integral of y over the bin is exact: h * (y0 + y1) / 2
        mid = 0.5 * (y0 + y1)
        exact = clip & (k_lo == 1.0)
        r_lo = np.where(exact, down(mid - f3[1]), down(y0 - f3[1]))
        r_hi = np.where(exact, up(mid - f3[0]), up(y1 - f3[0]))
        prod = Interval(r_lo, r_hi) * Interval(k_lo, k_hi)
        hb3 = np.broadcast_to(h, prod.lo.shape)
        num = sum_outward(down(prod.lo * hb3), up(prod.hi * hb3), axis=2)  # (n, T)
        # the linear bins: dN/dL_t - F dD/dL_t = n_t - F d_t
        num = num + (n_lin - Interval(f.lo[:, None], f.hi[:, None]) * d_lin)
        dfdl = num.divide_positive(Interval(d.lo[:, None], d.hi[:, None]))
        gx = dot(dfdl, lgx)
        gy = dot(dfdl, lgy)
        inf = np.full(f.lo.shape, np.inf)
        # no rule fires somewhere in the rectangle (D can be 0): no bound
        return CellEnclosure(
            Interval(np.where(bad, -inf, f.lo), np.where(bad, inf, f.hi)),
            Interval(np.where(bad, -inf, gx.lo), np.where(bad, inf, gx.hi)),
            Interval(np.where(bad, -inf, gy.lo), np.where(bad, inf, gy.hi)),
            Interval(
                np.where(bad[:, None], -np.inf, dfdl.lo), np.where(bad[:, None], np.inf, dfdl.hi)
            ),
        )

    def _weighted_average(
        self,
        firing: list[tuple[Interval, Interval, Interval]],
        x0: FloatArray,
        x1: FloatArray,
        y0: FloatArray,
        y1: FloatArray,
    ) -> CellEnclosure:
        out = self.out
        n = x0.size
        items: list[tuple[Interval, Interval, Interval, Interval, float, float]] = []
        if out.is_sugeno:
            for r, rule in enumerate(self.rules):
                term = out.terms[rule.consequent]
                if term.shape == "constant":
                    a, b, c0 = 0.0, 0.0, float(term.params[0])
                else:
                    a, b, c0 = (float(p) for p in term.params)
                z = _linear(a, b, c0, x0, x1, y0, y1)
                items.append((firing[r][0], firing[r][1], firing[r][2], z, a, b))
        else:
            level, lgx, lgy = self.levels(firing, slice(0, n))
            for t, term in enumerate(out.terms):
                z = Interval.point(np.full(n, membership.centre(term, out.low, out.high)))
                col = slice(t, t + 1)
                items.append((_col(level, col), _col(lgx, col), _col(lgy, col), z, 0.0, 0.0))
        w = _stack_sum([it[0] for it in items])
        bad = ~(w.lo > 0.0)
        w = Interval(np.where(bad, 1.0, w.lo), np.where(bad, 1.0, w.hi))
        num = _stack_sum([it[0] * it[3] for it in items])
        f = num.divide_positive(w)
        hull = Interval(
            np.min([it[3].lo for it in items], axis=0), np.max([it[3].hi for it in items], axis=0)
        )
        f = f.intersect(hull)
        grads = []
        for axis in (0, 1):
            terms = [(it[1] if axis == 0 else it[2]) * (it[3] - f) for it in items]
            for it in items:
                c = it[4] if axis == 0 else it[5]  # the linear term's own slope
                if c != 0.0:
                    part = it[0].scale(np.full(n, abs(c)))
                    terms.append(part if c > 0.0 else -part)
            grads.append(_stack_sum(terms).divide_positive(w))
        inf = np.full(n, np.inf)
        return CellEnclosure(
            Interval(np.where(bad, -inf, f.lo), np.where(bad, inf, f.hi)),
            *(Interval(np.where(bad, -inf, g.lo), np.where(bad, inf, g.hi)) for g in grads),
        )


def _rows(iv: Interval, rows: IntArray) -> Interval:
    return Interval(iv.lo[rows], iv.hi[rows])


def _sub(iv: Interval, sl: slice) -> Interval:
    return Interval(iv.lo[sl], iv.hi[sl])


def _col(iv: Interval, col: slice) -> Interval:
    return Interval(iv.lo[:, col][:, 0], iv.hi[:, col][:, 0])


def _concat(parts: list[Interval]) -> Interval:
    return Interval(np.concatenate([p.lo for p in parts]), np.concatenate([p.hi for p in parts]))


def _stack_sum(parts: list[Interval]) -> Interval:
    return sum_outward(np.stack([p.lo for p in parts]), np.stack([p.hi for p in parts]), axis=0)


def _centroid_range(mu: Interval, y0: FloatArray, y1: FloatArray, h: FloatArray) -> Interval:
    """The centroids of every set between ``mu.lo`` and ``mu.hi`` (per row; bins ``[y0, y1]``).

    The smallest takes the upper set left of a switch bin and the lower one right of it, the
    largest the reverse (Karnik-Mendel); ``y`` is taken at the bin's lower (upper) end, which
    can only lower (raise) the ratio. Every candidate switch is tried.
    """
    m_lo, m_hi = mu.lo * h, mu.hi * h

    def extreme(left: FloatArray, right: FloatArray, y: FloatArray, pick: str) -> FloatArray:
        zero = np.zeros((left.shape[0], 1))
        num = np.concatenate([zero, np.cumsum(y * left, axis=1)], axis=1)
        num = num + np.concatenate([np.cumsum((y * right)[:, ::-1], axis=1)[:, ::-1], zero], axis=1)
        den = np.concatenate([zero, np.cumsum(left, axis=1)], axis=1)
        den = den + np.concatenate([np.cumsum(right[:, ::-1], axis=1)[:, ::-1], zero], axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):
            if pick == "min":
                out: FloatArray = np.where(den > 0.0, num / den, np.inf).min(axis=1)
            else:
                out = np.where(den > 0.0, num / den, -np.inf).max(axis=1)
        # no set has mass (no rule fires): unbounded (the caller marks it)
        return np.where(np.isfinite(out), out, -np.inf if pick == "min" else np.inf)

    lo = extreme(m_hi, m_lo, y0, "min")
    hi = extreme(m_lo, m_hi, y1, "max")
    # the cumulative sums' rounding: at most (bins + 2) eps of the largest |y| each way
    slack = (y0.size + 2) * EPS * 4.0 * max(float(np.max(np.abs(y0))), float(np.max(np.abs(y1))))
    return Interval(down(lo - slack), up(hi + slack))


def _ordered(
    can: BoolArray,
    sure: BoolArray,
    order: BoolArray,
    level: Interval,
    c: Interval,
    p_lo: FloatArray,
    p_hi: FloatArray,
) -> tuple[BoolArray, BoolArray]:
    """``can`` and ``sure`` (term ``t`` is the largest clipped term and clipped, per bin;
    (n, T, B)) where ``L_s > L_t`` is known for ``order[:, s, t]`` (min implication).

    ``order[:, t, t]``: ``L_t > 0``. ``s`` beats ``t`` in a bin where ``C_s >= L_t`` on all of
    it: there ``min(L_s, C_s) >= min(L_s, L_t) = L_t >= min(L_t, C_t)``. A clipped ``t``
    (``C_t > L_t``) beats every ``s`` with ``L_t > L_s`` (``min(L_s, C_s) <= L_s < L_t``), and
    with ``L_t > 0`` every ``s`` whose term is 0 on the bin.
    """
    n_terms = order.shape[1]
    eye = np.eye(n_terms, dtype=bool)[None]
    higher = order & ~eye
    l_hi = level.hi[:, None, :, None]  # (n, 1, T_t, 1)
    c_lo_s = c.lo[None, :, None, :]  # (1, T_s, 1, B)
    beaten = np.any(higher[..., None] & (c_lo_s >= l_hi), axis=1)  # (n, T_t, B)
    others = ~eye[..., None]  # (1, T_t, T_s, 1)
    positive = np.diagonal(order, axis1=1, axis2=2)[:, :, None, None]  # (n, T_t, 1, 1)
    # every other term s: t is known higher, s is 0 on the bin while t is above 0, or s's
    # clipped value is surely below t's
    below = (
        higher[..., None]
        | (positive & (c.hi[None, None, :, :] <= 0.0))
        | (p_hi[:, None, :, :] < p_lo[:, :, None, :])
    )
    clipped = sure | ((c.lo[None] > level.hi[:, :, None]) & np.all(below | ~others, axis=2))
    return can & ~beaten, clipped & ~beaten


def _others_max(p: FloatArray) -> FloatArray:
    """For each term (axis 1), the largest value over the other terms."""
    order = np.sort(p, axis=1)
    top, second = (
        order[:, -1:, :],
        order[:, -2:-1, :] if p.shape[1] > 1 else np.zeros_like(order[:, -1:, :]),
    )
    # the term holding the top value sees the second; every other term sees the top
    is_top = p >= top
    return np.where(is_top, second, top)


def _linear(
    a: float, b: float, c0: float, x0: FloatArray, x1: FloatArray, y0: FloatArray, y1: FloatArray
) -> Interval:
    """``a x + b y + c0`` over the rectangles."""
    ax = Interval.point(x0).scale(np.full_like(x0, 0.0))  # zero, shaped
    if a != 0.0:
        ax = Interval(down(np.minimum(a * x0, a * x1)), up(np.maximum(a * x0, a * x1)))
    by = Interval.point(np.zeros_like(y0))
    if b != 0.0:
        by = Interval(down(np.minimum(b * y0, b * y1)), up(np.maximum(b * y0, b * y1)))
    return ax + by + Interval.point(np.full_like(x0, c0))
