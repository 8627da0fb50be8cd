"""An independent brute-force reference for interval type-2 inference.

Memberships come from the textbook definitions in ``_mamdani_reference`` (not fuzzkit's), rules
fire one at a time, the upper and lower output sets are sampled on a grid, and the centroid
interval is found by trying every switch point of the Karnik-Mendel characterisation: ``y_l`` is
the smallest centroid of an embedded set that follows the upper set left of a switch point and
the lower set right of it, ``y_r`` the largest of the reverse. Nothing here calls fuzzkit's
engine or type reduction.
"""

from __future__ import annotations

import itertools

import numpy as np
from _mamdani_reference import mu

from fuzzkit.fuzzy.model import Proposition
from fuzzkit.fuzzy.type2_model import Type2RuleBase


def _memberships(rb: Type2RuleBase, name: str, label: str, x: float) -> tuple[float, float]:
    var = rb.input(name)
    x = min(max(x, var.low), var.high)
    term = var.term(label)
    lt = rb.footprint.lower(name, label)
    up = float(mu(term, np.array([x]))[0])
    lo = up if lt is None else lt.scale * float(mu(lt.shape, np.array([x]))[0])
    return lo, up


def firing_intervals(rb: Type2RuleBase, point: dict[str, float]) -> list[tuple[float, float]]:
    """``[lower, upper]`` firing of each rule (AND-only antecedents, min or product)."""
    out = []
    for rule in rb.rules:
        ante = rule.antecedent
        props = [ante] if isinstance(ante, Proposition) else list(ante.operands)
        lo, up = 1.0, 1.0
        for p in props:
            assert isinstance(p, Proposition)
            a, b = _memberships(rb, p.variable, p.term, point[p.variable])
            if rb.operators.and_ == "min":
                lo, up = min(lo, a), min(up, b)
            else:
                lo, up = lo * a, up * b
        out.append((lo * rule.weight, up * rule.weight))
    return out


def output_sets(
    rb: Type2RuleBase, point: dict[str, float], y: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Upper and lower aggregated output sets (max) sampled at ``y``."""
    var = rb.outputs[0]
    upper = np.zeros_like(y)
    lower = np.zeros_like(y)
    for rule, (f_lo, f_up) in zip(rb.rules, firing_intervals(rb, point), strict=True):
        term = var.term(rule.consequents[0].term)
        lt = rb.footprint.lower(var.name, term.name)
        mu_up = mu(term, y)
        mu_lo = mu_up if lt is None else lt.scale * mu(lt.shape, y)
        if rb.operators.implication == "min":
            upper = np.maximum(upper, np.minimum(f_up, mu_up))
            lower = np.maximum(lower, np.minimum(f_lo, mu_lo))
        else:
            upper = np.maximum(upper, f_up * mu_up)
            lower = np.maximum(lower, f_lo * mu_lo)
    return upper, lower


def switch_interval(
    y: np.ndarray, lower: np.ndarray, upper: np.ndarray, weights: np.ndarray
) -> tuple[float, float]:
    """Every switch point tried, one at a time (quadrature ``weights`` per sample)."""
    best_l, best_r = np.inf, -np.inf
    wu, wl = weights * upper, weights * lower
    # prefix sums written as a loop over switch points, kept plain on purpose
    su = np.concatenate([[0.0], np.cumsum(wu)])
    sl = np.concatenate([[0.0], np.cumsum(wl)])
    syu = np.concatenate([[0.0], np.cumsum(wu * y)])
    syl = np.concatenate([[0.0], np.cumsum(wl * y)])
    for k in range(len(y) + 1):
        den_l = su[k] + sl[-1] - sl[k]
        den_r = sl[k] + su[-1] - su[k]
        if den_l > 0:
            best_l = min(best_l, (syu[k] + syl[-1] - syl[k]) / den_l)
        if den_r > 0:
            best_r = max(best_r, (syl[k] + syu[-1] - syu[k]) / den_r)
    return best_l, best_r


def centroid_interval(
    rb: Type2RuleBase, point: dict[str, float], n: int, trapezoid: bool = True
) -> tuple[float, float]:
    """``[y_l, y_r]`` on ``n`` samples of the output range (trapezoid weights, or plain sums
    as MATLAB and pyit2fls use when ``trapezoid`` is false)."""
    var = rb.outputs[0]
    y = np.linspace(var.low, var.high, n)
    upper, lower = output_sets(rb, point, y)
    weights = np.ones(n)
    if trapezoid:
        weights[0] = weights[-1] = 0.5
    return switch_interval(y, lower, upper, weights)


def vertex_interval(z: list[float], intervals: list[tuple[float, float]]) -> tuple[float, float]:
    """Min and max of ``sum(w z) / sum(w)`` over every corner of the box of weights (IT2
    Sugeno): the extremes of this ratio lie at corners, so trying all ``2^R`` is exact."""
    values = []
    for corner in itertools.product(*intervals):
        w = np.array(corner)
        if w.sum() > 0:
            values.append(float(w @ np.array(z) / w.sum()))
    return min(values), max(values)
