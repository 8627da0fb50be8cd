"""Sound bounds of a term's *computed* membership over an interval of inputs, and an input's
range cut into the cells on which those bounds hold (issue 40 item 3).

Coverage is a question about the arithmetic the engine runs: a Gaussian 40 sigmas from its mean
is mathematically positive but computes to 0, a steep sigmoid saturates to exactly 1 (so its
``NOT`` is 0) on an interval, and a product of two tiny memberships underflows. These bounds
are of the values ``fuzzkit.fuzzy.membership.evaluate_term`` returns, not of the formulas.

Why they are sound: every registered shape is, as computed, monotone between consecutive
parameters (a triangle between its corners, a Gaussian on each side of its mean, a sigmoid
everywhere, a spline between its knots), because each is a chain of IEEE operations that are
monotone under round-to-nearest (subtracting or dividing by a constant, squaring a quantity of
one sign, ``exp``, ``1 + t``, ``1 / t``). So over an interval that contains no parameter in
its interior, the computed membership lies between its values at the interval's two ends. The
two shapes that combine two sigmoids (``sigmoid_difference``, ``sigmoid_product``) are bounded
factor by factor, each factor monotone everywhere, and the difference or product of the
bounds is rounded as the engine rounds it (rounding is monotone, so the bound holds for the
computed value). :func:`cells` cuts a range at every parameter of every term, so the bounds of
each cell, and of any sub-interval of one, hold.
"""

from __future__ import annotations

import functools
import itertools
import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from fuzzkit.fuzzy.model import Term, Variable
from fuzzkit.fuzzy.shapes import shape as shape_record
from fuzzkit.fuzzy.shapes import sigmoid

FloatArray = npt.NDArray[np.float64]

#: Shapes computed from two sigmoids, bounded factor by factor: how the two are combined.
_TWO_SIGMOIDS = {"sigmoid_difference": "difference", "sigmoid_product": "product"}


@dataclass(frozen=True, slots=True)
class Cell:
    """Every float ``x`` with ``lo <= x <= hi``: a single point, or the floats strictly between
    two cut points; ``example`` is one of them (the point, or the middle)."""

    lo: float
    hi: float
    example: float


def cut_points(var: Variable) -> list[float]:
    """The range's ends, every support end and every parameter of every term inside it."""
    ends = {var.low, var.high}
    for t in var.terms:
        pieces = shape_record(t.shape).support(t.params)
        candidates = [v for piece in pieces for v in (piece[0], piece[2])]
        ends.update(v for v in (*candidates, *t.params) if var.low < v < var.high)
    return sorted(ends)


def cells(var: Variable) -> list[Cell]:
    """``var``'s range as cells: each cut point alone, then the floats between two of them."""
    xs = cut_points(var)
    out = [Cell(xs[0], xs[0], xs[0])]
    for a, b in itertools.pairwise(xs):
        lo, hi = math.nextafter(a, math.inf), math.nextafter(b, -math.inf)
        if lo <= hi:
            out.append(Cell(lo, hi, min(max(0.5 * (a + b), lo), hi)))
        out.append(Cell(b, b, b))
    return out


def enclosure(term: Term, lo: FloatArray, hi: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Lower and upper bounds of ``term``'s computed membership over each ``[lo[i], hi[i]]``.

    Each interval must contain none of the term's parameters in its interior (true of any
    sub-interval of a :func:`cells` cell). Raises UnknownShapeError for an unregistered shape.
    """
    record = shape_record(term.shape)
    combine = _TWO_SIGMOIDS.get(term.shape)
    if combine is None:
        at_lo, at_hi = record.evaluate(lo, term.params), record.evaluate(hi, term.params)
        return np.minimum(at_lo, at_hi), np.maximum(at_lo, at_hi)
    s1, c1, s2, c2 = term.params
    f1 = sigmoid(lo, s1, c1), sigmoid(hi, s1, c1)
    f2 = sigmoid(lo, s2, c2), sigmoid(hi, s2, c2)
    lo1, hi1 = np.minimum(*f1), np.maximum(*f1)
    lo2, hi2 = np.minimum(*f2), np.maximum(*f2)
    if combine == "product":
        return lo1 * lo2, hi1 * hi2
    d_lo, d_hi = lo1 - hi2, hi1 - lo2  # bounds of s1 - s2; the engine takes |s1 - s2|
    straddles = (d_lo <= 0.0) & (d_hi >= 0.0)
    low = np.where(straddles, 0.0, np.minimum(np.abs(d_lo), np.abs(d_hi)))
    return low, np.maximum(np.abs(d_lo), np.abs(d_hi))


def ordinal(x: float) -> int:
    """The rank of ``x`` among the floats (monotone: ``a < b`` iff ``ordinal(a) < ordinal(b)``)."""
    bits = int(np.float64(x).view(np.int64))
    return bits if bits >= 0 else -(bits & 0x7FFF_FFFF_FFFF_FFFF)


def _fromordinal(k: int) -> float:
    bits = k if k >= 0 else (-k) | -0x8000_0000_0000_0000
    return float(np.int64(bits).view(np.float64))


def halves(lo: float, hi: float) -> tuple[tuple[float, float], tuple[float, float]]:
    """``[lo, hi]`` (``lo < hi``) as two non-empty halves with as many floats each, so that 64
    halvings reach a single float wherever the interval lies (halving the value would take
    over a thousand near 0)."""
    mid = _fromordinal((ordinal(lo) + ordinal(hi)) // 2)
    mid = min(max(mid, lo), math.nextafter(hi, -math.inf))
    return (lo, mid), (math.nextafter(mid, math.inf), hi)


@dataclass(frozen=True, slots=True)
class Part:
    """A part of an input's range on which every term's computed membership is decided: above
    0 everywhere or 0 everywhere, and (for the terms ``parts`` was asked about) below 1
    everywhere or 1 everywhere. ``low`` and ``high`` bound each term's membership there, in
    the order of the variable's terms."""

    lo: float
    hi: float
    example: float
    low: tuple[float, ...]
    high: tuple[float, ...]

    def positive(self) -> frozenset[int]:
        """The indices of the terms above 0 here."""
        return frozenset(k for k, v in enumerate(self.low) if v > 0.0)


def _bounds(var: Variable, spans: list[tuple[float, float]]) -> list[tuple[tuple[float, ...], ...]]:
    """Per span, the (low, high) bounds of every term, from one enclosure call per term."""
    if not var.terms:  # a Sugeno input that only feeds linear terms
        return [((), ())] * len(spans)
    a = np.array([lo for lo, _ in spans])
    b = np.array([hi for _, hi in spans])
    pairs = [enclosure(t, a, b) for t in var.terms]
    low = np.array([lo for lo, _ in pairs]).T.tolist()
    high = np.array([hi for _, hi in pairs]).T.tolist()
    return [(tuple(lw), tuple(hg)) for lw, hg in zip(low, high, strict=True)]


def _decided(low: tuple[float, ...], high: tuple[float, ...], negated: frozenset[int]) -> bool:
    return all(
        (lo > 0.0 or hi == 0.0) and (k not in negated or hi < 1.0 or lo == 1.0)
        for k, (lo, hi) in enumerate(zip(low, high, strict=True))
    )


def _flags(low: tuple[float, ...], high: tuple[float, ...]) -> tuple[tuple[bool, bool], ...]:
    return tuple((lo > 0.0, hi < 1.0) for lo, hi in zip(low, high, strict=True))


#: Points per step of the search for where a membership reaches 0 or 1 (10 bits of the 64 of a
#: float per numpy call).
_SECTIONS = 1024


def _floats(ordinals: npt.NDArray[np.int64]) -> FloatArray:
    bits = np.where(ordinals >= 0, ordinals, (-ordinals) | np.int64(-(2**63)))
    return bits.view(np.float64)


def _flips(term: Term, lo: float, hi: float) -> list[float]:
    """Floats of ``[lo, hi]`` where ``term``'s computed membership becomes or stops being 0 or 1,
    found by sectioning (a proposal: :func:`parts` verifies every piece they make by its
    bounds, and halves what they leave undecided)."""
    record = shape_record(term.shape)
    found: list[float] = []
    stack = [(ordinal(lo), ordinal(hi))]
    while stack:
        a, b = stack.pop()
        step = max(1, (b - a) // _SECTIONS)
        ks = np.append(np.arange(a, b, step, dtype=np.int64), np.int64(b))
        mu = record.evaluate(_floats(ks), term.params)
        state = np.where(mu <= 0.0, 0, np.where(mu >= 1.0, 2, 1))
        for i in np.flatnonzero(state[1:] != state[:-1]).tolist():
            k0, k1 = int(ks[i]), int(ks[i + 1])
            if k1 - k0 == 1:
                found.append(float(_floats(np.array([k1]))[0]))
            else:
                stack.append((k0, k1))
    return sorted(found)


@functools.lru_cache(maxsize=512)
def parts(var: Variable, negated: frozenset[str] = frozenset()) -> tuple[Part, ...]:
    """``var``'s range as :class:`Part` s, in order: each :func:`cells` cell cut, by halving
    where the bounds leave a term undecided (down to single floats, which are evaluated as the
    engine evaluates them), at the floats where a term's computed membership reaches 0 (or,
    for the terms named in ``negated``, 1); the pieces of one cell with the same decisions
    are merged again. Rule bases whose memberships reach 0 and 1 only at cut points (the
    piecewise-linear partitions, Gaussians that do not underflow inside the range) keep their
    cells as they are."""
    neg = frozenset(k for k, t in enumerate(var.terms) if t.name in negated)
    all_cells = cells(var)
    out: list[Part] = []
    for cell, (low, high) in zip(
        all_cells, _bounds(var, [(c.lo, c.hi) for c in all_cells]), strict=True
    ):
        if cell.lo == cell.hi or _decided(low, high, neg):
            out.append(Part(cell.lo, cell.hi, cell.example, low, high))
            continue
        open_terms = [
            t
            for k, t in enumerate(var.terms)
            if not _decided((low[k],), (high[k],), frozenset({0}) if k in neg else frozenset())
        ]
        out.extend(_cut(var, cell, neg, open_terms))
    return tuple(out)


def _cut(var: Variable, cell: Cell, neg: frozenset[int], open_terms: list[Term]) -> list[Part]:
    """The decided parts of a cell the bounds leave undecided as a whole (``open_terms``: the
    terms they leave undecided)."""
    cuts = sorted({x for t in open_terms for x in _flips(t, cell.lo, cell.hi)} - {cell.lo})
    starts = [cell.lo, *cuts]
    ends = [math.nextafter(x, -math.inf) for x in cuts] + [cell.hi]
    spans = list(zip(starts, ends, strict=True))
    found: list[tuple[float, float, tuple[float, ...], tuple[float, ...]]] = []
    for (lo, hi), (low, high) in zip(spans, _bounds(var, spans), strict=True):
        stack = [(lo, hi, low, high)]
        while stack:  # what the proposed cuts leave undecided is halved (rare)
            lo, hi, low, high = stack.pop()
            if lo == hi or _decided(low, high, neg):
                found.append((lo, hi, low, high))
                continue
            halves_ = list(halves(lo, hi))
            for (h_lo, h_hi), (h_low, h_high) in reversed(
                list(zip(halves_, _bounds(var, halves_), strict=True))
            ):
                stack.append((h_lo, h_hi, h_low, h_high))
    out: list[Part] = []
    for lo, hi, low, high in found:
        if out and _flags(out[-1].low, out[-1].high) == _flags(low, high):
            last = out[-1]  # the union's bounds: the pieces' (tighter than one enclosure)
            low = tuple(map(min, last.low, low))
            high = tuple(map(max, last.high, high))
            lo = last.lo
            out.pop()
        example = cell.example if lo <= cell.example <= hi else min(max(0.5 * (lo + hi), lo), hi)
        out.append(Part(lo, hi, example, low, high))
    return out


def positive_parts(var: Variable) -> list[tuple[float, float]]:
    """The closed intervals of ``var``'s range where no term's computed membership is above 0
    (from :func:`parts`). A gap of a single point is ``(x, x)``."""
    gaps: list[tuple[float, float]] = []
    for part in parts(var):
        if part.positive():
            continue
        if gaps and math.nextafter(gaps[-1][1], math.inf) >= part.lo:
            gaps[-1] = (gaps[-1][0], part.hi)
        else:
            gaps.append((part.lo, part.hi))
    return gaps
