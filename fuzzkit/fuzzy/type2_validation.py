"""Semantic checks of an interval type-2 rule base's footprint (called by fuzzy.validation).

Paths follow :mod:`fuzzkit.fuzzy.validation`; a lower term's problems are under
``(..., "terms", label, "lower")``, its scale at ``(..., "lower", "scale")``, and a lower term
that rises above its upper one at ``(..., "terms", label)``.

**Lower under upper.** For two piecewise-linear shapes the check is exact: their difference is
linear between the union of their vertices and constant outside, so it is checked at those
vertices (and one point beyond each end), to rounding (1e-12). For other shapes it is checked
on :data:`GRID_POINTS` evenly spaced points over the variable's range plus every vertex the
shapes have; a violation narrower than the grid spacing could pass.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from fuzzkit.errors import did_you_mean
from fuzzkit.fuzzy import membership
from fuzzkit.fuzzy.model import Expression, Proposition, RuleBase, Term, Variable
from fuzzkit.fuzzy.type2_model import (
    MAX_RESOLUTION,
    TYPE_REDUCTIONS,
    LowerTerm,
    Type2RuleBase,
)

Path = tuple[str | int, ...]
Issue = tuple[Path, str]
TermChecker = Callable[[Term, Path], list[Issue]]

#: Points of the grid on which a smooth lower term is checked against its upper term.
GRID_POINTS = 10_001
#: Rounding allowance of the lower-under-upper check (memberships are in [0, 1]).
TOLERANCE = 1e-12


def _negated(expr: Expression) -> bool:
    if isinstance(expr, Proposition):
        return expr.negated
    return any(_negated(e) for e in expr.operands)


def lower_excess(upper: Term, lower: Term, scale: float, var: Variable) -> tuple[float, float]:
    """The largest ``scale * lower - upper`` and where it is (exact for piecewise linear)."""
    if upper.is_piecewise_linear and lower.is_piecewise_linear:
        xs = np.array(sorted(set(membership.breakpoints(upper) + membership.breakpoints(lower))))
        xs = np.concatenate([[xs[0] - 1.0], xs, [xs[-1] + 1.0]])
    else:
        extra = [
            x for t in (upper, lower) if t.is_piecewise_linear for x in membership.breakpoints(t)
        ]
        xs = np.unique(np.concatenate([np.linspace(var.low, var.high, GRID_POINTS), extra]))
    excess = scale * membership.evaluate_term(lower, xs) - membership.evaluate_term(upper, xs)
    k = int(np.argmax(excess))
    return float(excess[k]), float(xs[k])


def _check_lower(lt: LowerTerm, rb: RuleBase, check_term: TermChecker) -> list[Issue]:
    var = next((v for v in rb.inputs + rb.outputs if v.name == lt.variable), None)
    if var is None or lt.term not in var.term_names:
        return [((), f"lower term of unknown term {lt.variable}.{lt.term}")]
    kind = "inputs" if var in rb.inputs else "outputs"
    base: Path = (kind, var.name, "terms", lt.term)
    out: list[Issue] = []
    if not (math.isfinite(lt.scale) and 0.0 < lt.scale <= 1.0):
        out.append(((*base, "lower", "scale"), f"scale must be in (0, 1], got {lt.scale}"))
    upper = var.term(lt.term)
    if upper.is_sugeno or lt.shape.is_sugeno:
        out.append((base, "a Sugeno term (constant, linear) has no lower and upper functions"))
        return out
    shape_issues = check_term(lt.shape, (*base, "lower"))
    out.extend(shape_issues)
    if shape_issues or out or check_term(upper, (*base, "upper")):
        return out
    excess, at = lower_excess(upper, lt.shape, lt.scale, var)
    if excess > TOLERANCE:
        exact = upper.is_piecewise_linear and lt.shape.is_piecewise_linear
        out.append(
            (
                base,
                f"the lower membership function rises above the upper one at {var.name} = "
                f"{at:.6g} (by {excess:.3g}{'' if exact else ', on a grid'}); "
                "expected lower <= upper everywhere",
            )
        )
    return out


def footprint_problems(rb: Type2RuleBase, check_term: TermChecker) -> list[Issue]:
    """Every problem of ``rb``'s footprint; ``check_term`` is validation's shape check."""
    fp = rb.footprint
    out: list[Issue] = []
    if fp.type_reduction not in TYPE_REDUCTIONS:
        out.append(
            (
                ("type_reduction",),
                f"unknown type reduction {fp.type_reduction!r}"
                f"{did_you_mean(fp.type_reduction, TYPE_REDUCTIONS)}; expected one of "
                f"{', '.join(TYPE_REDUCTIONS)}",
            )
        )
    if fp.resolution is not None and not 2 <= fp.resolution <= MAX_RESOLUTION:
        out.append(
            (("resolution",), f"resolution must be 2..{MAX_RESOLUTION}, got {fp.resolution}")
        )
    for lt in fp.lowers:
        out.extend(_check_lower(lt, rb, check_term))
    mamdani = [v for v in rb.outputs if not v.is_sugeno]
    if mamdani and rb.operators.aggregation != "max":
        out.append(
            (
                ("operators", "aggregation"),
                f"an interval type-2 rule base aggregates with max, got "
                f"{rb.operators.aggregation!r}",
            )
        )
    want = "centroid" if mamdani else "weighted_average"
    if rb.defuzzifier != want:
        out.append(
            (
                ("defuzzifier",),
                f"an interval type-2 rule base is type-reduced (type_reduction:); its "
                f"defuzzifier must be {want}, got {rb.defuzzifier!r}",
            )
        )
    if fp.resolution is None:
        for var in mamdani:
            shapes, _ = fp.lower_terms(var)
            smooth = [t.name for t in var.terms + shapes if not t.is_piecewise_linear]
            if smooth:
                out.append(
                    (
                        ("outputs", var.name, "terms", smooth[0]),
                        f"exact (continuous) type reduction needs piecewise-linear output "
                        f"terms; {smooth[0]!r} is not (or set resolution: 101 to sample the "
                        "output range as MATLAB does)",
                    )
                )
    for k, rule in enumerate(rb.rules):
        if _negated(rule.antecedent):
            out.append(
                (
                    ("rules", k, "if"),
                    "'not' is not supported in interval type-2 rule bases (expected "
                    "propositions joined by and/or)",
                )
            )
    return out
