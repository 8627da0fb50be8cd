"""Numeric limits of a rule base: what the engines can resolve in double precision.

The engines integrate and interpolate over a variable's range; a term whose features (the
distance between two distinct points of a piecewise-linear term, a gaussian's sigma, a
sigmoid's ``1/|slope|``) are tiny beside that range, a range of subnormal width, or one far out
near the float limits cannot be evaluated reliably (breakpoints merge, slopes overflow). Such
rule bases are refused by validation with these limits, so ``validate`` never says ok for a
file that ``eval`` then cannot handle:

- a range's ends lie within ``±``:data:`MAX_MAGNITUDE` and its width is at least
  :data:`MIN_WIDTH` and at least :data:`MIN_RELATIVE_WIDTH` of its largest end;
- every term feature is at least :data:`RESOLUTION` of the range width.
"""

from __future__ import annotations

from fuzzkit.fuzzy.model import Term, Variable
from fuzzkit.fuzzy.shapes import shape

#: Range ends beyond this are refused (moments of the centroid square them).
MAX_MAGNITUDE = 1e100
#: The narrowest range, absolute (features of RESOLUTION of it stay normal floats).
MIN_WIDTH = 1e-100
#: The narrowest range relative to its largest end (so features are many float steps apart).
MIN_RELATIVE_WIDTH = 1e-6
#: The smallest term feature, relative to the range width.
RESOLUTION = 1e-9


def _fmt(x: float) -> str:
    return f"{x:.6g}"


def range_problem(var: Variable) -> str | None:
    """Why ``var``'s (finite, ordered) range is beyond the engines' numbers, or None."""
    low, high = var.low, var.high
    largest = max(abs(low), abs(high))
    width = high - low
    if largest > MAX_MAGNITUDE:
        return (
            f"range [{_fmt(low)}, {_fmt(high)}] reaches beyond ±{MAX_MAGNITUDE:g}; "
            "express the variable in larger units"
        )
    if width < MIN_WIDTH or width < MIN_RELATIVE_WIDTH * largest:
        return (
            f"range [{_fmt(low)}, {_fmt(high)}] is {_fmt(width)} wide, too narrow to resolve "
            f"(at least {MIN_WIDTH:g} and {MIN_RELATIVE_WIDTH:g} of its largest end); "
            "express the variable in smaller units or shift it towards 0"
        )
    return None


def term_problem(term: Term, var: Variable) -> str | None:
    """Why a valid ``term`` of ``var`` (whose range is fine) is too fine to evaluate, or None."""
    smallest = RESOLUTION * (var.high - var.low)
    for what, size in shape(term.shape).features(term.params):  # the shape registry's
        if size < smallest:
            return (
                f"term {term.name!r}: {what.format(_fmt(size))}, below the engines' "
                f"resolution of {RESOLUTION:g} of the range width ({_fmt(smallest)}); "
                "widen the term or narrow the range"
            )
    return None
