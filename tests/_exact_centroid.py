"""An exact reference for a piecewise-linear Mamdani output stage: rational arithmetic, no rounding.

The output terms are written out here from their textbook vertices (not taken from fuzzkit),
every firing level is read as the exact rational number its double is, and the aggregated set is
cut at every point where any two of the lines involved cross (edges, levels, scaled edges) and
where a bounded sum reaches 1. Between two cuts every implied set is one polynomial (a constant
level, an edge, a scaled edge; their probabilistic sum a product of such), chosen at the
interval's midpoint, and it is integrated exactly. So the centroid is the exact centroid of the
levels given, whatever their size: a level of 1e-22 is as exact as a level of 0.5.
"""

from __future__ import annotations

import itertools
from fractions import Fraction as Q

from _mamdani_reference import firing

from fuzzkit.fuzzy.model import RuleBase, Term

Poly = tuple[Q, ...]  # coefficients, constant first


def _vertices(term: Term, lo: Q, hi: Q) -> list[tuple[Q, Q]]:
    """The term's polygon as (y, mu) vertices; shoulders are flat out to the range ends."""
    p = [Q(v) for v in term.params]
    if term.shape == "triangle":
        return [(p[0], Q(0)), (p[1], Q(1)), (p[2], Q(0))]
    if term.shape == "trapezoid":
        return [(p[0], Q(0)), (p[1], Q(1)), (p[2], Q(1)), (p[3], Q(0))]
    if term.shape == "left_shoulder":
        return [(min(lo, p[0]) - 1, Q(1)), (p[0], Q(1)), (p[1], Q(0))]
    if term.shape == "right_shoulder":
        return [(p[0], Q(0)), (p[1], Q(1)), (max(hi, p[1]) + 1, Q(1))]
    raise NotImplementedError(f"exact reference: shape {term.shape!r}")


def _edges(term: Term, lo: Q, hi: Q) -> list[tuple[Q, Q, Poly]]:
    """The term's non-vertical pieces as (y0, y1, line)."""
    out = []
    for (y0, v0), (y1, v1) in itertools.pairwise(_vertices(term, lo, hi)):
        if y1 > y0:
            slope = (v1 - v0) / (y1 - y0)
            out.append((y0, y1, (v0 - slope * y0, slope)))
    return out


def _at(p: Poly, y: Q) -> Q:
    acc = Q(0)
    for c in reversed(p):
        acc = acc * y + c
    return acc


def _mul(a: Poly, b: Poly) -> Poly:
    out = [Q(0)] * (len(a) + len(b) - 1)
    for i, x in enumerate(a):
        for j, y in enumerate(b):
            out[i + j] += x * y
    return tuple(out)


def _add(a: Poly, b: Poly) -> Poly:
    n = max(len(a), len(b))
    return tuple((a[i] if i < len(a) else 0) + (b[i] if i < len(b) else 0) for i in range(n))


def _integral(p: Poly, u: Q, v: Q, power: int) -> Q:
    """int_u^v y^power p(y) dy."""
    return sum(
        (
            c * (v ** (k + power + 1) - u ** (k + power + 1)) / (k + power + 1)
            for k, c in enumerate(p)
        ),
        Q(0),
    )


class ExactSet:
    """The aggregated output set of ``rb``'s first output for per-rule firing levels."""

    def __init__(self, rb: RuleBase, levels: list[float]) -> None:
        out = rb.outputs[0]
        self.lo, self.hi = Q(out.low), Q(out.high)
        self.ops = rb.operators
        # one piece per rule consequent on this output: (level, edges of its term)
        self.pieces = [
            (Q(levels[r]), _edges(out.term(c.term), self.lo, self.hi))
            for r, rule in enumerate(rb.rules)
            for c in rule.consequents
            if c.variable == out.name
        ]
        lines: list[Poly] = []
        cuts = {self.lo, self.hi}
        for level, edges in self.pieces:
            for y0, y1, line in edges:
                cuts.update((y0, y1))
                lines.append(_mul((level,), line) if self.ops.implication == "product" else line)
            if self.ops.implication == "min":
                lines.append((level, Q(0)))
        for a, b in itertools.combinations(set(lines), 2):
            if a[1] != b[1]:
                cuts.add((b[0] - a[0]) / (a[1] - b[1]))
        points = sorted(y for y in cuts if self.lo <= y <= self.hi)
        self.segments: list[tuple[Q, Q, Poly]] = []
        for u, v in itertools.pairwise(points):
            self._segment(u, v)

    def _implied(self, level: Q, edges: list[tuple[Q, Q, Poly]], m: Q) -> Poly:
        for y0, y1, line in edges:
            if y0 < m < y1:
                if self.ops.implication == "product":
                    return _mul((level,), line)
                return (level,) if level <= _at(line, m) else line
        return (Q(0),)

    def _segment(self, u: Q, v: Q) -> None:
        m = (u + v) / 2
        parts = [self._implied(level, edges, m) for level, edges in self.pieces]
        agg = self.ops.aggregation
        if agg == "max":
            self.segments.append((u, v, max(parts, key=lambda p: _at(p, m))))
            return
        if agg == "probabilistic_sum":
            rest: Poly = (Q(1),)
            for p in parts:
                rest = _mul(rest, _add((Q(1),), tuple(-c for c in p)))
            self.segments.append((u, v, _add((Q(1),), tuple(-c for c in rest))))
            return
        total: Poly = (Q(0),)
        for p in parts:
            total = _add(total, p)
        su, sv = _at(total, u) - 1, _at(total, v) - 1
        if su * sv < 0:  # a line: where it reaches 1
            c = u + (v - u) * su / (su - sv)
            for a, b in ((u, c), (c, v)):
                self.segments.append((a, b, (Q(1),) if _at(total, (a + b) / 2) > 1 else total))
            return
        self.segments.append((u, v, (Q(1),) if _at(total, m) > 1 else total))

    def area_moment(self) -> tuple[Q, Q]:
        area = sum((_integral(p, u, v, 0) for u, v, p in self.segments), Q(0))
        moment = sum((_integral(p, u, v, 1) for u, v, p in self.segments), Q(0))
        return area, moment

    def bisector(self) -> float:
        area, _ = self.area_moment()
        rest = area / 2
        for u, v, p in self.segments:
            part = _integral(p, u, v, 0)
            if part >= rest and part > 0:
                a, b = float(u), float(v)
                for _ in range(200):  # bisection on doubles, each step exact
                    mid = 0.5 * (a + b)
                    if mid in (a, b):
                        break
                    if _integral(p, u, Q(mid), 0) < rest:
                        a = mid
                    else:
                        b = mid
                return 0.5 * (a + b)
            rest -= part
        return float(self.segments[-1][1])

    def maxima(self) -> tuple[Q, Q, Q]:
        """Height, smallest and largest point of maximum (linear sets only; values within
        1e-10 of the height, as a share of it, count as maximal, as the engine defines it)."""
        values: dict[Q, Q] = {}
        for u, v, p in self.segments:
            if len(p) > 2 and any(p[2:]):
                raise NotImplementedError("exact reference: maxima of a curved set")
            for y in (u, v):
                values[y] = max(values.get(y, Q(0)), _at(p, y))
        height = max(values.values())
        # values within 1e-10 of the height (a share) are one maximum: the engine's definition
        at_max = [y for y, f in values.items() if f >= height * (1 - Q(1, 10**10))]
        return height, min(at_max), max(at_max)


def exact_output(rb: RuleBase, point: dict[str, float]) -> float | None:
    """The first output of ``rb`` at ``point`` from the exact aggregated set (None: none fired)."""
    s = ExactSet(rb, firing(rb, point))
    area, moment = s.area_moment()
    if area == 0:
        return None
    d = rb.defuzzifier
    if d == "centroid":
        return float(moment / area)
    if d == "bisector":
        return s.bisector()
    _, som, lom = s.maxima()
    return float({"smallest_of_maximum": som, "largest_of_maximum": lom}.get(d, (som + lom) / 2))
