"""An independent reference Mamdani for the engine tests.

Membership functions are written out here from their textbook definitions (not taken from
fuzzkit.fuzzy.membership), and inference runs one rule at a time on a fine grid, so that a bug in
the engine or in the shape formulas cannot hide in both sides of a comparison.
"""

from __future__ import annotations

import math

import numpy as np

from fuzzkit.fuzzy.model import Expression, Proposition, RuleBase, Term

GRID = 200_001


def mu(term: Term, x: np.ndarray) -> np.ndarray:
    """Membership from the textbook definitions, written independently of fuzzkit."""
    p = term.params
    with np.errstate(divide="ignore", invalid="ignore"):
        if term.shape in ("triangle", "trapezoid"):
            a, b, c, d = (p[0], p[1], p[1], p[2]) if term.shape == "triangle" else p
            rise = np.where((x >= a) & (x < b), (x - a) / (b - a) if b > a else 0.0, 0.0)
            fall = np.where((x > c) & (x <= d), (d - x) / (d - c) if d > c else 0.0, 0.0)
            return np.where((x >= b) & (x <= c), 1.0, np.maximum(rise, fall))
        if term.shape == "left_shoulder":
            return np.where(x <= p[0], 1.0, np.where(x >= p[1], 0.0, (p[1] - x) / (p[1] - p[0])))
        if term.shape == "right_shoulder":
            return np.where(x >= p[1], 1.0, np.where(x <= p[0], 0.0, (x - p[0]) / (p[1] - p[0])))
        if term.shape == "gaussian":
            return np.exp(-((x - p[0]) ** 2) / (2.0 * p[1] ** 2))
        if term.shape == "bell":
            return 1.0 / (1.0 + np.abs((x - p[2]) / p[0]) ** (2.0 * p[1]))
        if term.shape == "sigmoid":
            return 1.0 / (1.0 + np.exp(-p[0] * (x - p[1])))
        # MATLAB's gauss2mf, smf, zmf, pimf, dsigmf, psigmf as its documentation writes them
        if term.shape == "gaussian_product":
            left = np.where(x <= p[0], np.exp(-((x - p[0]) ** 2) / (2.0 * p[1] ** 2)), 1.0)
            right = np.where(x >= p[2], np.exp(-((x - p[2]) ** 2) / (2.0 * p[3] ** 2)), 1.0)
            return left * right
        if term.shape == "s_shape":
            return smf(x, p[0], p[1])
        if term.shape == "z_shape":
            return zmf(x, p[0], p[1])
        if term.shape == "pi_shape":
            return smf(x, p[0], p[1]) * zmf(x, p[2], p[3])
        if term.shape in ("sigmoid_difference", "sigmoid_product"):
            s1 = 1.0 / (1.0 + np.exp(-p[0] * (x - p[1])))
            s2 = 1.0 / (1.0 + np.exp(-p[2] * (x - p[3])))
            return np.abs(s1 - s2) if term.shape == "sigmoid_difference" else s1 * s2
    raise AssertionError(term.shape)


def smf(x: np.ndarray, a: float, b: float) -> np.ndarray:
    m = (a + b) / 2
    return np.select(
        [x <= a, x <= m, x <= b],
        [0.0, 2 * ((x - a) / (b - a)) ** 2, 1 - 2 * ((x - b) / (b - a)) ** 2],
        1.0,
    )


def zmf(x: np.ndarray, a: float, b: float) -> np.ndarray:
    m = (a + b) / 2
    return np.select(
        [x <= a, x <= m, x <= b],
        [1.0, 1 - 2 * ((x - a) / (b - a)) ** 2, 2 * ((x - b) / (b - a)) ** 2],
        0.0,
    )


def firing(rb: RuleBase, point: dict[str, float]) -> list[float]:
    """Every rule's firing strength at ``point`` (inputs clamped), its weight applied."""
    grades = {}
    for v in rb.inputs:
        x = min(max(point[v.name], v.low), v.high)
        grades[v.name] = {t.name: float(mu(t, np.array(x))) for t in v.terms}

    def fire(e: Expression) -> float:
        if isinstance(e, Proposition):
            m = grades[e.variable][e.term]
            return 1.0 - m if e.negated else m
        vals = [fire(o) for o in e.operands]
        if e.op == "and":
            return min(vals) if rb.operators.and_ == "min" else math.prod(vals)
        acc = vals[0]
        for v in vals[1:]:
            acc = max(acc, v) if rb.operators.or_ == "max" else acc + v - acc * v
        return acc

    return [fire(rule.antecedent) * rule.weight for rule in rb.rules]


def reference(rb: RuleBase, point: dict[str, float], n: int = GRID) -> float | None:
    """Fine-grid Mamdani of the first output: one rule at a time, nothing vectorised.

    None when no rule fires (zero area).
    """
    out = rb.outputs[0]
    y = np.linspace(out.low, out.high, n)
    agg = np.zeros(n)
    for rule, a in zip(rb.rules, firing(rb, point), strict=True):
        m = mu(out.term(rule.consequents[0].term), y)
        imp = np.minimum(a, m) if rb.operators.implication == "min" else a * m
        if rb.operators.aggregation == "max":
            agg = np.maximum(agg, imp)
        elif rb.operators.aggregation == "bounded_sum":
            agg = np.minimum(1.0, agg + imp)
        else:
            agg = agg + imp - agg * imp
    area = float(np.trapezoid(agg, y))
    if area <= 1e-9 * (out.high - out.low):
        return None
    d = rb.defuzzifier
    if d == "centroid":
        return float(np.trapezoid(agg * y, y)) / area
    if d == "bisector":
        cum = np.concatenate([[0.0], np.cumsum(0.5 * (agg[1:] + agg[:-1]) * np.diff(y))])
        return float(np.interp(cum[-1] / 2, cum, y))
    at = np.nonzero(agg >= agg.max() - 1e-9)[0]
    som, lom = float(y[at[0]]), float(y[at[-1]])
    return {"smallest_of_maximum": som, "largest_of_maximum": lom}.get(d, (som + lom) / 2)
