"""Whether some rule fires everywhere: rule coverage over every combination of input labels.

An output is undefined (NaN, or its ``default``) wherever no rule concluding it fires. What is
checked is the engine's arithmetic: a rule fires where its computed firing strength is above
0, so a Gaussian tail that underflows to 0, a product of two tiny memberships that underflows,
and the ``NOT`` of a sigmoid that saturates to exactly 1 all count as not firing (issue 40
item 3). Each input's range is cut into parts (:func:`fuzzkit.fuzzy.membership_bounds.parts`)
on each of which every term's computed membership is decided, above 0 or 0, and for negated
terms below 1 or 1, with sound bounds; a combination of one part per input is a box, and each
rule's firing strength over a box is bounded by interval arithmetic on those bounds (AND as
min or product, OR as max or probabilistic sum, NOT as ``1 - mu``, the weight). A box is
covered when some rule's lower bound is above 0, empty when every upper bound is 0. Under min
AND the parts decide every box; under product AND a box whose product of lower bounds
underflows is halved along its widest input, up to :data:`MAX_SPLITS` times (and
:data:`MAX_BOXES` boxes per output), and what is still open then is reported as not covered
(never the other way round). This
covers the label peaks, the crossings and everything between, for overlapping, non-partition
and smooth terms alike. Where the product of cell counts exceeds :data:`MAX_COMBINATIONS`
the check is not made and says so (a warning). Inputs are checked on their ranges (``clamp``
rule bases never see other values).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TypeAlias

import numpy as np
import numpy.typing as npt

from fuzzkit.fuzzy.membership_bounds import Part, enclosure, parts
from fuzzkit.fuzzy.model import Compound, Expression, Proposition, RuleBase, Variable

PathPart: TypeAlias = str | int
Issue: TypeAlias = tuple[tuple[PathPart, ...], str]
FloatArray: TypeAlias = npt.NDArray[np.float64]
#: A bound of a firing strength over a grid of boxes: (lower, upper), broadcast.
Bounds: TypeAlias = tuple[FloatArray, FloatArray]

#: Combinations of input cells checked at most (a 3-input rule base of 9 labels per input
#: has about 40**3); beyond, the check is skipped with a warning rather than taking minutes.
MAX_COMBINATIONS = 2_000_000
#: Uncovered label combinations listed in one message of a rule list (the rest are counted).
MAX_LISTED = 6
#: Halvings of a box whose rules the bounds leave open, and of all such boxes of an output.
MAX_SPLITS = 12
MAX_BOXES = 256


@dataclass(frozen=True, slots=True)
class Region:
    """One input's interval of a box no rule is proven to fire on: the terms whose computed
    membership may be above 0 there (the labels a rule would need), and a point of it."""

    active: frozenset[str]
    example: float
    #: the region is a single point (a cut point: a peak, a support end, a range end)
    point: bool = False


def _term_bounds(var: Variable, lo: FloatArray, hi: FloatArray) -> dict[str, Bounds]:
    return {t.name: enclosure(t, lo, hi) for t in var.terms}


def _firing(
    expr: Expression, rb: RuleBase, bounds: dict[str, tuple[int, dict[str, Bounds]]], ndim: int
) -> Bounds:
    """Bounds of ``expr``'s computed firing strength over a grid of boxes (broadcast)."""
    if isinstance(expr, Compound):
        parts_ = [_firing(sub, rb, bounds, ndim) for sub in expr.operands]
        lo, hi = parts_[0]
        for p_lo, p_hi in parts_[1:]:
            if expr.op == "and" and rb.operators.and_ == "min":
                lo, hi = np.minimum(lo, p_lo), np.minimum(hi, p_hi)
            elif expr.op == "and":
                lo, hi = lo * p_lo, hi * p_hi
            elif rb.operators.or_ == "max":
                lo, hi = np.maximum(lo, p_lo), np.maximum(hi, p_hi)
            else:  # probabilistic sum a + b - ab: at least max(a, b) (halved: rounding)
                lo = 0.5 * np.maximum(lo, p_lo)
                hi = np.minimum(1.0, 2.0 * np.maximum(hi, p_hi))
        return lo, hi
    axis, by_term = bounds[expr.variable]
    t_lo, t_hi = by_term[expr.term]
    if expr.negated:
        t_lo, t_hi = 1.0 - t_hi, 1.0 - t_lo
    shape = [1] * ndim
    shape[axis] = t_lo.shape[0]
    return t_lo.reshape(shape), t_hi.reshape(shape)


def _rules_bounds(
    rb: RuleBase, out: Variable, bounds: dict[str, tuple[int, dict[str, Bounds]]], grid: list[int]
) -> tuple[npt.NDArray[np.bool_], npt.NDArray[np.bool_]]:
    """Over a grid of boxes: where some rule concluding ``out`` surely fires, and where some
    rule may fire."""
    ndim = len(rb.inputs)
    fires = np.zeros(grid, dtype=bool)
    may = np.zeros(grid, dtype=bool)
    for rule in rb.rules:
        if rule.weight > 0.0 and any(c.variable == out.name for c in rule.consequents):
            lo, hi = _firing(rule.antecedent, rb, bounds, ndim)
            fires |= lo * rule.weight > 0.0
            may |= hi * rule.weight > 0.0
    return fires, may


def _box_bounds(
    rb: RuleBase, box: Sequence[tuple[float, float]]
) -> dict[str, tuple[int, dict[str, Bounds]]]:
    return {
        v.name: (i, _term_bounds(v, np.array([lo]), np.array([hi])))
        for i, (v, (lo, hi)) in enumerate(zip(rb.inputs, box, strict=True))
    }


def _box_regions(rb: RuleBase, box: Sequence[tuple[float, float]]) -> tuple[Region, ...]:
    regions = []
    for (_, by_term), (lo, hi) in zip(_box_bounds(rb, box).values(), box, strict=True):
        active = frozenset(n for n, (_, t_hi) in by_term.items() if float(t_hi[0]) > 0.0)
        regions.append(Region(active, lo if lo == hi else min(max(0.5 * (lo + hi), lo), hi)))
    return tuple(regions)


def _split(box: tuple[tuple[float, float], ...]) -> list[tuple[tuple[float, float], ...]]:
    """``box`` halved along its widest input (relative to the size of its numbers)."""
    widths = [(hi - lo) / max(abs(lo), abs(hi), 1e-300) for lo, hi in box]
    k = int(np.argmax(widths))
    lo, hi = box[k]
    mid = min(max(0.5 * (lo + hi), lo), math.nextafter(hi, -math.inf))
    return [
        (*box[:k], half, *box[k + 1 :]) for half in ((lo, mid), (math.nextafter(mid, math.inf), hi))
    ]


def _negated(rb: RuleBase) -> dict[str, frozenset[str]]:
    """Per input, the terms some rule negates (their value 1 matters, not only 0)."""
    found: dict[str, set[str]] = {v.name: set() for v in rb.inputs}

    def walk(expr: Expression) -> None:
        if isinstance(expr, Compound):
            for sub in expr.operands:
                walk(sub)
        elif expr.negated:
            found[expr.variable].add(expr.term)

    for rule in rb.rules:
        walk(rule.antecedent)
    return {k: frozenset(v) for k, v in found.items()}


def _unproven(
    rb: RuleBase, out: Variable, all_parts: Sequence[Sequence[Part]]
) -> list[tuple[Region, ...]]:
    """The boxes (as regions per input) where no rule concluding ``out`` is proven to fire."""
    bounds = {
        v.name: (
            i,
            {
                t.name: (np.array([p.low[k] for p in ps]), np.array([p.high[k] for p in ps]))
                for k, t in enumerate(v.terms)
            },
        )
        for i, (v, ps) in enumerate(zip(rb.inputs, all_parts, strict=True))
    }
    fires, may = _rules_bounds(rb, out, bounds, [len(ps) for ps in all_parts])
    found: list[tuple[Region, ...]] = []
    open_boxes: list[tuple[tuple[tuple[float, float], ...], int]] = []
    for idx in np.argwhere(~fires):
        chosen = [all_parts[i][k] for i, k in enumerate(idx)]
        if may[tuple(idx)]:  # only under product AND: the product of the bounds underflows
            open_boxes.append((tuple((p.lo, p.hi) for p in chosen), 0))
        else:
            found.append(tuple(_region(p, v) for p, v in zip(chosen, rb.inputs, strict=True)))
    budget = MAX_BOXES
    while open_boxes:
        box, depth = open_boxes.pop()
        if depth >= MAX_SPLITS or budget <= 0 or all(lo == hi for lo, hi in box):
            found.append(_box_regions(rb, box))
            continue
        for half in _split(box):
            budget -= 1
            h_fires, h_may = _rules_bounds(rb, out, _box_bounds(rb, half), [1] * len(half))
            if bool(h_fires.any()):
                continue
            if bool(h_may.any()):
                open_boxes.append((half, depth + 1))
            else:
                found.append(_box_regions(rb, half))
    return found


def _region(part: Part, var: Variable) -> Region:
    names = frozenset(var.terms[k].name for k in part.positive())
    return Region(names, part.example, part.lo == part.hi)


def _fmt(x: float) -> str:
    return format(x, ".6g")


def rule_gaps(rb: RuleBase) -> tuple[list[Issue], list[Issue]]:
    """Errors and warnings for the places where no rule concluding an output fires.

    One issue per empty cell of a rule table (path ``("rules", "table", "cells", row, col)``),
    one per output for a rule list (path ``("rules",)``). An output with a ``default`` gets
    warnings (it takes the default there), one without gets errors (it would be NaN). Points
    where an input has no term above zero are left out: the input's coverage check reports
    them. ``rb`` must be valid otherwise (terms, references).
    """
    negated = _negated(rb)
    all_parts = [parts(v, negated[v.name]) for v in rb.inputs]
    count = math.prod(len(c) for c in all_parts)
    if count > MAX_COMBINATIONS:
        why = (
            f"rule coverage not checked: {count} combinations of input cells, more than "
            f"{MAX_COMBINATIONS}; where no rule fires, outputs take their default, or NaN"
        )
        return [], [(("rules",), why)]
    errors: list[Issue] = []
    warnings: list[Issue] = []
    for out in rb.outputs:
        # boxes where an input has no term above 0 are the input coverage check's
        empty = [regs for regs in _unproven(rb, out, all_parts) if all(r.active for r in regs)]
        if not empty:
            continue
        issues = _issues(rb, out, empty)
        (warnings if out.default is not None else errors).extend(issues)
    return errors, warnings


def _consequence(out: Variable) -> str:
    if out.default is not None:
        return f"{out.name!r} takes its default {_fmt(out.default)} there"
    return f"{out.name!r} would be NaN there; add the rule(s) or declare a default for {out.name!r}"


def _cells(
    rb: RuleBase, empty: list[tuple[Region, ...]]
) -> list[tuple[tuple[str, ...], tuple[float, ...]]]:
    """The label combinations no rule reaches, in label order, each with a point of it.

    A box where nothing fires makes every combination of its active labels rule-less there:
    a rule on those labels would fire.
    """
    cells_: dict[tuple[str, ...], tuple[tuple[float, ...], int]] = {}
    for chosen in empty:
        example = tuple(r.example for r in chosen)
        points = sum(r.point for r in chosen)
        for labels in itertools.product(*(sorted(r.active) for r in chosen)):
            # the example at the most cut points (e=0 rather than e=-2.8e-17 beside it)
            if labels not in cells_ or points > cells_[labels][1]:
                cells_[labels] = (example, points)
    orders = [v.term_names for v in rb.inputs]
    return sorted(
        ((labels, example) for labels, (example, _) in cells_.items()),
        key=lambda kv: [o.index(n) for o, n in zip(orders, kv[0], strict=True)],
    )


#: Why a table cell with a rule is reported: its firing strength computes to 0 somewhere.
UNDERFLOW = "its cell's rule computes a firing strength of 0 there (floating-point underflow)"


def _labelled_rules(rb: RuleBase, out: Variable) -> set[tuple[str, ...]]:
    """The label combinations (one label per input, in input order) that a rule of the form
    ``x1 is A and x2 is B ...`` concluding ``out`` names: a table's non-empty cells."""
    found = set()
    for rule in rb.rules:
        if not any(c.variable == out.name for c in rule.consequents):
            continue
        expr = rule.antecedent
        props = expr.operands if isinstance(expr, Compound) and expr.op == "and" else (expr,)
        by_var = {p.variable: p.term for p in props if isinstance(p, Proposition) and not p.negated}
        if len(by_var) == len(props) == len(rb.inputs):
            found.add(tuple(by_var.get(v.name, "") for v in rb.inputs))
    return found


def _issues(rb: RuleBase, out: Variable, empty: list[tuple[Region, ...]]) -> list[Issue]:
    """One issue per empty table cell of ``out``'s table, else one at the rules block."""
    names = rb.input_names
    cells = _cells(rb, empty)

    def at(labels: tuple[str, ...], example: tuple[float, ...]) -> str:
        where = " and ".join(f"{n} is {lab}" for n, lab in zip(names, labels, strict=True))
        point = ", ".join(f"{n}={_fmt(x)}" for n, x in zip(names, example, strict=True))
        return f"{where} (e.g. at {point})"

    t = rb.table
    if t is not None and t.output == out.name and set(names) == {t.rows, t.columns}:
        # the cell's path is (row label, column label), whichever input the rows are
        flip = names != (t.rows, t.columns)
        ruled = _labelled_rules(rb, out)
        return [
            (
                ("rules", "table", "cells", *(labels[::-1] if flip else labels)),
                f"no rule fires for output {out.name!r} where {at(labels, example)}, "
                + (UNDERFLOW if labels in ruled else "an empty cell")
                + f": {_consequence(out)}",
            )
            for labels, example in cells
        ]
    shown = "; where ".join(at(labels, example) for labels, example in cells[:MAX_LISTED])
    more = f"; and {len(cells) - MAX_LISTED} more" if len(cells) > MAX_LISTED else ""
    return [
        (
            ("rules",),
            f"no rule fires for output {out.name!r} where {shown}{more}: {_consequence(out)}",
        )
    ]
