"""The exact continuous IT2 engine as one compiled kernel over the points.

Per point, in one numba pass (no per-stage numpy dispatch), from the input values (or from the
piece levels) to the Karnik-Mendel interval of one output:

1. **Firing intervals** (:class:`FiringLayout`; piecewise-linear input terms, conjunctive
   antecedents): the type-1 fuzzifier's formula on the upper and the lower terms, the lower
   membership clipped to the upper one, AND (``min``/``product``) over the propositions, times
   the weight; the **piece levels** are each output term's largest rule firing.
2. **Cut points**: in every elementary interval of each set's geometry
   (:class:`fuzzkit.fuzzy.output_geometry.PiecewiseLinearGeometry`: term vertices and, for
   ``min`` implication, term-edge crossings) the interval's ends and the points where an edge
   meets a level (``min`` implication) or two scaled edges meet (``product``). Between the
   sorted union of both sets' points, ``U`` and ``L`` are linear.
3. **Sets** at the points (``L`` clipped to ``U`` against rounding), read as
   :meth:`~fuzzkit.fuzzy.output_geometry.PiecewiseLinearGeometry.values_at` reads them.
4. **Type reduction** (:func:`fuzzkit.fuzzy.type_reduction.interval_of_row`): prefix sums,
   binary-search bracket, Newton on the cubic piece.

Only the aggregation ``max`` occurs (IT2 validation accepts no other). The layouts travel as
one float and one integer array each: a numba call pays per argument, and a scalar evaluation
is mostly that call.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from fuzzkit.fuzzy import membership
from fuzzkit.fuzzy.model import Expression, Proposition, RuleBase, Variable
from fuzzkit.fuzzy.output_geometry import OutputPieces, PiecewiseLinearGeometry
from fuzzkit.fuzzy.type_reduction import interval_of_row
from fuzzkit.jit import jit

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]

#: One set's geometry as the kernel reads it: ``z0, z1`` (m,) the elementary intervals,
#: ``slot_piece`` (m, k) the piece on each slot (``n_pieces``: none), ``slope, icpt, root``
#: (m, k) the slot's line (:class:`~fuzzkit.fuzzy.output_geometry.PiecewiseLinearGeometry`).
Geometry = tuple[FloatArray, FloatArray, IntArray, FloatArray, FloatArray, FloatArray]

#: The output layout's integer header: implication product?, scratch width, terms, rule-term
#: pairs, then (intervals, slots) of the upper and of the lower set.
_OUT_HEADER = 8
#: The firing layout's integer header: inputs, terms per input (padded), rules, leaves per
#: rule (padded), AND product?
_FIRE_HEADER = 5


def _candidates(geometry: PiecewiseLinearGeometry, product: bool) -> int:
    """The most cut points one row of a set can give."""
    m, k = geometry.slope.shape
    return int(m * (2 + (k * (k - 1) // 2 if product else k * k)))


@dataclass(frozen=True)
class OutputLayout:
    """The input-independent arrays of one IT2 Mamdani output (continuous type reduction):
    which rule implies which term, and both sets' geometries, packed for the kernel."""

    floats: FloatArray
    ints: IntArray

    @classmethod
    def of(
        cls,
        pieces: OutputPieces,
        upper: PiecewiseLinearGeometry,
        lower: PiecewiseLinearGeometry,
        product: bool,
    ) -> OutputLayout:
        counts = np.diff(np.append(pieces.starts, pieces.inst_rules.size))
        inst_terms = np.repeat(pieces.used_terms, counts)
        geos = (upper, lower)
        width = sum(_candidates(g, product) for g in geos)
        header = [int(product), width, pieces.n_terms, pieces.inst_rules.size]
        for g in geos:
            header.extend(g.slope.shape)
        ints = np.concatenate(
            [header, pieces.inst_rules, inst_terms, *(g.slot_piece.ravel() for g in geos)]
        )
        floats = np.concatenate(
            [np.ravel(a) for g in geos for a in (g.z0, g.z1, g.slope, g.icpt, g.root)]
        )
        return cls(floats.astype(np.float64), ints.astype(np.int64))


@jit
def _line(slope: float, icpt: float, root: float, y: float) -> float:
    """A slot's line at ``y``, clipped at 0 (``slope * (y - root)``: accurate near its root)."""
    v = slope * (y - root) if slope != 0.0 else icpt
    return max(v, 0.0)


@jit
def _cuts(levels: FloatArray, geo: Geometry, product: bool, out: FloatArray) -> int:
    """One row's cut points of one set into ``out``, sorted and distinct; return how many.

    The elementary intervals are sorted and each one's candidates lie inside it, so sorting
    each interval's few candidates (insertion sort) sorts them all.
    """
    z0, z1, slot_piece, slope, icpt, root = geo
    m, kmax = slope.shape
    n_pieces = levels.shape[0]
    c = 0
    for k in range(m):
        a, b = z0[k], z1[k]
        start = c
        out[c] = a
        c += 1
        for q in range(kmax):
            pq = slot_piece[k, q]
            lq = levels[pq] if pq < n_pieces else 0.0
            if product:
                for p in range(q + 1, kmax):
                    pp = slot_piece[k, p]
                    lp = levels[pp] if pp < n_pieces else 0.0
                    den = lq * slope[k, q] - lp * slope[k, p]
                    x = (lp * icpt[k, p] - lq * icpt[k, q]) / den if den != 0.0 else a
                    out[c] = min(max(x, a), b) if np.isfinite(x) else a
                    c += 1
            else:
                for p in range(kmax):
                    pp = slot_piece[k, p]
                    lp = levels[pp] if pp < n_pieces else 0.0
                    x = root[k, q] + lp / slope[k, q] if slope[k, q] != 0.0 else a
                    out[c] = min(max(x, a), b) if np.isfinite(x) else a
                    c += 1
        out[c] = b
        c += 1
        for i in range(start + 1, c):  # insertion sort of this interval's points
            v = out[i]
            j = i - 1
            while j >= start and out[j] > v:
                out[j + 1] = out[j]
                j -= 1
            out[j + 1] = v
        # drop repeats (with the previous interval's end too)
        w = start
        for i in range(start, c):
            if w == 0 or out[i] != out[w - 1]:
                out[w] = out[i]
                w += 1
        c = w
    return c


@jit
def _merge(a: FloatArray, na: int, b: FloatArray, nb: int, out: FloatArray) -> int:
    """The sorted union of ``a[:na]`` and ``b[:nb]`` (each sorted, distinct) into ``out``."""
    i = j = n = 0
    while i < na or j < nb:
        if j >= nb or (i < na and a[i] <= b[j]):
            v = a[i]
            i += 1
        else:
            v = b[j]
            j += 1
        if n == 0 or v != out[n - 1]:
            out[n] = v
            n += 1
    return n


@jit
def _values(
    levels: FloatArray, geo: Geometry, product: bool, y: FloatArray, n: int, out: FloatArray
) -> None:
    """The aggregated (max) set at the sorted ``y[:n]`` into ``out``: each point is read on
    the first interval whose end is not below it (``values_at``'s rule), walked in step."""
    _, z1, slot_piece, slope, icpt, root = geo
    m, kmax = slope.shape
    n_pieces = levels.shape[0]
    k = 0
    for i in range(n):
        while k < m - 1 and z1[k] < y[i]:
            k += 1
        v = 0.0
        for q in range(kmax):
            pq = slot_piece[k, q]
            lq = levels[pq] if pq < n_pieces else 0.0
            ell = _line(slope[k, q], icpt[k, q], root[k, q], y[i])
            v = max(v, lq * ell if product else min(lq, ell))
        out[i] = v


@jit
def _set(f: FloatArray, i: IntArray, side: int) -> Geometry:
    """``z0, z1, slot_piece, slope, icpt, root`` of the upper (``side`` 0) or lower (1) set."""
    n_inst = i[3]
    fo, io = 0, _OUT_HEADER + 2 * n_inst
    for s in range(side):
        m, k = i[4 + 2 * s], i[5 + 2 * s]
        fo += 2 * m + 3 * m * k
        io += m * k
    m, k = i[4 + 2 * side], i[5 + 2 * side]
    z0 = f[fo : fo + m]
    z1 = f[fo + m : fo + 2 * m]
    mk = m * k
    base = fo + 2 * m
    slope = f[base : base + mk].reshape((m, k))
    icpt = f[base + mk : base + 2 * mk].reshape((m, k))
    root = f[base + 2 * mk : base + 3 * mk].reshape((m, k))
    slot = i[io : io + mk].reshape((m, k))
    return z0, z1, slot, slope, icpt, root


@jit
def _row(
    lv_up: FloatArray,
    lv_lo: FloatArray,
    f: FloatArray,
    i: IntArray,
    scratch: FloatArray,
    out: FloatArray,
) -> None:
    """One point: cut both sets, read them at the cuts, type-reduce into ``out[:8]``
    (``scratch``: (4, width))."""
    product = i[0] != 0
    pts, y, up, lo = scratch[0], scratch[1], scratch[2], scratch[3]
    upper, lower = _set(f, i, 0), _set(f, i, 1)
    n = _merge(pts, _cuts(lv_up, upper, product, pts), up, _cuts(lv_lo, lower, product, up), y)
    _values(lv_up, upper, product, y, n, up)
    _values(lv_lo, lower, product, y, n, lo)
    for j in range(n):
        lo[j] = min(lo[j], up[j])
    interval_of_row(y, up, lo, n, out)


@jit
def _intervals(lv_up: FloatArray, lv_lo: FloatArray, f: FloatArray, i: IntArray) -> FloatArray:
    b_n = lv_up.shape[0]
    result = np.empty((b_n, 8))
    scratch = np.empty((4, i[1]))
    for b in range(b_n):
        _row(lv_up[b], lv_lo[b], f, i, scratch, result[b])
    return result


@jit
def _membership(form: FloatArray, x: float) -> float:
    """A piecewise-linear term in trapezoid form (``membership.trapezoid_form``) at ``x``:
    the type-1 fuzzifier's formula, operation for operation."""
    v = min(1.0 + (x - form[0]) * form[2], 1.0 + (form[1] - x) * form[3])
    return float(min(max(v, 0.0), 1.0))


@jit
def _evaluate(
    x: FloatArray, ff: FloatArray, fi: IntArray, f: FloatArray, i: IntArray
) -> FloatArray:
    b_n = x.shape[0]
    n_in, n_t, n_rules, n_leaves = fi[0], fi[1], fi[2], fi[3]
    product_and = fi[4] != 0
    rl = n_rules * n_leaves
    leaf_input = fi[_FIRE_HEADER : _FIRE_HEADER + rl].reshape((n_rules, n_leaves))
    leaf_term = fi[_FIRE_HEADER + rl : _FIRE_HEADER + 2 * rl].reshape((n_rules, n_leaves))
    low, high = ff[:n_in], ff[n_in : 2 * n_in]
    tf = n_in * n_t * 4
    upper_forms = ff[2 * n_in : 2 * n_in + tf].reshape((n_in, n_t, 4))
    lower_forms = ff[2 * n_in + tf : 2 * n_in + 2 * tf].reshape((n_in, n_t, 4))
    h0 = 2 * n_in + 2 * tf
    heights = ff[h0 : h0 + n_in * n_t].reshape((n_in, n_t))
    weights = ff[h0 + n_in * n_t : h0 + n_in * n_t + n_rules]
    n_terms, n_inst = i[2], i[3]
    inst_rules = i[_OUT_HEADER : _OUT_HEADER + n_inst]
    inst_terms = i[_OUT_HEADER + n_inst : _OUT_HEADER + 2 * n_inst]
    result = np.empty((b_n, 8))
    scratch = np.empty((4, i[1]))
    xs = np.empty(n_in)
    f_up, f_lo = np.empty(n_rules), np.empty(n_rules)
    lv_up, lv_lo = np.empty(n_terms), np.empty(n_terms)
    for b in range(b_n):
        for k in range(n_in):
            xs[k] = min(max(x[b, k], low[k]), high[k])
        for r in range(n_rules):
            fu, fl = 1.0, 1.0
            for k in range(n_leaves):
                v = leaf_input[r, k]
                if v < 0:
                    break
                t = leaf_term[r, k]
                mu_u = _membership(upper_forms[v, t], xs[v])
                mu_l = min(heights[v, t] * _membership(lower_forms[v, t], xs[v]), mu_u)
                if product_and:
                    fu, fl = fu * mu_u, fl * mu_l
                else:
                    fu, fl = min(fu, mu_u), min(fl, mu_l)
            f_up[r], f_lo[r] = fu * weights[r], fl * weights[r]
        lv_up[:] = 0.0
        lv_lo[:] = 0.0
        for j in range(n_inst):
            r, t = inst_rules[j], inst_terms[j]
            lv_up[t] = max(lv_up[t], f_up[r])
            lv_lo[t] = max(lv_lo[t], f_lo[r])
        _row(lv_up, lv_lo, f, i, scratch, result[b])
    return result


def continuous_intervals(
    levels_up: FloatArray, levels_lo: FloatArray, layout: OutputLayout
) -> FloatArray:
    """Per row of the piece levels (B, K): ``y_l, y_r, A_U, M_U, A_L, M_L, first, last``
    (B, 8), as :func:`fuzzkit.fuzzy.type_reduction.interval_of_row` defines them."""
    return _intervals(
        np.ascontiguousarray(levels_up, dtype=np.float64),
        np.ascontiguousarray(levels_lo, dtype=np.float64),
        layout.floats,
        layout.ints,
    )


@dataclass(frozen=True)
class FiringLayout:
    """The input-independent arrays of an IT2 rule base's fuzzification and rule firing,
    packed for the kernel, for the rule bases the compiled path covers: piecewise-linear
    input terms (upper and lower) and antecedents that are conjunctions of propositions (no
    ``or``; ``not`` is refused in IT2). Inputs are clamped to their range (under
    ``out_of_range: extend``, to +-1e100, as the type-1 fuzzifier bounds them)."""

    floats: FloatArray
    ints: IntArray

    @classmethod
    def of(
        cls, rb: RuleBase, lower_inputs: Sequence[Variable], heights: Sequence[FloatArray]
    ) -> FiringLayout | None:
        """The layout of ``rb`` (its upper terms; ``lower_inputs`` the same inputs with the
        lower shapes, ``heights`` their scales), or None where the compiled path does not
        apply."""
        variables = [*rb.inputs, *lower_inputs]
        if not all(t.is_piecewise_linear for v in variables for t in v.terms):
            return None
        leaves = [_conjuncts(rule.antecedent) for rule in rb.rules]
        props = [ls for ls in leaves if ls is not None]
        if len(props) != len(leaves) or not props:
            return None
        n_in, n_t = len(rb.inputs), max(len(v.terms) for v in rb.inputs)
        forms = np.zeros((2, n_in, n_t, 4))
        for side, vs in enumerate((rb.inputs, lower_inputs)):
            for k, v in enumerate(vs):
                for t, term in enumerate(v.terms):
                    forms[side, k, t] = membership.trapezoid_form(term)
        scale = np.zeros((n_in, n_t))
        for k, h in enumerate(heights):
            scale[k, : h.size] = h
        width = max(len(ls) for ls in props)
        leaf = np.full((2, len(props), width), -1, dtype=np.int64)
        for r, ls in enumerate(props):
            for k, prop in enumerate(ls):
                leaf[0, r, k] = rb.input_names.index(prop.variable)
                leaf[1, r, k] = rb.input(prop.variable).term_index(prop.term)
        bound = rb.out_of_range == "clamp"
        low = [v.low if bound else -membership.EXTEND_LIMIT for v in rb.inputs]
        high = [v.high if bound else membership.EXTEND_LIMIT for v in rb.inputs]
        weights = [rule.weight for rule in rb.rules]
        header = [n_in, n_t, len(props), width, int(rb.operators.and_ == "product")]
        floats = np.concatenate([low, high, forms.ravel(), scale.ravel(), weights])
        ints = np.concatenate([header, leaf.ravel()])
        return cls(floats.astype(np.float64), ints.astype(np.int64))


def _conjuncts(expr: Expression) -> list[Proposition] | None:
    """The propositions of a conjunction (nested ``and`` included), None if it has an ``or``."""
    if isinstance(expr, Proposition):
        return [expr]
    if expr.op != "and":
        return None
    out: list[Proposition] = []
    for e in expr.operands:
        part = _conjuncts(e)
        if part is None:
            return None
        out.extend(part)
    return out


def evaluate_points(x: FloatArray, firing: FiringLayout, output: OutputLayout) -> FloatArray:
    """From the input values (B, I), no NaN, to ``y_l, y_r, A_U, M_U, A_L, M_L, first, last``
    (B, 8) of one output, in one compiled pass."""
    return _evaluate(
        np.ascontiguousarray(x, dtype=np.float64),
        firing.floats,
        firing.ints,
        output.floats,
        output.ints,
    )
