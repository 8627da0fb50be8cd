"""Sugeno (Takagi-Sugeno-Kang) output stage: the batch evaluator and a pure-Python scalar path.

A Sugeno output's terms are ``constant`` (``z = value``) or ``linear``
(``z = c_1 x_1 + ... + c_n x_n + c_0``, inputs in declaration order). Every rule consequent on
the output counts on its own with its rule's weighted firing strength ``w``:
``weighted_average`` is ``sum(w z) / sum(w)``, ``weighted_sum`` is ``sum(w z)``; when
``sum(w) == 0`` the output takes its default (NaN when none). Implication and aggregation do
not apply (as in MATLAB, and in fuzzylite with aggregation none; see
docs/rulebase-format.md). ``linear`` terms see the same input values as the
membership functions (clamped under ``out_of_range: clamp``); results are not clamped.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import numpy.typing as npt

from fuzzkit.fuzzy import membership
from fuzzkit.fuzzy.model import Compound, Expression, RuleBase, Variable

FloatArray = npt.NDArray[np.float64]


class SugenoOutput:
    """One Sugeno (Takagi-Sugeno-Kang) output: a weighted mean or sum over the fired rules.

    Every consequent ``k`` of the output contributes its rule's weighted firing strength
    ``w_k`` and its term's value ``z_k`` (a constant, or ``c . x + c0`` at the input values the
    terms see): ``sum(w z) / sum(w)`` (``weighted_average``) or ``sum(w z)``
    (``weighted_sum``). Implication and aggregation do not apply: rules sharing a term count
    separately, as in MATLAB and in fuzzylite with aggregation none. When ``sum(w) == 0`` the
    output takes its default.
    """

    def __init__(self, rb: RuleBase, out: Variable) -> None:
        self.name = out.name
        self.default = math.nan if out.default is None else float(out.default)
        self.average = rb.defuzzifier == "weighted_average"
        n = len(rb.inputs)
        coef = np.zeros((len(out.terms), n + 1))
        for t, term in enumerate(out.terms):
            if term.shape == "constant":
                coef[t, n] = term.params[0]
            else:
                coef[t] = term.params
        inst = [
            (r, out.term_index(c.term))
            for r, rule in enumerate(rb.rules)
            for c in rule.consequents
            if c.variable == out.name
        ]
        self.inst_rules = np.array([r for r, _ in inst], dtype=np.intp)
        per_inst = coef[np.array([t for _, t in inst], dtype=np.intp)].reshape(-1, n + 1)
        self.slopes = per_inst[:, :n].T.copy()  # (inputs, consequents)
        self.constants = per_inst[:, n].copy()
        self.linear = bool(np.any(self.slopes != 0.0))

    def __call__(self, firing: FloatArray, inputs: list[FloatArray]) -> FloatArray:
        w = firing[:, self.inst_rules]
        if self.linear:
            z = np.stack(inputs, axis=1) @ self.slopes + self.constants
            num = (w * z).sum(axis=1)
        else:
            num = w @ self.constants
        tot = w.sum(axis=1)
        if self.average:
            with np.errstate(invalid="ignore", divide="ignore"):
                num = num / tot
        return np.where(tot > 0, num, self.default)


# A compiled condition: ("is", input, term, negated), ("and" | "or", operands), or
# ("all", ((input, term, negated), ...)) for an AND of propositions.
_Node = tuple[Any, ...]


def _compile(expr: Expression, rb: RuleBase) -> _Node:
    if isinstance(expr, Compound):
        subs = tuple(_compile(e, rb) for e in expr.operands)
        if expr.op == "and" and all(s[0] == "is" for s in subs):
            return ("all", tuple(s[1:] for s in subs))  # the common case, one loop
        return (expr.op, subs)
    pos = rb.input_names.index(expr.variable)
    return ("is", pos, rb.inputs[pos].term_index(expr.term), expr.negated)


class SugenoScalarPath:
    """Pure-Python single-point evaluation of a rule base whose outputs are all Sugeno.

    Applies when every input term is piecewise linear (any conditions: AND, OR, NOT, weights).
    Same formulas as the batch engine, without numpy's per-call overhead; results agree with
    it to rounding (sums are taken in another order).
    """

    def __init__(self, rb: RuleBase) -> None:
        self.clamp = rb.out_of_range == "clamp"
        self.ranges = [(v.low, v.high) for v in rb.inputs]
        self.forms = [[membership.trapezoid_form(t) for t in v.terms] for v in rb.inputs]
        self.product_and = rb.operators.and_ == "product"
        self.max_or = rb.operators.or_ == "max"
        self.rules = [(_compile(r.antecedent, rb), r.weight) for r in rb.rules]
        self.average = rb.defuzzifier == "weighted_average"
        self.outputs: list[tuple[list[tuple[int, tuple[float, ...], float]], float]] = []
        n = len(rb.inputs)
        for out in rb.outputs:
            cons = []
            for k, rule in enumerate(rb.rules):
                for c in rule.consequents:
                    if c.variable == out.name:
                        p = out.term(c.term).params
                        if out.term(c.term).shape == "constant":
                            cons.append((k, (0.0,) * n, p[0]))
                        else:
                            cons.append((k, tuple(p[:-1]), p[-1]))
            self.outputs.append((cons, math.nan if out.default is None else float(out.default)))

    def _fire(self, node: _Node, mus: list[list[float]]) -> float:
        if node[0] == "all":
            acc = 1.0
            for i, t, negated in node[1]:
                m = 1.0 - mus[i][t] if negated else mus[i][t]
                acc = acc * m if self.product_and else min(acc, m)
            return acc
        if node[0] == "is":
            m = mus[node[1]][node[2]]
            return 1.0 - m if node[3] else m
        parts = [self._fire(sub, mus) for sub in node[1]]
        acc = parts[0]
        for p in parts[1:]:
            if node[0] == "and":
                acc = acc * p if self.product_and else min(acc, p)
            else:
                acc = max(acc, p) if self.max_or else acc + p - acc * p
        return acc

    def __call__(self, values: Sequence[float]) -> list[float]:
        xs = []
        for (low, high), x in zip(self.ranges, values, strict=True):
            if x != x:  # NaN: never a correction
                return [math.nan] * len(self.outputs)
            if self.clamp:
                x = low if x < low else high if x > high else x
            else:
                x = (
                    -membership.EXTEND_LIMIT
                    if x < -membership.EXTEND_LIMIT
                    else min(x, membership.EXTEND_LIMIT)
                )
            xs.append(float(x))
        mus = [
            [
                min(max(min(1.0 + (x - b) * sr, 1.0 + (c - x) * sf), 0.0), 1.0)
                for b, c, sr, sf in forms
            ]
            for x, forms in zip(xs, self.forms, strict=True)
        ]
        w = [self._fire(node, mus) * weight for node, weight in self.rules]
        result = []
        for cons, default in self.outputs:
            num = tot = 0.0
            for k, coefs, c0 in cons:
                if w[k] != 0.0:
                    num += w[k] * (sum(c * x for c, x in zip(coefs, xs, strict=True)) + c0)
                    tot += w[k]
            if tot > 0.0:
                result.append(num / tot if self.average else num)
            else:
                result.append(default)
        return result


def sugeno_scalar_path(rb: RuleBase) -> SugenoScalarPath | None:
    """The scalar path when every output is Sugeno and every input term piecewise linear."""
    if not rb.outputs or not all(o.is_sugeno for o in rb.outputs):
        return None
    if any(not t.is_piecewise_linear for v in rb.inputs for t in v.terms):
        return None
    return SugenoScalarPath(rb)
