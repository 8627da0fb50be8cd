"""Whether some rule fires everywhere: rule coverage over every combination of input labels.

An output is undefined (NaN, or its ``default``) wherever no rule concluding it fires. A rule's
firing strength is above zero exactly where its condition's propositions are: ``x is T`` where
``mu_T(x) > 0`` (the term's support, known exactly), ``x is not T`` where ``mu_T(x) < 1``. So
along each input, the points that matter are the ends of every support, every term parameter
(the ends of every core: a triangle's peak, a trapezoid's plateau, a Gaussian's mean) and the
range's ends; between two consecutive ones, which terms are above zero and which are below one
does not change. :func:`regions` tests every such point and one point inside every interval
between them, and merges the points with the same active terms into one *region* of the input.
Every combination of one region per input is then decided exactly, rule by rule, for the
whole box it stands for; this covers the label peaks, the crossings and everything between,
for overlapping non-partition terms too. Where the product of region counts exceeds
:data:`MAX_COMBINATIONS` the check is not made and says so (a warning).

What is checked is the model's arithmetic: a term whose membership is mathematically positive
but underflows to 0 in floating point (a Gaussian 40 sigmas from its mean) counts as active.
Inputs are checked on their ranges (``clamp`` rule bases never see other values).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TypeAlias

import numpy as np
import numpy.typing as npt

from fuzzkit.fuzzy.membership import evaluate_term
from fuzzkit.fuzzy.model import Compound, Expression, RuleBase, Variable
from fuzzkit.fuzzy.shapes import Piece
from fuzzkit.fuzzy.shapes import shape as shape_record

PathPart: TypeAlias = str | int
Issue: TypeAlias = tuple[tuple[PathPart, ...], str]
BoolArray: TypeAlias = npt.NDArray[np.bool_]

#: Combinations of input regions checked at most (a 3-input rule base of 9 labels per input
#: has about 20**3); beyond, the check is skipped with a warning rather than taking minutes.
MAX_COMBINATIONS = 2_000_000
#: Uncovered label combinations listed in one message of a rule list (the rest are counted).
MAX_LISTED = 6


@dataclass(frozen=True, slots=True)
class Region:
    """A part of an input's range on which the same terms are above 0 and below 1."""

    active: frozenset[str]
    below_one: frozenset[str]
    example: float


def _inside(x: float, pieces: Sequence[Piece]) -> bool:
    return any(
        (lo < x or (lo == x and lo_in)) and (x < hi or (x == hi and hi_in))
        for lo, lo_in, hi, hi_in in pieces
    )


def regions(var: Variable) -> list[Region]:
    """The distinct regions of ``var``'s range, each with its first point as the example."""
    supports = {t.name: shape_record(t.shape).support(t.params) for t in var.terms}
    ends = {var.low, var.high}
    for t in var.terms:
        candidates = [v for piece in supports[t.name] for v in (piece[0], piece[2])]
        ends.update(v for v in (*candidates, *t.params) if var.low < v < var.high)
    xs = sorted(ends)
    points = sorted({*xs, *(0.5 * (a + b) for a, b in itertools.pairwise(xs))})
    seen: dict[tuple[frozenset[str], frozenset[str]], Region] = {}
    for x in points:
        active = frozenset(n for n, pieces in supports.items() if _inside(x, pieces))
        below = frozenset(
            t.name for t in var.terms if float(evaluate_term(t, np.array([x]))[0]) < 1.0
        )
        seen.setdefault((active, below), Region(active, below, x))
    return list(seen.values())


def _fires(expr: Expression, by_var: dict[str, tuple[int, list[Region]]], ndim: int) -> BoolArray:
    """Where ``expr`` is above zero, over the grid of region combinations (broadcast)."""
    if isinstance(expr, Compound):
        parts = [_fires(sub, by_var, ndim) for sub in expr.operands]
        out = parts[0]
        for p in parts[1:]:
            out = (out & p) if expr.op == "and" else (out | p)
        return out
    axis, regs = by_var[expr.variable]
    flags = np.array(
        [(expr.term in r.below_one) if expr.negated else (expr.term in r.active) for r in regs]
    )
    shape = [1] * ndim
    shape[axis] = len(regs)
    return flags.reshape(shape)


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
    all_regions = [[r for r in regions(v) if r.active] for v in rb.inputs]
    count = math.prod(len(r) for r in all_regions)
    if count > MAX_COMBINATIONS:
        why = (
            f"rule coverage not checked: {count} combinations of input regions, more than "
            f"{MAX_COMBINATIONS}; where no rule fires, outputs take their default, or NaN"
        )
        return [], [(("rules",), why)]
    if count == 0:
        return [], []
    ndim = len(rb.inputs)
    by_var = {v.name: (i, all_regions[i]) for i, v in enumerate(rb.inputs)}
    errors: list[Issue] = []
    warnings: list[Issue] = []
    for out in rb.outputs:
        fired = np.zeros([len(r) for r in all_regions], dtype=bool)
        for rule in rb.rules:
            if rule.weight > 0.0 and any(c.variable == out.name for c in rule.consequents):
                fired |= _fires(rule.antecedent, by_var, ndim)
        empty = [tuple(int(i) for i in idx) for idx in np.argwhere(~fired)]
        if not empty:
            continue
        issues = _issues(rb, out, empty, all_regions)
        (warnings if out.default is not None else errors).extend(issues)
    return errors, warnings


def _consequence(out: Variable) -> str:
    if out.default is not None:
        return f"{out.name!r} takes its default {_fmt(out.default)} there"
    return f"{out.name!r} would be NaN there; add the rule(s) or declare a default for {out.name!r}"


def _cells(
    rb: RuleBase, empty: list[tuple[int, ...]], regs: list[list[Region]]
) -> list[tuple[tuple[str, ...], tuple[float, ...]]]:
    """The label combinations no rule reaches, in label order, each with a point of it.

    A combination of regions where nothing fires makes every combination of its active labels
    rule-less there: a rule on those labels would fire.
    """
    cells: dict[tuple[str, ...], tuple[float, ...]] = {}
    for idx in empty:
        chosen = [regs[i][k] for i, k in enumerate(idx)]
        example = tuple(r.example for r in chosen)
        for labels in itertools.product(*(sorted(r.active) for r in chosen)):
            cells.setdefault(labels, example)
    orders = [v.term_names for v in rb.inputs]
    return sorted(
        cells.items(), key=lambda kv: [o.index(n) for o, n in zip(orders, kv[0], strict=True)]
    )


def _issues(
    rb: RuleBase, out: Variable, empty: list[tuple[int, ...]], regs: list[list[Region]]
) -> list[Issue]:
    """One issue per empty table cell of ``out``'s table, else one at the rules block."""
    names = rb.input_names
    cells = _cells(rb, empty, regs)

    def at(labels: tuple[str, ...], example: tuple[float, ...]) -> str:
        where = " and ".join(f"{n} is {lab}" for n, lab in zip(names, labels, strict=True))
        point = ", ".join(f"{n}={_fmt(x)}" for n, x in zip(names, example, strict=True))
        return f"{where} (e.g. at {point})"

    t = rb.table
    if t is not None and t.output == out.name and names == (t.rows, t.columns):
        return [
            (
                ("rules", "table", "cells", *labels),
                f"no rule fires for output {out.name!r} where {at(labels, example)}, an empty "
                f"cell: {_consequence(out)}",
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
