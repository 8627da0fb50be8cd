"""Terms that do not fit their variable's range: wholly outside it, or a shoulder cut short.

A term whose membership is 0 everywhere on ``[low, high]`` can never take part (an error, at
the term). A shoulder is the label of everything beyond its plateau: a left shoulder whose
plateau ends before ``low`` (or a right one whose plateau starts after ``high``) never reaches
membership 1 inside the range, which is legal but almost always a typo (a warning, at the
term's points). Both are decided exactly from the shapes' supports and parameters.
"""

from __future__ import annotations

from typing import TypeAlias

from fuzzkit.fuzzy.model import RuleBase, Variable
from fuzzkit.fuzzy.shapes import shape as shape_record

PathPart: TypeAlias = str | int
Issue: TypeAlias = tuple[tuple[PathPart, ...], str]


def _fmt(x: float) -> str:
    return format(x, ".6g")


def _touches(var: Variable, lo: float, lo_in: bool, hi: float, hi_in: bool) -> bool:
    """Whether the support piece (lo, hi) holds a point of ``[var.low, var.high]``."""
    if hi < var.low or lo > var.high:
        return False
    if hi == var.low:
        return hi_in
    if lo == var.high:
        return lo_in
    return True


def misplaced_terms(rb: RuleBase) -> tuple[list[Issue], list[Issue]]:
    """Errors (terms wholly outside their range) and warnings (shoulders that never reach 1
    inside it) of every membership-function term; ``rb``'s terms must be valid."""
    errors: list[Issue] = []
    warnings: list[Issue] = []
    for kind, group in (("input", rb.inputs), ("output", rb.outputs)):
        for var in group:
            span = f"[{_fmt(var.low)}, {_fmt(var.high)}]"
            for term in var.terms:
                if term.is_sugeno:
                    continue
                base = (kind + "s", var.name, "terms", term.name)
                pieces = shape_record(term.shape).support(term.params)
                if not any(_touches(var, *piece) for piece in pieces):
                    errors.append(
                        (
                            base,
                            f"term {term.name!r} lies wholly outside the range {span} of "
                            f"{kind} {var.name!r} (its membership is 0 everywhere on it)",
                        )
                    )
                    continue
                if term.shape == "left_shoulder" and term.params[0] < var.low:
                    top, side = term.params[0], "ends before the range starts"
                elif term.shape == "right_shoulder" and term.params[1] > var.high:
                    top, side = term.params[1], "starts after the range ends"
                else:
                    continue
                warnings.append(
                    (
                        (*base, "points"),
                        f"shoulder {term.name!r} never reaches 1 inside the range {span} of "
                        f"{kind} {var.name!r}: its plateau (membership 1 at {_fmt(top)}) {side}",
                    )
                )
    return errors, warnings
