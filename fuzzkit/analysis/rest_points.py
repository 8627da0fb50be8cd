"""A proof that the set point is the loop's only rest point on an interval of the scaled error.

The loop rests where ``F(x, 0) = 0`` (:mod:`fuzzkit.analysis.equilibrium`). Sampling ``F`` can
miss a pair of zeros closer together than the samples; this module proves their absence with
sound bounds and no samples:

* **exact surface**: the interval ``[a, b]`` of ``x`` (with ``de = 0``) is cut into cells whose
  width grows geometrically away from ``x = 0`` (:data:`RATIO`), each cell's ``F`` is enclosed
  (:class:`fuzzkit.analysis.surface_enclosure.Enclosure`, :data:`BINS` output bins) and a cell
  whose enclosure holds 0 is bisected, :data:`DEPTH` times at most. A cell left holding 0 may
  hold a rest point. Those that touch the set point form the unresolved neighbourhood
  ``(-delta_neg, delta_pos)``; any other is a possible second rest point;
* **table surface**: ``F(x, 0)`` is piecewise linear with its kinks at the table's breakpoints
  and where the line ``de = 0`` crosses a cell's diagonal; its values there decide exactly.

The neighbourhood of the set point stays unresolved because ``F(0, 0) = 0``: its width is where
the enclosure's resolution (about one output bin, times the inverse slope) meets the surface.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fuzzkit.analysis.intervals import FloatArray, Interval
from fuzzkit.analysis.surface_enclosure import Enclosure
from fuzzkit.fuzzy.model import RuleBase
from fuzzkit.loop.compiled.table import TableArrays, table2

#: Width ratio of neighbouring cells away from the set point, and the first cell's edge.
RATIO = 1.125
START = 1e-4
#: Output bins of the value enclosure, and how often a cell holding 0 is bisected.
BINS = 2048
DEPTH = 10


@dataclass(frozen=True, slots=True)
class RestProof:
    """Where ``F(x, 0)`` may vanish on ``[low, high]`` besides ``x = 0``.

    ``near``: ``(-delta_neg, delta_pos)``, the unresolved neighbourhood of the set point
    (``(0, 0)`` for a table: exact). ``others``: intervals of ``x`` that may hold another rest
    point (empty: proven). ``method``: how.
    """

    low: float
    high: float
    near: tuple[float, float]
    others: tuple[tuple[float, float], ...]
    method: str

    @property
    def proven(self) -> bool:
        """No other rest point in ``[low, high]`` outside ``near``."""
        return not self.others

    def within(self, low: float, high: float) -> tuple[tuple[float, float], ...]:
        """The possible other rest points that meet ``[low, high]``."""
        return tuple(iv for iv in self.others if iv[0] <= high and iv[1] >= low)

    def as_dict(self) -> dict[str, object]:
        """JSON form."""
        return {
            "proven_on_scaled_error": [self.low, self.high],
            "unresolved_near_set_point": list(self.near),
            "possible_other_rest_points": [list(iv) for iv in self.others],
            "method": self.method,
        }


def _side(enc: Enclosure, edge: float) -> tuple[float, list[tuple[float, float]]]:
    """Cells from ``START`` to ``|edge|`` on the side of ``edge``'s sign: the unresolved
    reach next to 0 and the cells that may hold a zero farther out."""
    sign = 1.0 if edge > 0.0 else -1.0
    reach = abs(edge)
    if reach <= START:
        return reach, []
    n = max(1, math.ceil(math.log(reach / START) / math.log(RATIO)))
    bounds = np.unique(np.append(START * RATIO ** np.arange(n + 1), reach))
    bounds = bounds[bounds <= reach]
    cells = np.stack([bounds[:-1], bounds[1:]], 1)
    open_cells: list[FloatArray] = []
    for depth in range(DEPTH + 1):
        if cells.size == 0:
            break
        f = _enclose_line(enc, cells, sign)
        cells = cells[(f.lo <= 0.0) & (f.hi >= 0.0)]
        if cells.size == 0:
            break
        # a cell whose midpoint's own enclosure holds 0 is at the enclosure's resolution:
        # bisecting cannot clear it
        mid = 0.5 * (cells[:, 0] + cells[:, 1])
        at_mid = _enclose_line(enc, np.stack([mid, mid], 1), sign)
        stuck = (at_mid.lo <= 0.0) & (at_mid.hi >= 0.0)
        if depth == DEPTH:
            open_cells.append(cells)
            break
        open_cells.append(cells[stuck])
        cells, mid = cells[~stuck], mid[~stuck]
        cells = np.concatenate([np.stack([cells[:, 0], mid], 1), np.stack([mid, cells[:, 1]], 1)])
    left = np.concatenate(open_cells) if open_cells else np.zeros((0, 2))
    intervals = _merge(sorted((float(a), float(b)) for a, b in left))
    near = START
    others = []
    for a, b in intervals:
        if a <= near:
            near = max(near, b)
        else:
            others.append((a, b) if sign > 0 else (-b, -a))
    return near, others


def _enclose_line(enc: Enclosure, cells: FloatArray, sign: float) -> Interval:
    lo, hi = (cells[:, 0], cells[:, 1]) if sign > 0 else (-cells[:, 1], -cells[:, 0])
    zero = np.zeros_like(lo)
    return enc.enclose(lo, hi, zero, zero, tighten=False).f


def _merge(cells: list[tuple[float, float]]) -> list[tuple[float, float]]:
    out: list[tuple[float, float]] = []
    for a, b in cells:
        if out and a <= out[-1][1]:
            out[-1] = (out[-1][0], max(out[-1][1], b))
        else:
            out.append((a, b))
    return out


def prove_exact(rb: RuleBase, low: float, high: float) -> RestProof:
    """The proof on the exact surface of ``rb`` (inputs in role order, clamped)."""
    enc = Enclosure(rb, bins=BINS)
    near_pos, pos = _side(enc, high) if high > 0.0 else (0.0, [])
    near_neg, neg = _side(enc, low) if low < 0.0 else (0.0, [])
    return RestProof(
        low,
        high,
        (-near_neg, near_pos),
        tuple(sorted(neg + pos)),
        "sound: interval enclosures of F(x, 0) on cells growing away from the set point",
    )


def prove_table(table: TableArrays, low: float, high: float) -> RestProof:
    """The proof on a deployed table (exact: its values at the kinks of ``F(x, 0)``)."""
    bp0, bp1 = table.bp0, table.bp1
    knots = set(float(b) for b in bp0 if low <= b <= high) | {low, high, 0.0}
    j = int(np.searchsorted(bp1, 0.0, side="right")) - 1
    if 0 <= j < bp1.size - 1 and bp1[j] < 0.0:
        # the line de = 0 crosses this row of cells, and every cell's diagonal
        t = (0.0 - bp1[j]) / (bp1[j + 1] - bp1[j])
        for i in range(bp0.size - 1):
            for frac in (t, 1.0 - t):
                x = float(bp0[i] + frac * (bp0[i + 1] - bp0[i]))
                if low <= x <= high:
                    knots.add(x)
    xs = np.array(sorted(knots))
    fs = np.array([table2(bp0, bp1, table.values, table.splits, float(x), 0.0) for x in xs])
    others = []
    for k in range(xs.size - 1):
        a, b = float(xs[k]), float(xs[k + 1])
        if (
            (fs[k] * fs[k + 1] <= 0.0)
            and not (a == 0.0 and fs[k + 1] != 0.0)
            and not (b == 0.0 and fs[k] != 0.0)
        ):
            others.append((a, b))
    return RestProof(low, high, (0.0, 0.0), tuple(_merge(others)), "exact: the table's values")
