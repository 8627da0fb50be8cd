"""The exact engine (Mamdani and Sugeno outputs), vectorised over numpy arrays.

``Engine(rb).evaluate({"e": e, "de": de})`` evaluates a rule base at any number of points at
once (inputs are broadcast together); :func:`evaluate` and :func:`evaluate_point` are the
one-call conveniences.

Exactness
---------
For outputs whose terms are all piecewise linear (triangle, trapezoid, shoulders) the centroid
and bisector are computed in **closed form**: the output range is cut into elementary intervals
on which every term is linear (term vertices, and for min/max the crossings of term edges), and
inside each interval at the points where an edge meets a firing level (or, for product/max, two
scaled edges meet). Between those points the aggregated set is linear (max or bounded sum; a
bounded sum also gets the points where it reaches 1) and is integrated exactly by the trapezoid
and moment formulas, or it is a polynomial of known degree (probabilistic sum) and is integrated
exactly by Gauss-Legendre quadrature of sufficient order. The only error is floating-point
rounding (about 1e-15 of the output range).

Outputs with smooth terms (gaussian, bell, sigmoid) are integrated on a uniform grid whose
spacing is chosen from an a-priori trapezoid-rule bound (second-derivative and kink terms) so
that the area and moment errors are below 1e-9 of the output range (see ``_GridGeometry``).

Semantics
---------
* A NaN in any input makes every output NaN at that point: a bad sensor sample never becomes a
  correction. Infinite inputs are clamped like any out-of-range input under ``clamp``.
* ``out_of_range: clamp`` (default) evaluates memberships at the nearest range end;
  ``extend`` evaluates them where the input is.
* Rules sharing a consequent are aggregated with the aggregation operator, never overwritten.
* When no rule fires (zero area or zero total activation) an output takes its ``default``
  (NaN when none is given).
* Weighted average (paper eq. 10): ``sum(a_j c_j) / sum(a_j)`` over the output terms, with
  ``a_j`` the term's activation (its rules' firing strengths aggregated with the aggregation
  operator) and ``c_j`` the term centre of :func:`fuzzkit.fuzzy.membership.centre`.
* Mean of maximum is the midpoint of the smallest and largest of maximum (as in fuzzylite).
* Sugeno outputs (``constant``/``linear`` terms; see :mod:`fuzzkit.fuzzy.sugeno`): every rule
  consequent counts on its own with its weighted firing strength ``w`` and value ``z``;
  ``weighted_average`` is ``sum(w z) / sum(w)``, ``weighted_sum`` is ``sum(w z)``. Implication
  and aggregation do not apply (MATLAB ignores ImpMethod/AggMethod for Sugeno systems, and
  fuzzylite's WeightedAverage/WeightedSum, with aggregation none, read each activated
  term's degree). ``linear``
  terms see the input values the membership functions see (clamped under ``clamp``), and
  the result is not clamped to the output's range. No rule fired (``sum(w) == 0``): default.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
import numpy.typing as npt

from fuzzkit.errors import EvaluationError
from fuzzkit.fuzzy import membership
from fuzzkit.fuzzy.fastpath import PolyCentroid, ScalarPath, Segment, scalar_input
from fuzzkit.fuzzy.model import Compound, Expression, Proposition, RuleBase, Variable
from fuzzkit.fuzzy.sugeno import SugenoOutput, SugenoScalarPath, sugeno_scalar_path

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.intp]

_EXTEND_LIMIT = 1e100  # inputs are bounded by this under `extend` so no product overflows
_fmin = np.minimum
_fmax = np.maximum


# --------------------------------------------------------------------------- fuzzification


class _Fuzzifier:
    """Memberships of one input variable in all its terms: (B,) -> (B, T)."""

    def __init__(self, var: Variable, policy: str) -> None:
        self.low, self.high = var.low, var.high
        self.clamp = policy == "clamp"
        self.n_terms = len(var.terms)
        self.pl_index = np.array(
            [i for i, t in enumerate(var.terms) if t.is_piecewise_linear], dtype=np.intp
        )
        forms = np.array(
            [membership.trapezoid_form(var.terms[i]) for i in self.pl_index], dtype=np.float64
        ).reshape(-1, 4)
        self.core_start, self.core_end, self.rise, self.fall = (forms[:, k] for k in range(4))
        self.smooth = [(i, t) for i, t in enumerate(var.terms) if not t.is_piecewise_linear]

    def prepare(self, x: FloatArray) -> FloatArray:
        """The input value the terms see: clamped to the range, or bounded under ``extend``."""
        # bare ufuncs rather than np.clip: this runs once per input per call, and the
        # per-call overhead dominates scalar evaluation
        if self.clamp:
            return _fmin(_fmax(x, self.low), self.high)
        return _fmin(_fmax(x, -_EXTEND_LIMIT), _EXTEND_LIMIT)

    def __call__(self, x: FloatArray) -> FloatArray:
        x = self.prepare(x)
        xc = x[:, None]
        # x is finite and slopes are at most 1e200, so nothing overflows or becomes NaN
        pl = _fmin(
            _fmax(
                _fmin(
                    1.0 + (xc - self.core_start) * self.rise, 1.0 + (self.core_end - xc) * self.fall
                ),
                0.0,
            ),
            1.0,
        )
        if not self.smooth:
            return pl
        out = np.empty((x.shape[0], self.n_terms))
        out[:, self.pl_index] = pl
        for i, term in self.smooth:
            out[:, i] = membership.evaluate_term(term, x)
        return out


# --------------------------------------------------------------------------- rule firing


def _signature(expr: Expression) -> tuple[Any, ...]:
    if isinstance(expr, Proposition):
        return ("is", expr.variable, expr.negated)
    return (expr.op, tuple(_signature(e) for e in expr.operands))


def _leaves(expr: Expression) -> Iterator[Proposition]:
    if isinstance(expr, Proposition):
        yield expr
    else:
        for e in expr.operands:
            yield from _leaves(e)


@dataclass(frozen=True)
class _RuleGroup:
    """Rules of the same antecedent structure, evaluated together as columns."""

    signature: tuple[Any, ...]
    rule_index: IntArray
    leaf_terms: tuple[IntArray, ...]  # per leaf (DFS order): term index for each rule


class _Firing:
    """Firing strengths of all rules, weights applied: memberships -> (B, R)."""

    def __init__(self, rb: RuleBase) -> None:
        self.n_rules = len(rb.rules)
        self.and_op, self.or_op = rb.operators.and_, rb.operators.or_
        self.input_pos = {v.name: i for i, v in enumerate(rb.inputs)}
        by_sig: dict[tuple[Any, ...], list[int]] = {}
        for r, rule in enumerate(rb.rules):
            by_sig.setdefault(_signature(rule.antecedent), []).append(r)
        self.groups: list[_RuleGroup] = []
        for sig, idx in by_sig.items():
            leaves = [list(_leaves(rb.rules[r].antecedent)) for r in idx]
            leaf_terms = tuple(
                np.array(
                    [rb.input(ls[k].variable).term_index(ls[k].term) for ls in leaves],
                    dtype=np.intp,
                )
                for k in range(len(leaves[0]))
            )
            self.groups.append(_RuleGroup(sig, np.array(idx, dtype=np.intp), leaf_terms))
        weights = np.array([rule.weight for rule in rb.rules], dtype=np.float64)
        self.weights: FloatArray | None = None if np.all(weights == 1.0) else weights
        self.single_group_in_order = len(self.groups) == 1 and bool(
            np.array_equal(self.groups[0].rule_index, np.arange(self.n_rules))
        )

    def __call__(self, mus: list[FloatArray]) -> FloatArray:
        if self.single_group_in_order:
            g = self.groups[0]
            out = self._eval(g.signature, iter(g.leaf_terms), mus)
        else:
            out = np.empty((mus[0].shape[0], self.n_rules))
            for g in self.groups:
                out[:, g.rule_index] = self._eval(g.signature, iter(g.leaf_terms), mus)
        if self.weights is not None:
            out = out * self.weights
        return out

    def _eval(
        self, sig: tuple[Any, ...], leaf_terms: Iterator[IntArray], mus: list[FloatArray]
    ) -> FloatArray:
        if sig[0] == "is":
            col = np.take(mus[self.input_pos[sig[1]]], next(leaf_terms), axis=1)
            return 1.0 - col if sig[2] else col
        parts = [self._eval(s, leaf_terms, mus) for s in sig[1]]
        acc = parts[0]
        for p in parts[1:]:
            if sig[0] == "and":
                acc = np.minimum(acc, p) if self.and_op == "min" else acc * p
            else:
                acc = np.maximum(acc, p) if self.or_op == "max" else acc + p - acc * p
        return acc


# --------------------------------------------------------------------------- output stage


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


class _Pieces:
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


class _ExactGeometry:
    """Closed-form integration of the aggregated set of a piecewise-linear output."""

    def __init__(self, rb: RuleBase, out: Variable, pieces: _Pieces) -> None:
        self.implication = rb.operators.implication
        self.aggregation = rb.operators.aggregation
        lo, hi = out.low, out.high
        zs = {lo, hi}
        for t in out.terms:
            zs.update(v for v in membership.breakpoints(t) if lo < v < hi)
        z = _merge_close(np.array(sorted(zs)), hi - lo)
        if self.implication == "min" and self.aggregation == "max":
            # edges of different terms crossing inside an interval are static breakpoints
            extra = []
            for z0, z1 in itertools.pairwise(z):
                s, c = self._lines(out, z0, z1)
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
            s, c = self._lines(out, self.z0[k], self.z1[k])
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
        self.kmax = kmax
        self.gl = _gauss_legendre(kmax // 2 + 2)

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

    def _aggregate(self, y: FloatArray, lv: FloatArray, final: bool = True) -> FloatArray:
        """Aggregated membership at points y (B, m, C), slot levels lv (B, m, K)."""
        ell = np.maximum(
            self.slope[None, :, None, :] * y[..., None] + self.icpt[None, :, None, :], 0.0
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
        z0 = np.broadcast_to(self.z0[None, :, None], (b, len(self.z0), 1))
        z1 = np.broadcast_to(self.z1[None, :, None], (b, len(self.z0), 1))
        with np.errstate(divide="ignore", invalid="ignore"):
            if self.implication == "min" and self.aggregation == "max":
                cand = (lv[:, :, None, :] - c[..., :, None]) / s[..., :, None]
                cand = cand.reshape(b, len(self.z0), -1)
            elif self.implication == "min":
                cand = (lv - c) / s
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

    def integrals(
        self, levels: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        """Per-segment area and moment (B, S), segment starts/ends (B, S), and values at points."""
        pts, lv = self.sample_points(levels)
        b = pts.shape[0]
        p0, p1 = pts[..., :-1], pts[..., 1:]
        h = p1 - p0
        if self.aggregation != "probabilistic_sum":
            f = self._aggregate(pts, lv)
            f0, f1 = f[..., :-1], f[..., 1:]
            area = 0.5 * h * (f0 + f1)
            moment = h / 6.0 * (p0 * (2 * f0 + f1) + p1 * (f0 + 2 * f1))
        else:
            xg, wg = self.gl
            mid, half = 0.5 * (p0 + p1), 0.5 * h
            nodes = mid[..., None] + half[..., None] * xg  # (B, m, C-1, n)
            fn = self._aggregate(nodes.reshape(b, nodes.shape[1], -1), lv).reshape(nodes.shape)
            area = half * (fn * wg).sum(-1)
            moment = half * (fn * wg * nodes).sum(-1)
            f = self._aggregate(pts, lv)
        return (
            area.reshape(b, -1),
            moment.reshape(b, -1),
            p0.reshape(b, -1),
            p1.reshape(b, -1),
            np.stack([f[..., :-1], f[..., 1:]], axis=-1).reshape(b, -1, 2),
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
        ell = np.maximum(
            self.slope[interval][:, None, None, :] * y[..., None]
            + self.icpt[interval][:, None, None, :],
            0.0,
        )
        imp = np.minimum(lv_i, ell) if self.implication == "min" else lv_i * ell
        f = _probabilistic_sum(imp)[:, 0, :]
        return cast(FloatArray, 0.5 * t * (f * wg).sum(-1))

    def maxima(self, levels: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Height, smallest and largest point of maximum (B,)."""
        pts, lv = self.sample_points(levels)
        b = pts.shape[0]
        f = self._aggregate(pts, lv).reshape(b, -1)
        y = pts.reshape(b, -1)
        height = f.max(axis=1)
        at_max = f >= height[:, None] - 1e-12
        som = np.where(at_max, y, np.inf).min(axis=1)
        lom = np.where(at_max, y, -np.inf).max(axis=1)
        return height, som, lom


def _partition_centroid(geo: _ExactGeometry, rb: RuleBase, n_terms: int) -> PolyCentroid | None:
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


class _GridGeometry:
    """Grid integration of an output with smooth terms, spacing from an a-priori bound.

    The trapezoid rule's error on a cell is at most ``h^3 M2 / 12`` where the aggregated set is
    twice differentiable with ``|f''| <= M2``, and at most ``L h^2 / 4`` on a cell holding a
    kink (``|f'| <= L``). With at most ``n_kinks`` kinks the total error is below
    ``W h^2 M2 / 12 + n_kinks L h^2 / 4`` (``W`` the range width); ``h`` is chosen to keep it
    under 1e-9 W for the area (the moment's bound is the same times max |y|).
    """

    tolerance = 1e-9
    max_points = 1 << 20

    def __init__(self, rb: RuleBase, out: Variable, pieces: _Pieces) -> None:
        self.implication = rb.operators.implication
        self.aggregation = rb.operators.aggregation
        lo, hi = out.low, out.high
        width = hi - lo
        probe = np.linspace(lo, hi, 200_001)
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


class _Output:
    """Defuzzifies one output variable from the rule firing strengths."""

    def __init__(self, rb: RuleBase, out: Variable) -> None:
        self.name = out.name
        self.default = math.nan if out.default is None else float(out.default)
        self.defuzzifier = rb.defuzzifier
        self.pieces = _Pieces(rb, out)
        self.centres = np.array([membership.centre(t, out.low, out.high) for t in out.terms])
        self.geometry: _ExactGeometry | _GridGeometry | None = None
        self.fast_centroid: PolyCentroid | None = None
        if self.defuzzifier != "weighted_average" and not self.pieces.empty:
            if all(t.is_piecewise_linear for t in out.terms):
                geo = _ExactGeometry(rb, out, self.pieces)
                self.geometry = geo
                if self.defuzzifier == "centroid":
                    self.fast_centroid = _partition_centroid(geo, rb, len(out.terms))
            else:
                self.geometry = _GridGeometry(rb, out, self.pieces)

    def __call__(self, firing: FloatArray, inputs: list[FloatArray]) -> FloatArray:
        b = firing.shape[0]
        if self.pieces.empty:
            return np.full(b, self.default)
        if self.defuzzifier == "weighted_average":
            act = self.pieces.activations(firing)
            tot = act.sum(axis=1)
            with np.errstate(invalid="ignore", divide="ignore"):
                val = (act @ self.centres) / tot
            return np.where(tot > 0, val, self.default)
        levels = self.pieces.levels(firing)
        if self.fast_centroid is not None:
            return self.fast_centroid.centroid(levels, self.default)
        geo = self.geometry
        if isinstance(geo, _ExactGeometry):
            return self._exact(geo, levels)
        if isinstance(geo, _GridGeometry):
            return self._grid(geo, levels)
        raise RuntimeError("output stage has no geometry")  # unreachable by construction

    def _exact(self, geo: _ExactGeometry, levels: FloatArray) -> FloatArray:
        d = self.defuzzifier
        if d in ("centroid", "bisector"):
            area, moment, *_ = geo.integrals(levels)
            total = area.sum(axis=1)
            ok = total > 1e-300
            if d == "centroid":
                with np.errstate(invalid="ignore", divide="ignore"):
                    val = moment.sum(axis=1) / total
            else:
                val = geo.bisector(levels)
            return np.where(ok, val, self.default)
        height, som, lom = geo.maxima(levels)
        val = {"smallest_of_maximum": som, "largest_of_maximum": lom}.get(d, 0.5 * (som + lom))
        return np.where(height > 0, val, self.default)

    def _grid(self, geo: _GridGeometry, levels: FloatArray) -> FloatArray:
        # compiled single pass per point: no (points x grid) array, see fuzzy.grid_kernel
        from fuzzkit.fuzzy.grid_kernel import (
            AGGREGATIONS,
            DEFUZZIFIERS,
            IMPLICATIONS,
            grid_defuzzify,
        )

        return grid_defuzzify(
            np.ascontiguousarray(levels, dtype=np.float64),
            geo.piece_mu_t,
            geo.y,
            float(geo.dy),
            IMPLICATIONS[geo.implication],
            AGGREGATIONS[geo.aggregation],
            DEFUZZIFIERS.get(self.defuzzifier, DEFUZZIFIERS["mean_of_maximum"]),
            self.default,
        )


# --------------------------------------------------------------------------- public API


class Engine:
    """Exact evaluator of one rule base; build once, call many times.

    Parameters
    ----------
    rulebase
        A rule base; it is validated (``fuzzkit.fuzzy.validation.ensure_valid``).

    Raises
    ------
    RuleBaseError
        If the rule base is inconsistent.

    Examples
    --------
    >>> import fuzzkit
    >>> eng = fuzzkit.Engine(fuzzkit.load("macvicar_whelan"))
    >>> round(eng.evaluate_point(e=0.0, de=0.0)["du"], 12)
    0.0
    """

    def __init__(self, rulebase: RuleBase) -> None:
        from fuzzkit.fuzzy.validation import ensure_valid

        ensure_valid(rulebase)
        self.rulebase = rulebase
        self.input_names = rulebase.input_names
        self.output_names = rulebase.output_names
        self._fuzzifiers = [_Fuzzifier(v, rulebase.out_of_range) for v in rulebase.inputs]
        self._firing = _Firing(rulebase)
        self._outputs: list[_Output | SugenoOutput] = [
            SugenoOutput(rulebase, o) if o.is_sugeno else _Output(rulebase, o)
            for o in rulebase.outputs
        ]
        self._linear = any(isinstance(o, SugenoOutput) and o.linear for o in self._outputs)
        self._scalar: ScalarPath | SugenoScalarPath | None = _scalar_path(
            rulebase, self._outputs
        ) or sugeno_scalar_path(rulebase)

    def _coerce(self, inputs: Mapping[str, npt.ArrayLike]) -> list[FloatArray]:
        unknown = sorted(set(inputs) - set(self.input_names))
        missing = [n for n in self.input_names if n not in inputs]
        if unknown or missing:
            parts = []
            if missing:
                parts.append("missing input(s) " + ", ".join(repr(n) for n in missing))
            if unknown:
                parts.append("unknown input(s) " + ", ".join(repr(n) for n in unknown))
            raise EvaluationError(
                f"rule base {self.rulebase.name!r}: {'; '.join(parts)} "
                f"(expected {', '.join(self.input_names)})"
            )
        arrays = []
        for n in self.input_names:
            try:
                arrays.append(np.asarray(inputs[n], dtype=np.float64))
            except (TypeError, ValueError) as exc:
                raise EvaluationError(
                    f"input {n!r}: expected numbers, got {inputs[n]!r:.60}"
                ) from exc
        try:
            return list(np.broadcast_arrays(*arrays))
        except ValueError as exc:
            shapes = ", ".join(
                f"{n}{a.shape}" for n, a in zip(self.input_names, arrays, strict=True)
            )
            raise EvaluationError(f"input shapes do not broadcast together: {shapes}") from exc

    #: Points evaluated together: the intermediate arrays scale with it (firing strengths,
    #: levels, geometry per point), so memory stays bounded whatever the batch size.
    chunk_points = 8192

    def evaluate(self, inputs: Mapping[str, npt.ArrayLike]) -> dict[str, FloatArray]:
        """Evaluate at every point of the broadcast inputs; each output has their shape.

        Large batches are evaluated :attr:`chunk_points` at a time into the result arrays, so
        the working memory does not grow with the batch.
        """
        arrays = self._coerce(inputs)
        shape = arrays[0].shape
        flat = [a.reshape(-1) for a in arrays]
        size = flat[0].size
        step = self.chunk_points
        if size <= step:
            result = self._evaluate_flat(flat)
            return {k: v.reshape(shape) for k, v in result.items()}
        out = {name: np.empty(size) for name in self.output_names}
        for s in range(0, size, step):
            part = self._evaluate_flat([a[s : s + step] for a in flat])
            for name, v in part.items():
                out[name][s : s + step] = v
        return {k: v.reshape(shape) for k, v in out.items()}

    def _evaluate_flat(self, flat: list[FloatArray]) -> dict[str, FloatArray]:
        bad = np.isnan(flat[0])
        for a in flat[1:]:
            bad |= np.isnan(a)
        any_bad = bool(bad.any())
        if any_bad:
            flat = [np.where(bad, 0.0, a) for a in flat]
        mus = [fz(x) for fz, x in zip(self._fuzzifiers, flat, strict=True)]
        firing = self._firing(mus)
        if self._linear:
            flat = [fz.prepare(x) for fz, x in zip(self._fuzzifiers, flat, strict=True)]
        result = {}
        for out in self._outputs:
            val = out(firing, flat)
            result[out.name] = np.where(bad, np.nan, val) if any_bad else val
        return result

    def evaluate_point(
        self, inputs: Mapping[str, float] | None = None, **kw: float
    ) -> dict[str, float]:
        """Evaluate at one point: ``evaluate_point(e=0.3, de=-0.2) -> {"du": ...}``."""
        merged = dict(inputs, **kw) if inputs else kw
        if self._scalar is not None and len(merged) == len(self.input_names):
            try:
                values = [float(merged[n]) for n in self.input_names]
            except (KeyError, TypeError, ValueError):
                values = None
            if values is not None:
                return dict(zip(self.output_names, self._scalar(values), strict=True))
        if len(merged) == len(self.input_names):
            try:
                flat = [np.array([float(merged[n])]) for n in self.input_names]
            except (KeyError, TypeError, ValueError):
                flat = None
            if flat is not None:
                res = self._evaluate_flat(flat)
                return {k: float(v[0]) for k, v in res.items()}
        res2 = self.evaluate(merged)  # slow path: reports what is wrong
        return {k: float(v.reshape(-1)[0]) for k, v in res2.items()}

    def point_function(self, output: str | None = None) -> Callable[..., float]:
        """A plain function ``f(*inputs) -> float`` of one output, inputs in declaration order.

        For control loops that call the engine once per sample: it skips building and reading
        dictionaries, and uses the pure-Python scalar path when the rule base has its shape.
        """
        name = output or self.output_names[0]
        if name not in self.output_names:
            raise EvaluationError(
                f"rule base {self.rulebase.name!r} has no output {name!r} "
                f"(expected one of {', '.join(self.output_names)})"
            )
        idx = self.output_names.index(name)
        scalar = self._scalar
        if scalar is not None:
            return lambda *values: scalar(values)[idx]
        names = self.input_names
        return lambda *values: self.evaluate_point(dict(zip(names, values, strict=True)))[name]

    def firing_strengths(self, inputs: Mapping[str, npt.ArrayLike]) -> FloatArray:
        """Weighted firing strength of every rule at every point, shape (points, rules)."""
        flat = [a.reshape(-1) for a in self._coerce(inputs)]
        return self._firing([fz(x) for fz, x in zip(self._fuzzifiers, flat, strict=True)])


def _scalar_path(rb: RuleBase, outputs: list[_Output | SugenoOutput]) -> ScalarPath | None:
    """The pure-Python single-point evaluator, when the rule base has its shape."""
    if any(not t.is_piecewise_linear for v in rb.inputs for t in v.terms):
        return None
    if any(not isinstance(o, _Output) or o.fast_centroid is None for o in outputs):
        return None
    pos = {v.name: i for i, v in enumerate(rb.inputs)}
    out_pos = {v.name: i for i, v in enumerate(rb.outputs)}
    table: dict[tuple[int, ...], list[tuple[float, tuple[tuple[int, int], ...]]]] = {}
    for rule in rb.rules:
        ante = rule.antecedent
        props = [ante] if isinstance(ante, Proposition) else list(ante.operands)
        if isinstance(ante, Compound) and ante.op != "and":
            return None
        if not all(isinstance(p, Proposition) and not p.negated for p in props):
            return None
        by_input = {
            pos[p.variable]: rb.input(p.variable).term_index(p.term)
            for p in props
            if isinstance(p, Proposition)
        }
        if len(by_input) != len(props) or len(by_input) != len(rb.inputs):
            return None
        key = tuple(by_input[i] for i in range(len(rb.inputs)))
        cons = tuple(
            (out_pos[c.variable], rb.output(c.variable).term_index(c.term))
            for c in rule.consequents
        )
        table.setdefault(key, []).append((rule.weight, cons))
    inputs = [
        scalar_input(
            v.low,
            v.high,
            rb.out_of_range == "clamp",
            [membership.trapezoid_form(t) for t in v.terms],
            [p for t in v.terms for p in membership.breakpoints(t)],
        )
        for v in rb.inputs
    ]
    outs = []
    for o, var in zip(outputs, rb.outputs, strict=True):
        if not isinstance(o, _Output) or o.fast_centroid is None:  # checked above (for mypy)
            return None
        outs.append((o.fast_centroid, len(var.terms), o.default))
    return ScalarPath(inputs, table, rb.operators.and_ == "product", outs)


_ENGINES: dict[int, tuple[RuleBase, Engine]] = {}


def engine_for(rulebase: RuleBase) -> Engine:
    """A cached Engine for ``rulebase`` (keyed by identity; the model is immutable)."""
    hit = _ENGINES.get(id(rulebase))
    if hit is not None and hit[0] is rulebase:
        return hit[1]
    eng = Engine(rulebase)
    if len(_ENGINES) > 64:
        _ENGINES.clear()
    _ENGINES[id(rulebase)] = (rulebase, eng)
    return eng


def evaluate(rulebase: RuleBase, inputs: Mapping[str, npt.ArrayLike]) -> dict[str, FloatArray]:
    """Evaluate ``rulebase`` at the broadcast inputs: ``{name: array}`` -> ``{output: array}``."""
    return engine_for(rulebase).evaluate(inputs)


def evaluate_point(
    rulebase: RuleBase, inputs: Mapping[str, float] | None = None, **kw: float
) -> dict[str, float]:
    """Evaluate ``rulebase`` at one point; returns ``{output: float}``."""
    return engine_for(rulebase).evaluate_point(inputs, **kw)


#: Public names of the output-stage building blocks, for code generators that emit the same
#: breakpoint sweep (``fuzzkit.codegen.exact``): which rule feeds which piece, and the
#: elementary intervals with every piece's line in them.
OutputPieces = _Pieces
PiecewiseLinearGeometry = _ExactGeometry
#: Centroid tables of a partition-style output (``None`` when more than two terms overlap or the
#: operators are not min/max): the engine's fast centroid, which generated code can reuse.
partition_centroid = _partition_centroid
